"""The public module paths: every documented module imports (the API reference's and the architecture map's), the
module paths the moves into sub-packages took away (``pixelworld_env`` 2026-11-25, ``sb3_smc`` 2026-11-27) are gone,
and the old ``sb3_smc`` modules whose paths are packages now (``envs``, ``smc``, ``tasks``) still give their names."""

from __future__ import annotations

import importlib
import importlib.util
import re
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _modules(package: str, *names: str) -> list[str]:
    return [package, *(f"{package}.{name}" for name in names)]


PUBLIC = (
    # pixelworld_env: docs/architecture.md (the layout and its table), docs/api/pixelworld_env.md
    *_modules("pixelworld_env", "errors", "validation", "yaml_loading", "atomic", "cli", "demo"),
    *_modules("pixelworld_env.core", "constants", "kinds", "objects", "shapes", "regions", "scene", "world",
              "kernels", "render"),
    *_modules("pixelworld_env.concepts", "parser", "predicates", "evaluate", "errors"),
    *_modules("pixelworld_env.generation", "definitions", "experiment_files", "dataset", "dataset_spec", "sampling",
              "placement", "csp", "oracle"),
    *_modules("pixelworld_env.datasets", "catalog", "cache", "loading"),
    *_modules("pixelworld_env.envs", "env", "vector", "registration"),
    # sb3_smc: docs/architecture.md's table, docs/api/*.md
    *_modules("sb3_smc", "errors", "cli", "demo"),
    *_modules("sb3_smc.core", "layout", "dag", "hyperparameters", "names"),
    *_modules("sb3_smc.tasks", "task", "resolved_task"),
    *_modules("sb3_smc.smc", "smc", "policies", "numpy_actors"),
    *_modules("sb3_smc.envs", "smc_step", "wrapper", "gymnasium_vec_env", "vec_env", "hierarchical_vec_env", "factory",
              "leaf_calls"),
    *_modules("sb3_smc.learning", "bias", "features", "callbacks", "training", "batched", "env_group",
              "group_checkpoint", "evaluation"),
    *_modules("sb3_smc.records", "spec", "results", "base"),
    *_modules("sb3_smc.common", "kernels", "discounting", "threads"),
    *_modules("sb3_smc.common.recurrent", "policies", "buffers", "type_aliases", "gru", "layers", "lean_recurrence",
              "lean_update"),
    *_modules("sb3_smc.recurrent_trpo"),
    *_modules("sb3_smc.library", "library", "manifest", "upgrade", "pretrained", "storage", "errors", "model_file",
              "files"),
    *_modules("sb3_smc.fewshot", "learn", "choice"),
    # sb3_smc.zoo.record_video is a launcher: it runs rl_zoo3's record_video on import
    *_modules("sb3_smc.zoo", "configs", "trpo", "ppo", "ppo_lstm", "recurrent_trpo", "entries", "importing"),
    *_modules("sb3_smc.curricula", "format", "shipped", "designed", "trainer", "options", "scheduler", "jobs",
              "run_directory", "executors", "pretrained", "reuse"),
    *_modules("sb3_smc.experiments", "design", "runner", "wall_clock", "cnn", "report", "figures", "tables",
              "statistics", "bootstrap", "claims", "sweep", "experience", "extension", "paper", "few_shot",
              "few_shot_report", "cannot", "tabular"),
)


PACKAGES = {"sb3_smc.envs": "sb3_smc.envs.factory", "sb3_smc.smc": "sb3_smc.smc.smc",
            "sb3_smc.tasks": "sb3_smc.tasks.task"}
"""The old ``sb3_smc`` modules whose paths are packages now -> the module whose names each package re-exports."""
REMOVED = (
    *(f"pixelworld_env.{name}" for name in (
        "catalog", "constants", "csp", "dataset_spec", "definitions", "env", "experiment_files", "kernels", "loading",
        "objects", "oracle", "placement", "regions", "registration", "render", "sampling", "scene", "shapes", "vector",
        "world", "_moved")),
    *(f"sb3_smc.{name}" for name in (
        "batched", "bias", "callbacks", "dag", "evaluation", "features", "gymnasium_vec_env", "hyperparameters",
        "layout", "numpy_actors", "policies", "resolved_task", "smc_step", "vec_env", "wrapper", "_moved")),
)
"""The deprecated shims of the old module paths, removed after their release."""


def api_reference_modules() -> set[str]:
    """The modules the API reference renders (its ``::: module`` lines)."""
    return {m for page in (ROOT / "docs" / "api").glob("*.md")
            for m in re.findall(r"^::: ([\w.]+)\s*$", page.read_text(encoding="utf-8"), re.M)}


def test_the_api_reference_documents_public_modules_and_no_old_path():
    documented = api_reference_modules()
    assert documented and documented <= set(PUBLIC)
    assert not documented & {*REMOVED, *PACKAGES, "sb3_smc.training"}


def test_every_documented_module_imports():
    """In a fresh interpreter."""
    code = "import importlib, sys\nfor m in sys.argv[1:]: importlib.import_module(m)"
    done = subprocess.run([sys.executable, "-c", code, *PUBLIC], capture_output=True, text=True, cwd=ROOT,
                          timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]


@pytest.mark.parametrize("old", REMOVED)
def test_an_old_module_path_is_gone(old):
    assert importlib.util.find_spec(old) is None


def test_the_package_roots_hold_only_their_entry_points():
    assert {p.stem for p in (ROOT / "pixelworld_env").glob("*.py")} == {
        "__init__", "atomic", "cli", "demo", "errors", "validation", "yaml_loading"}
    assert {p.stem for p in (ROOT / "sb3_smc").glob("*.py")} == {"__init__", "cli", "demo", "errors", "training"}


def test_sb3_smc_training_keeps_only_the_class_path_of_version_0_1_models():
    """sb3-smc 0.1's archives name ``sb3_smc.training.SequenceLstmPolicy`` (``tests/test_library.py`` unpickles it);
    the module holds nothing else."""
    module = importlib.import_module("sb3_smc.training")
    assert module.__all__ == ["SequenceLstmPolicy"]
    assert {n for n in vars(module) if not n.startswith("_")} == {"SequenceLstmPolicy"}


@pytest.mark.parametrize("old", sorted(PACKAGES))
def test_an_old_module_path_that_is_a_package_now_gives_its_names(old):
    new = importlib.import_module(PACKAGES[old])
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        package = importlib.import_module(old)
        names = getattr(new, "__all__", [n for n in vars(new) if not n.startswith("_")])
        assert names and all(getattr(package, name) is getattr(new, name) for name in names)
        namespace: dict = {}
        exec(f"from {old} import *", namespace)
        assert all(namespace[name] is getattr(new, name) for name in names)


@pytest.mark.parametrize("package", ["pixelworld_env.datasets", "pixelworld_env.generation"])
def test_the_names_of_the_old_datasets_and_generation_modules_are_gone(package):
    """Those names live in their modules (``datasets.cache``, ``generation.dataset`` ...), not in the packages."""
    with pytest.raises(ImportError, match="cannot import name"):
        exec(f"from {package} import {'load_or_generate' if package.endswith('datasets') else 'generate'}", {})
