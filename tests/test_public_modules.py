"""The public module paths: every documented module imports (the API reference's and the architecture map's), and
every path the move into sub-packages took away (2026-11-25) still imports for a release, with a
``DeprecationWarning`` that names the new path (``pixelworld_env._moved``)."""

from __future__ import annotations

import importlib
import re
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from pixelworld_env._moved import MODULES, NAMES

ROOT = Path(__file__).resolve().parents[1]


def _modules(package: str, *names: str) -> list[str]:
    return [package, *(f"{package}.{name}" for name in names)]


PUBLIC = (
    # pixelworld_env: docs/architecture.md (the layout and its table), docs/api/pixelworld_env.md
    *_modules("pixelworld_env", "errors", "validation", "atomic", "cli", "demo"),
    *_modules("pixelworld_env.core", "constants", "objects", "shapes", "regions", "scene", "world", "kernels",
              "render"),
    *_modules("pixelworld_env.concepts", "parser", "predicates", "evaluate", "errors"),
    *_modules("pixelworld_env.generation", "definitions", "experiment_files", "dataset", "dataset_spec", "sampling",
              "placement", "csp", "oracle"),
    *_modules("pixelworld_env.datasets", "catalog", "cache", "loading"),
    *_modules("pixelworld_env.envs", "env", "vector", "registration"),
    # sb3_smc: docs/architecture.md's table, docs/api/*.md
    *_modules("sb3_smc", "errors", "cli", "demo"),
    *_modules("sb3_smc.core", "layout", "dag", "hyperparameters"),
    *_modules("sb3_smc.tasks", "task", "resolved_task"),
    *_modules("sb3_smc.smc", "smc", "policies", "numpy_actors"),
    *_modules("sb3_smc.envs", "smc_step", "wrapper", "gymnasium_vec_env", "vec_env", "factory"),
    *_modules("sb3_smc.learning", "bias", "features", "callbacks", "training", "batched", "evaluation"),
    *_modules("sb3_smc.records", "spec", "results", "base"),
    *_modules("sb3_smc.common", "kernels", "discounting", "threads"),
    *_modules("sb3_smc.common.recurrent", "policies", "buffers", "type_aliases", "gru", "layers", "lean_update"),
    *_modules("sb3_smc.recurrent_trpo"),
    *_modules("sb3_smc.library", "library", "manifest", "upgrade", "pretrained", "storage", "errors"),
    # sb3_smc.zoo.record_video is a launcher: it runs rl_zoo3's record_video on import
    *_modules("sb3_smc.zoo", "configs", "trpo", "ppo", "ppo_lstm", "recurrent_trpo", "entries", "importing"),
    *_modules("sb3_smc.curricula", "format", "shipped", "designed", "trainer", "options", "scheduler", "jobs",
              "run_directory", "executors", "pretrained", "reuse"),
    *_modules("sb3_smc.experiments", "design", "runner", "wall_clock", "cnn", "report", "figures", "tables",
              "statistics", "bootstrap", "claims", "sweep", "paper"),
)


def api_reference_modules() -> set[str]:
    """The modules the API reference renders (its ``::: module`` lines)."""
    return {m for page in (ROOT / "docs" / "api").glob("*.md")
            for m in re.findall(r"^::: ([\w.]+)\s*$", page.read_text(encoding="utf-8"), re.M)}


def test_the_api_reference_documents_public_modules_and_no_old_path():
    documented = api_reference_modules()
    assert documented and documented <= set(PUBLIC)
    assert not documented & (set(MODULES) | set(NAMES))


def test_every_documented_module_imports_and_none_uses_an_old_path():
    """In a fresh interpreter, with the old paths' deprecation warnings made errors."""
    code = "import importlib, sys\nfor m in sys.argv[1:]: importlib.import_module(m)"
    done = subprocess.run([sys.executable, "-W", "error:pixelworld_env:DeprecationWarning", "-c", code, *PUBLIC],
                          capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]


@pytest.mark.parametrize(("old", "new"), sorted(MODULES.items()))
def test_an_old_module_path_warns_naming_its_new_path_and_gives_its_names(old, new):
    fresh = importlib.import_module(new)
    sys.modules.pop(old, None)
    with pytest.warns(DeprecationWarning, match=rf"{re.escape(old)} moved to {re.escape(new)}") as caught:
        __import__(old)
    shim = sys.modules[old]
    assert len(caught) == 1 and Path(caught[0].filename) == Path(__file__)  # the importing line is blamed
    names = getattr(fresh, "__all__", [n for n in vars(fresh) if not n.startswith("_")])
    assert names and all(getattr(shim, name) is getattr(fresh, name) for name in names)
    assert (ROOT / "pixelworld_env" / f"{old.rsplit('.', 1)[1]}.py").is_file()


@pytest.mark.parametrize("package", sorted(NAMES))
def test_the_names_of_an_old_module_now_a_package_resolve_with_the_warning(package):
    module = importlib.import_module(package)
    for name, home in NAMES[package].items():
        vars(module).pop(name, None)  # resolved by an earlier run: resolve it again
        with pytest.warns(DeprecationWarning, match=rf"{re.escape(package)}\.{name} moved to {re.escape(home)}"):
            value = getattr(module, name)
        assert value is getattr(importlib.import_module(home), name)
        with warnings.catch_warnings():
            warnings.simplefilter("error", DeprecationWarning)
            assert getattr(module, name) is value  # warned once
    with pytest.raises(ImportError, match="cannot import name 'no_such_name'"):
        exec(f"from {package} import no_such_name", {})


def test_the_old_paths_are_the_modules_the_move_took_away():
    """``git show fc6e2e9 --stat``: 22 modules at the package's root moved into sub-packages."""
    old = {m.rsplit(".", 1)[1] for m in [*MODULES, *NAMES]}
    assert old == {"catalog", "constants", "csp", "dataset_spec", "datasets", "definitions", "env", "experiment_files",
                   "generation", "kernels", "loading", "objects", "oracle", "placement", "regions", "registration",
                   "render", "sampling", "scene", "shapes", "vector", "world"}
