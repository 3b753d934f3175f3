"""``train_worlds=N``: the first ``N`` worlds of a training split in one fixed order (nested, deterministic across
processes, stratified by label and over a pool's members), refused before any work where it cannot apply; through
``sb3_smc`` (the spec, training, evaluation and its record); ``register_worlds``; evaluations that cannot report
worlds of another split as the split they name; registered tasks whose entry point takes ``**kwargs``."""

from __future__ import annotations

import hashlib
import json
import math
import os
import subprocess
import sys
from collections import Counter
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces

import pixelworld_env
from pixelworld_env import PixelWorldEnv, Scene, load_dataset, register_worlds
from pixelworld_env.concepts.errors import ConceptSyntaxError, UndeclaredVariableError, UnknownPredicateError
from pixelworld_env.datasets import catalog
from pixelworld_env.datasets.loading import few_worlds, training_order
from pixelworld_env.envs import registration
from pixelworld_env.envs.vector import PixelWorldVectorEnv
from pixelworld_env.errors import PixelWorldError, PixelWorldTypeError
from sb3_smc.errors import SMCError
from sb3_smc.learning import evaluation
from sb3_smc.learning.evaluation import evaluate
from sb3_smc.learning.training import train_smc, untrained_smc
from sb3_smc.records import EvaluationRecord, RecordError, TaskSpec, TrainingSpec
from sb3_smc.tasks.resolved_task import resolve_task
from sb3_smc.tasks.task import SMCTask

CL = "cl_self-in-container_vs_noncontainer"  # 50 training worlds, 25 of each label
CL_ID = f"PW-{CL}-v0"
BA = "ba_self-in-container_from_on-floor"  # 25 training worlds
BA_ID = f"PW-{BA}-v0"
CL_POOL = "cl_self-in-container"  # 3 members of 50 training worlds
BA_POOL = "ba_self-on-floor"  # 2 members of 25 training worlds
SIZES = {CL_ID: 50, BA_ID: 25}
REFUSED_SPLITS = ("test", "all")


def scenes_of(env_id: str, **kwargs: Any) -> tuple[Scene, ...]:
    env = gym.make(env_id, **kwargs)
    try:
        return tuple(env.unwrapped.scenes)
    finally:
        env.close()


def labels_of(env_id: str, **kwargs: Any) -> list[int]:
    env = gym.make(env_id, **kwargs)
    try:
        return list(env.unwrapped.labels)
    finally:
        env.close()


def digest(scenes: tuple[Scene, ...] | list[Scene]) -> str:
    return hashlib.sha256(json.dumps([s.to_dict() for s in scenes], sort_keys=True).encode()).hexdigest()


# --------------------------------------------------------------------------------------------- 1. nested, fixed


@pytest.mark.parametrize("env_id", [CL_ID, BA_ID])
def test_the_worlds_of_n_are_the_first_n_of_those_of_m(env_id: str) -> None:
    full = SIZES[env_id]
    counts = [1, 2, 4, 8, 25, full] if full != 25 else [1, 2, 4, 8, 25]
    cuts = {n: scenes_of(env_id, train_worlds=n) for n in counts}
    for n in counts:
        assert len(cuts[n]) == n
        assert len(set(cuts[n])) == n  # no world twice
    for n in counts:
        for m in counts:
            if n < m:
                assert cuts[m][:n] == cuts[n], (n, m)
    whole = scenes_of(env_id)  # every world of the training split
    assert len(whole) == full
    assert set(cuts[full]) == set(whole)  # the full cut: the split reordered
    again = {n: scenes_of(env_id, train_worlds=n) for n in counts}
    assert again == cuts  # the same on every make


SUBPROCESS = """
import hashlib, json, sys
import gymnasium as gym
import pixelworld_env  # registers the ids
out = {}
for env_id, counts in json.loads(sys.argv[1]).items():
    for n in counts:
        env = gym.make(env_id, train_worlds=n)
        scenes = env.unwrapped.scenes
        out[f"{env_id}:{n}"] = hashlib.sha256(
            json.dumps([s.to_dict() for s in scenes], sort_keys=True).encode()).hexdigest()
print(json.dumps(out))
"""


def test_the_same_worlds_in_a_fresh_process_with_a_fresh_cache(tmp_path: Path) -> None:
    """Another process, another hash seed and an empty dataset cache (the datasets generated anew): the same worlds,
    as on another machine."""
    wanted = {CL_ID: [1, 2, 4, 8, 25, 50], BA_ID: [1, 4, 25]}
    here = {f"{env_id}:{n}": digest(scenes_of(env_id, train_worlds=n)) for env_id, counts in wanted.items()
            for n in counts}
    env = {**os.environ, "PIXELWORLD_CACHE": str(tmp_path / "cache"), "PYTHONHASHSEED": "12345"}
    done = subprocess.run([sys.executable, "-c", SUBPROCESS, json.dumps(wanted)], capture_output=True, text=True,
                          env=env, timeout=120, cwd=Path(__file__).resolve().parents[1])
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout.strip().splitlines()[-1]) == here
    assert any((tmp_path / "cache").iterdir())  # the child did generate its own datasets


def test_the_order_is_pinned() -> None:
    """The order itself (dataset, scene index) does not depend on anything of the machine: seeds from the name,
    numpy's legacy RandomState. A change here changes every ``train_worlds`` result ever recorded."""
    train = load_dataset(CL, split="train")
    order = training_order([train])
    assert sorted(order) == [(0, i) for i in range(50)]  # a permutation of the split
    assert [train.labels[i] for _, i in order[:10]] == [1, 0] * 5
    scenes, labels = few_worlds([train], 8)
    assert scenes == [train.scenes[i] for _, i in order[:8]] and labels == [1, 0] * 4


# ------------------------------------------------------------------------------------------------ 2. stratified


def test_classification_worlds_alternate_labels_positive_first() -> None:
    train = load_dataset(CL, split="train")
    for n in range(1, 51):
        _, labels = few_worlds([train], n)
        assert labels.count(1) == math.ceil(n / 2) and labels.count(0) == n // 2, n
    for n in (1, 2, 3, 7, 8, 25, 50):
        labels = labels_of(CL_ID, train_worlds=n)
        assert labels.count(1) == math.ceil(n / 2) and labels.count(0) == n // 2, n
        assert labels == [1, 0] * (n // 2) + [1] * (n % 2)


def _worlds_of(members: tuple[str, ...]) -> list[dict[int, set[Scene]]]:
    """Each member's training worlds by label."""
    out = []
    for member in members:
        train = load_dataset(member, split="train")
        out.append({label: {s for s, v in zip(train.scenes, train.labels, strict=True) if v == label}
                    for label in set(train.labels)})
    return out


def test_a_classification_pools_worlds_spread_over_its_members_per_label() -> None:
    """The j-th negative world among the ``N`` is one of member ``j mod 3``'s: the members in turn, so as even as ``N``
    allows. (The members share their positive worlds: a positive scene may belong to several members and comes once,
    where it first comes; the negative ones are each member's own and name their member exactly.)"""
    members = catalog.concept_pools()[CL_POOL]
    assert len(members) == 3
    worlds = _worlds_of(members)
    assert all(not (worlds[a][0] & worlds[b][0]) for a in range(3) for b in range(a + 1, 3))
    pool_id = f"PW-{CL_POOL}-v0"
    distinct = len(training_order([load_dataset(m, split="train") for m in members]))
    for n in (1, 2, 3, 4, 5, 6, 7, 11, 12, 30, 75, distinct - 1, distinct):
        env = gym.make(pool_id, train_worlds=n)
        scenes, labels = list(env.unwrapped.scenes), list(env.unwrapped.labels)
        env.close()
        assert len(scenes) == n
        ones = min(math.ceil(n / 2), len(set().union(*(w[1] for w in worlds))))  # as equal as the worlds allow
        assert labels.count(1) == ones and labels.count(0) == n - ones, n
        for label in (0, 1):
            chosen = [s for s, v in zip(scenes, labels, strict=True) if v == label]
            for j, scene in enumerate(chosen):
                assert scene in (worlds[j % 3][0] if label == 0 else set().union(*(w[1] for w in worlds))), (n, j)
            if label == 0:  # exact membership: counts as even as n allows
                counts = Counter(next(k for k in range(3) if s in worlds[k][0]) for s in chosen)
                spread = [counts.get(k, 0) for k in range(3)]
                assert max(spread) - min(spread) <= 1 and spread == sorted(spread, reverse=True), (n, spread)
    assert scenes_of(pool_id, train_worlds=12) == scenes_of(pool_id, train_worlds=75)[:12]  # nested over a pool


def test_n_worlds_of_a_pool_are_n_distinct_worlds() -> None:
    """A pool's members share worlds; each comes once, so N worlds are N different worlds."""
    for pool in (CL_POOL, "cl_self-inside-container"):
        for n in (4, 8, 25):
            scenes = scenes_of(f"PW-{pool}-v0", train_worlds=n)
            assert len(set(scenes)) == n, (pool, n, len(set(scenes)))


def test_a_bring_about_pools_worlds_take_its_members_in_turn() -> None:
    members = catalog.concept_pools()[BA_POOL]
    assert len(members) == 2
    worlds = [w[1] for w in _worlds_of(members)]
    assert not worlds[0] & worlds[1]  # no world of both: membership is exact
    pool_id = f"PW-{BA_POOL}-v0"
    for n in (1, 2, 3, 9, 50):
        scenes = scenes_of(pool_id, train_worlds=n)
        assert [0 if s in worlds[0] else 1 for s in scenes] == [j % 2 for j in range(n)], n
        assert len(set(scenes)) == n


# ------------------------------------------------------------------------------------------------- 3. refusals


@pytest.fixture
def no_loading(monkeypatch: pytest.MonkeyPatch) -> None:
    """Any dataset load fails the test: the refusals come before any work."""

    def refuse(*args: Any, **kwargs: Any) -> None:
        raise AssertionError(f"a dataset was loaded: {args} {kwargs}")

    monkeypatch.setattr(registration, "load_dataset", refuse)


BAD_VALUES = [
    (0, PixelWorldError, r"train_worlds must be >= 1, got 0"),
    (-1, PixelWorldError, r"train_worlds must be >= 1, got -1"),
    (2.5, PixelWorldTypeError, r"train_worlds must be an integer, got 2\.5"),
    (True, PixelWorldTypeError, r"train_worlds must be an integer, got True"),
    ("4", PixelWorldTypeError, r"train_worlds must be an integer, got '4'"),
]


@pytest.mark.parametrize(("value", "error", "message"), BAD_VALUES)
@pytest.mark.parametrize("env_id", [CL_ID, BA_ID, f"PW-{CL_POOL}-v0"])
def test_bad_values_are_refused_before_any_dataset_loads(no_loading: None, env_id: str, value: Any,
                                                         error: type[Exception], message: str) -> None:
    with pytest.raises(error, match=message):
        gym.make(env_id, train_worlds=value)
    with pytest.raises(error, match=message):
        gym.make_vec(env_id, 4, train_worlds=value)


@pytest.mark.parametrize("split", REFUSED_SPLITS)
def test_another_split_than_train_is_never_cut(no_loading: None, split: str) -> None:
    message = rf"train_worlds=3 cuts the training split; split='{split}' is never cut"
    with pytest.raises(PixelWorldError, match=message):
        gym.make(CL_ID, split=split, train_worlds=3)
    with pytest.raises(PixelWorldError, match=message):
        gym.make_vec(CL_ID, 4, split=split, train_worlds=3)
    with pytest.raises(PixelWorldError, match=message):
        pixelworld_env.make_env([CL], split=split, train_worlds=3)


@pytest.mark.parametrize("env_id", [CL_ID, BA_ID])
def test_more_worlds_than_the_split_has_are_refused_naming_the_count(env_id: str) -> None:
    full = SIZES[env_id]
    assert len(scenes_of(env_id, train_worlds=full)) == full
    message = rf"train_worlds={full + 1}: the training split of .* has {full} worlds"
    with pytest.raises(PixelWorldError, match=message):
        gym.make(env_id, train_worlds=full + 1)
    with pytest.raises(PixelWorldError, match=message):
        gym.make_vec(env_id, 2, train_worlds=full + 1)


def test_the_native_vector_env_holds_the_cut_worlds() -> None:
    vector = gym.make_vec(CL_ID, 4, train_worlds=3)
    try:
        assert isinstance(vector, PixelWorldVectorEnv)
        assert vector.num_envs == 4 and vector.split == "train"
        assert vector.scenes == scenes_of(CL_ID, train_worlds=3)
        assert list(vector.labels) == [1, 0, 1]
        obs, _ = vector.reset(seed=0)
        assert len(obs) == 4
    finally:
        vector.close()
    synced = gym.make_vec(CL_ID, 2, vectorization_mode="sync", train_worlds=3)
    try:
        assert all(tuple(e.unwrapped.scenes) == scenes_of(CL_ID, train_worlds=3) for e in synced.envs)
    finally:
        synced.close()


# ------------------------------------------------------------------------------------------------- 4. sb3_smc


def test_the_spec_stores_train_worlds_in_the_tasks_env_kwargs() -> None:
    spec = TrainingSpec.create(CL_ID, train_worlds=4)
    assert spec.task.env_kwargs == {"train_worlds": 4} and spec.task.train_worlds == 4
    assert TrainingSpec.create(CL_ID).task.train_worlds is None
    assert TrainingSpec.from_dict(spec.to_dict()) == spec
    assert TrainingSpec.from_json(spec.to_json()) == spec
    assert TrainingSpec.from_json(spec.to_json()).task.train_worlds == 4
    kept = TrainingSpec.create(CL_ID, train_worlds=2, env_kwargs={"observation": "hand"})
    assert kept.task.env_kwargs == {"observation": "hand", "train_worlds": 2}
    on_task = TrainingSpec.create(TaskSpec(CL_ID, env_kwargs={"observation": "hand"}), train_worlds=3)
    assert on_task.task.env_kwargs == {"observation": "hand", "train_worlds": 3} and on_task.task.train_worlds == 3


def test_the_spec_refuses_train_worlds_twice_or_of_bad_values() -> None:
    with pytest.raises(RecordError, match="give train_worlds once"):
        TrainingSpec.create(CL_ID, train_worlds=4, env_kwargs={"train_worlds": 4})
    with pytest.raises(RecordError, match="give train_worlds once"):
        TrainingSpec.create(TaskSpec(CL_ID, env_kwargs={"train_worlds": 2}), train_worlds=4)
    for value, message in ((0, ">= 1"), (-1, ">= 1"), (True, "an integer"), (2.5, "an integer"), ("4", "an integer")):
        with pytest.raises(RecordError, match=f"train_worlds must be {message}"):
            TrainingSpec.create(CL_ID, train_worlds=value)


def test_untrained_smc_refuses_a_cut_test_split_before_building_a_model() -> None:
    with pytest.raises(PixelWorldError, match="split='test' is never cut"):
        untrained_smc(CL_ID, split="test", train_worlds=4)
    with pytest.raises(PixelWorldError, match="has 50 worlds"):
        untrained_smc(CL_ID, train_worlds=51)


@pytest.fixture(scope="module")
def trained() -> Any:
    return train_smc(CL_ID, total_timesteps=2000, train_worlds=4, log_every=0)


def test_train_smc_on_four_worlds_and_the_test_on_every_test_world(trained: Any) -> None:
    smc = trained
    assert smc.spec.task.train_worlds == 4 and smc.spec.task.env_kwargs == {"train_worlds": 4}
    assert smc.spec.budget.total_timesteps == 2000
    assert smc.record is not None and smc.record.total_timesteps >= 2000 and smc.record.training_returns
    test = evaluate(smc, repeats=1)
    assert len(test.scores) == len(load_dataset(CL, split="test").scenes) == 50
    assert test.record.split == "test" and test.record.train_worlds is None
    assert "train_worlds" not in test.record.to_dict()  # JSON as before the feature
    train = evaluate(smc, split="train", repeats=1)
    assert len(train.scores) == 4 and train.record.split == "train" and train.record.train_worlds == 4
    assert [e.label for e in train.environments] == [1, 0, 1, 0]
    data = train.record.to_dict()
    assert data["train_worlds"] == 4
    assert EvaluationRecord.from_dict(data).to_dict() == data
    assert EvaluationRecord.from_json(train.record.to_json()).train_worlds == 4
    keys = {(r.env_id, r.split): r.train_worlds for r in smc.evaluations}
    assert keys[(CL_ID, "test")] is None and keys[(CL_ID, "train")] == 4


def test_the_resolved_task_cuts_the_training_split_only(trained: Any) -> None:
    task = resolve_task(trained.spec.task, smc="x")
    cut = scenes_of(CL_ID, train_worlds=4)
    env = task.make_env(20, smc="x")
    assert tuple(env.unwrapped.scenes) == cut and env.unwrapped.train_worlds == 4
    env.close()
    for split in REFUSED_SPLITS:
        env = task.make_env(20, smc="x", split=split)
        whole = scenes_of(CL_ID, split=split)
        assert tuple(env.unwrapped.scenes) == whole and env.unwrapped.train_worlds is None
        assert env.unwrapped.split == split
        env.close()
    vector = task.make_vector_env(2, 20)
    assert vector.scenes == cut
    vector.close()


def test_evaluation_records_without_train_worlds_are_unchanged() -> None:
    old = {"smc": "a", "env_id": CL_ID, "split": "test", "kind": "classification", "repeats": 1,
           "evaluation_seed": 0, "score": 0.5, "environment_scores": [0.0, 1.0], "mean_length": 3.0,
           "call_counts": {}}
    record = EvaluationRecord.from_dict(old)
    assert record.train_worlds is None and record.to_dict() == old
    cut = EvaluationRecord.from_dict({**old, "split": "train", "train_worlds": 2})
    assert cut.train_worlds == 2 and EvaluationRecord.from_json(cut.to_json()).to_dict() == cut.to_dict()
    for bad in (0, True, 1.5):
        with pytest.raises(RecordError, match="train_worlds"):
            EvaluationRecord.from_dict({**old, "train_worlds": bad})


# --------------------------------------------------------------- 5. no training worlds reported as test worlds


OWN_ID = "TestTrainWorldsChosenScenes-v0"


def _chosen_scenes(max_steps: int = 100) -> PixelWorldEnv:
    train = load_dataset(CL, split="train")
    return PixelWorldEnv(list(train.scenes[:5]), kind="classification", concept=train.concept,
                         labels=list(train.labels[:5]), macros=catalog.macros(), max_steps=max_steps)


def test_an_own_id_over_chosen_scenes_cannot_be_evaluated_as_a_split() -> None:
    if OWN_ID not in gym.registry:
        gym.register(OWN_ID, entry_point=_chosen_scenes)
    smc = untrained_smc(OWN_ID)
    for split in ("test", "train"):
        with pytest.raises(SMCError, match=rf"runs worlds of no known split \(5 worlds\), not the {split} split"):
            evaluate(smc, split=split, repeats=1)
    assert not smc.evaluations


def test_the_refusal_names_a_remedy_that_exists() -> None:
    if OWN_ID not in gym.registry:
        gym.register(OWN_ID, entry_point=_chosen_scenes)
    smc = untrained_smc(OWN_ID)
    with pytest.raises(SMCError) as raised:
        evaluate(smc, split="test", repeats=1)
    if "evaluate_worlds" in str(raised.value):
        assert hasattr(evaluation, "evaluate_worlds")


WORLDS_ID = "TestTrainWorldsOwnWorlds-v0"


@pytest.fixture(scope="module")
def own_worlds() -> dict[str, Any]:
    train, test = load_dataset(CL, split="train"), load_dataset(CL, split="test")
    def pick(dataset: Any, per_label: int) -> tuple[list[Scene], list[int]]:  # the positives, then the negatives
        chosen = [i for label in (1, 0) for i in [j for j, v in enumerate(dataset.labels) if v == label][:per_label]]
        return [dataset.scenes[i] for i in chosen], [dataset.labels[i] for i in chosen]

    (train_scenes, train_labels), (test_scenes, test_labels) = pick(train, 3), pick(test, 2)
    parts = {"train": train_scenes, "train_labels": train_labels, "test": test_scenes, "test_labels": test_labels}
    assert train_labels == [1, 1, 1, 0, 0, 0] and test_labels == [1, 1, 0, 0]
    if WORLDS_ID not in gym.registry:
        assert register_worlds(WORLDS_ID, kind="classification", concept=train.concept, **parts) == WORLDS_ID
    return {**parts, "concept": train.concept}


def test_register_worlds_has_splits_and_train_worlds(own_worlds: dict[str, Any]) -> None:
    assert scenes_of(WORLDS_ID) == tuple(own_worlds["train"])
    assert scenes_of(WORLDS_ID, split="test") == tuple(own_worlds["test"])
    assert scenes_of(WORLDS_ID, split="all") == tuple(own_worlds["train"] + own_worlds["test"])
    two = gym.make(WORLDS_ID, train_worlds=2).unwrapped
    assert len(two.scenes) == 2 and list(two.labels) == [1, 0] and two.train_worlds == 2 and two.split == "train"
    assert set(two.scenes) <= set(own_worlds["train"])
    assert tuple(two.scenes) == scenes_of(WORLDS_ID, train_worlds=5)[:2]
    for split in REFUSED_SPLITS:
        with pytest.raises(PixelWorldError, match="never cut"):
            gym.make(WORLDS_ID, split=split, train_worlds=2)
    with pytest.raises(PixelWorldError, match="has 6 worlds"):
        gym.make(WORLDS_ID, train_worlds=7)
    with pytest.raises(PixelWorldTypeError, match="an integer"):
        gym.make(WORLDS_ID, train_worlds=True)
    vector = gym.make_vec(WORLDS_ID, 3, train_worlds=2)
    assert isinstance(vector, PixelWorldVectorEnv) and vector.scenes == tuple(two.scenes)
    vector.close()


def test_evaluate_on_register_worlds_runs_its_test_worlds(own_worlds: dict[str, Any]) -> None:
    smc = untrained_smc(WORLDS_ID)
    test = evaluate(smc, split="test", repeats=1)
    assert len(test.scores) == len(own_worlds["test"]) and test.record.train_worlds is None
    assert [e.label for e in test.environments] == own_worlds["test_labels"]
    train = evaluate(smc, split="train", repeats=1)
    assert len(train.scores) == len(own_worlds["train"])
    cut = untrained_smc(WORLDS_ID, train_worlds=2)
    assert cut.spec.task.train_worlds == 2
    assert len(evaluate(cut, split="test", repeats=1).scores) == len(own_worlds["test"])  # the test is never cut
    on_train = evaluate(cut, split="train", repeats=1)
    assert len(on_train.scores) == 2 and on_train.record.train_worlds == 2


def test_register_worlds_refuses_what_does_not_fit(own_worlds: dict[str, Any]) -> None:
    train, test = own_worlds["train"], own_worlds["test"]
    ok = {"kind": "classification", "concept": own_worlds["concept"], "train": train, "test": test,
          "train_labels": own_worlds["train_labels"], "test_labels": own_worlds["test_labels"]}
    with pytest.raises(PixelWorldError, match="registered already"):
        register_worlds(WORLDS_ID, **ok)
    with pytest.raises(PixelWorldError, match="registered already"):
        register_worlds(CL_ID, **ok)
    fresh = "TestTrainWorldsRefused-v0"
    bad = [
        ({"train_labels": own_worlds["train_labels"][:-1]}, PixelWorldError, "one label, 0 or 1, per world"),
        ({"test_labels": [*own_worlds["test_labels"], 1]}, PixelWorldError, "one label, 0 or 1, per world"),
        ({"train_labels": [2] * len(train)}, PixelWorldError, "one label, 0 or 1, per world"),
        ({"train_labels": [True] * len(train)}, PixelWorldError, "one label, 0 or 1, per world"),
        ({"train_labels": None}, PixelWorldError, "needs one label"),
        ({"kind": "bring-about"}, PixelWorldError, "a bring-about task has no labels"),
        ({"concept": "?x container(x) &"}, ConceptSyntaxError, "syntax error at position 17"),
        ({"concept": "no_such_predicate(self)"}, UnknownPredicateError, "unknown predicate or macro"),
        ({"concept": "container(y)"}, UndeclaredVariableError, "variable 'y'"),
        ({"kind": "regression"}, PixelWorldError, "kind must be"),
        ({"train": []}, PixelWorldTypeError, "non-empty list"),
        ({"test": train[0]}, PixelWorldTypeError, "non-empty list"),
    ]
    for change, error, message in bad:
        with pytest.raises(error, match=message):
            register_worlds(fresh, **{**ok, **change})
        assert fresh not in gym.registry, change  # nothing registered by a refused call
    with pytest.raises(PixelWorldTypeError, match="non-empty string"):
        register_worlds("", **ok)


def test_register_worlds_of_a_bring_about_task() -> None:
    ba_id = "TestTrainWorldsOwnBringAbout-v0"
    train, test = load_dataset(BA, split="train"), load_dataset(BA, split="test")
    if ba_id not in gym.registry:
        register_worlds(ba_id, kind="bring-about", concept=train.concept, train=list(train.scenes[:5]),
                        test=[s.to_ascii() for s in test.scenes[:3]], kinds=test.scenes[0].ascii_kinds())
    env = gym.make(ba_id, train_worlds=3).unwrapped
    assert env.kind == "bring-about" and len(env.scenes) == 3 and set(env.scenes) <= set(train.scenes[:5])
    assert len(scenes_of(ba_id, split="test")) == 3
    smc = untrained_smc(ba_id)
    assert len(evaluate(smc, split="test", repeats=1).scores) == 3


# ------------------------------------------------------------------ 6. registered tasks that take **kwargs


class Corridor(gym.Env):
    """Cells 0..4, a drawn start; left, right, stay."""

    def __init__(self) -> None:
        self.observation_space = spaces.Discrete(5)
        self.action_space = spaces.Discrete(3)
        self.position = 0

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        self.position = int(self.np_random.integers(5))
        return self.position, {}

    def step(self, action):
        self.position = int(np.clip(self.position + (-1, 1, 0)[action], 0, 4))
        return self.position, 0.0, False, False, {}


def _corridor_task(max_steps: int) -> SMCTask:
    return SMCTask(Corridor(), "bring-about", goal=lambda env: env.position == 4, primitive_names=("L", "R", "S"),
                   max_steps=max_steps)


KWARGS_ID, SPLIT_ID = "TestTrainWorldsKwargsTask-v0", "TestTrainWorldsSplitTask-v0"
RECEIVED: dict[str, list[dict[str, Any]]] = {KWARGS_ID: [], SPLIT_ID: []}


def _kwargs_entry(max_steps: int = 100, **kwargs: Any) -> SMCTask:
    RECEIVED[KWARGS_ID].append(dict(kwargs))
    return _corridor_task(max_steps)


def _split_entry(max_steps: int = 100, split: str = "unset") -> SMCTask:
    RECEIVED[SPLIT_ID].append({"split": split})
    return _corridor_task(max_steps)


def test_a_task_whose_entry_point_takes_kwargs_is_not_given_split() -> None:
    if KWARGS_ID not in gym.registry:
        gym.register(KWARGS_ID, entry_point=_kwargs_entry)
    RECEIVED[KWARGS_ID].clear()
    smc = untrained_smc(KWARGS_ID)
    for split in ("test", "train"):
        result = evaluate(smc, split=split, repeats=1, starts=3)
        assert len(result.scores) == 3 and result.record.train_worlds is None
    assert RECEIVED[KWARGS_ID] and all("split" not in kwargs for kwargs in RECEIVED[KWARGS_ID])


def test_a_task_whose_entry_point_takes_split_is_given_it() -> None:
    if SPLIT_ID not in gym.registry:
        gym.register(SPLIT_ID, entry_point=_split_entry)
    RECEIVED[SPLIT_ID].clear()
    smc = untrained_smc(SPLIT_ID)
    # the training environments get the spec's split ("unset": the one instance that tells the task's kind and layout)
    assert "train" in {r["split"] for r in RECEIVED[SPLIT_ID]} <= {"train", "unset"}
    RECEIVED[SPLIT_ID].clear()
    evaluate(smc, split="test", repeats=1, starts=2)
    assert RECEIVED[SPLIT_ID] == [{"split": "test"}]
