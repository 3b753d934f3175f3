"""SMCLibrary: save/load round trip in a fresh process, validation errors, crash-safe saves in place and the merge
with other writers, old (pickled) libraries loaded only with trust."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import textwrap
import unicodedata
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import torch
from sb3_contrib import TRPO, RecurrentPPO
from stable_baselines3 import PPO

import pixelworld_env  # noqa: F401  (registers the PW-* ids)
from sb3_smc.envs.wrapper import HierarchicalSMCWrapper
from sb3_smc.learning.evaluation import evaluate
from sb3_smc.learning.training import train_smc
from sb3_smc.library import (
    FORMAT,
    FORMAT_VERSION,
    CorruptModelError,
    LayoutMismatchError,
    LibraryConflictError,
    LibraryError,
    ManifestError,
    MissingChildError,
    SMCLibrary,
    UnknownSMCError,
    UntrustedModelError,
    storage,
)
from sb3_smc.library.manifest import ENTRY_CHECKSUM, MANIFEST_CHECKSUM, content_sha256, model_path, seal
from sb3_smc.records import Budget, EvaluationRecord, TaskSpec, TrainingRecord, TrainingSpec, package_versions
from sb3_smc.smc.policies import ScriptedPolicy, policy_from_model
from sb3_smc.smc.smc import SMC
from sb3_smc.tasks.task import SMCTask
from tests.helpers import sb3_smc_cli

CL_ID = "PW-cl_self-in-left-corner_vs_on-hline-v0"
BA_ID = "PW-ba_self-in-container_from_on-floor-v0"
ROOT = Path(__file__).resolve().parents[1]


def _records(name: str, env_id: str, algo: str, seed: int, children: tuple[SMC, ...]):
    """A spec, a training record (numpy numbers included) and a test evaluation, as train_smc / evaluate make."""
    spec = TrainingSpec(name=name, task=TaskSpec(env_id).resolved(), algo=algo, seed=seed,
                        hyperparameters={"gamma": 0.99, "policy_kwargs": {"net_arch": (32,)}},
                        budget=Budget(64, 1, 32), children=tuple(c.name for c in children))
    record = TrainingRecord(training_returns=(0.1, float("nan"), 0.2, 0.25),
                            success_rates=(0.0, float("nan"), 0.5, 0.5),
                            selected_update=np.int64(3), selected_return=np.float32(0.25), total_timesteps=64,
                            primitive_steps=80, wall_time_s=1.5, versions=package_versions())
    evaluation = EvaluationRecord(smc=name, env_id=env_id, split="test", kind=spec.task.kind, repeats=10,
                                  evaluation_seed=0, score=0.5, environment_scores=(0.5, 0.5), mean_length=3.5,
                                  call_counts={})
    return {"spec": spec, "record": record, "evaluations": (evaluation,)}


def _smc(name: str, env_id: str, algo: type, children=(), seed: int = 0, learn: bool = False) -> SMC:
    """An SMC with an untrained model whose weights are perturbed (far from uniform probabilities), or trained."""
    env = HierarchicalSMCWrapper(gym.make(env_id), children)
    policy = "MlpLstmPolicy" if algo is RecurrentPPO else "MlpPolicy"
    kwargs = {"policy_kwargs": {"lstm_hidden_size": 32}} if algo is RecurrentPPO else {}
    model = algo(policy, env, n_steps=32, batch_size=32, seed=seed, device="cpu", **kwargs)
    if learn:
        model.learn(32)
    generator = torch.Generator().manual_seed(seed)
    with torch.no_grad():
        for parameter in model.policy.parameters():
            parameter.add_(0.3 * torch.randn(parameter.shape, generator=generator))
    return SMC(name, env.unwrapped.kind, policy_from_model(model), children=children, model=model,
               **_records(name, env_id, algo.__name__, seed, tuple(children)))


@pytest.fixture(scope="module")
def smcs() -> dict[str, SMC]:
    torch.set_num_threads(1)
    corner = _smc("corner", CL_ID, RecurrentPPO)                       # recurrent, classification
    container = _smc("container", BA_ID, TRPO, seed=1)                  # MLP, bring-about
    corner_ppo = _smc("corner-ppo", CL_ID, PPO, seed=2)                 # PPO
    climber = _smc("climber", BA_ID, RecurrentPPO, children=(corner, container), seed=3, learn=True)  # two levels
    return {s.name: s for s in (corner, container, corner_ppo, climber)}


@pytest.fixture(scope="module")
def saved(smcs, tmp_path_factory) -> Path:
    library = SMCLibrary([smcs["climber"], smcs["corner-ppo"]])
    return library.save(tmp_path_factory.mktemp("saved") / "library")


@pytest.fixture
def copy(saved, tmp_path) -> Path:
    """A private copy of the saved library, to break."""
    return Path(shutil.copytree(saved, tmp_path / "library"))


def _edit(path: Path, change) -> None:
    """Change the manifest of the library in ``path`` as an edit meant to be kept would (a manifest of the current
    version is written with fresh checksums: storage.write_manifest)."""
    manifest = json.loads((path / "manifest.json").read_text())
    sealed = MANIFEST_CHECKSUM in manifest
    change(manifest)
    (path / "manifest.json").write_text(json.dumps(seal(manifest) if sealed else manifest))


def _model_file(path: Path, name: str) -> Path:
    """The model file of SMC ``name`` in the library in ``path``, as its manifest entry names it."""
    return path / json.loads((path / "manifest.json").read_text())["smcs"][name]["model"]


def _readdress(path: Path, name: str, data: bytes) -> Path:
    """Store ``data`` as the model file of SMC ``name`` with a manifest that records it (its SHA-256 and file name:
    an edit meant to be kept), so that what is checked is the file's content, not its checksum."""
    digest = hashlib.sha256(data).hexdigest()
    file = path / model_path(digest)
    file.write_bytes(data)
    _edit(path, lambda m: m["smcs"][name].update(model=model_path(digest), sha256=digest))
    return file


def _model_names(path: Path) -> list[str]:
    return sorted(os.listdir(path / "models"))


def _observations(size: int, n: int = 6, seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 2, size=(n, size)).astype(np.float32)


def _trace(policy, observations: np.ndarray) -> np.ndarray:
    """Probabilities of ``policy`` along ``observations`` (one call: the state carries over)."""
    state, rows = policy.initial_state(), []
    for obs in observations:
        probabilities, state = policy.probabilities(obs, state)
        rows.append(probabilities)
    return np.array(rows)


# ------------------------------------------------------------------------------------------------ round trip

def test_round_trip_in_a_fresh_process(smcs, saved, tmp_path):
    expected = {}
    for name, smc in smcs.items():
        observations = _observations(smc.observation_size, seed=len(name))
        expected[f"{name}/obs"] = observations
        expected[f"{name}/probs"] = _trace(smc.policy, observations)
    np.savez(tmp_path / "expected.npz", **expected)
    records = {name: [smc.spec.to_dict(), smc.record.to_dict(), [e.to_dict() for e in smc.evaluations]]
               for name, smc in smcs.items()}
    (tmp_path / "records.json").write_text(json.dumps(records))
    script = textwrap.dedent(f"""
        import json, sys
        import torch
        torch.set_num_threads(1)
        import gymnasium as gym
        import numpy as np
        import pixelworld_env
        from sb3_smc.library import SMCLibrary

        library = SMCLibrary.load({str(saved)!r})
        assert library.names == ("corner", "container", "climber", "corner-ppo"), library.names
        expected = np.load({str(tmp_path / "expected.npz")!r})
        records = json.load(open({str(tmp_path / "records.json")!r}))
        for name in library.names:
            smc = library[name]
            state, rows = smc.policy.initial_state(), []
            for obs in expected[name + "/obs"]:
                p, state = smc.policy.probabilities(obs, state)
                rows.append(p)
            np.testing.assert_allclose(np.array(rows), expected[name + "/probs"], rtol=0, atol=1e-12)
            got = [smc.spec.to_dict(), smc.record.to_dict(), [e.to_dict() for e in smc.evaluations]]
            assert got == records[name], (got, records[name])
            assert smc.test_score == 0.5
        climber = library["climber"]
        assert [c.name for c in climber.children] == ["corner", "container"]
        assert climber.children[0] is library["corner"] and climber.children[1] is library["container"]
        assert type(climber.model).__name__ == "RecurrentPPO" and type(library["container"].model).__name__ == "TRPO"
        assert type(library["corner-ppo"].model).__name__ == "PPO"
        assert climber.action_names[-2:] == ("SMC:corner", "SMC:container")
        # the two-level SMC runs as an action, calling its own children
        env = library.wrap(gym.make({BA_ID!r}), ["climber"], call_step_cap=20)
        env.reset(seed=0)
        _, _, _, _, info = env.step(env.action_names.index("SMC:climber"))
        assert info["smc_calls"][-1]["smc"] == "climber", info
        print("ok")
    """)
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert result.returncode == 0, result.stdout + result.stderr
    assert result.stdout.strip().endswith("ok")


def test_the_digest_names_the_weights_whatever_file_holds_them(smcs, saved):
    """``SMC.digest``: the same after a save and load (another model file), another for other weights or other
    children's weights; ``None`` where a scripted policy is called."""
    loaded = SMCLibrary.load(saved)
    digests = {name: smc.digest for name, smc in smcs.items()}
    assert all(re.fullmatch(r"[0-9a-f]{64}", d) for d in digests.values()) and len(set(digests.values())) == 4
    assert loaded["climber"].digest == digests["climber"] and loaded["corner"].digest == digests["corner"]
    model = loaded["corner"].model
    with torch.no_grad():
        next(model.policy.parameters()).view(-1)[0] += 1e-6
    assert loaded["corner"].digest != digests["corner"] and loaded["climber"].digest != digests["climber"]
    assert loaded["container"].digest == digests["container"]
    scripted = SMC("walker", "bring-about", ScriptedPolicy(5, lambda obs, step: 1))
    env = HierarchicalSMCWrapper(gym.make(BA_ID), [scripted])
    model = PPO("MlpPolicy", env, n_steps=32, batch_size=32, device="cpu")
    assert scripted.digest is None
    assert SMC("parent", "bring-about", policy_from_model(model), children=[scripted], model=model).digest is None


def test_manifest_records_each_smc_once(saved, smcs):
    """An entry is its model file, checksum and records; what the SMC is and the summaries are read from them. The
    checksums of the manifest's own content: one per entry, of its name and fields, and one of the whole. The model
    file is named by the SHA-256 of its bytes, which are the model's (storage.model_bytes: weights and settings)."""
    manifest = json.loads((saved / "manifest.json").read_text())
    assert manifest["format"] == FORMAT and manifest["version"] == FORMAT_VERSION == 6
    assert {"sb3_smc", "stable_baselines3", "sb3_contrib", "torch"} <= set(manifest["created_with"])
    raw = manifest["smcs"]["climber"]
    assert set(raw) == {"model", "sha256", "spec", "record", "evaluations", ENTRY_CHECKSUM}
    assert raw[ENTRY_CHECKSUM] == content_sha256(["climber", {k: v for k, v in raw.items() if k != ENTRY_CHECKSUM}])
    assert manifest[MANIFEST_CHECKSUM] == content_sha256({k: v for k, v in manifest.items() if k != MANIFEST_CHECKSUM})
    assert re.fullmatch(r"[0-9a-f]{64}", raw["sha256"]) and raw["model"] == f"models/{raw['sha256']}.safetensors"
    assert (saved / raw["model"]).read_bytes() == storage.model_bytes(smcs["climber"].model)
    assert storage.sha256(saved / raw["model"]) == raw["sha256"]
    assert _model_names(saved) == sorted(f"{entry['sha256']}.safetensors" for entry in manifest["smcs"].values())
    entries = storage.check_manifest(manifest, saved / "manifest.json")
    entry = entries["climber"]
    assert (entry.kind, entry.algo, entry.children, entry.frame_stack) == ("bring-about", "RecurrentPPO",
                                                                           ("corner", "container"), 1)
    assert entry.action_names == smcs["climber"].action_names
    assert entry.observation == {"size": 81 + 2 + 7, "window": 81, "outcomes": 2, "previous_action": 7}
    assert entry.summary() == {"env_id": BA_ID, "datasets": ["ba_self-in-container_from_on-floor"], "seed": 3,
                               "selected_update": 3, "training_return": 0.25, "test_score": 0.5,
                               "total_timesteps": 64}
    assert entries["corner"].action_names == ("SIG0", "SIG1", "DOWN", "RIGHT", "UP", "LEFT")


def test_mapping_interface_and_add(smcs):
    library = SMCLibrary()
    stored = library.add(smcs["climber"])  # children first, recursively
    assert library.names == ("corner", "container", "climber") and len(library) == 3
    assert stored is smcs["climber"] and "corner" in library and "nope" not in library
    library.add(smcs["corner"])  # the same SMC again: nothing changes
    assert library.names == ("corner", "container", "climber")
    with pytest.raises(LibraryError, match="child of"):
        library.remove("corner")
    assert library.remove("climber") is smcs["climber"]


def test_unknown_name_suggests_close_names(smcs):
    library = SMCLibrary([smcs["climber"]])
    with pytest.raises(UnknownSMCError, match="did you mean 'corner'") as info:
        library["coner"]
    assert isinstance(info.value, KeyError) and "no SMC named 'coner'" in str(info.value)
    with pytest.raises(UnknownSMCError, match="did you mean 'climber'"):
        library.wrap(gym.make(BA_ID), ["climbr"])


def test_conflicting_and_replaced_smcs(smcs):
    library = SMCLibrary([smcs["climber"]])
    other_corner = _smc("corner", CL_ID, RecurrentPPO, seed=7)
    with pytest.raises(LibraryError, match="different SMC named 'corner'"):
        library.add(other_corner)
    library.add(other_corner, replace=True)
    assert library["corner"] is other_corner
    assert library["climber"].children[0] is other_corner  # the parent calls the new child by name


def test_scripted_smcs_cannot_be_stored():
    scripted = SMC("walker", "bring-about", ScriptedPolicy(5, lambda obs, step: 1))
    with pytest.raises(LibraryError, match="'walker' has no model .*scripted"):
        SMCLibrary().add(scripted)
    env = HierarchicalSMCWrapper(gym.make(BA_ID), [scripted])
    model = PPO("MlpPolicy", env, n_steps=32, batch_size=32, device="cpu")
    parent = SMC("parent", "bring-about", policy_from_model(model), children=[scripted], model=model)
    library = SMCLibrary()
    with pytest.raises(LibraryError, match="'walker' has no model"):
        library.add(parent)
    assert len(library) == 0


def test_add_is_all_or_nothing(smcs):
    corner, container = smcs["corner"], smcs["container"]
    scripted = SMC("walker", "bring-about", ScriptedPolicy(5, lambda obs, step: 1))
    env = HierarchicalSMCWrapper(gym.make(BA_ID), [corner, scripted])
    model = PPO("MlpPolicy", env, n_steps=32, batch_size=32, device="cpu")
    parent = SMC("parent", "bring-about", policy_from_model(model), children=[corner, scripted], model=model)
    library = SMCLibrary([container])
    with pytest.raises(LibraryError, match="'walker' has no model"):
        library.add(parent)
    assert library.names == ("container",)  # 'corner' was not left behind


def test_model_that_does_not_fit_the_smc_is_refused(smcs):
    corner = smcs["corner"]
    wrong = SMC("corner", "bring-about", corner.policy, model=corner.model)  # 5 actions, the model has 6
    with pytest.raises(LayoutMismatchError, match="has 6 actions"):
        SMCLibrary().add(wrong)


# ------------------------------------------------------------------------------------------------ environments

def test_wrap_and_env_for(saved):
    library = SMCLibrary.load(saved)
    env = library.wrap(gym.make(CL_ID), ["container", "climber"], include_primitives=False)
    assert env.action_names == ("SIG0", "SIG1", "SMC:container", "SMC:climber")
    assert env.observation_space.shape == (81 + 2 + 4,)
    own = library.env_for("climber", gym.make(BA_ID))
    assert own.action_names == library["climber"].action_names
    obs, _ = own.reset(seed=0)
    action, _ = library["climber"].model.predict(obs)
    assert own.action_space.contains(int(action))


def test_env_of_the_other_kind_is_a_layout_mismatch(saved):
    library = SMCLibrary.load(saved)
    with pytest.raises(LayoutMismatchError, match="'corner' acts on classification tasks.*bring-about task"):
        library.env_for("corner", gym.make(BA_ID))
    with pytest.raises(LayoutMismatchError, match="'container' acts on bring-about tasks.*classification task"):
        library.env_for("container", gym.make(CL_ID))
    with pytest.raises(LayoutMismatchError, match="a PixelWorld environment or an SMCTask .* got CartPoleEnv"):
        library.wrap(gym.make("CartPole-v1"), ["corner"])
    with pytest.raises(LayoutMismatchError, match="already wrapped"):
        library.wrap(library.wrap(gym.make(CL_ID), ["corner"]), ["container"])


CART_ID = "TestCartRight-v0"
"""CartPole as an SMC task (bring-about: the cart right of the centre): a Gymnasium environment that is not PixelWorld,
sensor 4 values, primitives A0 and A1."""


def _cart_right(env: gym.Env) -> bool:
    return bool(env.state[0] > 0.05)


def _cart_task(max_steps: int = 100, **kwargs) -> SMCTask:
    return SMCTask(gym.make("CartPole-v1"), "bring-about", goal=_cart_right, max_steps=max_steps, **kwargs)


def test_smcs_of_an_smc_task_are_actions_of_that_task(saved, tmp_path):
    """wrap and env_for take any task the wrapper takes (an SMCTask as PixelWorld), and name what does not fit."""
    if CART_ID not in gym.registry:
        gym.register(CART_ID, entry_point=_cart_task)
    settings = dict(algo="PPO", total_timesteps=256, n_envs=2, n_steps=128, batch_size=128, max_steps=20,
                    log_every=0)
    child = train_smc(CART_ID, seed=0, name="right", **settings)
    parent = train_smc(CART_ID, seed=1, name="right-twice", children=[child], **settings)
    library = SMCLibrary.load(SMCLibrary([parent]).save(tmp_path / "library"))
    env = library.wrap(gym.make(CART_ID, max_steps=20), ["right"])
    assert env.action_names == ("SIG1", "A0", "A1", "SMC:right") and env.observation_space.shape == (4 + 1 + 4,)
    env.reset(seed=0)
    *_, info = env.step(env.action_names.index("SMC:right"))
    assert info["smc_calls"][-1]["smc"] == "right"
    own = library.env_for("right-twice", _cart_task(20))  # the SMC's own view: its model acts on it
    assert own.action_names == library["right-twice"].action_names == ("SIG1", "A0", "A1", "SMC:right")
    obs, _ = own.reset(seed=0)
    action, _ = library["right-twice"].model.predict(obs)
    own.step(int(action))
    pixelworld = SMCLibrary.load(saved)
    with pytest.raises(LayoutMismatchError) as info:
        pixelworld.wrap(gym.make(CART_ID), ["corner"])
    assert str(info.value) == (
        f"SMC 'corner' does not fit the environment '{CART_ID}': it senses 81 values, the task gives 4; its primitive "
        "actions are ['DOWN', 'RIGHT', 'UP', 'LEFT'], the task's ['A0', 'A1'] (it was trained on another environment "
        "or observation)")
    with pytest.raises(LayoutMismatchError, match=re.escape(
            f"SMC 'right' does not fit the environment '{BA_ID}': it senses 4 values, the task gives 81; its "
            "primitive actions are ['A0', 'A1'], the task's ['DOWN', 'RIGHT', 'UP', 'LEFT']")):
        library.wrap(gym.make(BA_ID), ["right"])
    with pytest.raises(LayoutMismatchError, match=re.escape(
            "SMC 'right-twice' does not fit the environment 'CartPole-v1': its primitive actions are ['A0', 'A1'], "
            "the task's ['push-left', 'push-right'] (it was")):
        library.env_for("right-twice", _cart_task(primitive_names=("push-left", "push-right")))
    with pytest.raises(LayoutMismatchError, match="'right' acts on bring-about tasks.*is a classification task"):
        library.env_for("right", SMCTask(gym.make("CartPole-v1"), "classification", label=lambda env: 0))
    with pytest.raises(LayoutMismatchError, match="a PixelWorld environment or an SMCTask .* got CartPoleEnv"):
        library.wrap(gym.make("CartPole-v1"), ["right"])  # the bare environment: no task to act on


def test_an_smc_of_minigrid_is_an_action_of_minigrid(tmp_path):
    """The issue's case: an SMC trained on a Minigrid DoorKey task, an action of another DoorKey task."""
    pytest.importorskip("minigrid")
    from sb3_smc.examples.minigrid_doorkey import OBSERVATION, at_goal, register, task_id

    register(5)
    get_key = train_smc(task_id(5, "get-key"), name="GetKey", algo="PPO", total_timesteps=256, n_envs=2,
                        n_steps=128, batch_size=128, max_steps=20, log_every=0)
    doorkey = SMCTask(gym.make("MiniGrid-DoorKey-8x8-v0"), "bring-about", goal=at_goal, observation=OBSERVATION)
    env = SMCLibrary([get_key]).wrap(doorkey, ["GetKey"])
    assert env.action_names[-1] == "SMC:GetKey" and env.observation_space.shape == (151 + 1 + 9,)
    env.reset(seed=0)
    *_, info = env.step(env.action_names.index("SMC:GetKey"))
    assert info["smc_calls"][-1]["smc"] == "GetKey"


# ------------------------------------------------------------------------------------------------ broken libraries

@pytest.mark.parametrize(("damage", "message"), [
    (lambda data: data[: len(data) // 2], r"tensor '.*' lies outside the file"),
    (lambda data: data[:100], r"truncated or not a model file \(its header says \d+ bytes, the file has 92"),
    (lambda data: data[:5], r"truncated \(5 bytes"),
    (lambda data: os.urandom(len(data)), "truncated or not a model file"),
    (lambda data: len(data[8:]).to_bytes(8, "little") + data[8:], "not a model file \\(its header is not JSON"),
], ids=["half", "header-cut", "five-bytes", "random", "bad-header"])
def test_corrupt_model_file(copy, damage, message):
    """A damaged model file fails its checksum; stored with a checksum of the damaged bytes (a manifest edited to
    match), it is still refused, for what it holds."""
    model = _model_file(copy, "corner")
    data = damage(model.read_bytes())
    model.write_bytes(data)
    with pytest.raises(CorruptModelError, match=rf"'corner': model file {re.escape(str(model))} does not match the "
                                                "SHA-256 recorded"):
        SMCLibrary.load(copy)
    file = _readdress(copy, "corner", data)
    with pytest.raises(CorruptModelError, match=rf"'corner': model file {re.escape(str(file))}: {message}"):
        SMCLibrary.load(copy)


def test_modified_model_file_fails_its_checksum(copy):
    shutil.copyfile(_model_file(copy, "climber"), _model_file(copy, "corner"))
    with pytest.raises(CorruptModelError, match="'corner': model file .* does not match the SHA-256"):
        SMCLibrary.load(copy)


def test_missing_model_file(copy):
    _model_file(copy, "container").unlink()
    with pytest.raises(CorruptModelError, match="'container': model file .* is missing"):
        SMCLibrary.load(copy)


def test_a_model_file_that_is_a_link_is_refused(copy, tmp_path):
    """A library's files are its own: a model file that is a symbolic link (here to the very same bytes) is refused,
    and so is a manifest that names a file whose name is not its SHA-256."""
    model = _model_file(copy, "corner")
    outside = tmp_path / "elsewhere.safetensors"
    shutil.move(model, outside)
    model.symlink_to(outside)
    with pytest.raises(CorruptModelError, match=f"'corner': model file {re.escape(str(model))} is a symbolic link"):
        SMCLibrary.load(copy)
    model.unlink()
    shutil.move(outside, model)
    assert SMCLibrary.load(copy).names == ("corner", "container", "climber", "corner-ppo")
    other = json.loads((copy / "manifest.json").read_text())["smcs"]["climber"]["model"]
    _edit(copy, lambda m: m["smcs"]["corner"].update(model=other))
    with pytest.raises(ManifestError, match=f"entry 'corner': model file '{other}' is not named by its recorded "
                                            "SHA-256"):
        SMCLibrary.load(copy)
    _edit(copy, lambda m: m["smcs"]["corner"].update(model="models/corner.bin"))
    with pytest.raises(ManifestError, match=r"entry 'corner': model path 'models/corner.bin' must be "
                                            r"models/<its SHA-256>\.safetensors"):
        SMCLibrary.load(copy)


@pytest.mark.parametrize(("version", "message"), [
    (7, "version 7 is newer than this sb3_smc reads .*upgrade sb3_smc"),
    (0, "incompatible manifest version 0"),
    ("1", "version must be an integer"),
])
def test_incompatible_manifest_version(copy, version, message):
    _edit(copy, lambda m: m.update(version=version))
    with pytest.raises(ManifestError, match=message):
        SMCLibrary.load(copy)


def test_not_a_manifest(copy, tmp_path):
    _edit(copy, lambda m: m.update(format="something-else"))
    with pytest.raises(ManifestError, match="not an SMC library manifest"):
        SMCLibrary.load(copy)
    (copy / "manifest.json").write_text('{"format": "sb3-smc-library", "vers')
    with pytest.raises(ManifestError, match="not valid JSON"):
        SMCLibrary.load(copy)
    with pytest.raises(ManifestError, match="no SMC library at .*manifest.json not found"):
        SMCLibrary.load(tmp_path / "nowhere")


def test_missing_field(copy):
    _edit(copy, lambda m: m["smcs"]["corner"].pop("evaluations"))
    with pytest.raises(ManifestError, match=r"entry 'corner' lacks the field\(s\) \['evaluations'\]"):
        SMCLibrary.load(copy)


@pytest.mark.parametrize(("change", "error", "message"), [
    (lambda e: e["spec"]["wrapper"].update(include_primitives=False), ManifestError,
     "entry 'corner': .*noprim.* needs children"),
    (lambda e: e.update(record={"training_returns": []}), ManifestError,
     r"entry 'corner': record: missing field\(s\) \['success_rates'"),
    (lambda e: e.update(kind="bring-about"), ManifestError,  # a fact of the spec, stored a second time
     r"entry 'corner': unknown field\(s\) \['kind'\] \(since version 3 an entry reads what the SMC is from its "
     r"spec\)"),
    (lambda e: e.update(test_score=1.0), ManifestError, r"entry 'corner': unknown field\(s\) \['test_score'\]"),
    (lambda e: e.update(smc={"kind": "classification"}), ManifestError,
     "entry 'corner': an entry with a spec has no 'smc' field"),
    (lambda e: e["spec"]["task"].update(kind=None), ManifestError, "entry 'corner': spec.task.kind is null"),
    (lambda e: e.update(spec=None), ManifestError, "entry 'corner' has no spec and no 'smc' field"),
    (lambda e: e.update(model="/etc/corner.zip"), ManifestError, "model path '/etc/corner.zip' must be relative"),
])
def test_bad_entries_name_the_entry_and_field(copy, change, error, message):
    _edit(copy, lambda m: change(m["smcs"]["corner"]))
    with pytest.raises(error, match=message):
        SMCLibrary.load(copy)


def test_an_smc_without_a_spec_says_what_it_is(smcs, tmp_path):
    """An SMC trained elsewhere (no spec) is stored with an ``smc`` field: kind, algo, children, primitives, frames."""
    bare = {name: dataclasses.replace(smc, spec=None, record=None, evaluations=())
            for name, smc in smcs.items() if name in ("corner", "container")}
    climber = dataclasses.replace(smcs["climber"], spec=None, children=(bare["corner"], bare["container"]))
    path = SMCLibrary([climber]).save(tmp_path / "library")
    raw = json.loads((path / "manifest.json").read_text())["smcs"]
    assert raw["climber"]["smc"] == {"kind": "bring-about", "algo": "RecurrentPPO", "children": ["corner", "container"],
                                     "include_primitives": True, "frame_stack": 1}
    assert raw["container"]["spec"] is None and raw["container"]["smc"]["algo"] == "TRPO"
    loaded = SMCLibrary.load(path)
    assert loaded["climber"].spec is None and loaded["climber"].record == smcs["climber"].record
    assert loaded["climber"].action_names == smcs["climber"].action_names
    for field, value, message in (("kind", "pushing", "unknown kind 'pushing'"),
                                  ("algo", "NoSuchAlgorithm", "unknown algorithm"),
                                  ("frame_stack", 0, "smc.frame_stack must be a positive integer"),
                                  ("children", ["corner", "corner"], "smc.children must be distinct names")):
        _edit(path, lambda m, f=field, v=value: m["smcs"]["climber"]["smc"].update({f: v}))
        with pytest.raises(ManifestError, match=f"entry 'climber': {message}"):
            SMCLibrary.load(path)
        _edit(path, lambda m, f=field: m["smcs"]["climber"]["smc"].update({f: raw["climber"]["smc"][f]}))
    SMCLibrary.load(path)


def test_a_spec_that_does_not_describe_the_model_is_not_saved(smcs, tmp_path):
    """The entry reads the algorithm from the spec: a model of another one is refused at save, not lost at load."""
    corner = smcs["corner"]
    other = dataclasses.replace(corner, spec=dataclasses.replace(corner.spec, algo="RecurrentTRPO"))
    with pytest.raises(LibraryError, match="SMC 'corner': its training spec does not describe its model "
                                           r"\(algo: spec 'RecurrentTRPO', model 'RecurrentPPO'\)"):
        SMCLibrary([other]).save(tmp_path / "library")
    assert not (tmp_path / "library").exists()


def test_missing_child(copy):
    def rename(manifest):
        manifest["smcs"]["corner-v2"] = manifest["smcs"].pop("corner")

    _edit(copy, rename)
    with pytest.raises(MissingChildError, match="'climber' calls child 'corner', which is not in the library; "
                                                "did you mean 'corner-v2'"):
        SMCLibrary.load(copy)


def test_cycle(copy):
    _edit(copy, lambda m: m["smcs"]["corner"]["spec"].update(children=["climber"]))
    with pytest.raises(LibraryError, match="cycle: (corner -> climber -> corner|climber -> corner -> climber)"):
        SMCLibrary.load(copy)


def test_manifest_actions_disagree_with_the_model(copy):
    # consistent in itself, but the model has 6 actions and 87 inputs
    _edit(copy, lambda m: m["smcs"]["corner-ppo"]["spec"]["task"].update(kind="bring-about"))
    with pytest.raises(LayoutMismatchError, match=r"'corner-ppo': the PPO model in .* has 6 actions, but its action "
                                                  r"names are 5"):
        SMCLibrary.load(copy)


def test_manifest_observation_disagrees_with_the_model(copy):
    # the TRPO SMC's spec claims 2 stacked frames; its model takes one
    _edit(copy, lambda m: m["smcs"]["container"]["spec"].update(frame_stack=2))
    with pytest.raises(LayoutMismatchError, match=r"'container': .* observation shape \(86,\), but its observation "
                                                  r"layout is \(172,\)"):
        SMCLibrary.load(copy)


def test_unknown_algorithm(copy):
    _edit(copy, lambda m: m["smcs"]["corner"]["spec"].update(algo="NoSuchAlgorithm"))
    with pytest.raises(ManifestError, match="entry 'corner': .*algo.*'NoSuchAlgorithm'"):
        SMCLibrary.load(copy)


def test_the_library_command_shows_each_smc_without_loading_a_model(saved, copy):
    code, out, err = sb3_smc_cli("library", str(saved))
    assert code == 0, err
    lines = out.splitlines()
    assert lines[0] == f"{saved}: 4 SMC(s), manifest version 6 (sb3_smc {package_versions()['sb3_smc']})"
    climber = next(line.split() for line in lines if line.startswith("climber "))
    assert climber == ["climber", "bring-about", "RecurrentPPO", "corner,container", BA_ID[3:-3], "3", "3", "0.250",
                       "50.0"]
    assert lines[-1].startswith("task: the env id")
    code, out, _ = sb3_smc_cli("library", str(saved), "--json")
    rows = {row["name"]: row for row in json.loads(out)}
    assert rows["corner-ppo"] == {"name": "corner-ppo", "kind": "classification", "algo": "PPO", "children": [],
                                  "env_id": CL_ID, "datasets": ["cl_self-in-left-corner_vs_on-hline"], "seed": 2,
                                  "selected_update": 3, "training_return": 0.25, "test_score": 0.5,
                                  "total_timesteps": 64}
    with open(_model_file(copy, "corner"), "r+b") as handle:  # damaged: only --check opens the models
        handle.seek(100)
        handle.write(b"\0" * 8)
    assert sb3_smc_cli("library", str(copy))[0] == 0
    code, _, err = sb3_smc_cli("library", str(copy), "--check")
    assert code == 2 and "sb3-smc library: error: SMC 'corner': model file" in err


def test_the_library_command_aligns_wide_names(copy):
    """A name of CJK characters takes two columns per character: the table is aligned by display width."""
    _edit(copy, lambda m: m["smcs"].update({"左の角": m["smcs"].pop("corner-ppo")}))
    code, out, err = sb3_smc_cli("library", str(copy))
    assert code == 0, err
    rows = out.splitlines()[1:-1]  # the last line says what the task column holds
    assert [row.split()[0] for row in rows] == ["name", "corner", "container", "climber", "左の角"]

    def columns(text: str) -> int:
        return sum(2 if unicodedata.east_asian_width(char) in "WF" else 1 for char in text)

    kinds = [next(kind for kind in ("kind", "classification", "bring-about") if kind in row) for row in rows]
    assert {columns(row[:row.index(kind)]) for row, kind in zip(rows, kinds, strict=True)} == {len("container  ")}
    assert rows[-1].startswith("左の角" + " " * 5 + "classification  PPO")


# ------------------------------------------------------------------------------------------------ saves in place

def _leftovers(folder: Path) -> list[str]:
    """The hidden files and folders under ``folder`` but a library's lock: what an unfinished write leaves (the
    temporary files of atomic_write, a folder renamed aside)."""
    return sorted(str(p.relative_to(folder)) for p in folder.rglob(".*") if p.name != storage.LOCK)


def _failing_write(monkeypatch, fails) -> None:
    """``storage.atomic_write`` dies (a full disk) after writing half of each file for which ``fails(path)``; the
    real atomic_write writes the half and cleans up."""
    real = storage.atomic_write

    def write(path, data):
        if not fails(Path(path)):
            return real(path, data)

        def half(handle):
            handle.write(data[: len(data) // 2])
            raise OSError("disk full")

        return real(path, half)

    monkeypatch.setattr(storage, "atomic_write", write)


def _state(path: Path) -> tuple[bytes, dict[str, str | None], list[str]]:
    """What the library in ``path`` is: its manifest's bytes, each SMC (loaded) by the digest of its weights, its model
    files."""
    library = SMCLibrary.load(path)
    return (path / "manifest.json").read_bytes(), {name: library[name].digest for name in library}, _model_names(path)


def _files_of(*models) -> list[str]:
    """The model files the models are stored as (content-addressed)."""
    return sorted(f"{hashlib.sha256(storage.model_bytes(model)).hexdigest()}.safetensors" for model in models)


@pytest.mark.parametrize("failing", ["model", "manifest"])
def test_a_failed_save_keeps_the_previous_library(smcs, tmp_path, monkeypatch, failing):
    """A save that dies writing a model file, or the manifest (after all the model files), leaves the previous library
    as it was (the same manifest bytes, the same SMCs) and no temporary file; model files written before the failed
    manifest are named by no entry and are deleted by the next save."""
    target = tmp_path / "library"
    SMCLibrary([smcs["corner"]]).save(target)
    before = _state(target)
    assert before[1] == {"corner": smcs["corner"].digest} and before[2] == _files_of(smcs["corner"].model)
    _failing_write(monkeypatch, (lambda p: p.suffix == ".safetensors") if failing == "model" else
                   (lambda p: p.name == "manifest.json"))
    library = SMCLibrary([smcs["climber"]])
    with pytest.raises(OSError, match="disk full"):
        library.save(target)
    assert (target / "manifest.json").read_bytes() == before[0]
    written = _model_names(target)
    if failing == "model":  # the first new model file (container's) failed: nothing new
        assert written == before[2]
    else:  # every model file written, none named
        assert written == _files_of(*(smcs[n].model for n in ("corner", "container", "climber")))
    assert _state(target)[:2] == before[:2] and _leftovers(tmp_path) == []
    monkeypatch.undo()
    SMCLibrary.load(target).save()  # a save of the same library: the files no entry names go
    assert _state(target)[1:] == before[1:]
    library.save(target)  # and the failed save, repeated, goes through
    assert SMCLibrary.load(target).names == ("corner", "container", "climber")
    assert _model_names(target) == _files_of(*(smcs[n].model for n in ("corner", "container", "climber")))
    assert _leftovers(tmp_path) == []


def test_save_to_own_path_and_refusals(smcs, tmp_path):
    library = SMCLibrary([smcs["corner"]])
    with pytest.raises(LibraryError, match="needs a path"):
        library.save()
    library.save(tmp_path / "library")
    library.add(smcs["container"])
    library.save()
    assert SMCLibrary.load(tmp_path / "library").names == ("corner", "container")
    (tmp_path / "notes").mkdir()
    (tmp_path / "notes" / "todo.txt").write_text("keep me")
    with pytest.raises(LibraryError, match="refusing to write to .*notes: it is a non-empty directory without "
                                           "manifest.json"):
        library.save(tmp_path / "notes")
    (tmp_path / "file").write_text("keep me")
    with pytest.raises(LibraryError, match="it is a file"):
        library.save(tmp_path / "file")
    assert sorted(os.listdir(tmp_path / "notes")) == ["todo.txt"] and (tmp_path / "notes" / "todo.txt").read_text() \
        == "keep me"
    assert (tmp_path / "file").read_text() == "keep me"
    assert _leftovers(tmp_path) == []


def test_an_interrupted_replacement_of_the_folder_is_reported(saved, tmp_path):
    """A library replaced whole (pixelworld_env.atomic.replace_directory, as build_pretrained does) and interrupted
    between its two renames is at ``.<name>.old-<random>``: loading the missing library says where, and that copy
    is the library; another folder's copy is not mentioned."""
    shutil.copytree(saved, tmp_path / ".other.old-def456")
    with pytest.raises(ManifestError, match=r"no SMC library at .*library: .*manifest.json not found$"):
        SMCLibrary.load(tmp_path / "library")
    shutil.copytree(saved, tmp_path / ".library.old-abc123")
    with pytest.raises(ManifestError, match=re.escape(
            f"manifest.json not found; a replacement of this folder was interrupted: found the previous library at "
            f"{tmp_path / '.library.old-abc123'} (rename it to library to recover it)")):
        SMCLibrary.load(tmp_path / "library")
    (tmp_path / ".library.old-abc123").rename(tmp_path / "library")
    assert _state(tmp_path / "library") == _state(saved)


ODD = 'cl: left corner <v1>?*|"'
"""A name that is no file name on some systems (":", "<", "?", "*", "|", '"'; a name has no "/": core/names.py)."""


def test_names_that_are_not_file_names(smcs, tmp_path):
    """A model file is named by its bytes, whatever the SMC's name: an SMC whose name is no file name on some systems
    round-trips under it; two SMCs of the same model share one file, which stays while an entry names it."""
    corner = smcs["corner"]
    odd = SMC(ODD, corner.kind, corner.policy, model=corner.model)
    path = SMCLibrary([odd, corner]).save(tmp_path / "library")
    entries = json.loads((path / "manifest.json").read_text())["smcs"]
    digest = hashlib.sha256(storage.model_bytes(corner.model)).hexdigest()
    assert entries[ODD]["model"] == f"models/{digest}.safetensors" == entries["corner"]["model"]
    assert entries[ODD]["sha256"] == digest and _model_names(path) == [f"{digest}.safetensors"]
    loaded = SMCLibrary.load(path)
    assert loaded.names == (ODD, "corner")
    assert loaded[ODD].name == ODD and loaded[ODD].spec is None
    assert loaded[ODD].digest == corner.digest
    storage.remove_from_library(path, ["corner"])
    assert _model_names(path) == [f"{digest}.safetensors"]
    assert SMCLibrary.load(path).names == (ODD,)
    storage.remove_from_library(path, [ODD])
    assert _model_names(path) == [] and SMCLibrary.load(path).names == ()


# ------------------------------------------------------------------------------------------------ other writers

@pytest.fixture(scope="module")
def rivals() -> dict[str, SMC]:
    """SMCs named as some of ``smcs`` with other weights: what another writer stores under those names."""
    torch.set_num_threads(1)
    return {"corner": _smc("corner", CL_ID, RecurrentPPO, seed=7),
            "corner2": _smc("corner", CL_ID, RecurrentPPO, seed=8),
            "container": _smc("container", BA_ID, TRPO, seed=9)}


def _digests(path: Path) -> dict[str, str | None]:
    library = SMCLibrary.load(path)
    return {name: library[name].digest for name in library}


def test_two_writers_that_add_different_smcs_keep_both(smcs, tmp_path):
    """Two library objects loaded from one folder each add an SMC and save: both SMCs are kept. A library that never
    read the folder keeps what it holds too; an SMC a writer read (or wrote) is its own to drop."""
    path = SMCLibrary([smcs["corner"]]).save(tmp_path / "library")
    first, second = SMCLibrary.load(path), SMCLibrary.load(path)
    first.add(smcs["container"])
    second.add(smcs["corner-ppo"])
    first.save()
    second.save()
    assert _digests(path) == {name: smcs[name].digest for name in ("corner", "container", "corner-ppo")}
    assert _model_names(path) == _files_of(*(smcs[n].model for n in ("corner", "container", "corner-ppo")))
    SMCLibrary([smcs["climber"]]).save(path)  # never read it: what it does not hold is kept
    assert set(SMCLibrary.load(path).names) == {"corner", "container", "corner-ppo", "climber"}
    second.remove("corner-ppo")  # one it wrote: dropped; those it never knew (climber, container): kept
    second.save()
    assert _digests(path) == {name: smcs[name].digest for name in ("corner", "container", "climber")}
    assert _model_names(path) == _files_of(*(smcs[n].model for n in ("corner", "container", "climber")))
    assert second.names == ("corner",)


def test_changing_an_smc_another_writer_changed_is_a_conflict(smcs, rivals, tmp_path):
    """An SMC this library read and another writer changed since: replacing it again, or saving it as it was read
    (which would undo the other's change), is refused (LibraryConflictError) and nothing is written; the same change
    is no conflict; a library loaded again makes the change."""
    path = SMCLibrary([smcs["climber"]]).save(tmp_path / "library")
    first, second, unchanged, alike = (SMCLibrary.load(path) for _ in range(4))
    first.add(rivals["corner"], replace=True)
    first.save()
    before = _state(path)
    assert before[1]["corner"] == rivals["corner"].digest != smcs["corner"].digest
    second.add(rivals["corner2"], replace=True)
    conflict = (f"{path / 'manifest.json'}: SMC 'corner' was changed by another writer since this library was "
                "loaded; nothing was saved: load the library again and repeat the change")
    with pytest.raises(LibraryConflictError, match=re.escape(conflict)):
        second.save()
    assert _state(path) == before  # not even the new model file
    unchanged.add(smcs["corner-ppo"])
    with pytest.raises(LibraryConflictError, match=re.escape(conflict)):
        unchanged.save()
    assert _state(path) == before
    alike.add(rivals["corner"], replace=True)  # the very change the other writer made
    alike.save()
    assert _state(path)[1:] == before[1:]
    again = SMCLibrary.load(path)
    again.add(rivals["corner2"], replace=True)
    again.save()
    after = _digests(path)
    assert (after["corner"], after["container"]) == (rivals["corner2"].digest, before[1]["container"])
    assert _model_names(path) == _files_of(rivals["corner2"].model, smcs["container"].model, smcs["climber"].model)


def test_other_conflicts_with_another_writer(smcs, rivals, tmp_path):
    """Two writers adding different SMCs of one name, or a save removing a child that an SMC another writer added
    calls: LibraryConflictError, nothing written."""
    path = SMCLibrary([smcs["corner"]]).save(tmp_path / "library")
    first, second, third = (SMCLibrary.load(path) for _ in range(3))
    first.add(smcs["container"])
    first.save()
    before = _state(path)
    second.add(rivals["container"])
    with pytest.raises(LibraryConflictError, match="another writer added a different SMC named 'container'; nothing "
                                                   "was saved"):
        second.save()
    assert _state(path) == before
    second.remove("container")
    second.add(smcs["container"])  # the same SMC: no conflict
    second.save()
    assert _state(path)[1:] == before[1:]
    first.add(smcs["climber"])
    first.save()
    before = _state(path)
    third.remove("corner")
    with pytest.raises(LibraryConflictError, match="SMC 'climber' \\(kept from the library on disk\\) calls 'corner', "
                                                   "which this save removes; nothing was saved"):
        third.save()
    assert _state(path) == before


def test_overwrite_makes_the_folder_hold_exactly_the_library(smcs, rivals, tmp_path):
    """``save(overwrite=True)`` drops the SMCs on disk this library does not hold (and their model files), and
    replaces those another writer changed."""
    path = SMCLibrary([smcs["corner"]]).save(tmp_path / "library")
    stale, other = SMCLibrary.load(path), SMCLibrary.load(path)
    other.add(smcs["container"])
    other.add(rivals["corner"], replace=True)
    other.save()
    stale.add(smcs["corner-ppo"])
    with pytest.raises(LibraryConflictError):
        stale.save()
    stale.save(overwrite=True)
    assert _digests(path) == {"corner": smcs["corner"].digest, "corner-ppo": smcs["corner-ppo"].digest}
    assert _model_names(path) == _files_of(smcs["corner"].model, smcs["corner-ppo"].model)
    SMCLibrary([smcs["container"]]).save(path, overwrite=True)
    assert _digests(path) == {"container": smcs["container"].digest}
    assert _model_names(path) == _files_of(smcs["container"].model)


def test_train_smc_output_round_trips(tmp_path):
    """What ``train_smc`` returns (here a frame-stacked TRPO SMC) is stored with its provenance and replays."""
    smc = train_smc(CL_ID, algo="TRPO", total_timesteps=64, n_envs=1, n_steps=32, batch_size=32, frame_stack=2,
                    seed=4, printer=lambda line: None)
    result = evaluate(smc, repeats=1)
    assert smc.evaluations == (result.record,) and smc.test_score == result.score
    library = SMCLibrary([smc])
    entry = library.entry(smc.name)
    assert (entry["spec"], entry["record"]) == (smc.spec.to_dict(), smc.record.to_dict())
    assert entry["spec"]["frame_stack"] == 2 and entry["evaluations"] == [result.record.to_dict()]
    loaded = SMCLibrary.load(library.save(tmp_path / "library"))[smc.name]
    assert type(loaded.policy).__name__ == "FrameStackPolicy" and loaded.policy.n_stack == 2
    observations = _observations(smc.observation_size)
    np.testing.assert_allclose(_trace(loaded.policy, observations), _trace(smc.policy, observations), rtol=0,
                               atol=1e-12)
    assert (loaded.spec, loaded.record, loaded.evaluations) == (smc.spec, smc.record, smc.evaluations)
    again = evaluate(loaded, repeats=1)
    assert again.to_dict() == result.to_dict()


# ------------------------------------------------------------------------------------------------ version 1

V1_MANIFEST = Path(__file__).parent / "data" / "library_v1_manifest.json"
"""The manifest sb3-smc 0.1 wrote for a three-SMC library (a RecurrentPPO child, a frame-stacked TRPO child and a
noprim level-2 parent whose ``metadata["test_score"]`` was set by hand). The models are trained here from the
converted specs (the original archives are large); that 0.1's own archives load was checked by hand."""


def test_version_1_libraries_load_through_the_conversion(tmp_path):
    v1 = json.loads(V1_MANIFEST.read_text())
    assert v1["version"] == 1
    converted = storage.check_manifest(json.loads(V1_MANIFEST.read_text()), V1_MANIFEST)
    root = tmp_path / "library"
    (root / "models").mkdir(parents=True)
    trained: dict[str, SMC] = {}
    for name in storage.topological_order(converted, V1_MANIFEST):
        spec = converted[name].spec
        smc = train_smc(spec, children=trained, stop_at_max_return=False)  # the whole budget, as 0.1 trained
        trained[name] = smc
        smc.model.save(root / v1["smcs"][name]["model"])
        v1["smcs"][name]["sha256"] = storage.sha256(root / v1["smcs"][name]["model"])
    (root / "manifest.json").write_text(json.dumps(v1))

    first = storage.topological_order(converted, V1_MANIFEST)[0]
    with pytest.raises(UntrustedModelError, match=re.escape(
            f"SMC {first!r}: {root / v1['smcs'][first]['model']} is a pickled Stable-Baselines3 archive")):
        SMCLibrary.load(root)  # its models unpickle: only with trust
    library = SMCLibrary.load(root, trust=True)
    for name, entry in v1["smcs"].items():
        smc, meta = library[name], entry["metadata"]
        assert smc.spec == trained[name].spec
        assert (smc.spec.task.env_id, smc.spec.seed, smc.spec.algo) == (meta["env_id"], meta["seed"], meta["algo"])
        assert smc.spec.budget.steps_per_update == meta["steps_per_update"]
        assert smc.spec.hyperparameters["policy"] == meta["policy"] and smc.spec.frame_stack == meta["frame_stack"]
        assert smc.spec.wrapper.to_dict() == {"include_primitives": entry["include_primitives"], **meta["wrapper"]}
        assert smc.record.to_dict()["training_returns"] == [None if r != r else r for r in meta["training_returns"]]
        assert smc.record.selected_update == meta["selected_update"] and smc.record.versions == v1["created_with"]
    top = library["cl_self-in-container_vs_noncontainer"]
    assert not top.include_primitives and top.spec.children == tuple(c.name for c in top.children)
    (evaluation,) = top.evaluations
    assert (evaluation.split, evaluation.score, evaluation.repeats, evaluation.evaluation_seed) == \
        ("test", 0.25, None, None)
    # saved again, it is a library of the current version with the same records, which loads without trust
    again = SMCLibrary.load(library.save(tmp_path / "v5"))
    assert json.loads((tmp_path / "v5" / "manifest.json").read_text())["version"] == FORMAT_VERSION
    assert all(again[n].spec == library[n].spec and again[n].evaluations == library[n].evaluations for n in again)
    assert {n: again[n].digest for n in again} == {n: trained[n].digest for n in trained}
    # converted in place (what the error says to do): the pickled archives go
    assert SMCLibrary.load(root, trust=True).save() == root
    assert json.loads((root / "manifest.json").read_text())["version"] == FORMAT_VERSION
    assert _model_names(root) == _model_names(tmp_path / "v5") and all(n.endswith(".safetensors")
                                                                       for n in _model_names(root))
    assert {n: m[n].digest for m in [SMCLibrary.load(root)] for n in m} == {n: trained[n].digest for n in trained}


def test_version_1_entry_that_cannot_be_converted(tmp_path):
    v1 = json.loads(V1_MANIFEST.read_text())
    del v1["smcs"]["cl_self-in-left-corner_vs_on-hline"]["metadata"]["wrapper"]
    with pytest.raises(ManifestError, match="version-1 entry 'cl_self-in-left-corner_vs_on-hline' cannot be "
                                            "converted .*wrapper"):
        storage.check_manifest(v1, V1_MANIFEST)


# ------------------------------------------------------------------------------------------------ version 2

V2_MANIFEST = Path(__file__).parent / "data" / "library_v2_manifest.json"
"""Two entries of the pretrained library as version 2 wrote them (sb3-smc before manifest version 3: each entry also
repeating its spec's facts, its action names and observation, and seven summary fields). Their model files were the
shipped ones as pickled SB3 archives (``models/<name>.zip``); the fixture writes those of the shipped SMCs (now
stored in version 5's format) with ``model.save`` and records their checksums."""
PRETRAINED = ROOT / "sb3_smc" / "library" / "data" / "pretrained"


@pytest.fixture(scope="module")
def v2_models(tmp_path_factory) -> dict[str, bytes]:
    """By entry of V2_MANIFEST, the shipped SMC's model as the SB3 archive version 2 stored (``model.save``)."""
    names = list(json.loads(V2_MANIFEST.read_text())["smcs"])
    shipped, folder = SMCLibrary.load(PRETRAINED, names=names), tmp_path_factory.mktemp("v2-models")
    archives = {}
    for name in names:
        shipped[name].model.save(folder / "model.zip")
        archives[name] = (folder / "model.zip").read_bytes()
    return archives


@pytest.fixture
def v2_library(tmp_path, v2_models) -> Path:
    root = tmp_path / "v2"
    (root / "models").mkdir(parents=True)
    manifest = json.loads(V2_MANIFEST.read_text())
    for name, entry in manifest["smcs"].items():
        (root / entry["model"]).write_bytes(v2_models[name])
        entry["sha256"] = hashlib.sha256(v2_models[name]).hexdigest()  # version 2 has no checksums of its content
    (root / "manifest.json").write_text(json.dumps(manifest, indent=2))
    return root


def test_version_2_libraries_load_and_their_summaries_are_what_is_derived(v2_library, tmp_path):
    v2 = json.loads(V2_MANIFEST.read_text())
    assert v2["version"] == 2
    first = next(iter(v2["smcs"]))
    with pytest.raises(UntrustedModelError, match=re.escape(
            f"SMC {first!r}: {v2_library / v2['smcs'][first]['model']} is a pickled Stable-Baselines3 archive")):
        SMCLibrary.load(v2_library)
    library = SMCLibrary.load(v2_library, trust=True)
    shipped = SMCLibrary.pretrained("search2-canon")
    entries = storage.check_manifest(v2, V2_MANIFEST)
    for name, raw in v2["smcs"].items():
        smc, entry = library[name], entries[name]
        assert (smc.spec, smc.record, smc.evaluations) == (shipped[name].spec, shipped[name].record,
                                                           shipped[name].evaluations)
        assert entry.summary() == {field: raw[field] for field in storage.SUMMARY_FIELDS}
        assert (list(entry.action_names), entry.observation) == (raw["action_names"], raw["observation"])
        assert (entry.kind, entry.algo, list(entry.children)) == (raw["kind"], raw["algo"], raw["children"])
    assert {n: library[n].digest for n in library} == {n: shipped[n].digest for n in library}  # the same weights
    again = SMCLibrary.load(library.save(tmp_path / "v5"))
    assert json.loads((tmp_path / "v5" / "manifest.json").read_text())["version"] == FORMAT_VERSION
    assert all((again[n].spec, again[n].record, again[n].evaluations) == (library[n].spec, library[n].record,
                                                                          library[n].evaluations) for n in library)
    SMCLibrary.load(v2_library, trust=True).save()  # converted in place: the archives go
    assert _model_names(v2_library) == _model_names(tmp_path / "v5")
    assert (v2_library / "manifest.json").read_bytes() == (tmp_path / "v5" / "manifest.json").read_bytes()


V2_NAME = "cl_self-in-left-corner_vs_on-hline@0"


@pytest.mark.parametrize(("change", "error", "message"), [
    (lambda e: e["action_names"].reverse(), LayoutMismatchError, "action names .* do not match its kind"),
    (lambda e: e["observation"].update(size=90), LayoutMismatchError, "observation .* does not match"),
    (lambda e: e.update(seed=7), ManifestError, "'seed' is 7, but its records say 0"),
    (lambda e: e.update(test_score="high"), ManifestError, "'test_score' is 'high', but its records say 0.97"),
    (lambda e: e.update(include_primitives=False), ManifestError,
     r"its training spec disagrees with the entry \(include_primitives: spec True, entry False\)"),
    (lambda e: e.update(algo="PPO"), ManifestError, "algo: spec 'RecurrentPPO', entry 'PPO'"),
    (lambda e: e.pop("algo"), ManifestError, r"lacks the field\(s\) \['algo'\]"),
])
def test_a_version_2_entry_that_contradicts_itself_is_still_an_error(v2_library, change, error, message):
    _edit(v2_library, lambda m: change(m["smcs"][V2_NAME]))
    with pytest.raises(error, match=message):
        SMCLibrary.load(v2_library)


def test_adding_to_a_version_2_library_writes_the_current_version(v2_library, smcs, tmp_path):
    """A run directory's library of version 2 goes on growing: the next SMC stored writes the whole manifest as the
    current version, with the checksums of its content; its old models stay pickled archives (loaded with trust) until
    the library is saved with trust."""
    storage.add_to_library(v2_library, "corner", storage.entry_for(smcs["corner"]),
                           storage.model_bytes(smcs["corner"].model))
    manifest = json.loads((v2_library / "manifest.json").read_text())
    assert manifest["version"] == FORMAT_VERSION and list(manifest["smcs"]) == [
        *json.loads(V2_MANIFEST.read_text())["smcs"], "corner"]
    assert manifest["created_with"] == package_versions()  # who converted it
    assert all(set(entry) == {"model", "sha256", "spec", "record", "evaluations", ENTRY_CHECKSUM}
               for entry in manifest["smcs"].values())
    assert seal(manifest) == manifest
    assert manifest["smcs"][V2_NAME]["model"] == f"models/{V2_NAME}.zip"
    assert manifest["smcs"]["corner"]["model"] == f"models/{manifest['smcs']['corner']['sha256']}.safetensors"
    with pytest.raises(UntrustedModelError, match=re.escape(f"{v2_library / 'models' / V2_NAME}.zip is a pickled")):
        SMCLibrary.load(v2_library)
    library = SMCLibrary.load(v2_library, trust=True)
    assert library["corner"].spec == smcs["corner"].spec and library[V2_NAME].test_score == 0.97
    assert library["corner"].digest == smcs["corner"].digest
    assert SMCLibrary.load(v2_library, names=["corner"]).names == ("corner",)  # its own model: no trust needed


def test_an_old_library_is_not_rewritten_where_that_would_lose_something(v2_library, smcs, tmp_path):
    """Fields a user added to a version-2 entry, or a version-1 library's metadata, are not dropped by an add."""
    add = lambda: storage.add_to_library(v2_library, "corner", storage.entry_for(smcs["corner"]),  # noqa: E731
                                         storage.model_bytes(smcs["corner"].model))
    before = (v2_library / "manifest.json").read_text()
    _edit(v2_library, lambda m: m["smcs"][V2_NAME].update(notes="keep me"))
    edited = (v2_library / "manifest.json").read_text()
    with pytest.raises(ManifestError, match=f"entry '{V2_NAME}': \\['notes'\\]\\); move them elsewhere first"):
        add()
    assert (v2_library / "manifest.json").read_text() == edited != before
    SMCLibrary.load(v2_library, trust=True)  # reading it is fine
    _edit(v2_library, lambda m: m.update(version=1))
    with pytest.raises(ManifestError, match=r"version-1 library .*convert it first: SMCLibrary.load\(path, "
                                            r"trust=True\).save\(\) writes it in the current version"):
        add()


def test_a_version_2_entry_without_a_spec_loads(smcs, tmp_path):
    """Version 2 wrote an SMC trained elsewhere with its kind, algo, children ... and null records."""
    bare = dataclasses.replace(smcs["corner-ppo"], spec=None, record=None, evaluations=())
    path = SMCLibrary([bare]).save(tmp_path / "library")
    manifest = json.loads((path / "manifest.json").read_text())
    manifest.pop(MANIFEST_CHECKSUM)
    entry = manifest["smcs"]["corner-ppo"]
    entry.pop(ENTRY_CHECKSUM)
    smc = entry.pop("smc")
    entry.update(smc, action_names=list(bare.action_names), env_id=None, datasets=[], seed=None,
                 selected_update=None, training_return=None, test_score=None, total_timesteps=None,
                 observation={"size": 87, "window": 81, "outcomes": 0, "previous_action": 6})
    (path / "manifest.json").write_text(json.dumps({**manifest, "version": 2}))
    loaded = SMCLibrary.load(path)["corner-ppo"]
    assert (loaded.kind, loaded.spec, type(loaded.model).__name__) == ("classification", None, "PPO")
    assert loaded.action_names == bare.action_names


def test_version_0_1_models_name_a_policy_class_that_still_imports():
    """sb3-smc 0.1 pickled its LSTM policy class as sb3_smc.training.SequenceLstmPolicy (the one name that module
    keeps)."""
    import pickle

    from sb3_smc.common.recurrent import SequenceLstmPolicy

    legacy = pickle.loads(b"csb3_smc.training\nSequenceLstmPolicy\n.")  # the class by reference, as SB3 saves it
    assert legacy is SequenceLstmPolicy


# ------------------------------------------------------------------------------------------------ manifest gaps

def test_a_missing_checksum_is_an_error_not_a_skipped_check(copy):
    _edit(copy, lambda m: m["smcs"]["corner"].pop("sha256"))
    with pytest.raises(ManifestError, match=r"entry 'corner' lacks the field\(s\) \['sha256'\]"):
        SMCLibrary.load(copy)
    _edit(copy, lambda m: m["smcs"]["corner"].update(sha256="abc"))
    with pytest.raises(ManifestError, match="'sha256' must be the 64 hex digits"):
        SMCLibrary.load(copy)


def test_an_edited_manifest_is_refused_naming_the_file_and_the_smc(copy):
    """The manifest's own content is checksummed: an entry changed by hand (here its spec's seed) stops load(), the
    library command with or without --check, and changes in place, naming the file and the SMC; so does a change
    outside the entries. How the file is laid out is not its content; an edit meant to be kept is written with
    fresh checksums."""
    path = copy / "manifest.json"
    original = path.read_text()

    def write(change) -> None:
        manifest = json.loads(original)
        change(manifest)
        path.write_text(json.dumps(manifest, indent=2))

    write(lambda m: m["smcs"]["corner"]["spec"].update(seed=7))
    message = (f"{path}: the entry of SMC 'corner' does not match its 'entry_sha256': edited by hand or damaged "
               "since sb3_smc wrote it; restore it, or write an edit meant to be kept with "
               "sb3_smc.library.storage.write_manifest")
    with pytest.raises(ManifestError) as info:
        SMCLibrary.load(copy)
    assert str(info.value) == message
    for options in ((), ("--check",)):
        code, _, err = sb3_smc_cli("library", str(copy), *options)
        assert (code, err) == (2, f"sb3-smc library: error: {message}\n")
    with pytest.raises(ManifestError, match=re.escape(message)):
        storage.remove_from_library(copy, ["corner-ppo"])
    write(lambda m: m["smcs"].update({"corner-ppo2": m["smcs"].pop("corner-ppo")}))  # a name is content too
    with pytest.raises(ManifestError, match="the entry of SMC 'corner-ppo2' does not match its 'entry_sha256'"):
        SMCLibrary.load(copy)
    outside = (f"{path}: the manifest does not match its 'manifest_sha256' outside the SMC entries (its created_with "
               "changed, or a whole entry was added or removed): edited by hand or damaged")
    for change in (lambda m: m["created_with"].update(torch="1.0"), lambda m: m["smcs"].pop("corner-ppo")):
        write(change)
        with pytest.raises(ManifestError, match=re.escape(outside)):
            SMCLibrary.load(copy)
    write(lambda m: m["smcs"]["corner"].pop(ENTRY_CHECKSUM))
    with pytest.raises(ManifestError, match="entry 'corner': 'entry_sha256' must be the 64 hex digits .* got None"):
        SMCLibrary.load(copy)
    write(lambda m: m.update(manifest_sha256="abc"))
    with pytest.raises(ManifestError, match="'manifest_sha256' must be the 64 hex digits .* got 'abc'"):
        SMCLibrary.load(copy)
    path.write_text(json.dumps(json.loads(original)))  # on one line: the same content
    assert SMCLibrary.load(copy).names == ("corner", "container", "climber", "corner-ppo")
    manifest = json.loads(original)
    manifest["smcs"]["corner"]["spec"]["seed"] = 7
    storage.write_manifest(path, manifest)  # an edit meant to be kept
    assert SMCLibrary.load(copy)["corner"].spec.seed == 7


def test_an_unchanged_manifest_is_checked_once_per_process(copy, monkeypatch):
    """Loading SMCs one at a time (an experiment's evaluations) checks an unchanged manifest once; the manifest's
    bytes key what is kept, so an edit in place of the same size, at once, is seen; the entries returned are the
    caller's to change."""
    calls = []
    real = storage.check_manifest
    monkeypatch.setattr(storage, "check_manifest", lambda manifest, where: calls.append(where) or real(manifest, where))
    assert SMCLibrary.load(copy, names=["corner"]).names == ("corner",)
    assert SMCLibrary.load(copy, names=["climber"]).names == ("corner", "container", "climber")
    entries, created_with, _ = storage.checked_entries(copy)
    entries.clear()
    created_with.clear()
    again = SMCLibrary.load(copy)
    assert again.names == ("corner", "container", "climber", "corner-ppo") and again.created_with
    assert len(calls) == 1
    path = copy / "manifest.json"
    text = path.read_text()
    edited = text.replace('"seed": 3', '"seed": 4', 1)  # the climber's spec, the same size
    assert edited != text and len(edited) == len(text)
    path.write_text(edited)
    with pytest.raises(ManifestError, match="the entry of SMC 'climber' does not match its 'entry_sha256'"):
        SMCLibrary.load(copy, names=["corner"])
    path.write_text(text)
    assert SMCLibrary.load(copy, names=["corner"]).names == ("corner",) and len(calls) == 2


def test_the_manifest_is_written_as_json_dumps_writes_it(saved):
    """``manifest_text``, which writes a manifest entry by entry (an add writes only its own entry), gives
    ``json.dumps(..., indent=2)`` character for character: for a real library's manifest, with texts given for some
    entries, for nested values, escapes and non-ASCII names, and for an empty library."""
    sealed = seal(storage.read_manifest(saved)[0])
    assert storage.manifest_text(sealed) == json.dumps(sealed, indent=2)
    texts: dict[str, str] = {}
    storage.manifest_text(sealed, texts)
    assert set(texts) == set(sealed["smcs"])
    assert storage.manifest_text(sealed, dict(texts)) == json.dumps(sealed, indent=2)
    odd = {"format": "x", "created_with": {"a\n\"b": [1, 2.5, None, {"c": []}]}, "smcs": {
        "n\u00e9/\u2603": {"x": {"y": [{}, [], "z\t"]}, "e": {}}, "plain": {"list": [[1], [2, [3]]]}}, "v": 4}
    assert storage.manifest_text(odd) == json.dumps(odd, indent=2)
    empty = seal(storage.new_manifest({}))
    assert storage.manifest_text(empty) == json.dumps(empty, indent=2)


def test_the_manifest_checksum_is_joined_from_the_entries_texts(saved):
    """``seal`` joins the whole manifest's canonical text from its entries' (kept in ``known`` from one seal to the
    next): the checksum is ``content_sha256`` of the whole content, for a real manifest and for names out of order,
    non-ASCII and escapes, and stays so after one entry changes and only its texts are dropped from ``known``."""
    def whole(sealed: dict) -> str:
        return content_sha256({k: v for k, v in sealed.items() if k != MANIFEST_CHECKSUM})

    sealed = seal(storage.read_manifest(saved)[0])
    assert sealed[MANIFEST_CHECKSUM] == whole(sealed)
    odd = {"version": 4, "format": "x", "created_with": {"b": 1, "a\n\"": [None, 2.5]}, "smcs": {
        "z": {"y": 1, "a": [{"q": 1, "p": 2}]}, "A": {}, "n\u00e9/\u2603": {"\u00e9": "\t"}, "m": {"x": "z"}}}
    known: dict[str, tuple[str, str]] = {}
    assert seal(odd, known)[MANIFEST_CHECKSUM] == whole(seal(odd)) and set(known) == set(odd["smcs"])
    odd["smcs"]["m"] = {"x": "changed"}
    del known["m"]
    assert seal(odd, known) == seal(odd) and seal(odd)[MANIFEST_CHECKSUM] == whole(seal(odd))
    assert seal(storage.new_manifest({}))[MANIFEST_CHECKSUM] == whole(seal(storage.new_manifest({})))


def test_adding_smcs_one_by_one_checks_the_manifest_once(copy, tmp_path, monkeypatch):
    """A run adds its SMCs one by one: while the manifest holds the bytes this process's last add wrote, the next
    add starts from that add's manifest, not reading and checking every entry again, and writes the same bytes as an
    add that does; an edit by another writer in between is seen and kept; a replaced entry gets a new checksum."""
    calls = []
    real = storage.check_entries
    monkeypatch.setattr(storage, "check_entries", lambda manifest, where: calls.append(where) or real(manifest, where))
    saved = json.loads((copy / "manifest.json").read_text())["smcs"]["corner"]
    model = (copy / saved["model"]).read_bytes()

    def entry(name: str, seed: int = 0) -> dict:
        spec = {**saved["spec"], "name": name, "seed": seed}
        return {k: v for k, v in {**saved, "spec": spec}.items() if k not in ("model", "sha256", ENTRY_CHECKSUM)}

    other = Path(shutil.copytree(copy, tmp_path / "other"))
    for name in ("a", "b", "c"):
        storage.add_to_library(copy, name, entry(name), model)
    assert len(calls) == 1
    for name in ("a", "b", "c"):  # each add reading and checking the manifest
        storage._ADDED.clear()
        storage.add_to_library(other, name, entry(name), model)
    assert (copy / "manifest.json").read_bytes() == (other / "manifest.json").read_bytes()
    edited = json.loads((copy / "manifest.json").read_text())
    edited["smcs"]["a"]["spec"]["seed"] = 9
    storage.write_manifest(copy / "manifest.json", edited)  # another writer's edit
    storage.add_to_library(copy, "d", entry("d"), model)
    assert len(calls) == 5
    storage.add_to_library(copy, "d", entry("d", seed=4), model, replace=True)
    library = SMCLibrary.load(copy)
    assert (library["a"].spec.seed, library["d"].spec.seed) == (9, 4) and len(calls) == 6
    assert library.names[-4:] == ("a", "b", "c", "d")


def test_version_3_libraries_load_and_get_checksums_when_written(copy):
    """A library written before the manifest's content had checksums (version 3) loads as it is; the next write of
    its manifest (a save, an SMC added or removed in place) stores it as the current version with them."""
    manifest = json.loads((copy / "manifest.json").read_text())
    v3 = {**{k: v for k, v in manifest.items() if k != MANIFEST_CHECKSUM}, "version": 3,
          "smcs": {name: {k: v for k, v in entry.items() if k != ENTRY_CHECKSUM}
                   for name, entry in manifest["smcs"].items()}}
    (copy / "manifest.json").write_text(json.dumps(v3, indent=2))
    assert SMCLibrary.load(copy).names == ("corner", "container", "climber", "corner-ppo")
    storage.remove_from_library(copy, ["corner-ppo"])
    written = json.loads((copy / "manifest.json").read_text())
    assert written["version"] == FORMAT_VERSION and seal(written) == written
    assert written["created_with"] == v3["created_with"] and list(written["smcs"]) == ["corner", "container", "climber"]
    assert SMCLibrary.load(copy).names == ("corner", "container", "climber")
    _edit(copy, lambda m: m.update(version=3))  # a version-3 manifest that holds checksums: fields it does not have
    with pytest.raises(ManifestError, match=r"entry 'corner': unknown field\(s\) \['entry_sha256'\]"):
        SMCLibrary.load(copy)


def test_version_4_libraries_load_with_trust_and_convert_when_saved(copy, smcs):
    """A library of version 4 (every library sb3-smc wrote before the safe model files) names pickled SB3 archives
    ``models/<name>.zip``: it loads only with trust, and saving it so writes it as version 5, in place, its archives
    deleted (no entry names them); it then loads without trust, the same SMCs."""
    manifest = json.loads((copy / "manifest.json").read_text())
    for name, entry in manifest["smcs"].items():
        (copy / entry["model"]).unlink()
        smcs[name].model.save(copy / "models" / f"{name}.zip")
        entry.update(model=f"models/{name}.zip", sha256=storage.sha256(copy / "models" / f"{name}.zip"))
    (copy / "manifest.json").write_text(json.dumps(seal({**manifest, "version": 4}), indent=2))
    with pytest.raises(UntrustedModelError, match=re.escape(f"SMC 'corner': {copy / 'models' / 'corner.zip'} is a "
                                                            "pickled Stable-Baselines3 archive")):
        SMCLibrary.load(copy)
    digests = {name: smc.digest for name, smc in smcs.items()}
    old = SMCLibrary.load(copy, trust=True)
    assert {name: old[name].digest for name in old} == digests
    old.save()
    written = json.loads((copy / "manifest.json").read_text())
    assert written["version"] == FORMAT_VERSION and seal(written) == written
    assert _model_names(copy) == _files_of(*(smc.model for smc in smcs.values()))
    assert _digests(copy) == digests
    assert {n: e["spec"] for n, e in written["smcs"].items()} == {n: e["spec"] for n, e in manifest["smcs"].items()}


def test_a_model_of_another_algorithm_is_refused(copy):
    """The manifest's algorithm is the model file's: an entry whose spec names another one, or whose file holds
    another algorithm's model (the PPO SMC's file, of the same layout), is refused before a model is built."""
    model = _model_file(copy, "corner")
    _edit(copy, lambda m: m["smcs"]["corner"]["spec"].update(algo="PPO"))
    with pytest.raises(CorruptModelError, match=f"'corner': model file {re.escape(str(model))}: holds a RecurrentPPO "
                                                "model, but the manifest says PPO"):
        SMCLibrary.load(copy)
    _edit(copy, lambda m: m["smcs"]["corner"]["spec"].update(algo="RecurrentPPO"))
    SMCLibrary.load(copy, names=["corner"])
    file = _readdress(copy, "corner", _model_file(copy, "corner-ppo").read_bytes())
    with pytest.raises(CorruptModelError, match=f"'corner': model file {re.escape(str(file))}: holds a PPO model, but "
                                                "the manifest says RecurrentPPO"):
        SMCLibrary.load(copy)


@pytest.mark.parametrize(("change", "message"), [
    (lambda e: e.update(metadata=5), "version-1 entry .*'metadata' must be an object, got 5"),
    (lambda e: e.update(seed="zero"), "version-1 entry .*'seed' must be int or null, got 'zero'"),
    (lambda e: e.update(test_score="high"), "version-1 entry .*'test_score' must be int or float or null, got 'high'"),
])
def test_bad_version_1_entries_name_the_entry_and_field(change, message):
    v1 = json.loads(V1_MANIFEST.read_text())
    change(v1["smcs"]["cl_self-in-left-corner_vs_on-hline"])
    with pytest.raises(ManifestError, match=message):
        storage.check_manifest(v1, V1_MANIFEST)


def test_bare_observation_models_are_explained(tmp_path):
    """What rl_zoo3 trains without the shipped configs (the bare 81-value window) cannot be an SMC: say why."""
    env = gym.make(CL_ID)
    model = PPO("MlpPolicy", env, n_steps=32, batch_size=32, device="cpu")
    smc = SMC("bare", "classification", ScriptedPolicy(6, lambda obs, step: 0), model=model)
    with pytest.raises(LayoutMismatchError, match="observation shape \\(81,\\).*the bare PixelWorld observation.*"
                                                  "sb3_smc.zoo.smc_env"):
        SMCLibrary([smc])


def test_saved_files_follow_the_umask(smcs, tmp_path):
    old = os.umask(0o022)
    try:
        path = SMCLibrary([smcs["corner"]]).save(tmp_path / "library")
        from pixelworld_env.atomic import atomic_write

        cache_file = atomic_write(tmp_path / "cache" / "x.json.gz", b"data")
    finally:
        os.umask(old)
    assert (path.stat().st_mode & 0o777) == 0o755
    assert ((path / "manifest.json").stat().st_mode & 0o777) == 0o644 == ((path / storage.LOCK).stat().st_mode & 0o777)
    assert (_model_file(path, "corner").stat().st_mode & 0o777) == 0o644
    assert ((path / "models").stat().st_mode & 0o777) == 0o755
    assert (cache_file.stat().st_mode & 0o777) == 0o644
