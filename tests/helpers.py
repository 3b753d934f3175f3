"""Helpers shared by several test modules: the reference data, small hand-drawn environments, test policies."""

from __future__ import annotations

import gzip
import importlib.util
import json
import os
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

from pixelworld_env import PixelWorldEnv, Scene

REFERENCE = Path(os.environ.get("PIXELWORLD_REFERENCE",
                                Path(__file__).resolve().parents[2] / "shared" / "reference"))
SAMPLES = REFERENCE / "aaai18_samples"


def require_reference() -> Path:
    """The reference folder, or a loud failure (never a silent skip) when it is missing."""
    if not (SAMPLES / "index.json").is_file():
        pytest.fail(
            f"reference data not found at {REFERENCE}: these tests need ../shared/reference beside the "
            "checkout (or PIXELWORLD_REFERENCE pointing at it)",
            pytrace=False,
        )
    return REFERENCE


def sample_files() -> list[Path]:
    """Every decoded dataset file (empty when the reference is missing; the tests then fail loudly)."""
    return sorted(SAMPLES.glob("*.jsonl.gz")) if SAMPLES.is_dir() else []


def read_samples(path: Path) -> tuple[dict, list[dict]]:
    """The header and the sample records of one decoded dataset file."""
    with gzip.open(path, "rt", encoding="utf-8") as handle:
        header = json.loads(handle.readline())
        return header, [json.loads(line) for line in handle]


CONTAINER = """
#########
#...S...#
#.a...a.#
#.a...a.#
#.aaaaa.#
#=======#
#.......#
#########
"""
IN_CONTAINER = "?x container(x) & inside_supported(self,x)"


def make(kind: str = "bring-about", text: str = CONTAINER, **kwargs) -> PixelWorldEnv:
    scenes = [Scene.from_ascii(text, {"a": "container"})]
    return PixelWorldEnv(scenes, kind=kind, concept=kwargs.pop("concept", IN_CONTAINER), **kwargs)


def classification_env(**kwargs) -> PixelWorldEnv:
    inside = Scene.from_ascii(CONTAINER.replace("#...S...#", "#.......#").replace("#.a...a.#\n#.aaaaa.#",
                                                                                    "#.a.S.a.#\n#.aaaaa.#"),
                              {"a": "container"})
    outside = Scene.from_ascii(CONTAINER, {"a": "container"})
    return PixelWorldEnv([inside, outside], kind="classification", concept=IN_CONTAINER, **kwargs)



class UniformPolicy:
    """Stochastic test policy: uniform over the actions (the evaluation's sampling decides everything)."""

    def __init__(self, n_actions: int) -> None:
        self.n_actions = n_actions

    def initial_state(self) -> None:
        return None

    def probabilities(self, observation: np.ndarray, state: None) -> tuple[np.ndarray, None]:
        return np.full(self.n_actions, 1.0 / self.n_actions), None


def import_script(folder: str, name: str) -> ModuleType:
    """The script ``<folder>/<name>.py`` of the repository (``benchmarks``, ``tools``: not packages) as a module."""
    path = Path(__file__).resolve().parents[1] / folder / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def import_benchmark(name: str) -> ModuleType:
    """The script ``benchmarks/<name>.py`` imported as a module."""
    return import_script("benchmarks", name)


def import_tool(name: str) -> ModuleType:
    """The script ``tools/<name>.py`` imported as a module."""
    return import_script("tools", name)


def sb3_smc_cli(*argv: str) -> tuple[int, str, str]:
    """``sb3-smc`` run in this process: its exit status, stdout and stderr (argparse's errors included)."""
    import contextlib
    import io

    from sb3_smc.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(list(argv))
        except SystemExit as exit_:
            code = exit_.code
    return code, out.getvalue(), err.getvalue()
