"""Train one SMC on a ``PW-*`` environment with sb3-contrib RecurrentPPO (default) or TRPO (spec §5).

:func:`train_smc` builds ``n_envs`` copies of the environment's training split, each inside
:class:`~sb3_smc.wrapper.HierarchicalSMCWrapper` (also for a flat SMC, so every SMC sees the same observation
layout: the one-hot window, the outcome vector of its children and its previous action), trains a paper-sized
policy with the signal-bias initialisation of spec §5.2, keeps the snapshot of the update with the highest mean
training return (spec §5.4, ties -> earliest) and returns it as an :class:`~sb3_smc.smc.SMC` whose policy is a
numpy copy of the selected actor.

Defaults (measured, see ``docs/training.md``): 16 environments x 125 steps = 2,000 steps per update, 200
updates (400,000 steps), gamma 0.99, GAE lambda 1, episodes of at most 100 decisions.

* ``RecurrentPPO`` (with :class:`SequenceLstmPolicy` and :class:`CompactRecurrentRolloutBuffer`: sb3-contrib's
  numbers, faster): one LSTM layer of 32 units for the actor (the paper's GRU-32 size) with the action layer
  directly on its output (``net_arch=[]``); a critic without memory, linear in the observation
  (``enable_critic_lstm=False``, like the paper's linear feature baseline); one 2,000-step minibatch, 4 epochs,
  learning rate 3e-3, clip 0.2.
* ``TRPO``: ``MlpPolicy`` with one hidden layer of 32 tanh units (actor and critic), KL step 0.01 (the paper's
  NPO step size). An MLP has no memory of its own; its memory is what the observation carries — the previous
  action and the outcome vector of the children — plus, optionally, the last ``frame_stack`` observations
  (:class:`FrameStackPolicy` replays the stacking when the SMC is called as a child).
"""

from __future__ import annotations

import copy
import math
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
import torch
from sb3_contrib import TRPO, RecurrentPPO
from sb3_contrib.common.recurrent.buffers import RecurrentRolloutBuffer
from sb3_contrib.common.recurrent.policies import RecurrentActorCriticPolicy
from sb3_contrib.common.recurrent.type_aliases import RNNStates
from stable_baselines3.common.vec_env import DummyVecEnv

from sb3_smc.callbacks import SMCTrainingCallback
from sb3_smc.smc import CALL_PREFIX, MOVES, SMC, StepPolicy

__all__ = [
    "ALGORITHMS",
    "CompactRecurrentRolloutBuffer",
    "DEFAULT_HYPERPARAMETERS",
    "FrameStackPolicy",
    "FreshInfoVecEnv",
    "SequenceLstmPolicy",
    "STEPS_PER_UPDATE",
    "SequenceStates",
    "apply_signal_bias",
    "initial_action_probabilities",
    "make_training_env",
    "resolve_children",
    "smc_name_from_env_id",
    "train_smc",
    "use_compact_buffer",
]

STEPS_PER_UPDATE = 2000
"""Environment steps per policy update (the paper's batch size)."""
DEFAULT_N_ENVS = 16
SIGNAL_WEIGHT, NONSIGNAL_WEIGHT, SMC_WEIGHT = 1.0, 20.0, 20.0
"""Weights of the bias rule of spec §5.2 (their sum with both groups present is 41)."""

ALGORITHMS = ("RecurrentPPO", "TRPO")

DEFAULT_HYPERPARAMETERS: dict[str, dict[str, Any]] = {
    "RecurrentPPO": {
        "policy": "SequenceLstmPolicy",
        "gamma": 0.99,
        "gae_lambda": 1.0,
        "batch_size": STEPS_PER_UPDATE,
        "n_epochs": 4,
        "learning_rate": 3e-3,
        "clip_range": 0.2,
        "ent_coef": 0.0,
        "policy_kwargs": {"lstm_hidden_size": 32, "n_lstm_layers": 1, "net_arch": [],
                          "shared_lstm": False, "enable_critic_lstm": False},
    },
    "TRPO": {
        "policy": "MlpPolicy",
        "gamma": 0.99,
        "gae_lambda": 1.0,
        "batch_size": STEPS_PER_UPDATE,
        "target_kl": 0.01,
        "learning_rate": 1e-3,
        "policy_kwargs": {"net_arch": {"pi": [32], "vf": [32]}},
    },
}
"""Constructor arguments of each algorithm (``n_steps`` is ``2000 // n_envs``); keyword arguments of
:func:`train_smc` override them (``policy_kwargs`` key by key)."""


# -------------------------------------------------------------------------------------------------- bias rule

def _group(name: str) -> str:
    if name.startswith("SIG"):
        return "signal"
    if name.startswith(CALL_PREFIX):
        return "smc"
    if name in MOVES:
        return "move"
    raise ValueError(f"unknown action name {name!r}: expected a signal (SIG*), a move {MOVES} or "
                     f"{CALL_PREFIX}<child>")


def initial_action_probabilities(action_names: Sequence[str], *, signal_weight: float = SIGNAL_WEIGHT,
                                 nonsignal_weight: float = NONSIGNAL_WEIGHT,
                                 smc_weight: float = SMC_WEIGHT) -> np.ndarray:
    """The initial action distribution of spec §5.2 ("init" policies).

    Signals share ``signal_weight`` equally, moves share ``nonsignal_weight`` and SMC actions ``smc_weight``;
    without SMC actions the moves take both shares (``nonsignal_weight + smc_weight``). Absent groups are
    dropped and the rest renormalised: classification flat SIG0 = SIG1 = 1/82 and each move 10/41;
    with SMCs the moves share 20/41 and the SMCs 20/41; without moves (noprim) signals 1/21 and SMCs 20/21.
    """
    groups = [_group(name) for name in action_names]
    if not groups:
        raise ValueError("no actions")
    counts = {g: groups.count(g) for g in ("signal", "move", "smc")}
    weights = {"signal": signal_weight, "move": nonsignal_weight, "smc": smc_weight}
    if counts["smc"] == 0:
        weights["move"] = nonsignal_weight + smc_weight
    total = sum(weights[g] for g in weights if counts[g])
    probabilities = np.array([weights[g] / counts[g] / total for g in groups])
    return probabilities


def apply_signal_bias(model: Any, action_names: Sequence[str], **weights: float) -> np.ndarray:
    """Set the bias of the policy's action layer to ``log p`` (:func:`initial_action_probabilities`).

    SB3 initialises the action layer orthogonally with gain 0.01, so the initial logits are the bias up to
    about 1e-2 and the initial policy follows ``p``. Returns ``p``.
    """
    probabilities = initial_action_probabilities(action_names, **weights)
    action_net = model.policy.action_net
    if action_net.out_features != len(probabilities):
        raise ValueError(f"the action layer has {action_net.out_features} outputs for {len(probabilities)} actions")
    with torch.no_grad():
        action_net.bias.copy_(torch.as_tensor(np.log(probabilities), dtype=action_net.bias.dtype))
    return probabilities


# -------------------------------------------------------------------------------------------------- LSTM policy

def _lstm_by_length(lstm: torch.nn.LSTM, features: torch.Tensor, starts: torch.Tensor, lengths: torch.Tensor,
                    states: tuple[torch.Tensor, torch.Tensor]) -> torch.Tensor:
    """Run ``lstm`` over the sequences ``features[starts[i] : starts[i] + lengths[i]]`` of a flat batch.

    Sequences whose lengths fall in the same power-of-two bucket run together, padded only to the longest of
    their bucket, from their initial ``states`` (``(n_layers, n_seq, hidden)`` each). Returns the outputs at the
    same flat positions as ``features`` (zeros where no sequence covers a row).
    """
    n_rows = features.shape[0]
    positions, outputs = [], []
    low, high = 0, 1
    longest_overall = int(lengths.max()) if len(lengths) else 0
    while low < longest_overall:
        members = torch.nonzero((lengths > low) & (lengths <= high)).flatten()
        if len(members):
            longest = int(lengths[members].max())
            offsets = torch.arange(longest)
            index = starts[members, None] + offsets[None, :]  # (n_bucket, longest)
            valid = offsets[None, :] < lengths[members, None]
            index = torch.where(valid, index, starts[members, None])  # rows past the end: any row (causal LSTM)
            output, _ = lstm(features[index].transpose(0, 1), (states[0][:, members], states[1][:, members]))
            positions.append(index[valid])
            outputs.append(output.transpose(0, 1)[valid])
        low, high = high, 2 * high
    result = features.new_zeros((n_rows, lstm.hidden_size))
    if positions:
        result = result.index_put((torch.cat(positions),), torch.cat(outputs))
    return result


class SequenceStates(RNNStates):
    """``RNNStates`` of a compact minibatch (:class:`CompactRecurrentRolloutBuffer`) plus its sequence layout.

    ``starts``: the flat index where each sequence starts; ``lengths``: its length; ``resets``: 1.0 where the
    sequence starts an episode (its stored initial state is then replaced by zeros), else 0.0.
    """

    starts: torch.Tensor
    lengths: torch.Tensor
    resets: torch.Tensor


class CompactRecurrentRolloutBuffer(RecurrentRolloutBuffer):
    """sb3-contrib's recurrent rollout buffer without padding.

    The stock buffer pads every sequence of a minibatch (cut at episode starts) to the longest one, one tensor
    per sequence: with short episodes a 2,000-step minibatch becomes ~90,000 padded rows built by ~500,000 small
    ``torch.tensor`` calls. This buffer returns the minibatch's rows unpadded, in the stock order (sequence after
    sequence), with an all-ones ``mask`` and the layout in :class:`SequenceStates`; :class:`SequenceLstmPolicy`
    reads it. The minibatch order and sequence cuts are the stock ones.
    """

    def _get_samples(self, batch_inds: np.ndarray, env_change: np.ndarray, env: Any = None):
        from sb3_contrib.common.recurrent.type_aliases import RecurrentRolloutBufferSamples

        episode_starts = self.episode_starts[batch_inds].reshape(-1)
        seq_start = np.logical_or(episode_starts, env_change[batch_inds].reshape(-1))
        seq_start[0] = True
        starts = np.flatnonzero(seq_start)
        lengths = np.diff(np.append(starts, len(batch_inds)))

        def initial(array: np.ndarray) -> torch.Tensor:
            return self.to_torch(array[batch_inds][starts].swapaxes(0, 1)).contiguous()

        states = SequenceStates((initial(self.hidden_states_pi), initial(self.cell_states_pi)),
                                (initial(self.hidden_states_vf), initial(self.cell_states_vf)))
        states.starts = torch.as_tensor(starts, dtype=torch.long)
        states.lengths = torch.as_tensor(lengths, dtype=torch.long)
        states.resets = self.to_torch(episode_starts[starts])
        return RecurrentRolloutBufferSamples(
            observations=self.to_torch(self.observations[batch_inds]),
            actions=self.to_torch(self.actions[batch_inds]),
            old_values=self.to_torch(self.values[batch_inds].reshape(-1)),
            old_log_prob=self.to_torch(self.log_probs[batch_inds].reshape(-1)),
            advantages=self.to_torch(self.advantages[batch_inds].reshape(-1)),
            returns=self.to_torch(self.returns[batch_inds].reshape(-1)),
            lstm_states=states,
            episode_starts=self.to_torch(episode_starts),
            mask=torch.ones(len(batch_inds), dtype=torch.float32, device=self.device),
        )


class SequenceLstmPolicy(RecurrentActorCriticPolicy):
    """sb3-contrib's ``MlpLstmPolicy`` with a faster training pass (the same numbers on every real step).

    The stock policy runs its LSTM one time step at a time over padded minibatches whenever an episode starts
    inside them (a Python loop over up to ``n_steps`` steps, forward and backward). This policy runs it once per
    power-of-two bucket of sequence lengths, each padded only to its own longest sequence, from the sequences'
    initial states (zeroed where a sequence starts an episode). It reads compact minibatches of
    :class:`CompactRecurrentRolloutBuffer` (see :func:`use_compact_buffer`) and sb3-contrib's padded ones
    (plain ``RecurrentPPO``; the sequence lengths are then read from the padding, whose observations are all
    zeros, which a one-hot SMC observation never is). Collection and prediction are unchanged, and
    :func:`sb3_smc.policies.policy_from_model` reads it like ``MlpLstmPolicy``.
    """

    def evaluate_actions(self, obs, actions, lstm_states, episode_starts):
        n_seq = lstm_states.pi[0].shape[1]
        if not self.share_features_extractor or obs.dim() != 2:
            return super().evaluate_actions(obs, actions, lstm_states, episode_starts)
        if isinstance(lstm_states, SequenceStates):
            starts, lengths, resets = lstm_states.starts, lstm_states.lengths, lstm_states.resets
        else:  # sb3-contrib's padded layout: n_seq sequences of max_len rows, an episode start only first
            padded = episode_starts.reshape((n_seq, -1))
            max_len = padded.shape[1]
            if obs.shape[0] != n_seq * max_len or bool(padded[:, 1:].any()):
                return super().evaluate_actions(obs, actions, lstm_states, episode_starts)
            real = obs.reshape(n_seq, max_len, -1).ne(0).any(dim=2)
            steps = torch.arange(1, max_len + 1, device=obs.device).expand(n_seq, max_len)
            lengths = (steps * real).amax(dim=1).clamp(min=1)
            starts = torch.arange(n_seq, device=obs.device) * max_len
            resets = padded[:, 0]
        keep = (1.0 - resets).view(1, n_seq, 1)
        features = self.extract_features(obs)
        states = (lstm_states.pi[0] * keep, lstm_states.pi[1] * keep)
        latent_pi = _lstm_by_length(self.lstm_actor, features, starts, lengths, states)
        if self.lstm_critic is not None:
            states = (lstm_states.vf[0] * keep, lstm_states.vf[1] * keep)
            latent_vf = _lstm_by_length(self.lstm_critic, features, starts, lengths, states)
        elif self.shared_lstm:
            latent_vf = latent_pi.detach()
        else:
            latent_vf = self.critic(features)
        latent_pi = self.mlp_extractor.forward_actor(latent_pi)
        latent_vf = self.mlp_extractor.forward_critic(latent_vf)
        distribution = self._get_action_dist_from_latent(latent_pi)
        return self.value_net(latent_vf), distribution.log_prob(actions), distribution.entropy()


def use_compact_buffer(model: RecurrentPPO) -> bool:
    """Give a ``RecurrentPPO`` model with a :class:`SequenceLstmPolicy` a :class:`CompactRecurrentRolloutBuffer`.

    The model stays a plain ``RecurrentPPO`` (saved, loaded and stored in an ``SMCLibrary`` as such; a loaded
    model gets sb3-contrib's padded buffer back, which the policy also reads). Returns whether the buffer was
    replaced (not for other policies or ``Dict`` observations).
    """
    buffer = model.rollout_buffer
    if not isinstance(model.policy, SequenceLstmPolicy) or type(buffer) is not RecurrentRolloutBuffer:
        return False
    model.rollout_buffer = CompactRecurrentRolloutBuffer(
        model.n_steps, model.observation_space, model.action_space, buffer.hidden_state_shape, model.device,
        gamma=model.gamma, gae_lambda=model.gae_lambda, n_envs=model.n_envs)
    return True


# -------------------------------------------------------------------------------------------------- frame stacking

class FrameStackPolicy:
    """A :class:`~sb3_smc.smc.StepPolicy` for a policy trained under ``VecFrameStack(n_stack)``.

    The inner policy sees the last ``n_stack`` observations concatenated, oldest first, zeros before the start
    of the call (what ``VecFrameStack`` does for 1-D observations after a reset). Picklable when ``inner`` is.
    """

    def __init__(self, inner: StepPolicy, n_stack: int, observation_size: int) -> None:
        if n_stack < 1:
            raise ValueError(f"n_stack must be >= 1, got {n_stack}")
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


# -------------------------------------------------------------------------------------------------- environments

def smc_name_from_env_id(env_id: str) -> str:
    """``PW-<name>-v0`` -> ``<name>`` (the dataset or concept-pool name); other ids are returned unchanged."""
    name = env_id.split(":", 1)[-1]
    if name.startswith("PW-"):
        name = name[3:]
    head, sep, version = name.rpartition("-v")
    if sep and version.isdigit():
        name = head
    return name


def resolve_children(children: Any) -> tuple[SMC, ...]:
    """``None``, a sequence of SMCs, or ``(library, [names])`` -> a tuple of SMCs."""
    if children is None:
        return ()
    if (isinstance(children, tuple) and len(children) == 2 and not isinstance(children[0], SMC)
            and not isinstance(children[1], (str, SMC))):
        library, names = children
        return tuple(library[name] for name in names)
    resolved = tuple(children)
    bad = [type(c).__name__ for c in resolved if not isinstance(c, SMC)]
    if bad:
        raise TypeError(f"children must be SMCs (or (library, [names])), got {bad}")
    return resolved


def make_training_env(env_id: str, children: Sequence[SMC] = (), *, split: str = "train",
                      include_primitives: bool = True, max_steps: int = 100, count_primitive_steps: bool = False,
                      call_step_cap: int = 100, env_kwargs: Mapping[str, Any] | None = None) -> gym.Env:
    """One environment as an SMC sees it: ``gym.make(env_id, split=...)`` inside the hierarchical wrapper."""
    import pixelworld_env  # noqa: F401  (registers the PW-* ids)
    from sb3_smc.wrapper import HierarchicalSMCWrapper

    kwargs = {"disable_env_checker": True, **dict(env_kwargs or {})}
    env = gym.make(env_id, split=split, max_steps=max_steps, **kwargs)
    return HierarchicalSMCWrapper(env, tuple(children), include_primitives=include_primitives,
                                  count_primitive_steps=count_primitive_steps, call_step_cap=call_step_cap)


def _datasets(env_id: str) -> list[str]:
    try:
        spec = gym.spec(env_id)
    except gym.error.Error:
        return []
    return list(spec.kwargs.get("datasets", ()))


def _jsonable(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, (bool, int, float, str)) or value is None:
        return value
    if isinstance(value, type):
        return f"{value.__module__}.{value.__qualname__}"
    if isinstance(value, np.generic):
        return value.item()
    return repr(value)


# -------------------------------------------------------------------------------------------------- training

class FreshInfoVecEnv(DummyVecEnv):
    """``DummyVecEnv`` that copies the step infos shallowly instead of deep-copying them.

    The hierarchical wrapper returns a new ``info`` dict (and a new ``smc_calls`` list) at every step, so the deep
    copy ``DummyVecEnv`` makes to avoid aliasing only costs time (about a tenth of the collection time).
    """

    def step_wait(self):
        for i, env in enumerate(self.envs):
            obs, self.buf_rews[i], terminated, truncated, info = env.step(self.actions[i])
            self.buf_dones[i] = terminated or truncated
            info["TimeLimit.truncated"] = truncated and not terminated
            if self.buf_dones[i]:
                info["terminal_observation"] = obs
                obs, self.reset_infos[i] = env.reset()
            self.buf_infos[i] = info
            self._save_obs(i, obs)
        return self._obs_from_buf(), np.copy(self.buf_rews), np.copy(self.buf_dones), [dict(i) for i in self.buf_infos]


def train_smc(
    env_id: str,
    *,
    algo: str = "RecurrentPPO",
    total_timesteps: int = 400_000,
    seed: int = 0,
    children: Any = None,
    include_primitives: bool = True,
    tensorboard_log: str | None = None,
    name: str | None = None,
    n_envs: int = DEFAULT_N_ENVS,
    signal_bias: bool = True,
    frame_stack: int = 1,
    max_steps: int = 100,
    count_primitive_steps: bool = False,
    call_step_cap: int = 100,
    env_kwargs: Mapping[str, Any] | None = None,
    log_every: int | None = None,
    callback: Any = None,
    printer: Callable[[str], None] = print,
    **hyperparams: Any,
) -> SMC:
    """Train an SMC on ``env_id``'s training split and return the snapshot with the best mean training return.

    * ``algo``: ``"RecurrentPPO"`` (LSTM 32) or ``"TRPO"`` (MLP 32); ``hyperparams`` override
      :data:`DEFAULT_HYPERPARAMETERS` (``policy_kwargs`` key by key); ``n_steps`` defaults to ``2000 // n_envs``.
    * ``children``: SMCs to use as actions, or ``(library, [names])``; ``include_primitives=False`` drops the
      moves (the "noprim" ablation). ``count_primitive_steps`` / ``call_step_cap`` go to the wrapper.
    * ``signal_bias``: the initial action distribution of spec §5.2 (on by default; without it episodes end after
      a few random signals and little is learned).
    * ``frame_stack``: stack the last k observations (meant for TRPO's memoryless MLP).
    * ``tensorboard_log``: a folder for SB3's curves and the SMC curves of
      :class:`~sb3_smc.callbacks.SMCTrainingCallback` (run name ``name``).
    * ``log_every``: print a progress line (through ``printer``) every that many updates; 0: quiet; ``None``
      (default): every 10 updates when training runs 50 updates or more, else quiet.

    The returned SMC's ``policy`` is a numpy copy of the selected snapshot's actor, ``model`` the SB3 model with
    the selected weights loaded, ``metadata`` the provenance (env id, datasets, kind, algo, seed, hyperparameters,
    selected update, its training return, the return of every update, step counts, wall time).
    """
    from stable_baselines3.common.callbacks import CallbackList
    from stable_baselines3.common.vec_env import VecFrameStack, VecMonitor

    from sb3_smc.policies import policy_from_model

    if algo not in ALGORITHMS:
        raise ValueError(f"algo must be one of {ALGORITHMS}, got {algo!r}")
    if n_envs < 1:
        raise ValueError(f"n_envs must be >= 1, got {n_envs}")
    if frame_stack < 1:
        raise ValueError(f"frame_stack must be >= 1, got {frame_stack}")
    if algo == "RecurrentPPO" and frame_stack != 1:
        raise ValueError("frame_stack is meant for memoryless policies (TRPO); RecurrentPPO has an LSTM")
    kids = resolve_children(children)
    name = name or smc_name_from_env_id(env_id)

    wrapper_settings = {"max_steps": max_steps, "count_primitive_steps": count_primitive_steps,
                        "call_step_cap": call_step_cap}
    envs = [make_training_env(env_id, kids, include_primitives=include_primitives, env_kwargs=env_kwargs,
                              **wrapper_settings) for _ in range(n_envs)]
    kind = envs[0].unwrapped.kind
    action_names = tuple(envs[0].action_names)
    observation_size = int(envs[0].observation_space.shape[0])
    venv = VecMonitor(FreshInfoVecEnv([(lambda e=e: e) for e in envs]))
    if frame_stack > 1:
        venv = VecFrameStack(venv, frame_stack)
    venv.seed(seed)

    settings = copy.deepcopy(DEFAULT_HYPERPARAMETERS[algo])
    policy_kwargs = settings.pop("policy_kwargs")
    policy_kwargs.update(hyperparams.pop("policy_kwargs", None) or {})
    settings.update(hyperparams)
    settings.setdefault("n_steps", max(1, STEPS_PER_UPDATE // n_envs))
    policy_name = settings.pop("policy")
    policy_class = SequenceLstmPolicy if policy_name == "SequenceLstmPolicy" else policy_name
    steps_per_update = settings["n_steps"] * n_envs
    settings["batch_size"] = min(settings.get("batch_size") or steps_per_update, steps_per_update)

    algo_class = _algorithm(algo)
    model = algo_class(policy_class, venv, policy_kwargs=policy_kwargs, seed=seed, device="cpu",
                       tensorboard_log=tensorboard_log, verbose=0, **settings)
    if isinstance(model, RecurrentPPO):
        use_compact_buffer(model)
    initial = apply_signal_bias(model, action_names) if signal_bias else None

    total_updates = math.ceil(total_timesteps / steps_per_update)
    if log_every is None:
        log_every = 10 if total_updates >= 50 else 0
    stats = SMCTrainingCallback(kind=kind, children=[child.name for child in kids], total_updates=total_updates,
                                log_every=log_every, name=name, printer=printer)
    callbacks = CallbackList([stats, callback]) if callback is not None else stats
    start = time.perf_counter()
    model.learn(total_timesteps=total_timesteps, callback=callbacks, tb_log_name=name, progress_bar=False)
    wall_time = time.perf_counter() - start
    stats.on_training_end()  # no-op when SB3 already called it; makes the totals final either way

    best = stats.best
    returns = best.returns
    if best.state is not None:
        model.policy.load_state_dict(best.state)
    policy: StepPolicy = policy_from_model(model)
    if frame_stack > 1:
        policy = FrameStackPolicy(policy, frame_stack, observation_size)

    metadata = {
        "env_id": env_id,
        "dataset": smc_name_from_env_id(env_id),
        "datasets": _datasets(env_id),
        "kind": kind,
        "algo": algo,
        "policy": policy_name,
        "seed": seed,
        "hyperparameters": _jsonable({**settings, "policy_kwargs": policy_kwargs}),
        "n_envs": n_envs,
        "steps_per_update": steps_per_update,
        "signal_bias": signal_bias,
        "initial_action_probabilities": None if initial is None else [float(p) for p in initial],
        "frame_stack": frame_stack,
        "include_primitives": include_primitives,
        "children": [child.name for child in kids],
        "action_names": list(action_names),
        "wrapper": wrapper_settings,
        "env_kwargs": _jsonable(dict(env_kwargs or {})),
        "selected_update": best.best_update,
        "training_return": best.best_return if best.best_update is not None else None,
        "final_training_return": returns[-1] if returns else None,
        "training_returns": list(returns),
        "training_success_rates": [row["smc/success_rate"] for row in stats.history],
        "updates": len(returns),
        "total_timesteps": int(model.num_timesteps),
        "primitive_steps": stats.total_primitive_steps,
        "wall_time_s": wall_time,
        "torch_threads": torch.get_num_threads(),
    }
    return SMC(name, kind, policy, children=kids, include_primitives=include_primitives, metadata=metadata,
               model=model)


def _algorithm(algo: str) -> type:
    return {"RecurrentPPO": RecurrentPPO, "TRPO": TRPO}[algo]
