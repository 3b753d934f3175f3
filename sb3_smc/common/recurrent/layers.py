"""Recurrent layers behind ``torch.nn.LSTM``'s interface, which sb3-contrib's recurrent machinery (rollout buffer,
``RNNStates``, ``predict``) expects: :class:`GRUAsLSTM` runs a ``torch.nn.GRU`` and carries the LSTM's ``(h, c)``
pair (``c`` unchanged: zeros from the first step on, so the buffers stay valid and never matter)."""

from __future__ import annotations

from typing import Any

import torch
from torch import nn

from sb3_smc.errors import SMCError

__all__ = ["GRUAsLSTM"]


class GRUAsLSTM(nn.Module):
    """A ``torch.nn.GRU`` with ``nn.LSTM``'s call signature: ``forward(x, (h, c)) -> (output, (h_n, c))``."""

    def __init__(self, input_size: int, hidden_size: int, num_layers: int = 1, **gru_kwargs: Any) -> None:
        super().__init__()
        unsupported = sorted(set(gru_kwargs) - {"bias", "dropout"})
        if unsupported:
            raise SMCError(f"GRU options {unsupported} are not supported (bias and dropout are)")
        self.gru = nn.GRU(input_size, hidden_size, num_layers=num_layers, **gru_kwargs)

    # the attributes sb3-contrib and sb3-smc read from an nn.LSTM
    input_size = property(lambda self: self.gru.input_size)
    hidden_size = property(lambda self: self.gru.hidden_size)
    num_layers = property(lambda self: self.gru.num_layers)
    bias = property(lambda self: self.gru.bias)
    dropout = property(lambda self: self.gru.dropout)
    batch_first = False
    bidirectional = False
    proj_size = 0

    def forward(self, x: torch.Tensor, states: tuple[torch.Tensor, torch.Tensor]
                ) -> tuple[torch.Tensor, tuple[torch.Tensor, torch.Tensor]]:
        h, c = states
        output, h_n = self.gru(x, h.contiguous())
        return output, (h_n, c)

    def step(self, x: torch.Tensor, states: tuple[torch.Tensor, torch.Tensor]
             ) -> tuple[torch.Tensor, tuple[torch.Tensor, torch.Tensor]]:
        """One time step for a batch ``x`` ``(batch, input)`` with ``torch.gru_cell`` per layer."""
        gru, hs = self.gru, []
        for k in range(gru.num_layers):
            bias = (getattr(gru, f"bias_ih_l{k}"), getattr(gru, f"bias_hh_l{k}")) if gru.bias else (None, None)
            x = torch.gru_cell(x, states[0][k], getattr(gru, f"weight_ih_l{k}"), getattr(gru, f"weight_hh_l{k}"),
                               *bias)
            hs.append(x)
        return x, (torch.stack(hs), states[1])
