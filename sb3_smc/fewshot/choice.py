"""Which of a library's SMCs to offer a new concept as actions: the held-out rule, and the automatic choice from the
concept's few examples alone (no person picks the children).

The automatic choice calls every candidate once from the start of each example world (``repeats`` times, from
seeds of ``seed``) in the task's own environment, and scores it:

* classification: how well its outcomes separate the labels, ``|mean outcome on positive worlds - mean outcome on
  negative worlds| / 2`` (an outcome is +1 for ``SIG1``, -1 for ``SIG0``, 0 for a timeout), in ``[0, 1]``; with
  examples of one label only, how decisive its outcomes are (``mean |outcome|``);
* the kinds with a goal (bring-about, bring-about-or-cannot): how often the goal holds when its call ends, on the
  example worlds that allow it, in ``[0, 1]``.

The ``k`` best are kept, ties to the library's order. Deterministic for a given ``seed``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from sb3_smc.errors import SMCError
from sb3_smc.smc.smc import SMC

if TYPE_CHECKING:
    from pixelworld_env.envs.env import PixelWorldEnv

__all__ = ["DEFAULT_OFFERED", "Choice", "choose_smcs", "held_out"]

DEFAULT_OFFERED = 8
"""How many SMCs the automatic choice offers by default (the paper's canonical sets offer 6-13 nodes)."""


@dataclass(frozen=True)
class Choice:
    """The automatic choice: the SMCs kept (best first) and every candidate's score, by name."""

    chosen: tuple[str, ...]
    scores: dict[str, float]


def _trained_on(smc: SMC) -> set[str]:
    """The datasets ``smc`` and its descendants were trained on (from their specs)."""
    found = set(smc.spec.task.datasets) if smc.spec is not None else set()
    for child in smc.children:
        found |= _trained_on(child)
    return found


def held_out(library: Mapping[str, SMC], datasets: Sequence[str]) -> list[str]:
    """The SMCs of ``library`` that may be offered to a concept of ``datasets``: none that was trained on one of
    them, nor one that calls such an SMC (through any chain), in the library's order."""
    own = set(datasets)
    return [name for name, smc in library.items() if not _trained_on(smc) & own]


def choose_smcs(env_id: str, candidates: Sequence[SMC], *, train_worlds: int | None = None,
                k: int = DEFAULT_OFFERED, repeats: int = 4, seed: int = 0,
                env_kwargs: Mapping[str, Any] | None = None) -> Choice:
    """The ``k`` candidates whose calls best tell the concept from its examples (see the module's docstring).

    :param env_id: the concept's task; only its training worlds are read (``train_worlds``: its first ``N``).
    :param candidates: the SMCs that may be offered (already held out: :func:`held_out`).
    :param k: how many to keep (all, where there are fewer).
    :param repeats: calls of each candidate from each world.
    :param seed: the seed of the calls' draws.
    """
    import gymnasium as gym

    from sb3_smc.envs.factory import wrap_with_smcs
    from sb3_smc.records import WrapperSettings

    if not candidates:
        raise SMCError(f"{env_id}: no SMC to choose from (the library holds none that is not trained on the "
                       "concept's own datasets)")
    if not isinstance(k, int) or isinstance(k, bool) or k < 1:
        raise SMCError(f"k must be a positive integer, got {k!r}")
    kwargs = {**dict(env_kwargs or {}), **({"train_worlds": train_worlds} if train_worlds is not None else {})}
    env = wrap_with_smcs(gym.make(env_id, split="train", disable_env_checker=True, **kwargs), candidates,
                         WrapperSettings())
    if not env.pixelworld:
        raise SMCError(f"{env_id}: the automatic choice reads a PixelWorld task's example worlds; this is another "
                       "environment (offer a list of names instead)")
    base = cast("PixelWorldEnv", env.base)
    tracks_goal = base.task_kind.tracks_goal
    labels = np.asarray(base.labels if base.labels is not None else [1] * len(base.scenes))
    first = len(env.action_names) - len(candidates)
    outcomes = np.zeros((len(candidates), len(base.scenes), repeats))
    try:
        for world in range(len(base.scenes)):
            for j in range(len(candidates)):
                for repeat in range(repeats):
                    env.reset(seed=int(np.random.SeedSequence((seed, world, repeat)).generate_state(1)[0]),
                              options={"index": world})
                    _, _, _, _, info = env.step(first + j)
                    top = [call for call in info["smc_calls"] if call["depth"] == 1][-1]
                    outcomes[j, world, repeat] = float(base.goal_holds()) if tracks_goal else float(top["outcome"])
    finally:
        env.close()
    if tracks_goal:  # how often the call ends in the goal, on the worlds that allow it
        scores = outcomes[:, labels == 1].mean(axis=(1, 2)) if (labels == 1).any() else np.zeros(len(candidates))
    elif len(set(labels.tolist())) == 2:
        scores = np.abs(outcomes[:, labels == 1].mean(axis=(1, 2)) - outcomes[:, labels == 0].mean(axis=(1, 2))) / 2
    else:
        scores = np.abs(outcomes).mean(axis=(1, 2))
    order = sorted(range(len(candidates)), key=lambda j: (-scores[j], j))
    names = [smc.name for smc in candidates]
    return Choice(tuple(names[j] for j in order[:k]), {names[j]: float(scores[j]) for j in range(len(names))})
