"""The task kinds, as data: what a kind's signals are, what each signal is worth and what it tells a caller.

One frozen :class:`TaskKind` per kind in :data:`TASK_KINDS`; every step path reads it here (``PixelWorldEnv``, the
native vector env and its compiled kernel, ``sb3_smc``'s ``SMCTask``, the SMC wrapper and its compiled calls, the
action layout). Adding a kind is one entry (docs/architecture.md, "Where to add a kind"). A kind not in the table is
an error everywhere (:func:`task_kind`), never taken for another.

The rewards (docs/design.md, "Rewards"): a signal ends the episode with ``rewards[label][goal]``, the world's label
(0 or 1; 0 for kinds without labels) and whether the goal holds when it is given (0 for kinds that track no goal).
Where the kind tracks a goal, a move into the goal earns :data:`GOAL_POTENTIAL` and one out of it loses as much, so a
goal signal's total is its entry plus the potential collected; a timeout earns no signal reward.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from pixelworld_env.errors import PixelWorldError

__all__ = ["BRING_ABOUT", "BRING_ABOUT_OR_CANNOT", "CLASSIFICATION", "GOAL_POTENTIAL", "GOAL_REWARD", "KINDS",
           "SIGNAL_REWARD", "TASK_KINDS", "Kind", "Signal", "TaskKind", "all_signal_names", "kind_of_name",
           "signal_outcomes", "task_kind"]

Kind = Literal["classification", "bring-about", "bring-about-or-cannot"]
"""The kinds of task (and of dataset): a label to tell, a goal to bring about, or a goal to bring about where the
world allows it and to declare out of reach where it does not."""
CLASSIFICATION: Kind = "classification"
BRING_ABOUT: Kind = "bring-about"
BRING_ABOUT_OR_CANNOT: Kind = "bring-about-or-cannot"

SIGNAL_REWARD = 1.0
"""The reward of a right classification signal (a wrong one: minus it); a right cannot signal earns it too."""
GOAL_POTENTIAL = 0.5
"""Shaping potential while the goal holds: entering the goal earns it, leaving loses it."""
GOAL_REWARD = 1.0
"""A goal signal's total reward while the goal holds (its own entry is this minus the potential collected)."""

_RIGHT_GOAL = GOAL_REWARD - GOAL_POTENTIAL


@dataclass(frozen=True)
class Signal:
    """One signal action: its ``name``, its ``outcome`` in a caller's outcome vector when a called SMC gives it, and
    its ``rewards[label][goal]`` when it ends an episode."""

    name: str
    outcome: float
    rewards: tuple[tuple[float, float], tuple[float, float]]


@dataclass(frozen=True)
class TaskKind:
    """A task kind: its ``signals`` (the first actions of its environments, in this order), whether its episodes
    track the goal's truth (``tracks_goal``: shaping, the ``goal`` info key), what a world's label says (``label``:
    ``"label"`` the concept holds, ``"possible"`` the goal can be brought about; ``None``: no label), and the
    outcome a caller records for a call that ends without a signal (``cut_outcome``: cut at its cap, or the
    episode ended under it); ``score`` names what an evaluation's share of successful episodes is for it; ``prefix``
    begins the names of its datasets and concept pools (``cl_``, ``ba_``, ``bc_``)."""

    name: str
    prefix: str
    signals: tuple[Signal, ...]
    tracks_goal: bool
    label: Literal["label", "possible"] | None
    cut_outcome: float
    score: Literal["accuracy", "success rate"]
    description: str

    @property
    def signal_names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.signals)

    def reward(self, signal: int, label: int, goal: bool) -> float:
        """The reward of signal number ``signal`` given in a world of ``label`` (0 without labels) while the goal
        holds or not."""
        return self.signals[signal].rewards[label][int(goal)]

    def reward_table(self, n_actions: int) -> np.ndarray:
        """``(n_actions, 2, 2)`` float64: per action (the signals first) its ``rewards[label][goal]``, zeros for
        the other actions; the compiled kernels read a signal's reward there."""
        table = np.zeros((n_actions, 2, 2))
        for k, signal in enumerate(self.signals):
            table[k] = signal.rewards
        return table

    def reward_at_end(self, label: int, goal: bool) -> float:
        """What an episode that the environment itself ends earns besides its shaping (``SMCTask``): a goal kind's
        right goal signal while the goal holds, else nothing."""
        return _RIGHT_GOAL if self.tracks_goal and goal else 0.0


def _same_for_every_label(by_goal: tuple[float, float]) -> tuple[tuple[float, float], tuple[float, float]]:
    return by_goal, by_goal


def _by_label(label0: float, label1: float) -> tuple[tuple[float, float], tuple[float, float]]:
    return (label0, label0), (label1, label1)


TASK_KINDS: dict[str, TaskKind] = {kind.name: kind for kind in (
    TaskKind(CLASSIFICATION, "cl", (Signal("SIG0", -1.0, _by_label(SIGNAL_REWARD, -SIGNAL_REWARD)),
                              Signal("SIG1", 1.0, _by_label(-SIGNAL_REWARD, SIGNAL_REWARD))),
             tracks_goal=False, label="label", cut_outcome=0.0, score="accuracy",
             description="tell the world's label: SIG1 (the concept holds) or SIG0, +1 right, -1 wrong"),
    TaskKind(BRING_ABOUT, "ba", (Signal("SIG1", 1.0, _same_for_every_label((0.0, _RIGHT_GOAL))),),
             tracks_goal=True, label=None, cut_outcome=0.0, score="success rate",
             description="move until the concept holds, then SIG1: +1 in all with the shaping, 0 outside the goal "
                         "(AAAI-18's reward_mistake = 0)"),
    # SIG1 is bring-about's (0 outside the goal). A cost of -1 there was tried and measured (docs/results/cannot):
    # the flat SMC then stops signalling SIG1 at all. A wrong cannot signal while the goal holds also gives back the
    # potential collected, so that it totals -1.
    TaskKind(BRING_ABOUT_OR_CANNOT, "bc",
             (Signal("SIG1", 1.0, _same_for_every_label((0.0, _RIGHT_GOAL))),
              Signal("CANNOT", -1.0, ((SIGNAL_REWARD, -SIGNAL_REWARD - GOAL_POTENTIAL),
                                      (-SIGNAL_REWARD, -SIGNAL_REWARD - GOAL_POTENTIAL)))),
             tracks_goal=True, label="possible", cut_outcome=-0.5, score="success rate",
             description="bring the concept about and SIG1 where the world allows it (+1), or CANNOT where it does "
                         "not (+1); a wrong CANNOT -1, SIG1 outside the goal and a timeout 0"),
)}
"""Every task kind, by name."""
KINDS: tuple[str, ...] = tuple(TASK_KINDS)
"""The kinds' names, in the table's order."""


def task_kind(kind: object, where: str = "kind") -> TaskKind:
    """The :class:`TaskKind` named ``kind``; :class:`PixelWorldError` naming ``where`` and the kinds otherwise."""
    found = TASK_KINDS.get(kind) if isinstance(kind, str) else None
    if found is None:
        raise PixelWorldError(f"{where} must be one of {KINDS}, got {kind!r}")
    return found


def kind_of_name(name: str, where: str = "dataset") -> TaskKind:
    """The kind of a dataset or concept pool named ``name``, by its prefix (``cl_``, ``ba_``, ``bc_``);
    :class:`PixelWorldError` naming ``where`` for a name without one."""
    for kind in TASK_KINDS.values():
        if name.startswith(kind.prefix + "_"):
            return kind
    raise PixelWorldError(f"{where} {name!r}: its name must begin with a kind's prefix "
                          f"({', '.join(k.prefix + '_' for k in TASK_KINDS.values())}: "
                          f"{', '.join(TASK_KINDS)})")


def all_signal_names() -> tuple[str, ...]:
    """Every signal name of every kind, each once (action names no primitive may take)."""
    return tuple(signal_outcomes())


def signal_outcomes() -> dict[str, float]:
    """Each signal name's outcome in a caller's outcome vector; a name means the same outcome in every kind (checked:
    a caller reads a called SMC's signal by its name)."""
    outcomes: dict[str, float] = {}
    for kind in TASK_KINDS.values():
        for signal in kind.signals:
            if outcomes.setdefault(signal.name, signal.outcome) != signal.outcome:
                raise PixelWorldError(f"signal {signal.name!r} has two outcomes in the table of kinds")
    return outcomes
