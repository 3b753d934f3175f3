"""rl_zoo3 as users type it, against sb3-smc installed from a wheel, and the start-up hook of both kinds of install.

A module fixture builds the wheel and installs it (``--no-deps``) into a fresh virtual environment whose other
packages come from this interpreter's site-packages; every command then runs in that environment. Runs are short
(2,000 steps) but real: the literal ``rl_zoo3 train`` line, the conf modules, ``enjoy``, ``record_video``, the
TensorBoard curves, ``sb3-smc import-zoo`` and a level-2 zoo run calling an imported SMC. A second fixture makes the
editable install ``make`` makes (``pip install -e`` of the checkout) in another fresh environment: both must import
without a warning and run the README's literal ``rl_zoo3 train`` line on a concept pool.
"""

from __future__ import annotations

import json
import os
import site
import subprocess
import sys
import sysconfig
import tomllib
import venv
from pathlib import Path

import pytest
import yaml

pytest.importorskip("rl_zoo3", reason="rl_zoo3 is in the [test] extra: pip install -e '.[test]'")

ROOT = Path(__file__).resolve().parents[1]
FLAT = "PW-cl_self-in-left-corner_vs_on-hline-v0"
LEVEL2 = "PW-cl_self-in-container_vs_noncontainer-v0"
POOL = "PW-ba_self-in-container-v0"


class Installed:
    """A virtual environment with the sb3-smc wheel; ``run`` executes Python code or a console entry in it."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self.python = root / "bin" / "python"
        self.work = root / "work"
        self.work.mkdir()

    def run(self, code: str, *args: str, env: dict[str, str] | None = None, check: bool = True,
            options: tuple[str, ...] = ()) -> subprocess.CompletedProcess:
        """``python OPTIONS -c CODE ARGS`` in the environment's work folder."""
        result = subprocess.run([str(self.python), *options, "-c", code, *args], cwd=self.work, capture_output=True,
                                text=True, env={**os.environ, **(env or {})}, timeout=600)
        if check and result.returncode != 0:
            raise AssertionError(f"exit {result.returncode}\n--- stdout\n{result.stdout[-3000:]}\n--- stderr\n"
                                 f"{result.stderr[-3000:]}")
        return result

    def zoo(self, *args: str, **kwargs) -> subprocess.CompletedProcess:
        """``rl_zoo3 ARGS`` (the console script's entry point, ``rl_zoo3.cli:main``)."""
        return self.run("import sys; from rl_zoo3.cli import main; sys.argv = ['rl_zoo3', *sys.argv[1:]]; main()",
                        *args, **kwargs)

    def sb3_smc(self, *args: str, **kwargs) -> subprocess.CompletedProcess:
        """``sb3-smc ARGS`` (the console script's entry point, ``sb3_smc.cli:main``)."""
        return self.run("import sys; from sb3_smc.cli import main; sys.exit(main(sys.argv[1:]))", *args, **kwargs)

    def module(self, name: str, *args: str, **kwargs) -> subprocess.CompletedProcess:
        """``python -m NAME ARGS``."""
        return self.run("import runpy, sys; sys.argv = [sys.argv[1], *sys.argv[2:]]; "
                        "runpy.run_module(sys.argv[0], run_name='__main__', alter_sys=True)", name, *args, **kwargs)


def _fresh_environment(root: Path) -> tuple[Path, Path]:
    """A virtual environment under ``root`` whose dependencies come from this interpreter's site-packages (a path
    line: its .pth files, among them the editable install of the checkout, are not run there); (folder, purelib)."""
    env_dir = root / "venv"
    venv.EnvBuilder(with_pip=False).create(env_dir)
    purelib = Path(sysconfig.get_path("purelib", vars={"base": str(env_dir), "platbase": str(env_dir)}))
    (purelib / "_dependencies.pth").write_text("\n".join(site.getsitepackages()) + "\n")
    return env_dir, purelib


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> Installed:
    root = tmp_path_factory.mktemp("wheel-env")
    wheels = root / "wheels"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w",
                    str(wheels), str(ROOT)], check=True, capture_output=True, cwd=root)
    (wheel,) = wheels.glob("sb3_smc-*.whl")
    env_dir, purelib = _fresh_environment(root)
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "-q", "--target", str(purelib), str(wheel)],
                   check=True, capture_output=True)
    assert (purelib / "sb3_smc_gym_hook.pth").is_file()
    return Installed(env_dir)


@pytest.fixture(scope="module")
def editable(tmp_path_factory) -> Installed:
    """``pip install -e`` of the checkout, as ``make`` does, with the environment's own pip (the one on the path
    line; it leaves this interpreter's install of sb3-smc alone: "outside environment")."""
    env_dir, purelib = _fresh_environment(tmp_path_factory.mktemp("editable-env"))
    subprocess.run([str(env_dir / "bin" / "python"), "-m", "pip", "install", "--no-deps", "--no-build-isolation",
                    "--no-index", "-q", "-e", str(ROOT)], check=True, capture_output=True)
    assert (purelib / "sb3_smc_gym_hook.pth").is_file()
    return Installed(env_dir)


INSTALLS = ["installed", "editable"]
IMPORTS = {
    "import pixelworld_env": "import pixelworld_env",
    "import gymnasium": f"import gymnasium; assert '{POOL}' in gymnasium.registry",
    "import sb3_smc": "import sb3_smc, sb3_smc.learning.training",
    "pixelworld list": "import sys; from pixelworld_env.cli import main; sys.exit(main(['list']))",
    "sb3-smc curricula": "import sys; from sb3_smc.cli import main; sys.exit(main(['curricula']))",
}
"""What a user runs first -> the code it runs (the console scripts' entry points)."""


@pytest.mark.parametrize("install", INSTALLS)
@pytest.mark.parametrize("what", list(IMPORTS))
def test_imports_and_commands_warn_nothing(request: pytest.FixtureRequest, install: str, what: str) -> None:
    """``python -W error``: the hook stays quiet while ``pixelworld_env`` imports Gymnasium itself (it registers
    the ids at the end of its own import)."""
    environment: Installed = request.getfixturevalue(install)
    result = environment.run(IMPORTS[what], options=("-W", "error"), check=False)
    assert result.returncode == 0, result.stderr[-3000:]
    assert "Warning" not in result.stderr, result.stderr[-3000:]


@pytest.mark.parametrize("install", INSTALLS)
def test_each_install_imports_its_own_copy(request: pytest.FixtureRequest, install: str) -> None:
    environment: Installed = request.getfixturevalue(install)
    where = environment.run("import pixelworld_env, sb3_smc; print(pixelworld_env.__file__, sb3_smc.__file__)")
    home = ROOT if install == "editable" else environment.root
    assert all(path.startswith(str(home)) for path in where.stdout.split())


def test_the_wheel_ships_the_pretrained_library(installed: Installed) -> None:
    """Package data: the pretrained library's manifest, index and models are in the wheel and load by name."""
    check = ("from sb3_smc import SMCLibrary; from sb3_smc.library.pretrained import pretrained_curricula; "
             "print(len(pretrained_curricula()), len(SMCLibrary.pretrained('search2-canon')))")
    shipped = json.loads((ROOT / "sb3_smc" / "library" / "data" / "pretrained" / "pretrained.json").read_text())
    assert installed.run(check).stdout.split() == [str(len(shipped["curricula"])), "26"]  # as in the source tree


def test_the_wheel_carries_its_license_and_metadata(installed: Installed) -> None:
    """A wheel that stands alone: the LICENSE file, the license expression, authors, classifiers, the typed marker of
    both packages, and ``__version__`` of both equal to the distribution's."""
    check = ("import json, pixelworld_env, sb3_smc; from importlib import metadata as m; from pathlib import Path; "
             "d = m.distribution('sb3-smc'); "
             "print(json.dumps({'version': d.version, 'versions': [pixelworld_env.__version__, sb3_smc.__version__], "
             "'license': d.metadata['License-Expression'], 'license_files': d.metadata.get_all('License-File'), "
             "'author': d.metadata['Author'], 'classifiers': d.metadata.get_all('Classifier'), "
             "'license_text': (d.locate_file('') / next(f for f in d.files if f.name == 'LICENSE')).read_text(), "
             "'typed': [Path(p.__file__).with_name('py.typed').is_file() for p in (pixelworld_env, sb3_smc)]}))")
    meta = json.loads(installed.run(check).stdout)
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert meta["version"] == project["version"] and meta["versions"] == [meta["version"]] * 2
    assert meta["license"] == "MIT" and meta["license_files"] == ["LICENSE"]
    assert meta["license_text"] == (ROOT / "LICENSE").read_text() and meta["license_text"].startswith("MIT License")
    assert meta["author"] == "The sb3-smc developers" and "Typing :: Typed" in meta["classifiers"]
    assert meta["typed"] == [True, True]


@pytest.mark.parametrize("install", INSTALLS)
def test_the_readme_command_on_a_concept_pool(request: pytest.FixtureRequest, install: str) -> None:
    """The bare zoo line (docs/library.md, 'as typed'), in a wheel install and in the editable install of a clone."""
    environment: Installed = request.getfixturevalue(install)
    result = environment.zoo("train", "--algo", "trpo", "--env", POOL, "-n", "1000", "--num-threads", "1", "-f",
                             "pool")
    assert "could not register" not in result.stderr
    assert (environment.work / "pool" / "trpo" / f"{POOL}_1" / f"{POOL}.zip").is_file()


def test_the_hook_registers_the_ids_when_gymnasium_is_imported_and_not_before(installed: Installed) -> None:
    probe = ("import sys\n"
             "heavy = sorted(m for m in ('torch', 'pixelworld_env', 'sb3_smc', 'gymnasium') if m in sys.modules)\n"
             "import gymnasium, sb3_smc\n"
             "print(heavy, 'PW-cl_self-in-left-corner_vs_on-hline-v0' in gymnasium.registry,\n"
             "      sb3_smc.__file__.startswith(sys.prefix))\n")
    assert installed.run(probe).stdout.split() == ["[]", "True", "True"]  # nothing loaded at start; the wheel's copy
    off = installed.run(probe, env={"SB3_SMC_GYM_HOOK": "0"}).stdout.split()
    assert off[1] == "False"


def test_the_hook_imports_nothing_at_start_and_leaves_gymnasium_its_own_loader() -> None:
    """What the ``.pth`` line runs at every interpreter start imports no module (``os`` and ``sys`` are loaded before
    any ``.pth`` line runs) and puts one finder first on ``sys.meta_path``; importing Gymnasium then registers the
    ids, and the module keeps its own loader (``__loader__``, ``__spec__.loader``)."""
    code = ("import os, sys\n"
            "before = set(sys.modules)\n"
            "import _sb3_smc_gym_hook; _sb3_smc_gym_hook.install()\n"
            "print(sorted(set(sys.modules) - before), type(sys.meta_path[0]).__name__)\n"
            "import gymnasium\n"
            f"print('{POOL}' in gymnasium.registry, type(gymnasium.__loader__).__name__,\n"
            "      type(gymnasium.__spec__.loader).__name__, sorted(sys.meta_path[0].pending))\n")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), *site.getsitepackages()])}
    env.pop("SB3_SMC_GYM_HOOK", None)
    result = subprocess.run([sys.executable, "-S", "-c", code], env=env, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr[-3000:]
    assert result.stdout.split() == ["['_sb3_smc_gym_hook']", "_ImportWatcher", "True", "SourceFileLoader",
                                     "SourceFileLoader", "['rl_zoo3.utils']"]


@pytest.mark.parametrize("algo", ["trpo", "ppo"])
def test_the_literal_train_command(installed: Installed, algo: str) -> None:
    installed.zoo("train", "--algo", algo, "--env", FLAT, "-n", "2000", "--num-threads", "1", "-f", f"literal-{algo}")
    assert (installed.work / f"literal-{algo}" / algo / f"{FLAT}_1" / f"{FLAT}.zip").is_file()


def test_conf_module_trains_with_the_shipped_settings_and_tensorboard_curves(installed: Installed) -> None:
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    installed.zoo("train", "--algo", "ppo_lstm", "--env", FLAT, "-conf", "sb3_smc.zoo.ppo_lstm", "-n", "4000",
                  "--num-threads", "1", "-f", "logs", "--tensorboard-log", "tb")
    config = (installed.work / "logs" / "ppo_lstm" / f"{FLAT}_1" / FLAT / "config.yml").read_text()
    assert "sb3_smc.zoo.smc_env" in config and "MlpLstmPolicy" in config and "lstm_hidden_size=32" in config
    (events,) = (installed.work / "tb").rglob("events.out.tfevents.*")
    tags = EventAccumulator(str(events)).Reload().Tags()["scalars"]
    assert {"smc/accuracy", "smc/training_return", "smc/episode_length", "rollout/ep_rew_mean"} <= set(tags)


def test_enjoy_states_the_split_and_record_video_writes_an_mp4(installed: Installed) -> None:
    if not (installed.work / "logs" / "ppo_lstm").is_dir():
        installed.zoo("train", "--algo", "ppo_lstm", "--env", FLAT, "-conf", "sb3_smc.zoo.ppo_lstm", "-n", "2000",
                      "--num-threads", "1", "-f", "logs")
    out = installed.zoo("enjoy", "--algo", "ppo_lstm", "--env", FLAT, "-f", "logs", "--no-render", "-n", "60",
                        "--env-kwargs", "split:'test'")
    assert f"sb3-smc: {FLAT} serves the 'test' split: 50 environments" in out.stderr
    installed.module("rl_zoo3.record_video", "--algo", "ppo_lstm", "--env", FLAT, "-f", "logs", "-n", "30",
                     "-o", "videos", "--deterministic")
    videos = list((installed.work / "videos").rglob("*.mp4"))
    assert videos and videos[0].stat().st_size > 1000


def test_import_zoo_then_a_level2_zoo_run_calling_it(installed: Installed) -> None:
    installed.zoo("train", "--algo", "trpo", "--env", FLAT, "-conf", "sb3_smc.zoo.trpo", "-n", "2000",
                  "--num-threads", "1", "-f", "child")
    out = installed.sb3_smc("import-zoo", f"child/trpo/{FLAT}_1", "--library", "lib", "--name", "corner")
    assert "added SMC 'corner' (classification, TRPO)" in out.stdout
    # a level-2 run: the shipped TRPO settings with the imported SMC as an extra action
    settings = yaml.safe_load((ROOT / "zoo_configs" / "trpo.yml").read_text())["default"]
    settings["env_wrapper"] = [{"sb3_smc.zoo.smc_env": {"library": str(installed.work / "lib"),
                                                        "names": ["corner"]}}]
    (installed.work / "level2.yml").write_text(yaml.safe_dump({LEVEL2: settings}))
    installed.zoo("train", "--algo", "trpo", "--env", LEVEL2, "-conf", "level2.yml", "-n", "2000", "--num-threads",
                  "1", "-f", "parent")
    check = ("import sys\n"
             "from sb3_smc import SMCLibrary, evaluate\n"
             "from sb3_smc.zoo import import_zoo_model\n"
             "smc = import_zoo_model(sys.argv[1], 'lib', name='container')\n"
             "library = SMCLibrary.load('lib')\n"
             "parent = library['container']\n"
             "result = evaluate(parent, sys.argv[2], repeats=1)\n"
             "print(library.names, [c.name for c in parent.children], parent.action_names[-1],\n"
             "      result.call_counts().get('corner', 0) > 0, result.n_episodes)\n")
    out = installed.run(check, f"parent/trpo/{LEVEL2}_1", LEVEL2).stdout
    assert out.split() == ["('corner',", "'container')", "['corner']", "SMC:corner", "True", "50"]


def test_recurrent_trpo_with_a_gru_trains_enjoys_and_imports(installed: Installed) -> None:
    """``--algo recurrent_trpo`` exists in rl_zoo3 once the package is installed (the start-up hook); the paper's
    learner is the shipped settings with ``policy: MlpGruPolicy``."""
    settings = yaml.safe_load((ROOT / "zoo_configs" / "recurrent_trpo.yml").read_text())["default"]
    settings["policy"] = "MlpGruPolicy"
    (installed.work / "trpo_gru.yml").write_text(yaml.safe_dump({FLAT: settings}))
    installed.zoo("train", "--algo", "recurrent_trpo", "--env", FLAT, "-conf", "trpo_gru.yml", "-n", "2000",
                  "--num-threads", "1", "-f", "rtrpo")
    out = installed.zoo("enjoy", "--algo", "recurrent_trpo", "--env", FLAT, "-f", "rtrpo", "--no-render", "-n", "30")
    assert f"sb3-smc: {FLAT} serves the 'train' split" in out.stderr  # the zoo's default env kwargs
    check = ("import sys\n"
             "from sb3_smc.zoo import import_zoo_model\n"
             "smc = import_zoo_model(sys.argv[1], 'rlib', name='corner')\n"
             "print(type(smc.model).__name__, type(smc.model.policy).__name__, type(smc.policy).__name__)\n")
    out = installed.run(check, f"rtrpo/recurrent_trpo/{FLAT}_1").stdout
    assert out.split() == ["RecurrentTRPO", "SequenceGruPolicy", "NumpyGRUPolicy"]


def test_import_zoo_refuses_a_run_without_the_smc_wrapper(installed: Installed) -> None:
    if not (installed.work / "literal-trpo").is_dir():
        installed.zoo("train", "--algo", "trpo", "--env", FLAT, "-n", "2000", "--num-threads", "1", "-f",
                      "literal-trpo")
    out = installed.sb3_smc("import-zoo", f"literal-trpo/trpo/{FLAT}_1", "--library", "lib2", check=False)
    assert out.returncode == 2
    assert "did not use sb3-smc's wrapper" in out.stderr and "-conf sb3_smc.zoo.trpo" in out.stderr
    assert not (installed.work / "lib2").exists()


def test_a_zoo_run_on_a_minigrid_smc_task_imports_with_its_layout(installed: Installed) -> None:
    """rl_zoo3 on an SMC task of another environment (--gym-packages registers it), then imported into a library
    with the task's layout, and a level-2 zoo run calling it."""
    pytest.importorskip("minigrid")
    package, child_id, parent_id = ("sb3_smc.examples.minigrid_doorkey", "DoorKey5-get-key-v0",
                                    "DoorKey5-doorkey-v0")
    installed.zoo("train", "--algo", "ppo", "--env", child_id, "--gym-packages", package, "-conf", "sb3_smc.zoo.ppo",
                  "-n", "2000", "--num-threads", "1", "-f", "mg")
    out = installed.sb3_smc("import-zoo", f"mg/ppo/{child_id}_1", "--library", "mglib", "--name", "get-key")
    assert "added SMC 'get-key' (bring-about, PPO)" in out.stdout
    settings = yaml.safe_load((ROOT / "zoo_configs" / "ppo.yml").read_text())["default"]
    settings["env_wrapper"] = [{"sb3_smc.zoo.smc_env": {"library": str(installed.work / "mglib"),
                                                        "names": ["get-key"]}}]
    (installed.work / "mg2.yml").write_text(yaml.safe_dump({parent_id: settings}))
    run = installed.zoo("train", "--algo", "ppo", "--env", parent_id, "--gym-packages", package, "-conf", "mg2.yml",
                        "-n", "2000", "--num-threads", "1", "-f", "mgparent")
    assert "serves its environment's own start states (an SMC task), SMC actions ['get-key']" in run.stderr
    check = ("import sys\n"
             "from sb3_smc import SMCLibrary\n"
             "from sb3_smc.zoo import import_zoo_model\n"
             "smc = import_zoo_model(sys.argv[1], 'mglib', name='doorkey')\n"
             "library = SMCLibrary.load('mglib')\n"
             "print(library['doorkey'].layout.sensor_size, library['doorkey'].action_names[-1],\n"
             "      library['get-key'].layout == library['doorkey'].layout)\n")
    out = installed.run(check, f"mgparent/ppo/{parent_id}_1").stdout
    assert out.split() == ["151", "SMC:get-key", "True"]
