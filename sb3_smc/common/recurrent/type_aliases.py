"""The layout of a compact recurrent minibatch."""

from __future__ import annotations

import torch
from sb3_contrib.common.recurrent.type_aliases import RNNStates


class SequenceStates(RNNStates):
    """``RNNStates`` of a compact minibatch (:class:`CompactRecurrentRolloutBuffer`) plus its sequence layout.

    ``starts``: the flat index where each sequence starts; ``lengths``: its length; ``resets``: 1.0 where the
    sequence starts an episode (its stored initial state is then replaced by zeros), else 0.0.
    """

    starts: torch.Tensor
    lengths: torch.Tensor
    resets: torch.Tensor
