"""Step policies: trained SB3 actors re-implemented in numpy, scripted policies, and fast action sampling.

:func:`policy_from_model` copies the actor of a trained Stable-Baselines3 model out of torch once and returns a
:class:`~sb3_smc.smc.StepPolicy` that evaluates it in numpy, one observation at a time (about 20 times faster than
``model.predict`` at batch 1, see ``python -m tests.test_policies``):

* ``RecurrentPPO`` with ``MlpLstmPolicy`` -> :class:`NumpyLSTMPolicy` (any hidden size, any number of LSTM layers,
  shared LSTM or not, any policy ``net_arch``);
* ``PPO`` / ``TRPO`` (or any other ``ActorCriticPolicy``) with ``MlpPolicy`` -> :class:`NumpyMLPPolicy`.

Only ``Discrete`` action spaces and non-image ``Box`` observations through a ``FlattenExtractor`` are supported.
The numpy policies hold numpy arrays only (no torch modules), so they pickle small and load without torch.

:class:`FrameStackPolicy` replays ``VecFrameStack`` for a policy trained on stacked observations;
:class:`ScriptedPolicy` and :class:`SequencePolicy` are deterministic (one-hot) policies for tests and demos;
:func:`sample_action` draws an action from a probability vector by inverse-CDF sampling.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from sb3_smc.errors import SMCError, SMCTypeError

if TYPE_CHECKING:
    from stable_baselines3.common.base_class import BaseAlgorithm
    from stable_baselines3.common.policies import BasePolicy

    from sb3_smc.smc import StepPolicy

__all__ = [
    "ACTIVATIONS",
    "FrameStackPolicy",
    "NumpyGRUPolicy",
    "NumpyLSTMPolicy",
    "NumpyMLPPolicy",
    "ScriptedPolicy",
    "SequencePolicy",
    "policy_from_model",
    "sample_action",
    "sample_actions",
]

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


def _activation_spec(module: Any) -> tuple[str, float]:
    """``(name, parameter)`` of a torch activation module, or a ``TypeError`` for an unsupported one."""
    from torch import nn

    kind = type(module)
    name = ACTIVATIONS.get(kind.__name__)
    if name is None or getattr(nn, kind.__name__, None) is not kind:
        raise SMCTypeError(f"unsupported activation {kind.__name__} in the policy network "
                           f"(supported: {sorted(ACTIVATIONS)})")
    if name == "leaky_relu":
        return name, float(module.negative_slope)
    if name == "elu":
        return name, float(module.alpha)
    if name == "softplus" and (module.beta != 1 or module.threshold != 20):
        raise SMCTypeError(f"unsupported Softplus parameters (beta={module.beta}, threshold={module.threshold})")
    return name, 0.0


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

    @property
    def batch_from(self) -> int | None:
        """The fewest pending decisions worth one ``probabilities_batch`` call instead of single calls (None: never,
        for a compiled policy; see :data:`COMPILED_BATCH_FROM`)."""
        return COMPILED_BATCH_FROM if self._compiled is not None else 2

    @property
    def compiled_weights(self) -> tuple[np.ndarray, ...] | None:
        """The compiled step's weights as :func:`sb3_smc.common.kernels.leaf_call` takes them: ``(w_ih, w_hh,
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
        self.dtype = np.dtype(dtype)
        if not lstm:
            raise SMCError("NumpyLSTMPolicy needs at least one LSTM layer")
        self.hidden_size = int(np.shape(lstm[0][1])[0])
        self.n_layers = len(lstm)
        self.observation_size = int(observation_size)
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
        self.head = [_cast_layer(layer, self.dtype) for layer in head]
        self.n_actions = _n_outputs(self.head)
        self._compiled = (*self.lstm[0], *self.head[0][1:]) if _compilable(self) else None

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
        self.dtype = np.dtype(dtype)
        if not gru:
            raise SMCError("NumpyGRUPolicy needs at least one GRU layer")
        self.hidden_size = int(np.shape(gru[0][1])[0])
        self.n_layers = len(gru)
        self.observation_size = int(observation_size)
        self.gru = [tuple(np.ascontiguousarray(a, dtype=self.dtype) for a in layer) for layer in gru]
        for k, (w_ih, w_hh, b_ih, b_hh) in enumerate(self.gru):
            expected_in = self.observation_size if k == 0 else self.hidden_size
            gates = 3 * self.hidden_size
            if (w_ih.shape != (expected_in, gates) or w_hh.shape != (self.hidden_size, gates)
                    or b_ih.shape != (gates,) or b_hh.shape != (gates,)):
                raise SMCError(f"GRU layer {k}: inconsistent weight shapes {w_ih.shape}, {w_hh.shape}, "
                               f"{b_ih.shape}, {b_hh.shape}")
        self.head = [_cast_layer(layer, self.dtype) for layer in head]
        self.n_actions = _n_outputs(self.head)
        self._compiled = (*self.gru[0], *self.head[0][1:]) if _compilable(self) else None

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


def _compilable(policy: NumpyLSTMPolicy | NumpyGRUPolicy) -> bool:
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


_KERNELS: Any = None


def _flat(observation: np.ndarray, size: int) -> np.ndarray:
    """``observation`` as a 1-D array of ``size`` entries (the compiled steps read exactly that many)."""
    x = np.asarray(observation).reshape(-1)
    if x.dtype != np.float32 and x.dtype != np.float64:  # one compiled variant per input type: keep to these two
        x = x.astype(np.float64)
    if x.shape[0] != size:
        raise SMCError(f"observation of {x.shape[0]} values, but the policy takes {size}")
    return x


def _kernels() -> Any:
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


# ---------------------------------------------------------------------------------------------------------------
# From SB3 models
# ---------------------------------------------------------------------------------------------------------------

def policy_from_model(model: BaseAlgorithm | BasePolicy, dtype: Any = np.float64
                      ) -> NumpyMLPPolicy | NumpyLSTMPolicy | NumpyGRUPolicy:
    """Numpy copy of the actor of a trained SB3 model (or of its ``policy``), as a :class:`StepPolicy`.

    Supports ``RecurrentPPO`` + ``MlpLstmPolicy`` (:class:`NumpyLSTMPolicy`) or ``SequenceGruPolicy``
    (:class:`NumpyGRUPolicy`) and ``PPO`` / ``TRPO`` (any
    ``ActorCriticPolicy``) + ``MlpPolicy`` (:class:`NumpyMLPPolicy`), with a ``Discrete`` action space and a
    non-image ``Box`` observation space read through a ``FlattenExtractor``. Raises ``TypeError`` for other
    algorithms, policies, feature extractors, spaces or activation functions, and ``ValueError`` for unsupported
    LSTM options (projections, bidirectional, batch-first). The weights are copied once; later training of the
    model does not change the returned policy. The probabilities follow ``model.action_space`` order (index ``i``
    is action ``action_space.start + i``).
    """
    from gymnasium import spaces
    from stable_baselines3.common.distributions import CategoricalDistribution
    from stable_baselines3.common.policies import ActorCriticPolicy
    from stable_baselines3.common.torch_layers import FlattenExtractor, MlpExtractor

    policy = getattr(model, "policy", model)
    what = type(model).__name__ + ("" if policy is model else f" ({type(policy).__name__})")
    if not isinstance(policy, ActorCriticPolicy):
        raise SMCTypeError(f"policy_from_model supports actor-critic policies (PPO, TRPO, RecurrentPPO), not {what}")
    if not isinstance(policy.action_space, spaces.Discrete):
        raise SMCTypeError(f"policy_from_model supports Discrete action spaces only, {what} has "
                           f"{type(policy.action_space).__name__}")
    if not isinstance(policy.action_dist, CategoricalDistribution):
        raise SMCTypeError(f"unsupported action distribution {type(policy.action_dist).__name__} in {what}")
    space = policy.observation_space
    if not isinstance(space, spaces.Box):
        raise SMCTypeError(f"policy_from_model supports Box observations only, {what} has {type(space).__name__}")
    from stable_baselines3.common.preprocessing import is_image_space

    if policy.normalize_images and is_image_space(space, check_channels=False):
        raise SMCTypeError(f"image observations (normalised by SB3) are not supported: {space}")
    extractor = policy.pi_features_extractor
    if type(extractor) is not FlattenExtractor:
        raise SMCTypeError(f"policy_from_model supports FlattenExtractor only, {what} uses {type(extractor).__name__} "
                           "(use MlpPolicy / MlpLstmPolicy)")
    mlp = policy.mlp_extractor
    if not isinstance(mlp, MlpExtractor) or type(mlp).forward_actor is not MlpExtractor.forward_actor:
        raise SMCTypeError(f"unsupported mlp_extractor {type(mlp).__name__} in {what}")
    observation_size = int(np.prod(space.shape))
    head = _sequential_layers(mlp.policy_net) + [_linear_layer(policy.action_net)]

    try:
        from sb3_contrib.common.recurrent.policies import RecurrentActorCriticPolicy
    except ImportError:  # pragma: no cover - sb3-contrib is a dependency
        RecurrentActorCriticPolicy = None  # type: ignore[assignment,misc]  # noqa: N806  (a class or None)

    if RecurrentActorCriticPolicy is not None and isinstance(policy, RecurrentActorCriticPolicy):
        _check_overrides(policy, RecurrentActorCriticPolicy, ("get_distribution", "_process_sequence"), what)
        from sb3_smc.common.recurrent.gru import GRUAsLSTM

        if isinstance(policy.lstm_actor, GRUAsLSTM):
            return NumpyGRUPolicy(_gru_layers(policy.lstm_actor.gru), head, observation_size, dtype)
        return NumpyLSTMPolicy(_lstm_layers(policy.lstm_actor), head, observation_size, dtype)
    if hasattr(policy, "lstm_actor"):
        raise SMCTypeError(f"unsupported recurrent policy {what}")
    _check_overrides(policy, ActorCriticPolicy, ("get_distribution", "_get_action_dist_from_latent"), what)
    return NumpyMLPPolicy(head, observation_size, dtype)


def _check_overrides(policy: Any, base: type, methods: Sequence[str], what: str) -> None:
    for method in methods:
        if getattr(type(policy), method) is not getattr(base, method):
            raise SMCTypeError(f"{what} overrides {method}; policy_from_model cannot reproduce it")


def _numpy(tensor: Any) -> np.ndarray:
    return tensor.detach().cpu().double().numpy().copy()


def _linear_layer(module: Any) -> Layer:
    from torch import nn

    if type(module) is not nn.Linear:
        raise SMCTypeError(f"expected a Linear layer, got {type(module).__name__}")
    bias = _numpy(module.bias) if module.bias is not None else np.zeros(module.out_features)
    return "linear", _numpy(module.weight).T, bias


def _sequential_layers(net: Any) -> list[Layer]:
    from torch import nn

    modules = list(net) if isinstance(net, nn.Sequential) else [net]
    layers: list[Layer] = []
    for module in modules:
        if type(module) is nn.Linear:
            layers.append(_linear_layer(module))
        elif isinstance(module, nn.Dropout):  # the identity at inference
            continue
        else:
            name, param = _activation_spec(module)
            if name != "identity":
                layers.append((name, param, None))
    return layers


def _lstm_layers(lstm: Any) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    from torch import nn

    if type(lstm) is not nn.LSTM:
        raise SMCTypeError(f"expected torch.nn.LSTM as lstm_actor, got {type(lstm).__name__}")
    if lstm.bidirectional or lstm.proj_size or lstm.batch_first:
        raise SMCError("unsupported LSTM options (bidirectional, proj_size or batch_first) in lstm_actor")
    layers = []
    for k in range(lstm.num_layers):
        w_ih = _numpy(getattr(lstm, f"weight_ih_l{k}"))
        w_hh = _numpy(getattr(lstm, f"weight_hh_l{k}"))
        bias = np.zeros(w_ih.shape[0])
        if lstm.bias:
            bias = _numpy(getattr(lstm, f"bias_ih_l{k}")) + _numpy(getattr(lstm, f"bias_hh_l{k}"))
        layers.append((w_ih.T, w_hh.T, bias))
    return layers


def _gru_layers(gru: Any) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    layers = []
    for k in range(gru.num_layers):
        w_ih = _numpy(getattr(gru, f"weight_ih_l{k}"))
        w_hh = _numpy(getattr(gru, f"weight_hh_l{k}"))
        zeros = np.zeros(w_ih.shape[0])
        b_ih = _numpy(getattr(gru, f"bias_ih_l{k}")) if gru.bias else zeros
        b_hh = _numpy(getattr(gru, f"bias_hh_l{k}")) if gru.bias else zeros
        layers.append((w_ih.T, w_hh.T, b_ih, b_hh))
    return layers


# ---------------------------------------------------------------------------------------------------------------
# Scripted policies
# ---------------------------------------------------------------------------------------------------------------

class ScriptedPolicy:
    """Deterministic policy: ``choose(observation, step_in_call) -> action`` with one-hot probabilities.

    The state is the number of steps since the start of the call (``initial_state()`` is 0). Picklable when
    ``choose`` is (a module-level function, not a lambda or closure).
    """

    def __init__(self, n_actions: int, choose: Callable[[np.ndarray, int], int]) -> None:
        if n_actions < 1:
            raise SMCError(f"n_actions must be positive, got {n_actions}")
        self.n_actions = int(n_actions)
        self.choose = choose

    def initial_state(self) -> int:
        return 0

    def probabilities(self, observation: np.ndarray, state: int) -> tuple[np.ndarray, int]:
        return _one_hot(int(self.choose(observation, state)), self.n_actions), state + 1

    def __repr__(self) -> str:
        return f"{type(self).__name__}(n_actions={self.n_actions}, choose={getattr(self.choose, '__name__', '?')})"


class SequencePolicy:
    """Plays ``actions`` in order, one per step of the call, ignoring observations.

    After the last action it keeps repeating that action (``when_exhausted="repeat"``, the default) or raises
    ``IndexError`` (``when_exhausted="raise"``). The state is the number of steps since the start of the call.
    """

    def __init__(self, n_actions: int, actions: Sequence[int], when_exhausted: str = "repeat") -> None:
        if n_actions < 1:
            raise SMCError(f"n_actions must be positive, got {n_actions}")
        if when_exhausted not in ("repeat", "raise"):
            raise SMCError(f"when_exhausted must be 'repeat' or 'raise', got {when_exhausted!r}")
        self.n_actions = int(n_actions)
        self.actions = tuple(int(a) for a in actions)
        if not self.actions:
            raise SMCError("SequencePolicy needs at least one action")
        bad = [a for a in self.actions if not 0 <= a < self.n_actions]
        if bad:
            raise SMCError(f"actions {bad} out of range for {self.n_actions} actions")
        self.when_exhausted = when_exhausted

    def initial_state(self) -> int:
        return 0

    def probabilities(self, observation: np.ndarray, state: int) -> tuple[np.ndarray, int]:
        if state >= len(self.actions):
            if self.when_exhausted == "raise":
                raise IndexError(f"SequencePolicy exhausted after {len(self.actions)} actions")
            return _one_hot(self.actions[-1], self.n_actions), state + 1
        return _one_hot(self.actions[state], self.n_actions), state + 1

    def __repr__(self) -> str:
        return f"{type(self).__name__}(n_actions={self.n_actions}, actions={list(self.actions)})"


def _one_hot(action: int, n: int) -> np.ndarray:
    if not 0 <= action < n:
        raise SMCError(f"action {action} out of range for {n} actions")
    probs = np.zeros(n)
    probs[action] = 1.0
    return probs


# ---------------------------------------------------------------------------------------------------------------
# Frame stacking
# ---------------------------------------------------------------------------------------------------------------

class FrameStackPolicy:
    """A :class:`~sb3_smc.smc.StepPolicy` for a policy trained under ``VecFrameStack(n_stack)``.

    The inner policy sees the last ``n_stack`` observations concatenated, oldest first, zeros before the start
    of the call (what ``VecFrameStack`` does for 1-D observations after a reset). Picklable when ``inner`` is.
    """

    def __init__(self, inner: StepPolicy, n_stack: int, observation_size: int) -> None:
        if n_stack < 1:
            raise SMCError(f"n_stack must be >= 1, got {n_stack}")
        self.inner = inner
        self.n_stack = int(n_stack)
        self.observation_size = int(observation_size)

    def initial_state(self) -> tuple[np.ndarray, Any]:
        return np.zeros(self.n_stack * self.observation_size), self.inner.initial_state()

    def probabilities(self, observation: np.ndarray, state: tuple[np.ndarray, Any]) -> tuple[np.ndarray, Any]:
        frames, inner_state = state
        frames = np.concatenate((frames[self.observation_size:], np.asarray(observation, dtype=frames.dtype)))
        probabilities, inner_state = self.inner.probabilities(frames, inner_state)
        return probabilities, (frames, inner_state)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.inner!r}, n_stack={self.n_stack})"


# ---------------------------------------------------------------------------------------------------------------
# Sampling
# ---------------------------------------------------------------------------------------------------------------

def sample_action(probabilities: np.ndarray, rng: np.random.Generator) -> int:
    """Draw an action index from ``probabilities`` (1-D, non-negative, normalised or not) by inverse CDF.

    One ``rng.random()`` per call (much faster than ``rng.choice``); actions of zero probability are never drawn.
    A 1-D float64 array (what the numpy actors return) is drawn by the compiled
    :func:`sb3_smc.common.kernels.sample_index`, the same index as the numpy code below.
    """
    if type(probabilities) is np.ndarray and probabilities.dtype == np.float64 and probabilities.ndim == 1:
        index = _kernels().sample_index(probabilities, rng.random())
        if index < 0:
            raise SMCError(f"probabilities must have a positive finite sum, got {probabilities.sum()}")
        return index
    cdf = np.asarray(probabilities).cumsum()  # array methods: no numpy dispatch wrappers on this hot path
    total = cdf[-1]
    if not 0.0 < total < np.inf:
        raise SMCError(f"probabilities must have a positive finite sum, got {total}")
    index = int(cdf.searchsorted(rng.random() * total, side="right"))
    if index >= len(cdf):  # rounding at the top end: the last action of positive probability
        index = int(np.flatnonzero(np.asarray(probabilities) > 0)[-1])
    return index


def sample_actions(probabilities: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Draw one action per row of ``probabilities`` ``(B, n_actions)``, as :func:`sample_action` does per row."""
    p = np.asarray(probabilities, dtype=np.float64)
    cdf = np.cumsum(p, axis=1)
    total = cdf[:, -1:]
    if not np.all(total > 0.0):
        raise SMCError("every row of probabilities must have a positive finite sum")
    u = rng.random((len(p), 1)) * total
    index = (cdf <= u).sum(axis=1)
    top = index >= p.shape[1]
    if top.any():
        last = p.shape[1] - 1 - np.argmax(p[:, ::-1] > 0, axis=1)
        index[top] = last[top]
    return index
