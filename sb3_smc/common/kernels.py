"""Compiled (numba) steps of the numpy actors' default architecture: one recurrent layer and a linear action head.

A child SMC's decision is one step of a small recurrent network on a mostly one-hot observation (the 3 x 3
window, the outcome vector, the previous action). In numpy that is about a dozen array operations, each paying
numpy's call overhead on vectors of 32-128 numbers; here it is one compiled function that also skips the zero
inputs. :class:`~sb3_smc.smc.numpy_actors.NumpyLSTMPolicy` and :class:`~sb3_smc.smc.numpy_actors.NumpyGRUPolicy` use
these for float64 policies with one recurrent layer and ``net_arch=[]`` (the defaults: every SMC sb3-smc trains) and
keep their numpy code for every other architecture. The arithmetic is the numpy code's, summed in another order and
with :func:`accurate_tanh` (within 2 units in the last place of the C library's ``tanh``, which numpy calls): the
probabilities agree to 1e-14 (tested; in practice to a few units of the last place), so a sampled action differs
only when the uniform draw falls within that distance of a boundary. The module also holds the inverse-CDF draw of
:func:`~sb3_smc.smc.policies.sample_action`. Imported lazily (numba's import and the first compilation cost about a
second; the compiled code is cached next to this file).

The ``*_collection_step`` functions are the training side's counterpart: one data-collection step of
:class:`~sb3_smc.common.recurrent.policies.SequenceLstmPolicy` (or its GRU variant) for all environments at once,
in place of a dozen small torch calls (see its ``forward``).

Every compiled path (the single steps, the collection steps, and a leaf SMC's whole call,
:func:`sb3_smc.envs.leaf_calls.leaf_call`) runs the one :func:`lstm_cell` / :func:`gru_cell` and
:func:`linear_softmax`; the numpy actors' other architectures run the same arithmetic vectorised over rows in numpy
(``NumpyLSTMPolicy._layers`` / ``NumpyGRUPolicy._layers``), kept because numpy's vectorised batches beat the cell's
row-by-row steps there (``docs/benchmarks.md``, "One recurrent cell"). Which ``tanh`` a cell takes is
:data:`LIBM_TANH` / :data:`ACCURATE_TANH` / :data:`FAST_TANH`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["ACCURATE_TANH", "FAST_TANH", "LIBM_TANH", "accurate_tanh", "fast_tanh", "gru_cell", "gru_collection_step",
           "gru_collection_steps", "gru_linear_step", "linear_softmax", "lstm_cell", "lstm_collection_step",
           "lstm_collection_steps", "lstm_linear_step", "sample_index"]


@njit(cache=True)
def linear_softmax(h: np.ndarray, w_out: np.ndarray, b_out: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover
    """``out = softmax(h @ w_out + b_out)``."""
    n_actions = b_out.shape[0]
    for j in range(n_actions):
        out[j] = b_out[j]
    for i in range(h.shape[0]):
        hi = h[i]
        for j in range(n_actions):
            out[j] += hi * w_out[i, j]
    top = out.max()
    total = 0.0
    for j in range(n_actions):
        out[j] = np.exp(out[j] - top)
        total += out[j]
    for j in range(n_actions):
        out[j] /= total


@njit(cache=True)
def _add_rows(t: np.ndarray, x: np.ndarray, w: np.ndarray) -> None:  # pragma: no cover
    """``t += x @ w``, skipping the zero entries of ``x``."""
    for i in range(x.shape[0]):
        xi = x[i]
        if xi != 0.0:
            for j in range(t.shape[0]):
                t[j] += xi * w[i, j]


LIBM_TANH, ACCURATE_TANH, FAST_TANH = 0, 1, 2
"""How a cell computes ``tanh`` (:func:`lstm_cell`, :func:`gru_cell`): the C library's ``np.tanh`` (the training side's
collection steps, :func:`lstm_collection_step` and its kin: bit for bit what they have always computed, so trained
SMCs stay the same); :func:`accurate_tanh` (within 2 units in the last place of it: the numpy actors' steps and the
leaf calls, the steps of SMCs that are called or evaluated); :func:`fast_tanh` (float32 accuracy: the lean update's
collection)."""

_LN2_HI, _LN2_LO = 6.93147180369123816490e-01, 1.90821492927058770002e-10  # ln 2 split: k * _LN2_HI is exact
_INV_LN2 = 1.44269504088896338700e+00


@njit(cache=True, inline="always", error_model="numpy")
def accurate_tanh(x: float) -> float:  # pragma: no cover
    """``tanh(x)`` within 2 units in the last place of the C library's (tested), without a library call, so the
    loops around it vectorize (about 3x the C library's speed on a cell's 160 values).

    ``|x| < 0.625``: Cephes' rational form ``x + x^3 P(x^2) / Q(x^2)``. Else ``1 - 2 / (exp(2|x|) + 1)``, the
    exponential by Cody and Waite's reduction ``2|x| = k ln 2 + r`` (``|r| <= ln 2 / 2``), ``exp(r)`` by its Taylor
    polynomial of degree 13 and ``2^k`` by its binary digits (all exact). ``2|x|`` is clamped at 40 (``tanh`` is 1
    in double precision from ``|x| = 19.06``); NaN stays NaN, the sign of zero is kept."""
    a = abs(x)
    z = a * a
    p = (-9.64399179425052238628e-1 * z + -9.92877231001918586564e1) * z + -1.61468768441708447952e3
    q = ((z + 1.12811678491632931402e2) * z + 2.23548839060100448583e3) * z + 4.84406305325125486048e3
    small = a + a * z * p / q
    y = 40.0 if 2.0 * a > 40.0 else 2.0 * a
    k = np.floor(y * _INV_LN2 + 0.5)
    r = (y - k * _LN2_HI) - k * _LN2_LO
    e = ((((((1.0 / 6227020800.0 * r + 1.0 / 479001600.0) * r + 1.0 / 39916800.0) * r + 1.0 / 3628800.0) * r
              + 1.0 / 362880.0) * r + 1.0 / 40320.0) * r + 1.0 / 5040.0) * r + 1.0 / 720.0
    e = ((((((e * r + 1.0 / 120.0) * r + 1.0 / 24.0) * r + 1.0 / 6.0) * r + 0.5) * r + 1.0) * r) + 1.0
    scale = 1.0
    if k >= 32.0:
        scale, k = scale * 4294967296.0, k - 32.0
    if k >= 16.0:
        scale, k = scale * 65536.0, k - 16.0
    if k >= 8.0:
        scale, k = scale * 256.0, k - 8.0
    if k >= 4.0:
        scale, k = scale * 16.0, k - 4.0
    if k >= 2.0:
        scale, k = scale * 4.0, k - 2.0
    if k >= 1.0:
        scale *= 2.0
    large = 1.0 - 2.0 / (scale * e + 1.0)
    return np.copysign(small if a < 0.625 else large, x)


@njit(cache=True, inline="always", error_model="numpy")
def fast_tanh(x: float) -> float:  # pragma: no cover
    """``tanh(x)`` to float32 accuracy (absolute error below 3e-7) without a library call, so the loops around it
    vectorize: Eigen's rational approximation (``ptanh_float``), clamped to +-7.905. The lean update's arithmetic
    (:mod:`sb3_smc.common.recurrent.lean_update`) and its collection (:data:`FAST_TANH`)."""
    x = 7.90531110763549805 if x > 7.90531110763549805 else (-7.90531110763549805 if x < -7.90531110763549805 else x)
    x2 = x * x
    p = x2 * -2.76076847742355e-16 + 2.00018790482477e-13
    p = p * x2 + -8.60467152213735e-11
    p = p * x2 + 5.12229709037114e-08
    p = p * x2 + 1.48572235717979e-05
    p = p * x2 + 6.37261928875436e-04
    p = p * x2 + 4.89352455891786e-03
    q = x2 * 1.19825839466702e-06 + 1.18534705686654e-04
    q = q * x2 + 2.26843463243900e-03
    q = q * x2 + 4.89352518554385e-03
    return x * p / q


@njit(cache=True, inline="always", error_model="numpy")
def _tanh(x: float, mode: int) -> float:  # pragma: no cover
    """``tanh(x)`` as ``mode`` says (:data:`LIBM_TANH`, :data:`ACCURATE_TANH`, :data:`FAST_TANH`)."""
    if mode == LIBM_TANH:
        return np.tanh(x)
    return accurate_tanh(x) if mode == ACCURATE_TANH else fast_tanh(x)


@njit(cache=True, inline="always")
def lstm_cell(x: np.ndarray, h: np.ndarray, c: np.ndarray, w_ih: np.ndarray, w_hh: np.ndarray, bias: np.ndarray,
              gate_scale: float, h_next: np.ndarray, c_next: np.ndarray, tanh: int) -> None:  # pragma: no cover
    """The LSTM cell, the one place its arithmetic is written: one step of one layer for one row, in float64.

    ``x`` the layer's input, ``h`` / ``c`` the previous state; the weights transposed (``(inputs, 4 n)``), gates i,
    f, g, o in torch's order, ``bias`` the sum of torch's two biases. ``sigmoid(z) = 0.5 * tanh(z / 2) + 0.5`` with
    ``z / 2 = gate_scale * (preactivation)``: 0.5 for torch's weights, 1.0 for weights whose i, f, o columns are
    halved already (:class:`~sb3_smc.smc.numpy_actors.NumpyLSTMPolicy`'s). Writes ``h'`` / ``c'`` into ``h_next`` /
    ``c_next``. The zero entries of ``x`` and ``h`` are skipped (mostly one-hot observations). ``tanh``: which
    ``tanh`` (:data:`LIBM_TANH` ...)."""
    n = h.shape[0]
    t = bias.astype(np.float64)
    _add_rows(t, x, w_ih)
    _add_rows(t, h, w_hh)
    for j in range(4 * n):  # the gates' tanh: of gate_scale * t on i, f, o (sigmoids), of t on g
        z = t[j] if 2 * n <= j < 3 * n else gate_scale * t[j]
        t[j] = _tanh(z, tanh)
    for j in range(n):
        cell = (0.5 * t[n + j] + 0.5) * c[j] + (0.5 * t[j] + 0.5) * t[2 * n + j]
        c_next[j] = cell
        h_next[j] = (0.5 * t[3 * n + j] + 0.5) * _tanh(cell, tanh)


@njit(cache=True, error_model="numpy")  # no division checks: the cell's tanh vectorizes
def lstm_linear_step(x: np.ndarray, h: np.ndarray, c: np.ndarray, w_ih: np.ndarray, w_hh: np.ndarray,
                     bias: np.ndarray, w_out: np.ndarray, b_out: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover
    """One LSTM step and the action probabilities: ``(probabilities, h', c')``, ``h'`` / ``c'`` of shape ``(1, n)``.

    ``w_ih`` / ``w_hh`` / ``bias`` are :class:`~sb3_smc.smc.numpy_actors.NumpyLSTMPolicy`'s (transposed, gates i, f, g,
    o with the i, f, o rows halved so that ``sigmoid(z) = 0.5 * tanh(z / 2) + 0.5`` uses one tanh); ``h`` / ``c``
    are the previous state's rows."""
    if h.shape[0] != w_hh.shape[0] or c.shape[0] != w_hh.shape[0] or x.shape[0] != w_ih.shape[0]:
        raise ValueError("LSTM state or observation of the wrong size for this policy")
    probabilities = np.empty(b_out.shape[0])
    h_next = np.empty((1, h.shape[0]))
    c_next = np.empty((1, h.shape[0]))
    lstm_cell(x, h, c, w_ih, w_hh, bias, 1.0, h_next[0], c_next[0], ACCURATE_TANH)
    linear_softmax(h_next[0], w_out, b_out, probabilities)
    return probabilities, h_next, c_next


@njit(cache=True, inline="always")
def gru_cell(x: np.ndarray, h: np.ndarray, w_ih: np.ndarray, w_hh: np.ndarray, b_ih: np.ndarray, b_hh: np.ndarray,
             h_next: np.ndarray, tanh: int) -> None:  # pragma: no cover
    """The GRU cell, the one place its arithmetic is written: one step of one layer for one row, in float64, with
    torch's equations (gates r, z, n; ``n = tanh(W_in x + b_in + r * (W_hn h + b_hn))``, ``h' = (1 - z) * n + z * h``
    written ``n + z * (h - n)``). The weights transposed (``(inputs, 3 n)``); writes ``h'`` into ``h_next``; the
    zero entries of ``x`` and ``h`` are skipped; ``tanh`` as in :func:`lstm_cell`."""
    n = h.shape[0]
    gi = b_ih.astype(np.float64)
    _add_rows(gi, x, w_ih)
    gh = b_hh.astype(np.float64)
    _add_rows(gh, h, w_hh)
    for j in range(n):
        r = 0.5 * _tanh(0.5 * (gi[j] + gh[j]), tanh) + 0.5
        z = 0.5 * _tanh(0.5 * (gi[n + j] + gh[n + j]), tanh) + 0.5
        candidate = _tanh(gi[2 * n + j] + r * gh[2 * n + j], tanh)
        h_next[j] = candidate + z * (h[j] - candidate)


@njit(cache=True, error_model="numpy")  # no division checks: the cell's tanh vectorizes
def gru_linear_step(x: np.ndarray, h: np.ndarray, w_ih: np.ndarray, w_hh: np.ndarray, b_ih: np.ndarray,
                    b_hh: np.ndarray, w_out: np.ndarray, b_out: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover
    """One GRU step (torch's equations, gates r, z, n) and the action probabilities: ``(probabilities, h')``,
    ``h'`` of shape ``(1, n)``; the weights are :class:`~sb3_smc.smc.numpy_actors.NumpyGRUPolicy`'s (transposed)."""
    if h.shape[0] != w_hh.shape[0] or x.shape[0] != w_ih.shape[0]:
        raise ValueError("GRU state or observation of the wrong size for this policy")
    probabilities = np.empty(b_out.shape[0])
    h_next = np.empty((1, h.shape[0]))
    gru_cell(x, h, w_ih, w_hh, b_ih, b_hh, h_next[0], ACCURATE_TANH)
    linear_softmax(h_next[0], w_out, b_out, probabilities)
    return probabilities, h_next


@njit(cache=True)
def sample_index(probabilities: np.ndarray, u: float) -> int:  # pragma: no cover
    """The inverse-CDF draw of :func:`sb3_smc.smc.policies.sample_action` for a uniform ``u`` in [0, 1): the first index
    whose running sum exceeds ``u`` times the total (numpy's ``cumsum`` adds in the same order, so the index is the
    same as ``searchsorted(..., side="right")``); the last positive entry if rounding passes the end; -1 if the total
    is not positive and finite."""
    total = 0.0
    for value in probabilities:
        total += value
    if not (total > 0.0 and total < np.inf):
        return -1
    target = u * total
    running = 0.0
    for i in range(probabilities.shape[0]):
        running += probabilities[i]
        if running > target:
            return i
    for i in range(probabilities.shape[0] - 1, -1, -1):
        if probabilities[i] > 0.0:
            return i
    return -1


@njit(cache=True)
def _heads(x: np.ndarray, latent: np.ndarray, uniform: float, deterministic: bool, w_critic: np.ndarray,
           b_critic: np.ndarray, w_value: np.ndarray, b_value: float, w_action: np.ndarray, b_action: np.ndarray
           ) -> tuple[int, float, float]:  # pragma: no cover
    """The heads of one collection row: ``(action, value, log-probability)``. The critic is linear on the
    features ``x`` (``enable_critic_lstm=False``), the value linear on it; the action is drawn by inverse CDF at
    ``uniform`` (or the most probable one)."""
    n_critic = b_critic.shape[0]
    critic = b_critic.astype(np.float64)
    for i in range(x.shape[0]):
        xi = x[i]
        if xi != 0.0:
            for j in range(n_critic):
                critic[j] += xi * w_critic[i, j]
    value = b_value
    for j in range(n_critic):
        value += critic[j] * w_value[j]
    n_actions = b_action.shape[0]
    logits = b_action.astype(np.float64)
    for i in range(latent.shape[0]):
        for j in range(n_actions):
            logits[j] += latent[i] * w_action[i, j]
    top = logits.max()
    total = 0.0
    for j in range(n_actions):
        total += np.exp(logits[j] - top)
    action = n_actions - 1
    if deterministic:
        action = int(np.argmax(logits))
    else:
        target = uniform * total
        running = 0.0
        for j in range(n_actions):
            running += np.exp(logits[j] - top)
            if running > target:
                action = j
                break
    return action, value, logits[action] - top - np.log(total)


@njit(cache=True, inline="always")
def _collection_outputs(n: int, hidden: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                                       np.ndarray]:  # pragma: no cover
    """A collection step's outputs for ``n`` rows (actions, values ``(n, 1)``, log-probabilities, h', c'; zeros,
    which rows no policy acts in keep) and the rows' ``(4, hidden)`` scratch."""
    return (np.zeros(n, dtype=np.int64), np.zeros((n, 1), dtype=np.float32), np.zeros(n, dtype=np.float32),
            np.zeros((n, hidden), dtype=np.float32), np.zeros((n, hidden), dtype=np.float32), np.empty((4, hidden)))


@njit(cache=True, inline="always")
def _lstm_collection_row(x: np.ndarray, h: np.ndarray, c: np.ndarray, start: float, uniform: float,
                         deterministic: bool, exact: bool, w_ih: np.ndarray, w_hh: np.ndarray, bias: np.ndarray,
                         w_critic: np.ndarray, b_critic: np.ndarray, w_value: np.ndarray, b_value: float,
                         w_action: np.ndarray, b_action: np.ndarray, h_out: np.ndarray, c_out: np.ndarray,
                         scratch: np.ndarray) -> tuple[int, float, float]:  # pragma: no cover
    """One row of :func:`lstm_collection_step`: the state reset at an episode start, the cell (new state into
    ``h_out`` / ``c_out``) and the heads; ``scratch`` ``(4, hidden)`` float64."""
    previous_h, previous_c, latent, cell = scratch[0], scratch[1], scratch[2], scratch[3]
    keep = 1.0 - start
    for i in range(h.shape[0]):
        previous_h[i] = keep * h[i]
        previous_c[i] = keep * c[i]
    if exact:  # two calls with constant modes: each inlined cell keeps one tanh (its loops vectorize with fast_tanh)
        lstm_cell(x, previous_h, previous_c, w_ih, w_hh, bias, 0.5, latent, cell, LIBM_TANH)
    else:
        lstm_cell(x, previous_h, previous_c, w_ih, w_hh, bias, 0.5, latent, cell, FAST_TANH)
    for j in range(h.shape[0]):
        c_out[j] = cell[j]
        h_out[j] = latent[j]
    return _heads(x, latent, uniform, deterministic, w_critic, b_critic, w_value, b_value, w_action, b_action)


@njit(cache=True)
def lstm_collection_step(x: np.ndarray, h: np.ndarray, c: np.ndarray, starts: np.ndarray, uniforms: np.ndarray,
                         deterministic: bool, exact: bool, w_ih: np.ndarray, w_hh: np.ndarray, bias: np.ndarray,
                         w_critic: np.ndarray, b_critic: np.ndarray, w_value: np.ndarray, b_value: float,
                         w_action: np.ndarray, b_action: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover
    """One collection step of a one-layer LSTM actor with linear heads for ``n`` environments.

    ``x`` ``(n, features)``, ``h`` / ``c`` ``(n, hidden)`` the previous states (zeroed where ``starts`` is 1, as
    sb3-contrib does at an episode start), ``uniforms`` ``(n,)`` the draws, ``exact`` ``np.tanh`` in the cell (else
    :func:`fast_tanh`, the lean update's). The weights are transposed (``(inputs, outputs)``), ``bias`` the sum of
    torch's two LSTM biases, gates i, f, g, o. Returns ``(actions, values (n, 1), log-probabilities, h', c')`` in
    float32 (int64 actions), computed in float64."""
    n, hidden = h.shape
    if x.shape[0] != n or c.shape != h.shape or w_ih.shape[0] != x.shape[1] or w_hh.shape[0] != hidden:
        raise ValueError("observations or LSTM states of the wrong shape for this policy")
    actions, values, log_probs, h_next, c_next, scratch = _collection_outputs(n, hidden)
    for k in range(n):
        actions[k], value, log_probs[k] = _lstm_collection_row(
            x[k], h[k], c[k], starts[k], uniforms[k], deterministic, exact, w_ih, w_hh, bias, w_critic, b_critic,
            w_value, b_value, w_action, b_action, h_next[k], c_next[k], scratch)
        values[k, 0] = value
    return actions, values, log_probs, h_next, c_next


@njit(cache=True, inline="always")
def _group_shapes(x: np.ndarray, h: np.ndarray, starts: np.ndarray, uniforms: np.ndarray, bounds: np.ndarray,
                  members: np.ndarray, w_ih: np.ndarray, w_hh: np.ndarray) -> bool:  # pragma: no cover
    """Whether a group step's arrays fit: one row each of ``x``, ``h``, ``starts`` and ``uniforms``, the stacked
    weights' inputs and hidden size, ``bounds`` from 0 to the rows, not decreasing, one more than the policies, and
    ``members`` among the policies."""
    n, hidden = h.shape
    return not (x.shape[0] != n or starts.shape[0] != n or uniforms.shape[0] != n or w_ih.shape[1] != x.shape[1]
                or w_hh.shape[1] != hidden or bounds.shape[0] != w_ih.shape[0] + 1 or bounds[0] != 0
                or bounds[-1] != n or np.any(bounds[1:] < bounds[:-1])
                or (members.size > 0 and (members.min() < 0 or members.max() >= w_ih.shape[0])))


@njit(cache=True)
def lstm_collection_steps(x: np.ndarray, h: np.ndarray, c: np.ndarray, starts: np.ndarray, uniforms: np.ndarray,
                          bounds: np.ndarray, members: np.ndarray, exact: bool, w_ih: np.ndarray, w_hh: np.ndarray,
                          bias: np.ndarray, w_critic: np.ndarray, b_critic: np.ndarray, w_value: np.ndarray,
                          b_value: np.ndarray, w_action: np.ndarray, b_action: np.ndarray
                          ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover
    """:func:`lstm_collection_step` (sampling) for several policies of the same shapes in one call: policy ``m``
    acts in rows ``bounds[m]:bounds[m + 1]`` with weights ``w_ih[m]``, ``w_hh[m]`` ... (each stacked on a first
    axis), for the policies ``members`` only (the other rows: action 0, zeros). Each row is what
    :func:`lstm_collection_step` computes for it, bit for bit."""
    n, hidden = h.shape
    if c.shape != h.shape or not _group_shapes(x, h, starts, uniforms, bounds, members, w_ih, w_hh):
        raise ValueError("observations, LSTM states, bounds or members of the wrong shape for these policies")
    actions, values, log_probs, h_next, c_next, scratch = _collection_outputs(n, hidden)
    for m in members:
        for k in range(bounds[m], bounds[m + 1]):
            actions[k], value, log_probs[k] = _lstm_collection_row(
                x[k], h[k], c[k], starts[k], uniforms[k], False, exact, w_ih[m], w_hh[m], bias[m], w_critic[m],
                b_critic[m], w_value[m], b_value[m], w_action[m], b_action[m], h_next[k], c_next[k], scratch)
            values[k, 0] = value
    return actions, values, log_probs, h_next, c_next


@njit(cache=True, inline="always")
def _gru_collection_row(x: np.ndarray, h: np.ndarray, start: float, uniform: float, deterministic: bool,
                        exact: bool, w_ih: np.ndarray, w_hh: np.ndarray, b_ih: np.ndarray, b_hh: np.ndarray,
                        w_critic: np.ndarray, b_critic: np.ndarray, w_value: np.ndarray, b_value: float,
                        w_action: np.ndarray, b_action: np.ndarray, h_out: np.ndarray,
                        scratch: np.ndarray) -> tuple[int, float, float]:  # pragma: no cover
    """One row of :func:`gru_collection_step`: the state reset at an episode start, the cell (new state into
    ``h_out``) and the heads; ``scratch`` ``(2, hidden)`` float64."""
    previous, latent = scratch[0], scratch[1]
    keep = 1.0 - start
    for i in range(h.shape[0]):
        previous[i] = keep * h[i]
    if exact:  # constant modes, as in _lstm_collection_row
        gru_cell(x, previous, w_ih, w_hh, b_ih, b_hh, latent, LIBM_TANH)
    else:
        gru_cell(x, previous, w_ih, w_hh, b_ih, b_hh, latent, FAST_TANH)
    for j in range(h.shape[0]):
        h_out[j] = latent[j]
    return _heads(x, latent, uniform, deterministic, w_critic, b_critic, w_value, b_value, w_action, b_action)


@njit(cache=True)
def gru_collection_step(x: np.ndarray, h: np.ndarray, starts: np.ndarray, uniforms: np.ndarray,
                        deterministic: bool, exact: bool, w_ih: np.ndarray, w_hh: np.ndarray, b_ih: np.ndarray,
                        b_hh: np.ndarray,
                        w_critic: np.ndarray, b_critic: np.ndarray, w_value: np.ndarray, b_value: float,
                        w_action: np.ndarray, b_action: np.ndarray
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover
    """:func:`lstm_collection_step` for a one-layer GRU (torch's gates r, z, n): ``(actions, values, log-probabilities,
    h')``; ``exact`` as there."""
    n, hidden = h.shape
    if x.shape[0] != n or w_ih.shape[0] != x.shape[1] or w_hh.shape[0] != hidden:
        raise ValueError("observations or GRU states of the wrong shape for this policy")
    actions, values, log_probs, h_next, _, scratch = _collection_outputs(n, hidden)
    for k in range(n):
        actions[k], value, log_probs[k] = _gru_collection_row(
            x[k], h[k], starts[k], uniforms[k], deterministic, exact, w_ih, w_hh, b_ih, b_hh, w_critic, b_critic,
            w_value, b_value, w_action, b_action, h_next[k], scratch)
        values[k, 0] = value
    return actions, values, log_probs, h_next


@njit(cache=True)
def gru_collection_steps(x: np.ndarray, h: np.ndarray, starts: np.ndarray, uniforms: np.ndarray, bounds: np.ndarray,
                         members: np.ndarray, exact: bool, w_ih: np.ndarray, w_hh: np.ndarray, b_ih: np.ndarray,
                         b_hh: np.ndarray, w_critic: np.ndarray, b_critic: np.ndarray, w_value: np.ndarray,
                         b_value: np.ndarray, w_action: np.ndarray, b_action: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover
    """:func:`gru_collection_step` (sampling) for several policies of the same shapes in one call, as
    :func:`lstm_collection_steps` is :func:`lstm_collection_step`'s: each row bit for bit what the one-policy step
    computes for it."""
    n, hidden = h.shape
    if not _group_shapes(x, h, starts, uniforms, bounds, members, w_ih, w_hh):
        raise ValueError("observations, GRU states, bounds or members of the wrong shape for these policies")
    actions, values, log_probs, h_next, _, scratch = _collection_outputs(n, hidden)
    for m in members:
        for k in range(bounds[m], bounds[m + 1]):
            actions[k], value, log_probs[k] = _gru_collection_row(
                x[k], h[k], starts[k], uniforms[k], False, exact, w_ih[m], w_hh[m], b_ih[m], b_hh[m], w_critic[m],
                b_critic[m], w_value[m], b_value[m], w_action[m], b_action[m], h_next[k], scratch)
            values[k, 0] = value
    return actions, values, log_probs, h_next
