"""A trained model as a file that loads without running code: the weights as tensors in a `safetensors
<https://huggingface.co/docs/safetensors>`_ file, everything else as JSON in its header, and the model rebuilt from
them with its algorithm's class.

Stable-Baselines3's own ``model.save`` archive pickles part of the model (its spaces, schedules, policy class and
buffers) with cloudpickle, so loading one runs whatever code its author put there. This file holds:

* tensors: the policy's ``state_dict`` (``policy/<key>``), the optimiser's state (``policy.optimizer/state/<i>/<key>``;
  absent in a compact file), the observation space's bounds (``space/low``, ``space/high``);
* its metadata (one JSON string, :data:`METADATA_KEY`): ``format``, ``version``, ``algo``, ``policy_class`` (a class
  path), ``attributes`` (the constructor's arguments and the training counters, in
  :func:`~sb3_smc.core.hyperparameters.encode_value`'s JSON form), ``observation_space`` (dtype, shape),
  ``action_space`` (``n``, ``start``), ``optimizer`` (the optimiser's parameter groups and scalar state).

:func:`decode_model` checks all of it before it builds anything: the file's size, the header, every name and type;
classes are imported only from the modules of :data:`~sb3_smc.core.hyperparameters.SAFE_CLASS_MODULES` (another
module's class needs ``trust=True``); the policy is first built on PyTorch's ``meta`` device, where it allocates
nothing, and its parameters' names and shapes must be the file's before the real one is built. What is not stored is
runtime state that training sets again (the last observations, the episode buffers): a rebuilt model acts exactly as
the saved one (the same weights, bit for bit) and trains on from where it stopped.
"""

from __future__ import annotations

import inspect
import json
from collections import deque
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from sb3_smc.core.hyperparameters import ALGORITHM_REGISTRY, SCHEDULE_KEYS, algorithm_of, decode_value, encode_value
from sb3_smc.errors import SMCError
from sb3_smc.library.errors import CorruptModelError, LibraryError

if TYPE_CHECKING:
    from stable_baselines3.common.on_policy_algorithm import OnPolicyAlgorithm

__all__ = ["MAX_MODEL_BYTES", "MODEL_FORMAT", "MODEL_SUFFIX", "MODEL_VERSION", "check_model_bytes", "decode_model",
           "encode_model"]

MODEL_FORMAT = "sb3-smc-model"
"""The ``format`` of a model file's metadata."""
MODEL_VERSION = 1
"""The version of a model file's layout written."""
MODEL_SUFFIX = ".safetensors"
METADATA_KEY = "sb3_smc"
"""The one entry of the file's safetensors metadata: the JSON of the model's settings (keys sorted)."""
MAX_MODEL_BYTES = 256 * 2**20
"""The largest model file read (256 MiB; the paper's SMCs take 20-80 KB): a larger one is refused before it is read."""
MAX_ROLLOUT_VALUES = 10**8
"""The most values a rebuilt model's rollout buffer may hold (``n_steps x n_envs x`` observation size)."""

_COUNTERS = ("num_timesteps", "_total_timesteps", "_num_timesteps_at_start", "_n_updates", "_episode_num",
             "_current_progress_remaining", "n_envs", "start_time")
"""Training counters stored beside the constructor's arguments (numbers; ``start_time`` is 0.0 before training)."""
_NOT_STORED = {"policy", "env", "device", "_init_setup_model", "verbose", "tensorboard_log"}
"""Constructor arguments a file never sets: the environment and device are the caller's, a library's model is quiet,
and a TensorBoard folder written by another machine is not to be written to."""
_PREFIXES = ("policy/", "policy.optimizer/state/", "space/")


def _error(where: str, what: str) -> CorruptModelError:
    return CorruptModelError(f"{where}: {what}")


def _schedule_json(value: Any, key: str, where: str) -> Any:
    """A schedule's JSON form: a number (also for a constant schedule), or ``"lin_<x>"`` for a linear one (both
    recognised by their values)."""
    if not callable(value):
        return encode_value(value, key)
    start = float(value(1.0))
    points = [(p, float(value(p))) for p in (0.0, 0.25, 0.5, 0.75)]
    if all(v == start for _, v in points):
        return start
    if all(abs(v - p * start) <= 1e-12 * max(1.0, abs(start)) for p, v in points):
        return f"lin_{start!r}"
    raise SMCError(f"{where}: {key} is a schedule that is neither constant nor linear; a library stores only those "
                   "(a number, or 'lin_<initial value>')")


def _constructor_parameters(cls: type) -> list[str]:
    return [p for p in inspect.signature(cls).parameters if p not in ("args", "kwargs")]


def _attributes(model: OnPolicyAlgorithm, where: str) -> dict[str, Any]:
    attributes: dict[str, Any] = {}
    for key in _constructor_parameters(type(model)):
        if key in _NOT_STORED or key not in model.__dict__:
            continue
        value = model.__dict__[key]
        attributes[key] = _schedule_json(value, key, where) if key in SCHEDULE_KEYS else encode_value(value, key)
    for key in _COUNTERS:
        if key in model.__dict__:
            attributes[key] = encode_value(model.__dict__[key], key)
    return attributes


def encode_model(model: OnPolicyAlgorithm, *, optimizer_state: bool = True, where: str = "model") -> bytes:
    """The bytes of ``model``'s file (see the module's docstring). ``optimizer_state=False``: a compact file without
    the optimiser's running state (only further training uses it); the parameter groups are kept."""
    import torch
    from gymnasium import spaces
    from safetensors.torch import save

    algo = algorithm_of(type(model))
    if algo is None:
        raise SMCError(f"{where}: cannot store a {type(model).__name__} model (supported: "
                       f"{', '.join(ALGORITHM_REGISTRY)}; sb3_smc.register_algorithm adds a learner)")
    obs, act = model.observation_space, model.action_space
    if not isinstance(obs, spaces.Box) or not isinstance(act, spaces.Discrete):
        raise SMCError(f"{where}: a library stores models with a Box observation space and a Discrete action space, "
                       f"not {obs} and {act}")
    tensors: dict[str, torch.Tensor] = {}
    for key, value in model.policy.state_dict().items():
        tensors[f"policy/{key}"] = value.detach().cpu().contiguous().clone()
    optimizer = model.policy.optimizer.state_dict()
    scalars: dict[str, dict[str, Any]] = {}
    if optimizer_state:
        for index, state in optimizer["state"].items():
            for key, value in state.items():
                if isinstance(value, torch.Tensor):
                    tensors[f"policy.optimizer/state/{index}/{key}"] = value.detach().cpu().contiguous().clone()
                else:
                    scalars.setdefault(str(index), {})[key] = encode_value(value, f"optimizer state {key}")
    tensors["space/low"] = torch.as_tensor(obs.low).contiguous().clone()
    tensors["space/high"] = torch.as_tensor(obs.high).contiguous().clone()
    policy_class = type(model.policy)
    metadata = {
        "format": MODEL_FORMAT, "version": MODEL_VERSION, "algo": algo,
        "policy_class": f"{policy_class.__module__}.{policy_class.__qualname__}",
        "attributes": _attributes(model, where),
        "observation_space": {"dtype": str(obs.dtype), "shape": list(obs.shape)},
        "action_space": {"n": int(act.n), "start": int(act.start)},
        "optimizer": {"param_groups": encode_value(optimizer["param_groups"], "optimizer"), "scalars": scalars},
    }
    # one metadata string: safetensors writes a map of several in no fixed order, and the file is named by its bytes
    return save(tensors, metadata={METADATA_KEY: json.dumps(metadata, sort_keys=True, allow_nan=False)})


def _header(data: bytes, where: str) -> tuple[dict[str, Any], dict[str, Any]]:
    """``(tensor entries, metadata as JSON)`` of a safetensors file, its layout checked without reading a tensor."""
    if len(data) > MAX_MODEL_BYTES:
        raise _error(where, f"{len(data)} bytes, more than a model file may hold ({MAX_MODEL_BYTES})")
    if len(data) < 8:
        raise _error(where, f"truncated ({len(data)} bytes; a model file starts with an 8-byte header length)")
    size = int.from_bytes(data[:8], "little")
    if size > len(data) - 8:
        raise _error(where, f"truncated or not a model file (its header says {size} bytes, the file has "
                            f"{len(data) - 8} after the length)")
    try:
        header = json.loads(data[8:8 + size].decode("utf-8"))
    except (ValueError, RecursionError) as err:  # not JSON, not UTF-8, an endless integer, nested beyond reading
        raise _error(where, f"not a model file (its header is not JSON this package reads: {str(err)[:200]})") \
            from None
    if not isinstance(header, dict) or not isinstance(header.get("__metadata__"), dict):
        raise _error(where, "not an sb3-smc model file (no metadata in its header)")
    raw = header.pop("__metadata__")
    try:
        metadata = json.loads(raw[METADATA_KEY])
    except (KeyError, TypeError, ValueError, RecursionError) as err:
        raise _error(where, f"not an sb3-smc model file (its metadata has no JSON {METADATA_KEY!r}: {err!r})") from None
    if not isinstance(metadata, dict) or metadata.get("format") != MODEL_FORMAT:
        found = metadata.get("format") if isinstance(metadata, dict) else metadata
        raise _error(where, f"not an sb3-smc model file (format {found!r}, expected {MODEL_FORMAT!r})")
    if metadata.get("version") != MODEL_VERSION:
        raise _error(where, f"model file version {metadata.get('version')!r}; this sb3-smc reads version "
                            f"{MODEL_VERSION} (a newer sb3-smc wrote it?)")
    for field, kind in (("algo", str), ("policy_class", str), ("attributes", dict), ("observation_space", dict),
                        ("action_space", dict), ("optimizer", dict)):
        if not isinstance(metadata.get(field), kind):
            raise _error(where, f"metadata field {field!r} must be a {kind.__name__}, got "
                                f"{type(metadata.get(field)).__name__}")
    for name, info in header.items():
        if not isinstance(info, dict) or not name.startswith(_PREFIXES):
            raise _error(where, f"unexpected tensor {name!r}")
        offsets = info.get("data_offsets")
        if not (isinstance(offsets, list) and len(offsets) == 2 and all(isinstance(o, int) for o in offsets)
                and 0 <= offsets[0] <= offsets[1] <= len(data) - 8 - size):
            raise _error(where, f"tensor {name!r} lies outside the file (offsets {offsets})")
    return header, metadata


def check_model_bytes(data: bytes, algo: str | None, where: str) -> dict[str, Any]:
    """The metadata of a model file, after checking its layout and that it holds an ``algo`` model (``None``: any
    algorithm the package trains) (:class:`CorruptModelError` otherwise); nothing is built or imported."""
    header, metadata = _header(data, where)
    if metadata["algo"] not in ALGORITHM_REGISTRY:
        raise _error(where, f"holds a model of unknown algorithm {metadata['algo']!r} (known: "
                            f"{', '.join(ALGORITHM_REGISTRY)})")
    if algo is not None and metadata["algo"] != algo:
        raise _error(where, f"holds a {metadata['algo']} model, but the manifest says {algo}")
    if not any(name.startswith("policy/") for name in header):
        raise _error(where, "holds no policy weights")
    return metadata


def _space(metadata: Mapping[str, Any], tensors: Mapping[str, Any], where: str) -> tuple[Any, Any]:
    import numpy as np
    from gymnasium import spaces

    obs, act = metadata["observation_space"], metadata["action_space"]
    shape, dtype = obs.get("shape"), obs.get("dtype")
    if not (isinstance(shape, list) and all(isinstance(s, int) and s > 0 for s in shape)) or dtype not in (
            "float32", "float64"):
        raise _error(where, f"observation space {obs} is not a float32/float64 Box of a positive shape")
    import torch

    low, high = tensors.get("space/low"), tensors.get("space/high")
    if low is None or high is None or list(low.shape) != shape or list(high.shape) != shape:
        raise _error(where, f"the observation space's bounds are missing or not of its shape {shape}")
    if low.dtype not in (torch.float32, torch.float64) or high.dtype not in (torch.float32, torch.float64) or bool(
            (low > high).any()):
        raise _error(where, "the observation space's bounds must be float32/float64 tensors with low <= high")
    n, start = act.get("n"), act.get("start", 0)
    if not (isinstance(n, int) and not isinstance(n, bool) and 0 < n <= 10_000 and isinstance(start, int)
            and not isinstance(start, bool) and abs(start) < 2**31):
        raise _error(where, f"action space {act!r:.200} is not a Discrete space of 1-10000 actions")
    box = spaces.Box(low.numpy().astype(dtype), high.numpy().astype(dtype), dtype=np.dtype(dtype))
    return box, spaces.Discrete(n, start=start)


def _check_sizes(attributes: Mapping[str, Any], observation_size: int, where: str) -> None:
    n_steps, n_envs = attributes.get("n_steps", 1), attributes.get("n_envs", 1)
    for key, value in (("n_steps", n_steps), ("n_envs", n_envs)):
        if not isinstance(value, int) or isinstance(value, bool) or value < 1:
            raise _error(where, f"attribute {key} must be a positive integer, got {value!r}")
    if n_steps * n_envs * observation_size > MAX_ROLLOUT_VALUES:
        raise _error(where, f"its rollout buffer would hold {n_steps} x {n_envs} x {observation_size} values, more "
                            f"than {MAX_ROLLOUT_VALUES}")


MAX_POLICY_WIDTH = 65_536
"""The largest integer a model file's ``policy_kwargs`` may hold (a layer's width, a layer count); the paper's: 32."""
MAX_POLICY_NUMBERS = 256
"""The most integers a model file's ``policy_kwargs`` may hold (its layers' widths and counts)."""
MAX_LAYERS = 64
"""The most layers a model file's policy may have: ``n_lstm_layers``, and the length of any list of layer widths."""


def _check_policy_size(policy_kwargs: Mapping[str, Any], where: str) -> None:
    """Refuse a policy whose settings ask for more layers or wider ones than any SMC has, before anything is built
    (even on the meta device, thousands of layers take minutes)."""
    numbers: list[int] = []

    def walk(value: Any) -> None:
        if isinstance(value, bool):
            return
        if isinstance(value, int):
            numbers.append(value)
        elif isinstance(value, dict):
            for item in value.values():
                walk(item)
        elif isinstance(value, list):
            if len(value) > MAX_LAYERS:
                raise _error(where, f"its policy's settings list {len(value)} layers (at most {MAX_LAYERS})")
            for item in value:
                walk(item)

    walk(dict(policy_kwargs))
    layers = policy_kwargs.get("n_lstm_layers", 1)
    if isinstance(layers, int) and not isinstance(layers, bool) and layers > MAX_LAYERS:
        raise _error(where, f"its policy's settings ask for {layers:,} recurrent layers (at most {MAX_LAYERS})")
    if len(numbers) > MAX_POLICY_NUMBERS or any(abs(n) > MAX_POLICY_WIDTH for n in numbers):
        raise _error(where, f"its policy's settings ask for {len(numbers)} layer sizes or counts up to "
                            f"{max(map(abs, numbers), default=0):,} (at most {MAX_POLICY_NUMBERS} numbers of at most "
                            f"{MAX_POLICY_WIDTH:,})")


def decode_model(data: bytes, algo: str, where: str, *, trust: bool = False) -> OnPolicyAlgorithm:
    """The ``algo`` model a file holds, rebuilt on the CPU (see the module's docstring).

    :param trust: import classes from any module (a library of your own that names your own feature extractor);
        without it only those of :data:`~sb3_smc.core.hyperparameters.SAFE_CLASS_MODULES` are imported.
    :raises CorruptModelError: naming ``where`` and what is wrong, before anything is built.
    """
    import torch
    from safetensors import SafetensorError
    from safetensors.torch import load

    metadata = check_model_bytes(data, algo, where)
    try:
        tensors = load(data)
    except (SafetensorError, ValueError, RuntimeError) as err:
        raise _error(where, f"its tensors cannot be read ({err})") from None
    obs_space, action_space = _space(metadata, tensors, where)
    try:
        policy_class = decode_value({"__class__": metadata["policy_class"]}, "policy_class", trust=trust)
        attributes = {key: decode_value(value, key, trust=trust) for key, value in metadata["attributes"].items()}
        param_groups = decode_value(metadata["optimizer"].get("param_groups"), "optimizer", trust=trust)
    except SMCError as err:
        raise _error(where, str(err)) from None
    from stable_baselines3.common.policies import BasePolicy

    if not (isinstance(policy_class, type) and issubclass(policy_class, BasePolicy)):
        raise _error(where, f"policy_class {metadata['policy_class']!r} is not a Stable-Baselines3 policy")
    try:
        cls = ALGORITHM_REGISTRY[algo].load_class()
    except SMCError as err:
        raise LibraryError(f"{where}: {err}") from err
    allowed = set(_constructor_parameters(cls)) - _NOT_STORED
    unknown = sorted(set(attributes) - allowed - set(_COUNTERS))
    if unknown:
        raise _error(where, f"attributes {unknown} are not {algo}'s (it takes {sorted(allowed)})")
    for key in _COUNTERS:
        value = attributes.get(key, 0)
        if isinstance(value, bool) or not isinstance(value, int | float) or not abs(value) < 2**63:
            raise _error(where, f"attribute {key} must be a number below 2**63, got {value!r:.100}")
    _check_sizes(attributes, int(obs_space.shape[0]), where)
    policy_kwargs = attributes.get("policy_kwargs") or {}
    if not isinstance(policy_kwargs, dict):
        raise _error(where, f"attribute policy_kwargs must be a mapping, got {policy_kwargs!r:.100}")
    _check_policy_size(policy_kwargs, where)
    weights = {key[len("policy/"):]: value for key, value in tensors.items() if key.startswith("policy/")}
    try:
        # a subclass whose layers are made on the meta device too (SB3 moves some to ``policy.device``)
        on_meta = type("MetaProbe", (policy_class,), {"device": property(lambda self: torch.device("meta"))})
        with torch.device("meta"):
            probe = on_meta(obs_space, action_space, lambda _: 0.0, **policy_kwargs)
        shapes = {key: tuple(value.shape) for key, value in probe.state_dict().items()}
    except Exception as err:  # noqa: BLE001 - any failure to build the policy from the file's settings
        raise _error(where, f"its policy cannot be built from its settings ({type(err).__name__}: {err})") from None
    stored = {key: tuple(value.shape) for key, value in weights.items()}
    if shapes != stored:
        wrong = sorted(set(shapes) ^ set(stored)) or sorted(k for k in shapes if shapes[k] != stored[k])
        raise _error(where, f"its weights do not fit its policy's settings (first difference: {wrong[0]!r})")
    try:
        build: Any = cls  # as SB3's own load builds it: the settings come next, from the file
        model = build(policy=policy_class, env=None, device="cpu", _init_setup_model=False)
        model.__dict__.update(attributes)
        model.observation_space, model.action_space = obs_space, action_space
        model.n_envs = int(attributes.get("n_envs", 1))
        model._setup_model()
        optimizer = model.policy.optimizer.state_dict()
        if param_groups is not None:
            optimizer["param_groups"] = [{**group, "params": mine["params"]} for group, mine in
                                         zip(param_groups, optimizer["param_groups"], strict=True)]
        state: dict[int, dict[str, Any]] = {}
        for key, value in tensors.items():
            if key.startswith("policy.optimizer/state/"):
                index, name = key[len("policy.optimizer/state/"):].split("/", 1)
                state.setdefault(int(index), {})[name] = value
        for index, values in (metadata["optimizer"].get("scalars") or {}).items():
            state.setdefault(int(index), {}).update(values)
        optimizer["state"] = state
        parameters: dict[str, Any] = {"policy": weights, "policy.optimizer": optimizer}
        model.set_parameters(parameters, exact_match=True, device="cpu")
    except CorruptModelError:
        raise
    except Exception as err:  # noqa: BLE001 - SB3 and torch raise many kinds of errors for settings that do not fit
        raise _error(where, f"cannot rebuild its {algo} model ({type(err).__name__}: {err})") from None
    model._last_obs = None
    model.ep_info_buffer = deque(maxlen=model._stats_window_size)
    model.ep_success_buffer = deque(maxlen=model._stats_window_size)
    return model
