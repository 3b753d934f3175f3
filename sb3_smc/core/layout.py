"""What an SMC senses and does, torch-free: the task signals, PixelWorld's moves and window, the names of SMC actions,
an environment's :class:`Layout`, and the action list and observation size these give (:func:`smc_action_names`,
:func:`observation_size`). Records, the library, the wrapper and the SMC itself read them here."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from pixelworld_env.core.kinds import TASK_KINDS, all_signal_names
from sb3_smc.errors import SMCError

__all__ = ["CALL_PREFIX", "HAND_SIZE", "MOVES", "PIXELWORLD_LAYOUT", "SIGNALS", "SIGNAL_NAMES", "Layout",
           "observation_size", "smc_action_names"]

SIGNALS: dict[str, tuple[str, ...]] = {name: kind.signal_names for name, kind in TASK_KINDS.items()}
"""The signal actions of each task kind, in environment order (PixelWorld's table of kinds)."""
SIGNAL_NAMES = all_signal_names()
"""Every kind's signal names: action names no primitive may take."""
MOVES = ("DOWN", "RIGHT", "UP", "LEFT")
"""The primitive moves, in environment order."""
HAND_SIZE = 81
"""Length of the one-hot 3 x 3 window."""
CALL_PREFIX = "SMC:"
"""Action names of child SMCs are ``CALL_PREFIX + child.name``."""


@dataclass(frozen=True)
class Layout:
    """What an SMC senses and does on its environment: ``sensor_size`` sensor values at the start of its
    observation, and the names of the environment's ``primitives`` (its actions besides the signals)."""

    sensor_size: int = HAND_SIZE
    primitives: tuple[str, ...] = MOVES

    def __post_init__(self) -> None:
        object.__setattr__(self, "primitives", tuple(self.primitives))
        if not isinstance(self.sensor_size, int) or self.sensor_size < 1:
            raise SMCError(f"a layout needs sensor_size >= 1, got {self.sensor_size!r}")
        clash = [name for name in self.primitives
                 if name.startswith(CALL_PREFIX) or name in SIGNAL_NAMES or not name]
        if clash or len(set(self.primitives)) != len(self.primitives):
            raise SMCError(f"primitive action names must be unique, non-empty, and neither signals nor "
                           f"'{CALL_PREFIX}...', got {list(self.primitives)}")

    @property
    def sensor_name(self) -> str:
        """What the sensor part of the observation is called: PixelWorld's ``window``, else ``sensor``."""
        return "window" if self == PIXELWORLD_LAYOUT else "sensor"

    def describe(self, n_children: int, n_actions: int) -> str:
        """The observation in words: ``"81 window + 2 outcomes + 8 previous action"`` (``sensor`` off PixelWorld)."""
        outcomes = f"{n_children} outcome{'s' * (n_children != 1)}"
        return f"{self.sensor_size} {self.sensor_name} + {outcomes} + {n_actions} previous action"


PIXELWORLD_LAYOUT = Layout()
"""PixelWorld's layout: the one-hot 3 x 3 window and the four moves."""


def smc_action_names(kind: str, children: Sequence[str] = (), include_primitives: bool = True,
                     primitives: Sequence[str] = MOVES) -> tuple[str, ...]:
    """The action list of an SMC of task ``kind`` with child SMCs named ``children`` on an environment with these
    ``primitives`` (PixelWorld's moves by default)."""
    if kind not in SIGNALS:
        raise SMCError(f"kind must be one of {tuple(SIGNALS)}, got {kind!r}")
    moves = tuple(primitives) if include_primitives else ()
    return (*SIGNALS[kind], *moves, *(CALL_PREFIX + name for name in children))


def observation_size(n_children: int, n_actions: int, sensor_size: int = HAND_SIZE) -> int:
    """Length of an SMC's observation: sensor (PixelWorld's window by default), outcome vector, previous action (the
    parts' offsets and how they are written: :class:`sb3_smc.envs.smc_step.SMCObservation`)."""
    return sensor_size + n_children + n_actions
