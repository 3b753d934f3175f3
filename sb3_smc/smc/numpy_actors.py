"""The numpy actors: trained SB3 actors as numpy arrays, evaluated one observation (or one batch) at a time.

:class:`NumpyMLPPolicy` (a feed-forward actor), :class:`NumpyLSTMPolicy` and :class:`NumpyGRUPolicy` (recurrent
actors), their feed-forward layers and activations. The default recurrent architecture (float64, one recurrent
layer, a linear head) steps through the compiled kernels of :mod:`sb3_smc.common.kernels`; every other one through
the numpy code here. They hold numpy arrays only (no torch modules), so they pickle small and load without torch.
:func:`sb3_smc.smc.policies.policy_from_model` builds them from a trained model; ``sb3_smc.smc.policies`` re-exports
them.
"""

from __future__ import annotations

from collections.abc import Sequence
from types import ModuleType
from typing import Any

import numpy as np

from sb3_smc.errors import SMCError

__all__ = ["ACTIVATIONS", "COMPILED_BATCH_FROM", "LSTMState", "Layer", "NumpyGRUPolicy", "NumpyLSTMPolicy",
           "NumpyMLPPolicy"]

LSTMState = tuple[np.ndarray, np.ndarray]
"""Recurrent state of :class:`NumpyLSTMPolicy`: ``(h, c)``, each of shape ``(n_lstm_layers, lstm_hidden_size)``."""

Layer = tuple[str, Any, Any]
"""One step of a feed-forward stack: ``("linear", weight_T, bias)`` or ``(activation_name, parameter, None)``."""


# ---------------------------------------------------------------------------------------------------------------
# Activations
# ---------------------------------------------------------------------------------------------------------------

def _sigmoid(x: np.ndarray) -> np.ndarray:
    return 0.5 * np.tanh(0.5 * x) + 0.5


def _activate(name: str, param: float, x: np.ndarray) -> np.ndarray:
    if name == "tanh":
        return np.tanh(x)
    if name == "relu":
        return np.maximum(x, 0.0)
    if name == "leaky_relu":
        return np.where(x >= 0.0, x, param * x)
    if name == "elu":
        return np.where(x > 0.0, x, param * np.expm1(np.minimum(x, 0.0)))
    if name == "selu":
        alpha, scale = 1.6732632423543772, 1.0507009873554805
        return scale * np.where(x > 0.0, x, alpha * np.expm1(np.minimum(x, 0.0)))
    if name == "sigmoid":
        return _sigmoid(x)
    if name == "silu":
        return x * _sigmoid(x)
    if name == "softplus":  # torch's beta=1, threshold=20
        return np.where(x > 20.0, x, np.logaddexp(0.0, x))
    if name == "identity":
        return x
    raise SMCError(f"unknown activation {name!r}")


ACTIVATIONS: dict[str, str] = {"Tanh": "tanh", "ReLU": "relu", "LeakyReLU": "leaky_relu", "ELU": "elu",
                               "SELU": "selu", "Sigmoid": "sigmoid", "SiLU": "silu", "Softplus": "softplus",
                               "Identity": "identity"}
"""Supported ``torch.nn`` activation classes (by class name) -> numpy activation names; any other module in the
policy network is a ``TypeError``. ``LeakyReLU`` and ``ELU`` keep their parameter, ``Softplus`` needs the
defaults (beta 1, threshold 20)."""


def _forward(layers: Sequence[Layer], x: np.ndarray) -> np.ndarray:
    for name, a, b in layers:
        if name == "linear":
            x = x @ a
            x += b
        elif name == "tanh":
            x = np.tanh(x)
        else:
            x = _activate(name, a, x)
    return x


def _softmax(logits: np.ndarray) -> np.ndarray:
    """Softmax over the last axis; ``logits`` is overwritten (callers pass a fresh array)."""
    if logits.ndim == 1:
        logits -= logits.max()
        np.exp(logits, out=logits)
        logits /= logits.sum()
        return logits
    logits -= logits.max(axis=-1, keepdims=True)
    np.exp(logits, out=logits)
    logits /= logits.sum(axis=-1, keepdims=True)
    return logits


# ---------------------------------------------------------------------------------------------------------------
# Numpy actors
# ---------------------------------------------------------------------------------------------------------------

class NumpyMLPPolicy:
    """Feed-forward actor (features -> policy MLP -> ``action_net`` -> softmax) in numpy; state ``None``.

    ``layers`` is a list of ``("linear", weight_T, bias)`` (``x @ weight_T + bias``) and
    ``(activation_name, parameter, None)`` steps, ending with the action layer.
    """

    def __init__(self, layers: Sequence[Layer], observation_size: int, dtype: Any = np.float64) -> None:
        self.dtype = np.dtype(dtype)
        self.layers = [_cast_layer(layer, self.dtype) for layer in layers]
        self.observation_size = int(observation_size)
        self.n_actions = _n_outputs(self.layers)

    def initial_state(self) -> None:
        return None

    def probabilities(self, observation: np.ndarray, state: None = None) -> tuple[np.ndarray, None]:
        x = np.asarray(observation, dtype=self.dtype).reshape(-1)
        return _softmax(_forward(self.layers, x)), None

    def probabilities_batch(self, observations: np.ndarray, states: Sequence[None] | None = None
                            ) -> tuple[np.ndarray, list[None]]:
        """Probabilities ``(B, n_actions)`` of ``B`` observations ``(B, observation_size)``."""
        x = np.asarray(observations, dtype=self.dtype).reshape(len(observations), -1)
        return _softmax(_forward(self.layers, x)), [None] * len(x)

    def __repr__(self) -> str:
        return f"{type(self).__name__}(observation_size={self.observation_size}, n_actions={self.n_actions})"


class _RecurrentActor:
    """What the recurrent numpy actors share: the compiled step's weights (``_compiled``, None for the numpy code)
    and, from them, :attr:`batch_from`."""

    _compiled: tuple[np.ndarray, ...] | None

    def _stack(self, layers: Sequence[tuple[np.ndarray, ...]], cell: str, observation_size: int, dtype: Any) -> None:
        """The sizes of a stack of ``cell`` layers (each ``(w_ih_T, w_hh_T, ...)``): ``dtype``, ``hidden_size``,
        ``n_layers``, ``observation_size``; ``SMCError`` for an empty stack."""
        self.dtype = np.dtype(dtype)
        if not layers:
            raise SMCError(f"{type(self).__name__} needs at least one {cell} layer")
        self.hidden_size = int(np.shape(layers[0][1])[0])
        self.n_layers = len(layers)
        self.observation_size = int(observation_size)

    def _head(self, head: Sequence[Layer], first_layer: tuple[np.ndarray, ...]) -> None:
        """The feed-forward part after the recurrent layers, and the compiled step's weights where it applies."""
        self.head = [_cast_layer(layer, self.dtype) for layer in head]
        self.n_actions = _n_outputs(self.head)
        self._compiled = (*first_layer, *self.head[0][1:]) if _compilable(self) else None

    @property
    def batch_from(self) -> int | None:
        """The fewest pending decisions worth one ``probabilities_batch`` call instead of single calls (None: never,
        for a compiled policy; see :data:`COMPILED_BATCH_FROM`)."""
        return COMPILED_BATCH_FROM if self._compiled is not None else 2

    @property
    def compiled_weights(self) -> tuple[np.ndarray, ...] | None:
        """The compiled step's weights as :func:`sb3_smc.envs.leaf_calls.leaf_call` takes them: ``(w_ih, w_hh,
        first bias, second bias, w_out, b_out)`` (an LSTM's one bias first, an empty second), None for the numpy
        code."""
        if self._compiled is None:
            return None
        if isinstance(self, NumpyGRUPolicy):
            return self._compiled
        w_ih, w_hh, bias, w_out, b_out = self._compiled
        return w_ih, w_hh, bias, np.empty(0), w_out, b_out


class NumpyLSTMPolicy(_RecurrentActor):
    """Recurrent actor of an sb3-contrib ``RecurrentActorCriticPolicy`` in numpy.

    features -> ``n_lstm_layers`` stacked LSTM layers -> policy MLP -> ``action_net`` -> softmax. The state is
    ``(h, c)``, each ``(n_lstm_layers, lstm_hidden_size)``; :meth:`initial_state` is zeros, which is what
    sb3-contrib uses at an episode start (``episode_starts`` = 1), so a fresh call of the policy behaves like a
    new episode and later steps like ``episode_starts`` = 0. States are never modified in place.

    ``lstm`` is one ``(w_ih_T, w_hh_T, bias)`` per layer in torch's gate order (i, f, g, o), with
    ``bias = b_ih + b_hh``; ``head`` is the feed-forward part as in :class:`NumpyMLPPolicy`.
    """

    def __init__(self, lstm: Sequence[tuple[np.ndarray, np.ndarray, np.ndarray]], head: Sequence[Layer],
                 observation_size: int, dtype: Any = np.float64) -> None:
        self._stack(lstm, "LSTM", observation_size, dtype)
        # sigmoid(z) = 0.5 * tanh(z / 2) + 0.5: halve the i, f, o rows once so that one tanh serves all gates
        scale = np.full(4 * self.hidden_size, 0.5)
        scale[2 * self.hidden_size:3 * self.hidden_size] = 1.0
        self.lstm = [(np.ascontiguousarray(np.asarray(w_ih, dtype=np.float64) * scale, dtype=self.dtype),
                      np.ascontiguousarray(np.asarray(w_hh, dtype=np.float64) * scale, dtype=self.dtype),
                      np.ascontiguousarray(np.asarray(bias, dtype=np.float64) * scale, dtype=self.dtype))
                     for w_ih, w_hh, bias in lstm]
        for k, (w_ih, w_hh, bias) in enumerate(self.lstm):
            expected_in = self.observation_size if k == 0 else self.hidden_size
            gates = 4 * self.hidden_size
            if w_ih.shape != (expected_in, gates) or w_hh.shape != (self.hidden_size, gates) or bias.shape != (gates,):
                raise SMCError(f"LSTM layer {k}: inconsistent weight shapes {w_ih.shape}, {w_hh.shape}, "
                               f"{bias.shape}")
        self._head(head, self.lstm[0])

    def initial_state(self) -> LSTMState:
        zeros = np.zeros((self.n_layers, self.hidden_size), dtype=self.dtype)
        return zeros, zeros.copy()

    def probabilities(self, observation: np.ndarray, state: LSTMState) -> tuple[np.ndarray, LSTMState]:
        if self._compiled is not None:
            h_prev, c_prev = state
            probabilities, h, c = _kernels().lstm_linear_step(_flat(observation, self.observation_size), h_prev[0],
                                                              c_prev[0], *self._compiled)
            return probabilities, (h, c)
        x, h_next, c_next = self._layers(np.asarray(observation, dtype=self.dtype).reshape(-1), *state)
        return _softmax(_forward(self.head, x)), (h_next, c_next)

    def probabilities_batch(self, observations: np.ndarray, states: Sequence[LSTMState]
                            ) -> tuple[np.ndarray, list[LSTMState]]:
        """Probabilities ``(B, n_actions)`` and next states of ``B`` observations, one state per row (the same
        arithmetic as :meth:`probabilities`, batched)."""
        x = np.asarray(observations, dtype=self.dtype).reshape(len(observations), -1)
        if len(states) != len(x):
            raise SMCError(f"{len(x)} observations but {len(states)} states")
        if self._compiled is not None:
            return _one_by_one(self, x, states)
        h_prev = np.array([s[0] for s in states]).transpose(1, 0, 2)  # (layers, B, n)
        c_prev = np.array([s[1] for s in states]).transpose(1, 0, 2)
        x, h_next, c_next = self._layers(x, h_prev, c_prev)
        return _softmax(_forward(self.head, x)), list(zip(h_next.transpose(1, 0, 2), c_next.transpose(1, 0, 2),
                                                          strict=True))

    def _layers(self, x: np.ndarray, h_prev: np.ndarray, c_prev: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The stacked LSTM on ``x`` (``(..., input)``) from ``h_prev`` / ``c_prev`` (``(layers, ..., n)``):
        ``(last layer's h', h', c')``.

        :func:`sb3_smc.common.kernels.lstm_cell`'s arithmetic vectorised over rows (the i, f, o columns of the
        weights are halved, so one tanh serves all gates). Kept beside the compiled cell for the architectures it
        does not serve: numpy's vectorised ``tanh`` makes a batch of 16 rows about twice as fast as the compiled
        cell row by row, and a single row no slower (``docs/benchmarks.md``, "One recurrent cell")."""
        n = self.hidden_size
        h_next = np.empty_like(h_prev)
        c_next = np.empty_like(c_prev)
        for k, (w_ih, w_hh, bias) in enumerate(self.lstm):
            t = x @ w_ih
            t += h_prev[k] @ w_hh
            t += bias
            np.tanh(t, out=t)
            s = t * 0.5
            s += 0.5
            c = s[..., n:2 * n] * c_prev[k]
            c += s[..., :n] * t[..., 2 * n:3 * n]
            x = s[..., 3 * n:] * np.tanh(c)
            h_next[k] = x
            c_next[k] = c
        return x, h_next, c_next

    def __repr__(self) -> str:
        return (f"{type(self).__name__}(observation_size={self.observation_size}, hidden_size={self.hidden_size}, "
                f"n_layers={self.n_layers}, n_actions={self.n_actions})")


class NumpyGRUPolicy(_RecurrentActor):
    """Recurrent actor of a :class:`~sb3_smc.common.recurrent.SequenceGruPolicy` in numpy (the paper's GRU).

    features -> stacked GRU layers -> policy MLP -> ``action_net`` -> softmax, with torch's GRU equations (gate
    order r, z, n; ``n = tanh(W_in x + b_in + r * (W_hn h + b_hn))``, ``h' = (1 - z) * n + z * h``). The state is
    ``h``, shape ``(n_layers, hidden_size)``; :meth:`initial_state` is zeros, as at an episode start. States are
    never modified in place. ``gru`` is one ``(w_ih_T, w_hh_T, b_ih, b_hh)`` per layer.
    """

    def __init__(self, gru: Sequence[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]], head: Sequence[Layer],
                 observation_size: int, dtype: Any = np.float64) -> None:
        self._stack(gru, "GRU", observation_size, dtype)
        self.gru = [tuple(np.ascontiguousarray(a, dtype=self.dtype) for a in layer) for layer in gru]
        for k, (w_ih, w_hh, b_ih, b_hh) in enumerate(self.gru):
            expected_in = self.observation_size if k == 0 else self.hidden_size
            gates = 3 * self.hidden_size
            if (w_ih.shape != (expected_in, gates) or w_hh.shape != (self.hidden_size, gates)
                    or b_ih.shape != (gates,) or b_hh.shape != (gates,)):
                raise SMCError(f"GRU layer {k}: inconsistent weight shapes {w_ih.shape}, {w_hh.shape}, "
                               f"{b_ih.shape}, {b_hh.shape}")
        self._head(head, self.gru[0])

    def initial_state(self) -> np.ndarray:
        return np.zeros((self.n_layers, self.hidden_size), dtype=self.dtype)

    def _layers(self, x: np.ndarray, h_prev: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The stacked GRU on ``x`` (``(..., input)``) from ``h_prev`` (``(layers, ..., n)``): ``(last layer's h',
        h')``; :func:`sb3_smc.common.kernels.gru_cell`'s arithmetic vectorised over rows, kept for the reason
        :meth:`NumpyLSTMPolicy._layers` gives."""
        n = self.hidden_size
        h_next = np.empty_like(h_prev)
        for k, (w_ih, w_hh, b_ih, b_hh) in enumerate(self.gru):
            gi = x @ w_ih
            gi += b_ih
            gh = h_prev[k] @ w_hh
            gh += b_hh
            rz = _sigmoid(gi[..., :2 * n] + gh[..., :2 * n])
            candidate = np.tanh(gi[..., 2 * n:] + rz[..., :n] * gh[..., 2 * n:])
            x = candidate + rz[..., n:] * (h_prev[k] - candidate)
            h_next[k] = x
        return x, h_next

    def probabilities(self, observation: np.ndarray, state: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if self._compiled is not None:
            return _kernels().gru_linear_step(_flat(observation, self.observation_size), state[0], *self._compiled)
        x, h_next = self._layers(np.asarray(observation, dtype=self.dtype).reshape(-1), state)
        return _softmax(_forward(self.head, x)), h_next

    def probabilities_batch(self, observations: np.ndarray, states: Sequence[np.ndarray]
                            ) -> tuple[np.ndarray, list[np.ndarray]]:
        """Probabilities ``(B, n_actions)`` and next states of ``B`` observations, one state per row."""
        x = np.asarray(observations, dtype=self.dtype).reshape(len(observations), -1)
        if len(states) != len(x):
            raise SMCError(f"{len(x)} observations but {len(states)} states")
        if self._compiled is not None:
            return _one_by_one(self, x, states)
        h_prev = np.array(states).transpose(1, 0, 2)  # (layers, B, n)
        x, h_next = self._layers(x, h_prev)
        return _softmax(_forward(self.head, x)), list(h_next.transpose(1, 0, 2))

    def __repr__(self) -> str:
        return (f"{type(self).__name__}(observation_size={self.observation_size}, hidden_size={self.hidden_size}, "
                f"n_layers={self.n_layers}, n_actions={self.n_actions})")


def _compilable(policy: _RecurrentActor) -> bool:
    """Whether the compiled step of :mod:`sb3_smc.common.kernels` serves ``policy``: float64, one recurrent layer,
    one linear layer as the head (``net_arch=[]``)."""
    if not (policy.dtype == np.float64 and policy.n_layers == 1 and len(policy.head) == 1
            and policy.head[0][0] == "linear"):
        return False
    _, w_out, b_out = policy.head[0]
    return np.shape(w_out) == (policy.hidden_size, policy.n_actions) and np.shape(b_out) == (policy.n_actions,)


COMPILED_BATCH_FROM: int | None = None
"""``batch_from`` of a compiled policy: never. A compiled single step costs less than stacking the observations
and states of a group for one batch call, even for the groups of 4-6 decisions of a 16-environment level-2 job
(measured in ``SMCVecEnv``: 24.5 against 27-28.6 µs per child decision; ``docs/benchmarks.md``)."""


def _one_by_one(policy: Any, x: np.ndarray, states: Sequence[Any]) -> tuple[np.ndarray, list[Any]]:
    """``probabilities_batch`` of a compiled policy: its single steps, row by row."""
    answers = [policy.probabilities(row, state) for row, state in zip(x, states, strict=True)]
    return np.array([a[0] for a in answers]), [a[1] for a in answers]


_KERNELS: ModuleType | None = None


def _flat(observation: np.ndarray, size: int) -> np.ndarray:
    """``observation`` as a 1-D array of ``size`` entries (the compiled steps read exactly that many)."""
    x = np.asarray(observation).reshape(-1)
    if x.dtype != np.float32 and x.dtype != np.float64:  # one compiled variant per input type: keep to these two
        x = x.astype(np.float64)
    if x.shape[0] != size:
        raise SMCError(f"observation of {x.shape[0]} values, but the policy takes {size}")
    return x


def _kernels() -> ModuleType:
    """:mod:`sb3_smc.common.kernels`, imported on first use (numba loads in about a second)."""
    global _KERNELS
    if _KERNELS is None:
        from sb3_smc.common import kernels

        _KERNELS = kernels
    return _KERNELS


def _cast_layer(layer: Layer, dtype: np.dtype) -> Layer:
    name, a, b = layer
    if name == "linear":
        return name, np.ascontiguousarray(a, dtype=dtype), np.ascontiguousarray(b, dtype=dtype)
    _activate(name, a, np.zeros(1))  # fails early on an unknown name
    return name, float(a), None


def _n_outputs(layers: Sequence[Layer]) -> int:
    linear = [a for name, a, _ in layers if name == "linear"]
    if not linear:
        raise SMCError("the policy head needs at least the action layer")
    return int(linear[-1].shape[1])
