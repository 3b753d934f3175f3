"""One exception base per package: every error class derives from it, and the command lines turn it (and a user's
file problem) into a one-line message while anything else surfaces as the bug it is."""

from __future__ import annotations

import ast
import importlib
import io
from pathlib import Path

import pytest

import pixelworld_env
import sb3_smc
from pixelworld_env.cli import main as pixelworld_main
from pixelworld_env.errors import PixelWorldError, PixelWorldKeyError, PixelWorldTypeError
from pixelworld_env.validation import check_int, check_seed
from sb3_smc.errors import SMCError, SMCKeyError
from tests.helpers import sb3_smc_cli

ID = "PW-ba_self-in-container_from_directly-above-v0"
ROOT = Path(__file__).resolve().parents[1]


def _error_classes(package: str) -> list[type[BaseException]]:
    """Every public exception class (a class named ``...Error``) defined in the modules of ``package``: found in the
    source, so that no script module runs."""
    found = []
    for path in sorted((ROOT / package).rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        names = [node.name for node in tree.body if isinstance(node, ast.ClassDef) and node.name.endswith("Error")]
        if names:
            module = importlib.import_module(".".join(path.relative_to(ROOT).with_suffix("").parts))
            found += [getattr(module, name) for name in names]
    return found


def test_every_pixelworld_error_is_a_pixelworld_error() -> None:
    classes = _error_classes("pixelworld_env")
    assert {"ConceptSyntaxError", "GenerationError", "DefinitionError", "CatalogError", "UnknownDatasetError",
            "PixelWorldKeyError"} <= {c.__name__ for c in classes}
    assert [c for c in classes if not issubclass(c, PixelWorldError)] == []
    assert pixelworld_env.PixelWorldError is PixelWorldError and "PixelWorldError" in pixelworld_env.__all__


def test_every_sb3_smc_error_is_an_smc_error() -> None:
    classes = _error_classes("sb3_smc")
    assert {"RecordError", "RunSettingsError", "RunFileError", "CurriculumError", "LibraryError", "UnknownSMCError",
            "ZooRunError"} <= {c.__name__ for c in classes}
    assert [c for c in classes if not issubclass(c, SMCError)] == []
    assert sb3_smc.SMCError is SMCError and "SMCError" in sb3_smc.__all__


def test_package_errors_keep_the_builtin_they_replaced() -> None:
    with pytest.raises(TypeError, match=r"^seed must be an integer, got 1.5 \(float\)$") as info:
        check_int(1.5, "seed")
    assert isinstance(info.value, PixelWorldTypeError)
    with pytest.raises(ValueError, match=r"^seed must be in \[0, 2\*\*63 - 1\], got -1$") as info:
        check_seed(-1)
    assert type(info.value) is PixelWorldError
    for error in (PixelWorldKeyError("unknown name 'x'"), SMCKeyError("unknown name 'x'")):
        assert isinstance(error, KeyError) and isinstance(error, ValueError)
        assert str(error) == "unknown name 'x'"  # not quoted, as a KeyError's message would be


def test_pixelworld_cli_prints_a_package_error_in_one_line() -> None:
    with pytest.raises(SystemExit) as info:
        pixelworld_main(["show", ID, "--seed", "-1"], out=io.StringIO())
    assert info.value.code == "pixelworld show: error: dataset seed must be in [0, 2**63 - 1], got -1"


def test_pixelworld_cli_prints_a_file_problem_with_its_path(tmp_path: Path) -> None:
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    with pytest.raises(SystemExit) as info:
        pixelworld_main(["show", ID, "--png", str(blocker / "sheet.png")], out=io.StringIO())
    assert str(info.value.code).startswith("pixelworld show: error: ") and str(blocker) in str(info.value.code)


def test_pixelworld_cli_lets_a_bug_surface(monkeypatch: pytest.MonkeyPatch) -> None:
    def broken() -> None:
        raise RuntimeError("bug")

    monkeypatch.setattr("pixelworld_env.cli.registered_ids", broken)
    with pytest.raises(RuntimeError, match="^bug$"):
        pixelworld_main(["list"], out=io.StringIO())


def test_sb3_smc_cli_prints_a_package_error_in_one_line(tmp_path: Path) -> None:
    code, out, err = sb3_smc_cli("train", "con2-cl", "--out", str(tmp_path / "run"), "--ray-address", "auto")
    assert code == 2 and out == ""
    assert err == "sb3-smc train: error: a Ray address ('auto') is for backend 'ray', not 'local'\n"
    code, _, err = sb3_smc_cli("experiment", "--out", str(tmp_path / "e"), "--targets", "no_such_dataset")
    assert code == 2 and err.startswith("sb3-smc experiment: error: unknown dataset 'no_such_dataset'")  # pixelworld's


def test_sb3_smc_cli_prints_a_missing_file_with_its_path(tmp_path: Path) -> None:
    code, _, err = sb3_smc_cli("status", str(tmp_path / "nothing"))
    assert code == 2 and err.startswith("sb3-smc status: error: ") and str(tmp_path / "nothing") in err


def test_sb3_smc_cli_lets_a_bug_surface(monkeypatch: pytest.MonkeyPatch) -> None:
    def broken() -> None:
        raise RuntimeError("bug")

    monkeypatch.setattr("sb3_smc.curricula.shipped_curricula", broken)
    with pytest.raises(RuntimeError, match="^bug$"):
        sb3_smc_cli("curricula")


def test_training_and_vector_env_input_errors_are_package_errors() -> None:
    """Bad input to train_smc, the SMC envs and the native vector env: the package's errors, so the CLIs print
    them as messages."""
    import gymnasium as gym

    from sb3_smc import train_smc
    from sb3_smc.envs.wrapper import HierarchicalSMCWrapper

    with pytest.raises(SMCError, match="takes no argument 'spilt'"):
        train_smc(ID, total_timesteps=64, n_envs=2, n_steps=32, env_kwargs={"spilt": "test"})
    with pytest.raises(SMCError, match="learnin_rate"):
        train_smc(ID, total_timesteps=64, n_envs=2, n_steps=32, learnin_rate=0.1)
    with pytest.raises(SMCError, match="call_step_cap must be >= 1"):
        HierarchicalSMCWrapper(gym.make(ID), [], call_step_cap=0)
    with pytest.raises(PixelWorldError, match="render_mode='human' draws one env"):
        gym.make_vec(ID, num_envs=2, render_mode="human")
