"""The initial action distribution ("init" policies, the signal bias) and its installation in a model's action
layer (docs/design.md, "Initial action distribution (signal bias)")."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from sb3_smc.core.layout import CALL_PREFIX, MOVES, SIGNAL_NAMES
from sb3_smc.errors import SMCError

__all__ = ["NONSIGNAL_WEIGHT", "SIGNAL_WEIGHT", "SMC_WEIGHT", "apply_signal_bias", "initial_action_probabilities"]

SIGNAL_WEIGHT, NONSIGNAL_WEIGHT, SMC_WEIGHT = 1.0, 20.0, 20.0
"""Weights of the signal-bias rule (their sum with both groups present is 41)."""


def _group(name: str, primitives: Sequence[str]) -> str:
    if name in SIGNAL_NAMES:
        return "signal"
    if name.startswith(CALL_PREFIX):
        return "smc"
    if name in primitives:
        return "move"
    raise SMCError(f"unknown action name {name!r}: expected a signal {SIGNAL_NAMES}, a primitive "
                   f"{tuple(primitives)} or {CALL_PREFIX}<child>")


def initial_action_probabilities(action_names: Sequence[str], *, signal_weight: float = SIGNAL_WEIGHT,
                                 nonsignal_weight: float = NONSIGNAL_WEIGHT, smc_weight: float = SMC_WEIGHT,
                                 primitives: Sequence[str] = MOVES) -> np.ndarray:
    """The initial action distribution of the paper's "init" policies (the signal bias).

    Signals share ``signal_weight`` equally, moves (the environment's ``primitives``: PixelWorld's by default) share
    ``nonsignal_weight`` and SMC actions ``smc_weight``;
    without SMC actions the moves take both shares (``nonsignal_weight + smc_weight``). Absent groups are
    dropped and the rest renormalised: classification flat SIG0 = SIG1 = 1/82 and each move 10/41;
    with SMCs the moves share 20/41 and the SMCs 20/41; without moves (noprim) signals 1/21 and SMCs 20/21.
    """
    groups = [_group(name, primitives) for name in action_names]
    if not groups:
        raise SMCError("no actions")
    counts = {g: groups.count(g) for g in ("signal", "move", "smc")}
    weights = {"signal": signal_weight, "move": nonsignal_weight, "smc": smc_weight}
    if counts["smc"] == 0:
        weights["move"] = nonsignal_weight + smc_weight
    total = sum(weights[g] for g in weights if counts[g])
    probabilities = np.array([weights[g] / counts[g] / total for g in groups])
    return probabilities


def apply_signal_bias(model: Any, action_names: Sequence[str], primitives: Sequence[str] = MOVES,
                      **weights: float) -> np.ndarray:
    """Set the bias of the policy's action layer to ``log p`` (:func:`initial_action_probabilities`).

    SB3 initialises the action layer orthogonally with gain 0.01, so the initial logits are the bias up to
    about 1e-2 and the initial policy follows ``p``. Returns ``p``.
    """
    import torch

    probabilities = initial_action_probabilities(action_names, primitives=primitives, **weights)
    action_net = model.policy.action_net
    if action_net.out_features != len(probabilities):
        raise SMCError(f"the action layer has {action_net.out_features} outputs for {len(probabilities)} actions")
    with torch.no_grad():
        action_net.bias.copy_(torch.as_tensor(np.log(probabilities), dtype=action_net.bias.dtype))
    return probabilities
