"""The public module paths: every documented module imports (the API reference's and the architecture map's), and
every path the moves into sub-packages took away (``pixelworld_env`` 2026-11-25, ``sb3_smc`` 2026-11-27) still imports
for a release, with a ``DeprecationWarning`` that names the new path (``pixelworld_env._moved``, ``sb3_smc._moved``),
but the old ``sb3_smc`` modules whose paths are packages now: those re-export the old names without a warning."""

from __future__ import annotations

import importlib
import re
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from pixelworld_env._moved import MODULES as PIXELWORLD_MODULES
from pixelworld_env._moved import NAMES
from sb3_smc._moved import MODULES as SB3_SMC_MODULES
from sb3_smc._moved import PACKAGES

ROOT = Path(__file__).resolve().parents[1]
MODULES = {**PIXELWORLD_MODULES, **SB3_SMC_MODULES}
"""Every old module path -> its new module."""
SHIMS = {old: new for old, new in MODULES.items() if old not in PACKAGES}
"""The old module paths that are deprecated shims."""


def _modules(package: str, *names: str) -> list[str]:
    return [package, *(f"{package}.{name}" for name in names)]


PUBLIC = (
    # pixelworld_env: docs/architecture.md (the layout and its table), docs/api/pixelworld_env.md
    *_modules("pixelworld_env", "errors", "validation", "yaml_loading", "atomic", "cli", "demo"),
    *_modules("pixelworld_env.core", "constants", "objects", "shapes", "regions", "scene", "world", "kernels",
              "render"),
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
              "statistics", "bootstrap", "claims", "sweep", "experience", "paper", "few_shot", "few_shot_report"),
)


def api_reference_modules() -> set[str]:
    """The modules the API reference renders (its ``::: module`` lines)."""
    return {m for page in (ROOT / "docs" / "api").glob("*.md")
            for m in re.findall(r"^::: ([\w.]+)\s*$", page.read_text(encoding="utf-8"), re.M)}


def test_the_api_reference_documents_public_modules_and_no_old_path():
    documented = api_reference_modules()
    assert documented and documented <= set(PUBLIC)
    assert not documented & (set(MODULES) | set(NAMES))  # an old path that is a package now is not documented either


def test_every_documented_module_imports_and_none_uses_an_old_path():
    """In a fresh interpreter, with the old paths' deprecation warnings made errors."""
    code = "import importlib, sys\nfor m in sys.argv[1:]: importlib.import_module(m)"
    done = subprocess.run([sys.executable, "-W", "error:pixelworld_env:DeprecationWarning",
                           "-W", "error:sb3_smc:DeprecationWarning", "-c", code, *PUBLIC],
                          capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]


@pytest.mark.parametrize(("old", "new"), sorted(SHIMS.items()))
def test_an_old_module_path_warns_naming_its_new_path_and_gives_its_names(old, new):
    fresh = importlib.import_module(new)
    sys.modules.pop(old, None)
    with pytest.warns(DeprecationWarning, match=rf"{re.escape(old)} moved to {re.escape(new)}") as caught:
        __import__(old)
    shim = sys.modules[old]
    assert len(caught) == 1 and Path(caught[0].filename) == Path(__file__)  # the importing line is blamed
    names = getattr(fresh, "__all__", [n for n in vars(fresh) if not n.startswith("_")])
    assert names and all(getattr(shim, name) is getattr(fresh, name) for name in names)
    assert (ROOT / f"{old.replace('.', '/')}.py").is_file()


@pytest.mark.parametrize("old", sorted(PACKAGES))
def test_an_old_module_path_that_is_a_package_now_gives_its_names_without_a_warning(old):
    new = importlib.import_module(SB3_SMC_MODULES[old])
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        package = importlib.import_module(old)
        names = getattr(new, "__all__", [n for n in vars(new) if not n.startswith("_")])
        assert names and all(getattr(package, name) is getattr(new, name) for name in names)
        namespace: dict = {}
        exec(f"from {old} import *", namespace)
        assert all(namespace[name] is getattr(new, name) for name in names)
    assert (ROOT / old.replace(".", "/") / "__init__.py").is_file()


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
    """``git show fc6e2e9 --stat``: 22 modules at ``pixelworld_env``'s root moved into sub-packages; then 19 of
    ``sb3_smc``'s (all but ``__init__``, ``cli``, ``demo`` and ``errors``)."""
    old = {m.rsplit(".", 1)[1] for m in [*PIXELWORLD_MODULES, *NAMES]}
    assert old == {"catalog", "constants", "csp", "dataset_spec", "datasets", "definitions", "env", "experiment_files",
                   "generation", "kernels", "loading", "objects", "oracle", "placement", "regions", "registration",
                   "render", "sampling", "scene", "shapes", "vector", "world"}
    old = {m.rsplit(".", 1)[1] for m in SB3_SMC_MODULES}
    assert old == {"batched", "bias", "callbacks", "dag", "envs", "evaluation", "features", "gymnasium_vec_env",
                   "hyperparameters", "layout", "numpy_actors", "policies", "resolved_task", "smc", "smc_step", "tasks",
                   "training", "vec_env", "wrapper"}
    assert {path.stem for path in (ROOT / "sb3_smc").glob("*.py")} == {*old - {"envs", "smc", "tasks"}, "__init__",
                                                                      "_moved", "cli", "demo", "errors"}
