"""The paper's test protocol (``sb3_smc.learning.evaluation.evaluate``) with scripted SMCs on a real PixelWorld env."""

from __future__ import annotations

import numpy as np
import pytest

import pixelworld_env  # noqa: F401  (registers the PW-* ids)
from pixelworld_env.datasets.loading import load_dataset
from sb3_smc.core.layout import smc_action_names
from sb3_smc.learning.evaluation import evaluate
from sb3_smc.records import WrapperSettings
from sb3_smc.smc.policies import ScriptedPolicy
from sb3_smc.smc.smc import SMC
from tests.helpers import UniformPolicy

CORNER = "cl_self-in-left-corner_vs_on-hline"
CORNER_ID = f"PW-{CORNER}-v0"
ACTIONS = smc_action_names("classification")  # SIG0, SIG1, DOWN, RIGHT, UP, LEFT
SIG0, SIG1, LEFT = ACTIONS.index("SIG0"), ACTIONS.index("SIG1"), ACTIONS.index("LEFT")


def _cell(observation: np.ndarray, k: int) -> int:
    """Colour code of window cell ``k`` (row-major, 4 = the self) from the one-hot observation."""
    return int(np.argmax(observation[9 * k:9 * k + 9]))


def corner_rule(observation: np.ndarray, step: int) -> int:
    """Solves left-corner vs on-hline: walk left along the line; a wall on the left = corner, a gap below = line."""
    if _cell(observation, 3) != 0:
        return SIG1
    if _cell(observation, 7) == 0:
        return SIG0
    return LEFT


def always_sig1(observation: np.ndarray, step: int) -> int:
    return SIG1




def parent_rule(observation: np.ndarray, step: int) -> int:
    """Level-2 script: call the child once, then signal what the child signalled (its outcome entry)."""
    if step == 0:
        return len(ACTIONS)  # SMC:walker, the first action after the moves
    return SIG1 if observation[81] > 0 else SIG0


def scripted(name: str, choose, children=()) -> SMC:
    n_actions = len(smc_action_names("classification", [c.name for c in children]))
    return SMC(name, "classification", ScriptedPolicy(n_actions, choose), children=children)


@pytest.fixture(scope="module")
def test_labels() -> list[int]:
    return list(load_dataset(CORNER, split="test").labels)


def test_correct_script_scores_one(test_labels: list[int]) -> None:
    result = evaluate(scripted("corner", corner_rule), CORNER_ID, repeats=2)
    assert result.score == 1.0
    assert len(result.environments) == len(test_labels) == 50
    assert [env.label for env in result.environments] == test_labels
    assert all(env.score == 1.0 and len(env.episodes) == 2 for env in result.environments)
    for env in result.environments:
        for episode in env.episodes:
            assert episode.success and episode.signalled and episode.final_reward == 1.0
            assert episode.actions[-1] == (SIG1 if env.label else SIG0)
            assert set(episode.actions[:-1]) <= {LEFT}
            # one cell per move (every move here succeeds) plus the start
            assert len(episode.cells) == episode.length
            assert all(b == (a[0], a[1] - 1) for a, b in zip(episode.cells, episode.cells[1:], strict=False))


def test_always_sig1_scores_the_positive_fraction(test_labels: list[int]) -> None:
    result = evaluate(scripted("yes", always_sig1), CORNER_ID, repeats=3)
    assert result.score == pytest.approx(np.mean(test_labels))
    assert result.scores == [float(label) for label in test_labels]
    assert result.repeats == 3 and result.n_episodes == 150
    assert all(e.length == 1 and e.final_reward == (1.0 if e.success else -1.0) for e in result.episodes)


def test_success_is_final_reward_positive_and_scores_are_means() -> None:
    smc = SMC("random", "classification", UniformPolicy(len(ACTIONS)))
    result = evaluate(smc, CORNER_ID, repeats=4, seed=3)
    for env in result.environments:
        assert [e.repeat for e in env.episodes] == [0, 1, 2, 3]
        assert env.score == np.mean([e.final_reward > 0 for e in env.episodes])
        for e in env.episodes:
            assert e.success == (e.final_reward > 0)
            assert e.signalled == (e.actions[-1] in (SIG0, SIG1))
            assert e.signalled or e.length == 100
    assert result.score == pytest.approx(np.mean(result.scores))


def test_deterministic_for_a_seed() -> None:
    smc = SMC("random", "classification", UniformPolicy(len(ACTIONS)))
    first = evaluate(smc, CORNER_ID, repeats=2, seed=7)
    again = evaluate(smc, CORNER_ID, repeats=2, seed=7)
    other = evaluate(smc, CORNER_ID, repeats=2, seed=8)
    assert first.to_dict() == again.to_dict()
    assert [e.actions for e in first.episodes] != [e.actions for e in other.episodes]
    # repeats of one environment differ (different seeds), and an episode's seed reproduces it alone
    assert first.environments[0].episodes[0].actions != first.environments[0].episodes[1].actions


def test_train_split_and_summary() -> None:
    result = evaluate(scripted("corner", corner_rule), CORNER_ID, split="train", repeats=1)
    assert result.split == "train" and result.score == 1.0
    assert "accuracy 1.000" in result.summary()


def test_hierarchical_smc_records_child_moves_and_calls() -> None:
    walker = scripted("walker", corner_rule)
    parent = scripted("parent", parent_rule, children=(walker,))
    result = evaluate(parent, CORNER_ID, repeats=1)
    assert result.score == 1.0
    assert result.call_counts() == {"walker": 50}
    for e in result.episodes:
        assert e.length == 2 and e.calls == {"walker": 1}
        assert e.actions[0] == len(ACTIONS)
        # the child's moves are in the visited cells although the parent made no move itself
        assert len(e.cells) == e.primitive_steps + 1


def test_wrapper_settings_replace_the_specs_in_the_test() -> None:
    """``wrapper=`` replaces the SMC's wrapper settings for the test: with the calls' moves counted against an
    episode of 3 steps, no episode makes more than 3 moves; as trained (a call one step), some make more."""
    walker = scripted("walker", corner_rule)
    parent = scripted("parent", parent_rule, children=(walker,))
    as_trained = evaluate(parent, CORNER_ID, repeats=1, keep=False)
    counted = evaluate(parent, CORNER_ID, repeats=1, keep=False,
                       wrapper=WrapperSettings(count_primitive_steps=True, max_steps=3))
    assert max(e.primitive_steps for e in as_trained.episodes) > 3
    assert max(e.primitive_steps for e in counted.episodes) <= 3 < len(counted.episodes)
    assert counted.score < as_trained.score == 1.0


def test_kind_mismatch_is_an_error() -> None:
    smc = SMC("ba", "bring-about", UniformPolicy(5))
    with pytest.raises(ValueError, match="bring-about SMC"):
        evaluate(smc, CORNER_ID, repeats=1)
