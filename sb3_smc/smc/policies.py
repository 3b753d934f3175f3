"""Step policies: trained SB3 actors re-implemented in numpy, scripted policies, and fast action sampling.

:func:`policy_from_model` copies the actor of a trained Stable-Baselines3 model out of torch once and returns a
:class:`~sb3_smc.smc.smc.StepPolicy` that evaluates it in numpy, one observation at a time (about 20 times faster than
``model.predict`` at batch 1, see ``python -m tests.test_policies``):

* ``RecurrentPPO`` with ``MlpLstmPolicy`` -> :class:`NumpyLSTMPolicy` (any hidden size, any number of LSTM layers,
  shared LSTM or not, any policy ``net_arch``);
* ``PPO`` / ``TRPO`` (or any other ``ActorCriticPolicy``) with ``MlpPolicy`` -> :class:`NumpyMLPPolicy`.

Only ``Discrete`` action spaces and non-image ``Box`` observations through a ``FlattenExtractor`` are supported.
The numpy actors themselves are :mod:`sb3_smc.smc.numpy_actors`' (re-exported here); they hold numpy arrays only (no
torch modules), so they pickle small and load without torch.

:class:`FrameStackPolicy` replays ``VecFrameStack`` for a policy trained on stacked observations;
:class:`ScriptedPolicy` and :class:`SequencePolicy` are deterministic (one-hot) policies for tests and demos;
:func:`sample_action` draws an action from a probability vector by inverse-CDF sampling.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from sb3_smc.errors import SMCError, SMCTypeError
from sb3_smc.smc.numpy_actors import (
    ACTIVATIONS,
    COMPILED_BATCH_FROM,
    Layer,
    LSTMState,
    NumpyGRUPolicy,
    NumpyLSTMPolicy,
    NumpyMLPPolicy,
    _kernels,
)

if TYPE_CHECKING:
    from stable_baselines3.common.base_class import BaseAlgorithm
    from stable_baselines3.common.policies import BasePolicy

    from sb3_smc.smc.smc import StepPolicy

__all__ = [
    "ACTIVATIONS",
    "COMPILED_BATCH_FROM",
    "FrameStackPolicy",
    "LSTMState",
    "Layer",
    "NumpyGRUPolicy",
    "NumpyLSTMPolicy",
    "NumpyMLPPolicy",
    "ScriptedPolicy",
    "SequencePolicy",
    "policy_from_model",
    "sample_action",
    "sample_actions",
]


# ---------------------------------------------------------------------------------------------------------------
# From SB3 models
# ---------------------------------------------------------------------------------------------------------------

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
        from sb3_smc.common.recurrent.layers import GRUAsLSTM

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
    """A :class:`~sb3_smc.smc.smc.StepPolicy` for a policy trained under ``VecFrameStack(n_stack)``.

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
