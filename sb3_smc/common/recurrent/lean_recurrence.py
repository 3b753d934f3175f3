r"""The compiled recurrence of the lean updates: one recurrent layer (an LSTM or a GRU) run forward and backward
over every sequence of a batch in one numba loop, in float64, with no padding and no per-step torch calls.

:class:`Sequences` is a batch's layout (each sequence's first row, length and initial state). :func:`recurrence`
is the layer's outputs on it as a torch tensor whose gradient reaches the layer's four parameters
(:class:`LstmRecurrence` / :class:`GruRecurrence`, ``torch.autograd.Function``\ s around the kernels), for updates
whose heads stay in torch: the lean PPO epoch with other heads (:mod:`~sb3_smc.common.recurrent.lean_update`) and
RecurrentTRPO's lean policy step (:mod:`sb3_smc.recurrent_trpo`). The kernels skip zero inputs (a mostly one-hot
observation); their tanh is :func:`~sb3_smc.common.kernels.fast_tanh` (float32 accuracy, no library call, so the
loops vectorize) and their sums are in another order than torch's, so the outputs and gradients equal torch's
layer up to float rounding (tested), not bit for bit.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
import torch
from numba import njit
from torch import nn

from sb3_smc.common.kernels import fast_tanh
from sb3_smc.common.recurrent.layers import GRUAsLSTM
from sb3_smc.common.recurrent.type_aliases import SequenceStates

__all__ = ["GruRecurrence", "LstmRecurrence", "Sequences", "SparseRows", "compiled_layer", "gru_backward",
           "gru_forward", "lstm_backward", "lstm_forward", "recurrence"]


@njit(cache=True, fastmath=True, inline="always")
def _axpy(y: np.ndarray, a: float, x: np.ndarray) -> None:  # pragma: no cover
    """``y += a * x``."""
    for j in range(y.shape[0]):
        y[j] += a * x[j]


@njit(cache=True, fastmath=True, error_model="numpy")
def lstm_forward(ptr: np.ndarray, idx: np.ndarray, val: np.ndarray, w_ih_t: np.ndarray, w_hh_t: np.ndarray,
                 bias: np.ndarray, starts: np.ndarray, lengths: np.ndarray, h0: np.ndarray, c0: np.ndarray,
                 out_h: np.ndarray, gates: np.ndarray, tanh_c: np.ndarray,
                 cells: np.ndarray) -> None:  # pragma: no cover
    """The LSTM over each sequence ``rows starts[s] : starts[s] + lengths[s]`` of the inputs (their non-zero entries
    ``ptr``, ``idx``, ``val``: :class:`SparseRows`) from ``(h0[s], c0[s])``: writes each row's output ``h``
    (``out_h``), its gate activations i, f, g, o (``gates``), its cell and the cell's tanh. The weights transposed
    (``(inputs, 4 n)``), ``bias`` the sum of torch's two."""
    n = h0.shape[1]
    z = np.empty(4 * n)
    h = np.empty(n)
    c = np.empty(n)
    for s in range(starts.shape[0]):
        h[:] = h0[s]
        c[:] = c0[s]
        for t in range(starts[s], starts[s] + lengths[s]):
            z[:] = bias
            for e in range(ptr[t], ptr[t + 1]):
                _axpy(z, val[e], w_ih_t[idx[e]])
            for k in range(n):
                _axpy(z, h[k], w_hh_t[k])
            gate = gates[t]
            for j in range(4 * n):  # sigmoid(z) = 0.5 tanh(z / 2) + 0.5 on i, f, o; tanh on g (overwritten)
                gate[j] = 0.5 * fast_tanh(0.5 * z[j]) + 0.5
            for j in range(2 * n, 3 * n):
                gate[j] = fast_tanh(z[j])
            tc, out = tanh_c[t], out_h[t]
            for j in range(n):
                c[j] = gate[n + j] * c[j] + gate[j] * gate[2 * n + j]
            for j in range(n):
                tc[j] = fast_tanh(c[j])
            for j in range(n):
                h[j] = gate[3 * n + j] * tc[j]
                out[j] = h[j]
            cells[t] = c


@njit(cache=True, fastmath=True, error_model="numpy")
def lstm_backward(grad_h: np.ndarray, ptr: np.ndarray, idx: np.ndarray, val: np.ndarray, w_hh_t: np.ndarray,
                  starts: np.ndarray, lengths: np.ndarray, c0: np.ndarray, gates: np.ndarray, tanh_c: np.ndarray,
                  cells: np.ndarray, grad_z: np.ndarray, grad_w_ih_t: np.ndarray) -> None:  # pragma: no cover
    """Backpropagation through time of :func:`lstm_forward`: from the loss's gradient at each row's output
    (``grad_h``) writes the gradient at each row's gate pre-activations (``grad_z``) and adds the input weights'
    (transposed) to ``grad_w_ih_t``; the initial states get none (they are rollout data)."""
    n = c0.shape[1]
    dh = np.empty(n)
    dc = np.empty(n)
    for s in range(starts.shape[0]):
        first = starts[s]
        dh[:] = 0.0
        dc[:] = 0.0
        for t in range(first + lengths[s] - 1, first - 1, -1):
            gate, tc, gz, gh = gates[t], tanh_c[t], grad_z[t], grad_h[t]
            c_prev = cells[t - 1] if t > first else c0[s]
            for j in range(n):
                d_h = gh[j] + dh[j]
                d_c = dc[j] + d_h * gate[3 * n + j] * (1.0 - tc[j] * tc[j])
                gz[j] = d_c * gate[2 * n + j] * gate[j] * (1.0 - gate[j])
                gz[n + j] = d_c * c_prev[j] * gate[n + j] * (1.0 - gate[n + j])
                gz[2 * n + j] = d_c * gate[j] * (1.0 - gate[2 * n + j] * gate[2 * n + j])
                gz[3 * n + j] = d_h * tc[j] * gate[3 * n + j] * (1.0 - gate[3 * n + j])
                dc[j] = d_c * gate[n + j]
            for k in range(n):
                w_k, total = w_hh_t[k], 0.0
                for j in range(4 * n):
                    total += w_k[j] * gz[j]
                dh[k] = total
            for e in range(ptr[t], ptr[t + 1]):
                _axpy(grad_w_ih_t[idx[e]], val[e], gz)


@njit(cache=True)
def _nonzeros(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover
    """The non-zero entries of ``x``'s rows, row after row, in column order: :class:`SparseRows`' arrays."""
    rows, cols = x.shape
    count = 0
    for r in range(rows):
        for k in range(cols):
            if x[r, k] != 0.0:
                count += 1
    ptr = np.empty(rows + 1, dtype=np.int64)
    idx = np.empty(count, dtype=np.int64)
    val = np.empty(count)
    e = 0
    for r in range(rows):
        ptr[r] = e
        for k in range(cols):
            if x[r, k] != 0.0:
                idx[e] = k
                val[e] = x[r, k]
                e += 1
    ptr[rows] = e
    return ptr, idx, val


class SparseRows(NamedTuple):
    """A batch's inputs by their non-zero entries (an observation is mostly one-hot): row ``r``'s are
    ``val[ptr[r]:ptr[r + 1]]`` (float64) in the columns ``idx[ptr[r]:ptr[r + 1]]``, in column order, so that the
    kernels' sums over them are in the order of a dense loop that skips zeros."""

    ptr: np.ndarray
    idx: np.ndarray
    val: np.ndarray

    @classmethod
    def of(cls, x: np.ndarray) -> SparseRows:
        """The non-zero entries of ``x`` (``(rows, inputs)``)."""
        return cls(*_nonzeros(x))


class Sequences:
    """The sequences of one batch: each one's first row (``starts``), ``lengths`` and initial states ``h0``, ``c0``
    (float64, ``(sequences, hidden)``, zeros where a sequence starts an episode)."""

    def __init__(self, starts: np.ndarray, lengths: np.ndarray, h0: np.ndarray, c0: np.ndarray) -> None:
        self.starts, self.lengths, self.h0, self.c0 = starts, lengths, h0, c0

    @classmethod
    def cut(cls, cut: np.ndarray, h0: np.ndarray, c0: np.ndarray, resets: np.ndarray) -> Sequences:
        """Sequences starting at the rows where ``cut`` is true, from the states stored on those rows (``h0``,
        ``c0``: one row each), zeroed where ``resets`` (one per row) is 1."""
        starts = np.flatnonzero(cut)
        keep = 1.0 - resets[starts, None]
        return cls(starts, np.diff(np.append(starts, len(cut))), h0[starts].astype(np.float64) * keep,
                   c0[starts].astype(np.float64) * keep)

    def input_states(self, out_h: np.ndarray, dtype: type = np.float64) -> np.ndarray:
        """Each row's input state, from the layer's outputs ``out_h`` over these sequences: the row before's output,
        or its sequence's ``h0`` on a sequence's first row."""
        h_prev: np.ndarray = np.empty(out_h.shape, dtype=dtype)
        h_prev[1:] = out_h[:-1]
        h_prev[self.starts] = self.h0
        return h_prev

    @classmethod
    def of(cls, states: SequenceStates) -> Sequences:
        """The layout of a compact minibatch (:class:`SequenceStates`; the actor's first layer's states)."""
        keep = 1.0 - states.resets.numpy().astype(np.float64)[:, None]
        return cls(states.starts.numpy(), states.lengths.numpy(), states.pi[0][0].numpy().astype(np.float64) * keep,
                   states.pi[1][0].numpy().astype(np.float64) * keep)


class LstmRecurrence(torch.autograd.Function):
    """The LSTM layer's outputs over the sequences of a :class:`Sequences` (see :func:`lstm_forward`), with the
    gradients of its four parameters."""

    @staticmethod
    def forward(ctx: Any, x: np.ndarray, seqs: Sequences, sparse: SparseRows, w_ih: torch.Tensor, w_hh: torch.Tensor,
                b_ih: torch.Tensor, b_hh: torch.Tensor) -> torch.Tensor:
        rows, n = x.shape[0], w_hh.shape[1]
        w_ih64, w_hh64 = (w.detach().numpy().astype(np.float64) for w in (w_ih, w_hh))
        bias = b_ih.detach().numpy().astype(np.float64) + b_hh.detach().numpy()
        out_h, tanh_c, cells = np.empty((rows, n)), np.empty((rows, n)), np.empty((rows, n))
        gates = np.empty((rows, 4 * n))
        w_hh_t = np.ascontiguousarray(w_hh64.T)
        lstm_forward(*sparse, np.ascontiguousarray(w_ih64.T), w_hh_t, bias, seqs.starts, seqs.lengths, seqs.h0, seqs.c0,
                     out_h, gates, tanh_c, cells)
        ctx.saved = (x, sparse, seqs, w_hh_t, out_h, gates, tanh_c, cells)
        return torch.from_numpy(out_h.astype(np.float32))

    @staticmethod
    def backward(ctx: Any, grad_out: torch.Tensor) -> tuple[None, None, None, torch.Tensor, torch.Tensor,
                                                             torch.Tensor, torch.Tensor]:
        x, sparse, seqs, w_hh_t, out_h, gates, tanh_c, cells = ctx.saved
        grad_z = np.empty_like(gates)
        grad_w_ih_t = np.zeros((x.shape[1], gates.shape[1]))
        lstm_backward(grad_out.detach().numpy().astype(np.float64), sparse.ptr, sparse.idx, sparse.val, w_hh_t,
                      seqs.starts, seqs.lengths, seqs.c0, gates, tanh_c, cells, grad_z, grad_w_ih_t)
        h_prev = seqs.input_states(out_h)
        grad_bias = torch.from_numpy(grad_z.sum(axis=0).astype(np.float32))
        return (None, None, None, torch.from_numpy(grad_w_ih_t.T.astype(np.float32)),
                torch.from_numpy((grad_z.T @ h_prev).astype(np.float32)), grad_bias, grad_bias.clone())


@njit(cache=True, fastmath=True, error_model="numpy")
def gru_forward(ptr: np.ndarray, idx: np.ndarray, val: np.ndarray, w_ih_t: np.ndarray, w_hh_t: np.ndarray,
                b_ih: np.ndarray, b_hh: np.ndarray, starts: np.ndarray, lengths: np.ndarray, h0: np.ndarray,
                out_h: np.ndarray, gates: np.ndarray, hidden_n: np.ndarray) -> None:  # pragma: no cover
    """A GRU (torch's equations: gates r, z, n; ``n = tanh(W_in x + b_in + r * (W_hn h + b_hn))``,
    ``h' = n + z * (h - n)``) over each sequence ``rows starts[s] : starts[s] + lengths[s]`` of the inputs (as
    :func:`lstm_forward`'s) from ``h0[s]``: writes each row's output ``h`` (``out_h``), its gates r, z, n
    (``gates``) and ``W_hn h + b_hn`` (``hidden_n``). The weights transposed (``(inputs, 3 n)``)."""
    n = h0.shape[1]
    gi = np.empty(3 * n)
    gh = np.empty(3 * n)
    h = np.empty(n)
    for s in range(starts.shape[0]):
        h[:] = h0[s]
        for t in range(starts[s], starts[s] + lengths[s]):
            gi[:] = b_ih
            for e in range(ptr[t], ptr[t + 1]):
                _axpy(gi, val[e], w_ih_t[idx[e]])
            gh[:] = b_hh
            for k in range(n):
                _axpy(gh, h[k], w_hh_t[k])
            gate, hn, out = gates[t], hidden_n[t], out_h[t]
            for j in range(2 * n):  # sigmoid(z) = 0.5 tanh(z / 2) + 0.5 on r and z
                gate[j] = 0.5 * fast_tanh(0.5 * (gi[j] + gh[j])) + 0.5
            for j in range(n):
                hn[j] = gh[2 * n + j]
                gate[2 * n + j] = fast_tanh(gi[2 * n + j] + gate[j] * gh[2 * n + j])
            for j in range(n):
                h[j] = gate[2 * n + j] + gate[n + j] * (h[j] - gate[2 * n + j])
                out[j] = h[j]


@njit(cache=True, fastmath=True, error_model="numpy")
def gru_backward(grad_h: np.ndarray, ptr: np.ndarray, idx: np.ndarray, val: np.ndarray, w_hh_t: np.ndarray,
                 starts: np.ndarray, lengths: np.ndarray, h0: np.ndarray, out_h: np.ndarray, gates: np.ndarray,
                 hidden_n: np.ndarray, grad_gi: np.ndarray, grad_gh: np.ndarray,
                 grad_w_ih_t: np.ndarray) -> None:  # pragma: no cover
    """Backpropagation through time of :func:`gru_forward`: from the loss's gradient at each row's output
    (``grad_h``) writes the gradients at each row's input and hidden pre-activations (``grad_gi`` = the gradient of
    ``W_ih x + b_ih``, ``grad_gh`` = that of ``W_hh h + b_hh``) and adds the input weights' (transposed) to
    ``grad_w_ih_t``; the initial states get none (they are rollout data)."""
    n = h0.shape[1]
    dh = np.empty(n)
    for s in range(starts.shape[0]):
        first = starts[s]
        dh[:] = 0.0
        for t in range(first + lengths[s] - 1, first - 1, -1):
            gate, hn, gi, gh, g = gates[t], hidden_n[t], grad_gi[t], grad_gh[t], grad_h[t]
            h_prev = out_h[t - 1] if t > first else h0[s]
            for j in range(n):
                d = g[j] + dh[j]
                r, z, c = gate[j], gate[n + j], gate[2 * n + j]
                d_n = d * (1.0 - z) * (1.0 - c * c)
                d_z = d * (h_prev[j] - c) * z * (1.0 - z)
                d_r = d_n * hn[j] * r * (1.0 - r)
                gi[j], gi[n + j], gi[2 * n + j] = d_r, d_z, d_n
                gh[j], gh[n + j], gh[2 * n + j] = d_r, d_z, d_n * r
                dh[j] = d * z
            for k in range(n):
                w_k, total = w_hh_t[k], 0.0
                for j in range(3 * n):
                    total += w_k[j] * gh[j]
                dh[k] += total
            for e in range(ptr[t], ptr[t + 1]):
                _axpy(grad_w_ih_t[idx[e]], val[e], gi)


class GruRecurrence(torch.autograd.Function):
    """The GRU layer's outputs over the sequences of a :class:`Sequences` (see :func:`gru_forward`), with the
    gradients of its four parameters."""

    @staticmethod
    def forward(ctx: Any, x: np.ndarray, seqs: Sequences, sparse: SparseRows, w_ih: torch.Tensor, w_hh: torch.Tensor,
                b_ih: torch.Tensor, b_hh: torch.Tensor) -> torch.Tensor:
        rows, n = x.shape[0], w_hh.shape[1]
        w_ih64, w_hh64, b_ih64, b_hh64 = (w.detach().numpy().astype(np.float64) for w in (w_ih, w_hh, b_ih, b_hh))
        out_h, hidden_n, gates = np.empty((rows, n)), np.empty((rows, n)), np.empty((rows, 3 * n))
        w_hh_t = np.ascontiguousarray(w_hh64.T)
        gru_forward(*sparse, np.ascontiguousarray(w_ih64.T), w_hh_t, b_ih64, b_hh64, seqs.starts, seqs.lengths, seqs.h0,
                    out_h, gates, hidden_n)
        ctx.saved = (x, sparse, seqs, w_hh_t, out_h, gates, hidden_n)
        return torch.from_numpy(out_h.astype(np.float32))

    @staticmethod
    def backward(ctx: Any, grad_out: torch.Tensor) -> tuple[None, None, None, torch.Tensor, torch.Tensor,
                                                             torch.Tensor, torch.Tensor]:
        x, sparse, seqs, w_hh_t, out_h, gates, hidden_n = ctx.saved
        grad_gi, grad_gh = np.empty_like(gates), np.empty_like(gates)
        grad_w_ih_t = np.zeros((x.shape[1], gates.shape[1]))
        gru_backward(grad_out.detach().numpy().astype(np.float64), sparse.ptr, sparse.idx, sparse.val, w_hh_t,
                     seqs.starts, seqs.lengths, seqs.h0, out_h, gates, hidden_n, grad_gi, grad_gh, grad_w_ih_t)
        h_prev = seqs.input_states(out_h)
        return (None, None, None, torch.from_numpy(grad_w_ih_t.T.astype(np.float32)),
                torch.from_numpy((grad_gh.T @ h_prev).astype(np.float32)),
                torch.from_numpy(grad_gi.sum(axis=0).astype(np.float32)),
                torch.from_numpy(grad_gh.sum(axis=0).astype(np.float32)))


def compiled_layer(layer: Any) -> bool:
    """Whether :func:`recurrence` computes ``layer``: one ``nn.LSTM`` or :class:`GRUAsLSTM` layer with biases, no
    projection, sequence first."""
    if type(layer) is GRUAsLSTM:
        layer = layer.gru
    elif type(layer) is not nn.LSTM:
        return False
    return layer.num_layers == 1 and layer.bias and not getattr(layer, "proj_size", 0) and not layer.batch_first


def recurrence(layer: nn.LSTM | GRUAsLSTM, x: np.ndarray, seqs: Sequences,
               sparse: SparseRows | None = None) -> torch.Tensor:
    """``layer``'s outputs (float32, ``(rows, hidden)``) over the sequences ``seqs`` of the inputs ``x``
    (``(rows, inputs)``, float32), differentiable in the layer's parameters; ``layer`` as :func:`compiled_layer`
    accepts. ``sparse``: ``x``'s non-zero entries (:meth:`SparseRows.of`), for a caller that evaluates the layer on
    the same inputs many times (made here when not given)."""
    sparse = SparseRows.of(x) if sparse is None else sparse
    if isinstance(layer, GRUAsLSTM):
        gru = layer.gru
        return GruRecurrence.apply(x, seqs, sparse, gru.weight_ih_l0, gru.weight_hh_l0, gru.bias_ih_l0,
                                   gru.bias_hh_l0)
    return LstmRecurrence.apply(x, seqs, sparse, layer.weight_ih_l0, layer.weight_hh_l0, layer.bias_ih_l0,
                                layer.bias_hh_l0)
