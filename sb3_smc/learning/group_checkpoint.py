"""A group's training saved between two updates and resumed bit for bit: ``train_smcs(..., checkpoints=folder)``.

A group of :func:`~sb3_smc.learning.batched.train_smcs` holds everything its SMCs will become: each SMC's model with
its optimizer, rollout state and random streams, its callback (records, best snapshot, early stop), the group's
native vector env with its worlds and generators, and the group's collection arrays. Between two updates that state
is complete, so it is pickled as a whole (shared references kept) to ``<folder>/group-<digest>.pkl``
(:func:`checkpoint_path`: a digest of the SMCs' names), written then renamed, at most every ``every`` seconds. The file
holds a key, a digest of what decides the training (the specs, the children they call with their weights' digests,
``stop_at_max_return``, ``lean_update``, the package's version), so only the same group resumes from it. A later call
with the same group and folder loads it and goes on from that update: each SMC is the one an uninterrupted call gives
(weights, records and selection); its wall time is the time trained, not the time between the calls. The file is
removed when the group is done.

What is not pickled is rebuilt: the children SMCs (taken from the call's ``children``), the loggers (same folder and
outputs: TensorBoard goes on in the SMC's folder, in a new events file), the callbacks' printer (the call's), the
lean update's patches of the model (entered again), modules that objects keep (imported), and ``VecEnvWrapper``'s
class attributes.

A checkpoint is a pickle, so it is signed: the file starts with an HMAC-SHA256 of the pickle under a secret key of
the user (:func:`checkpoint_key`: ``$SB3_SMC_CHECKPOINT_KEY``, else ``~/.config/sb3-smc/checkpoint.key``, made on
first use, readable by the user only), checked before anything is unpickled. A checkpoint from elsewhere (a run
directory someone shared, a file planted in ``checkpoints/``) fails the check and is never unpickled. One that cannot
be used (unsigned, signed with another key, damaged, or written by another version of this package) is reported
through ``printer`` and removed, and the group trains from the start (a file the system cannot read, an ``OSError``,
is left alone and the error raised). A save that fails is reported and the group trains on without saving. The
machines of a Ray cluster resume each other's checkpoints where they share the key file (the same home folder, or
``SB3_SMC_CHECKPOINT_KEY`` naming one file).
"""

from __future__ import annotations

import hashlib
import hmac
import importlib
import importlib.metadata
import inspect
import io
import json
import os
import pickle
import sys
import tempfile
import time
import types
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import cloudpickle
from stable_baselines3.common.logger import HumanOutputFormat, Logger, TensorBoardOutputFormat, make_output_format
from stable_baselines3.common.vec_env import VecEnvWrapper

from pixelworld_env.atomic import atomic_write
from sb3_smc.errors import SMCError
from sb3_smc.records import TrainingSpec
from sb3_smc.smc.smc import SMC

__all__ = ["KEY_ENV", "GroupCheckpoint", "checkpoint_key", "checkpoint_path"]

FORMAT = 2  #: the layout of a checkpoint's payload (2: the group's slices know their index, 2026-11-28)
MAGIC = b"sb3-smc group checkpoint, HMAC-SHA256 signed\n"
"""How a checkpoint file starts; 32 bytes of HMAC follow, then the pickle."""
KEY_ENV = "SB3_SMC_CHECKPOINT_KEY"
"""The environment variable naming the key file that signs checkpoints (:func:`checkpoint_key`)."""


def checkpoint_key() -> bytes:
    """The user's secret key that signs group checkpoints: the file ``$SB3_SMC_CHECKPOINT_KEY`` names, else
    ``$XDG_CONFIG_HOME/sb3-smc/checkpoint.key`` (``~/.config`` by default), 32 random bytes made on first use with
    permissions 0600 (made whole, then linked into place: two processes starting at once agree on one key)."""
    named = os.environ.get(KEY_ENV)
    config = Path(os.environ.get("XDG_CONFIG_HOME") or Path.home() / ".config")
    path = Path(named) if named else config / "sb3-smc" / "checkpoint.key"
    if not path.is_file():
        path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")  # 0600, its own
        tmp = Path(name)
        try:
            os.write(fd, os.urandom(32))
            os.fsync(fd)
        finally:
            os.close(fd)
        try:
            os.link(tmp, path)
        except FileExistsError:
            pass  # another process made it first: its key is the key
        finally:
            tmp.unlink(missing_ok=True)
    key = path.read_bytes()
    if len(key) < 16:
        raise SMCError(f"{path}: a checkpoint key has at least 16 bytes, this file {len(key)} (remove it to make a "
                       "new one)")
    return key


class GroupCheckpoint:
    """The checkpoint file of one group: :meth:`load` at the start, :meth:`save` after updates, :meth:`remove` at
    the end.

    :param folder: where the group's file goes.
    :param specs: the group's specs, in order.
    :param children: the SMCs they call, by name (what the pickle refers to by name).
    :param every: the least seconds between two saves (``0``: after every update).
    :param settings: the other arguments that decide the training (in the key).
    :param printer: where a checkpoint that cannot be read is reported.
    """

    def __init__(self, folder: str | Path, specs: Sequence[TrainingSpec], children: Sequence[SMC], *, every: float,
                 settings: Mapping[str, Any], printer: Callable[[str], None]) -> None:
        what = {"specs": [spec.to_dict() for spec in specs], "settings": dict(settings), "version": _version(),
                "children": [[smc.name, _weights(smc)] for smc in children]}
        self.key = hashlib.sha256(json.dumps(what, sort_keys=True).encode()).hexdigest()
        self.path = checkpoint_path(folder, [spec.name for spec in specs])
        self.children = {smc.name: smc for smc in children}
        self.every, self.printer = every, printer
        self._saved = time.monotonic()
        self.failed = False  #: a save failed: the group trains on without saving

    def load(self) -> Any | None:
        """The state saved by :meth:`save`, or ``None`` where there is none (or it cannot be read: reported and
        removed)."""
        for stale in self.path.parent.glob(f".{self.path.name}.*.tmp"):  # a save killed while writing
            stale.unlink(missing_ok=True)
        if not self.path.is_file():
            return None
        try:
            data = self.path.read_bytes()
            head, signature, body = data[:len(MAGIC)], data[len(MAGIC):len(MAGIC) + 32], data[len(MAGIC) + 32:]
            if head != MAGIC:
                raise ValueError("not a signed checkpoint of this package; not unpickled")
            if not hmac.compare_digest(signature, hmac.new(checkpoint_key(), body, hashlib.sha256).digest()):
                raise ValueError("its signature is not this user's key's (written elsewhere, or damaged); not "
                                 "unpickled")
            payload = _Unpickler(io.BytesIO(body), self.children, self.printer).load()
            if not isinstance(payload, dict) or payload.get("format") != FORMAT or payload.get("key") != self.key:
                raise ValueError("not a checkpoint of this group (its specs, children, settings or the package's "
                                 "version differ)")
        except (OSError, MemoryError):  # the file may be fine: kept, and the error is the caller's
            raise
        except Exception as err:  # damaged, or another group's or version's: the group starts again
            self.printer(f"{self.path}: cannot resume from it ({type(err).__name__}: {err}); trained from the start")
            self.remove()
            return None
        self._saved = time.monotonic()
        return payload["state"]

    def due(self) -> bool:
        """Whether ``every`` seconds have passed since the last save (or the start), and saving has not failed."""
        return not self.failed and time.monotonic() - self._saved >= self.every

    def save(self, state: Any) -> None:
        """Write ``state`` (the group's jobs, env and collection, between two updates) atomically. A save that fails
        (a full disk, something that cannot be pickled) never fails the training: it is reported through
        ``printer`` and the group trains on without saving (a stop then resumes from the last save, if any)."""
        try:
            buffer = io.BytesIO()
            _Pickler(buffer, self.printer).dump({"format": FORMAT, "key": self.key, "state": state})
            body = buffer.getvalue()
            atomic_write(self.path, MAGIC + hmac.new(checkpoint_key(), body, hashlib.sha256).digest() + body)
        except Exception as err:
            self.failed = True
            self.printer(f"{self.path}: cannot save the group's training ({type(err).__name__}: {err}); it trains on "
                         "without checkpoints")
        self._saved = time.monotonic()

    def remove(self) -> None:
        self.path.unlink(missing_ok=True)


def checkpoint_path(folder: str | Path, names: Sequence[str]) -> Path:
    """The file of the group of SMCs ``names`` (in the group's order) in ``folder``: ``group-<digest of the
    names>.pkl``, which a scheduler finds without building the specs (the file holds the digest of everything that
    decides the training, checked when it is loaded)."""
    digest = hashlib.sha256("\n".join(names).encode()).hexdigest()[:20]
    return Path(folder) / f"group-{digest}.pkl"


class _Pickler(cloudpickle.CloudPickler):
    """Children SMCs, loggers and the printer by reference; ``VecEnvWrapper`` s without their class attributes;
    functions made at run time (a ``"lin_<x>"`` learning-rate schedule) by value, as SB3 saves them."""

    def __init__(self, file: io.BytesIO, printer: Callable[[str], None]) -> None:
        super().__init__(file, protocol=pickle.HIGHEST_PROTOCOL)
        self.printer = printer

    def persistent_id(self, obj: Any) -> Any:
        if isinstance(obj, SMC):
            return ("smc", obj.name)
        if isinstance(obj, Logger):
            return ("logger", obj.dir, tuple(_output_kind(fmt) for fmt in obj.output_formats),
                    dict(obj.name_to_value), dict(obj.name_to_count), dict(obj.name_to_excluded), obj.level)
        if obj is self.printer:
            return ("printer",)
        if isinstance(obj, types.ModuleType):  # a module an object keeps (the leaves' compiled calls)
            return ("module", obj.__name__)
        return None

    def reducer_override(self, obj: Any) -> Any:
        if isinstance(obj, VecEnvWrapper):
            state = {k: v for k, v in vars(obj).items() if k != "class_attributes"}
            return _wrapper, (type(obj), state)
        return super().reducer_override(obj)


class _Unpickler(pickle.Unpickler):
    def __init__(self, file: io.BytesIO, children: Mapping[str, SMC], printer: Callable[[str], None]) -> None:
        super().__init__(file)
        self.children, self.printer = children, printer

    def persistent_load(self, pid: Any) -> Any:
        if pid[0] == "smc":
            if pid[1] not in self.children:
                raise ValueError(f"it calls {pid[1]!r}, which this call does not give")
            return self.children[pid[1]]
        if pid[0] == "logger":
            folder, kinds, values, counts, excluded, level = pid[1:]
            outputs = [HumanOutputFormat(sys.stdout) if kind == "stdout" else make_output_format(kind, folder)
                       for kind in kinds]
            logger = Logger(folder=folder, output_formats=outputs)
            logger.name_to_value.update(values)
            logger.name_to_count.update(counts)
            logger.name_to_excluded.update(excluded)
            logger.set_level(level)
            return logger
        if pid[0] == "printer":
            return self.printer
        if pid[0] == "module":
            return importlib.import_module(pid[1])
        raise pickle.UnpicklingError(f"unknown reference {pid[0]!r}")


def _weights(smc: SMC) -> str | None:
    """A digest of what ``smc`` computes: its trained weights' digest, else its pickled policy's (a scripted or
    compiled numpy policy), else nothing but its name."""
    if smc.digest is not None:
        return smc.digest
    try:
        return hashlib.sha256(cloudpickle.dumps(smc.policy)).hexdigest()
    except Exception:  # a policy that cannot be pickled: the name only
        return None


def _version() -> str:
    try:
        return importlib.metadata.version("sb3-smc")
    except importlib.metadata.PackageNotFoundError:  # run from a checkout that is not installed
        return "unknown"


def _output_kind(fmt: Any) -> str:
    """The kind of a logger's output that a resumed logger opens again (TensorBoard, or the console)."""
    if isinstance(fmt, TensorBoardOutputFormat):
        return "tensorboard"
    if isinstance(fmt, HumanOutputFormat) and fmt.file is sys.stdout:
        return "stdout"
    raise SMCError(f"a group's checkpoint cannot reopen a logger output {type(fmt).__name__}")


def _wrapper(cls: type[VecEnvWrapper], state: dict[str, Any]) -> VecEnvWrapper:
    wrapper = cls.__new__(cls)
    vars(wrapper).update(state)
    wrapper.class_attributes = dict(inspect.getmembers(cls))
    return wrapper
