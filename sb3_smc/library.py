"""``SMCLibrary``: a directory of trained SMCs with a versioned manifest.

Layout on disk::

    my-library/
        manifest.json        {"format": "sb3-smc-library", "version": 1, "created_with": {...}, "smcs": {...}}
        models/<name>.zip    one SB3 ``model.save`` archive per SMC

Each manifest entry records what the SMC is (kind, algorithm, action names, observation layout, children by
name) and where it comes from (env id, datasets, seed, selected update, training return, test score, the whole
``SMC.metadata``), plus the SHA-256 of its model file. :meth:`SMCLibrary.load` validates all of it and rebuilds
every :class:`~sb3_smc.smc.SMC` (children first, its policy by :func:`sb3_smc.policies.policy_from_model`);
:meth:`SMCLibrary.save` writes a complete copy into a temporary directory beside the target and swaps it in with
two renames, so an interrupted save never leaves a half-written library. See ``docs/library.md``.
"""

from __future__ import annotations

import difflib
import hashlib
import json
import os
import platform
import re
import shutil
import tempfile
import uuid
import zipfile
from collections.abc import Iterator, Mapping, Sequence
from importlib import metadata as importlib_metadata
from pathlib import Path
from typing import Any

import numpy as np

from sb3_smc.smc import HAND_SIZE, SIGNALS, SMC, observation_size, smc_action_names

__all__ = [
    "FORMAT",
    "FORMAT_VERSION",
    "CorruptModelError",
    "LayoutMismatchError",
    "LibraryError",
    "ManifestError",
    "MissingChildError",
    "SMCLibrary",
    "UnknownSMCError",
]

FORMAT = "sb3-smc-library"
"""Value of the manifest's ``format`` field."""
FORMAT_VERSION = 1
"""Manifest version this module writes and reads."""
MANIFEST = "manifest.json"
MODELS = "models"
_SAVING = ".saving-"
_OLD = ".old-"


# ---------------------------------------------------------------------------------------------------------------
# Errors
# ---------------------------------------------------------------------------------------------------------------

class LibraryError(ValueError):
    """Any problem with an SMC library (base class of the errors below)."""


class ManifestError(LibraryError):
    """The manifest is missing, unreadable, of another format or version, or has wrong or missing fields."""


class UnknownSMCError(LibraryError, KeyError):
    """No SMC of that name in the library (the message suggests close names)."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


class MissingChildError(LibraryError):
    """An SMC's child is not in the library."""


class LayoutMismatchError(LibraryError):
    """Action names or observation size disagree (manifest vs. model, or SMC vs. environment)."""


class CorruptModelError(LibraryError):
    """A model file is missing, truncated, corrupt, modified since it was saved, or not loadable."""


# ---------------------------------------------------------------------------------------------------------------
# Helpers
# ---------------------------------------------------------------------------------------------------------------

def _algorithms() -> dict[str, type]:
    """Algorithm name (as in the manifest's ``algo``) -> SB3 class."""
    from sb3_contrib import TRPO, RecurrentPPO
    from stable_baselines3 import PPO

    return {"RecurrentPPO": RecurrentPPO, "TRPO": TRPO, "PPO": PPO}


ALGORITHMS = ("RecurrentPPO", "TRPO", "PPO")
"""Algorithms whose models a library stores (loaded with the class of the same name, ``device="cpu"``)."""


def _suggest(name: str, names: Sequence[str], empty: str = " (the library is empty)") -> str:
    close = difflib.get_close_matches(name, list(names), n=3, cutoff=0.5)
    if close:
        return f"; did you mean {' or '.join(repr(c) for c in close)}?"
    if not names:
        return empty
    shown = ", ".join(repr(n) for n in list(names)[:10])
    return f"; it has {len(names)}: {shown}{', ...' if len(names) > 10 else ''}"


def _versions() -> dict[str, str]:
    def version(dist: str) -> str:
        try:
            return importlib_metadata.version(dist)
        except importlib_metadata.PackageNotFoundError:
            return "unknown"

    return {"sb3_smc": version("sb3-smc"), "stable_baselines3": version("stable-baselines3"),
            "sb3_contrib": version("sb3-contrib"), "torch": version("torch"), "gymnasium": version("gymnasium"),
            "numpy": version("numpy"), "python": platform.python_version()}


def _jsonable(value: Any) -> Any:
    """``value`` as JSON data: numpy scalars/arrays become numbers/lists, tuples lists, other objects ``repr``."""
    if value is None or isinstance(value, bool | str):
        return value
    if isinstance(value, int | float):
        return value
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, Mapping):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple | set | frozenset):
        return [_jsonable(v) for v in value]
    if isinstance(value, Path):
        return str(value)
    return repr(value)


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _fsync_file(path: Path) -> None:
    with open(path, "rb") as handle:
        os.fsync(handle.fileno())


def _fsync_dir(path: Path) -> None:
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:  # pragma: no cover - platforms without directory descriptors
        return
    try:
        os.fsync(fd)
    except OSError:  # pragma: no cover
        pass
    finally:
        os.close(fd)


_SAFE = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.+=-]*")


def _model_files(names: Sequence[str]) -> dict[str, str]:
    """``name -> "models/<stem>.zip"``: the name itself when it is a safe file name, else a cleaned name + hash."""
    files: dict[str, str] = {}
    taken: set[str] = set()
    for name in names:
        stem = name
        if not _SAFE.fullmatch(name) or len(name) > 100 or name.casefold() in taken:
            cleaned = re.sub(r"[^A-Za-z0-9_.+=-]", "_", name)[:80].lstrip("._") or "smc"
            stem = f"{cleaned}-{hashlib.sha256(name.encode()).hexdigest()[:10]}"
        taken.add(stem.casefold())
        files[name] = f"{MODELS}/{stem}.zip"
    return files


def observation_layout(n_children: int, n_actions: int) -> dict[str, int]:
    """The manifest's ``observation``: total ``size``, then the parts in order (window, outcomes, previous action)."""
    return {"size": observation_size(n_children, n_actions), "window": HAND_SIZE, "outcomes": n_children,
            "previous_action": n_actions}


def _datasets(meta: Mapping[str, Any]) -> list[str]:
    value = meta.get("datasets") or meta.get("dataset")
    if not value:
        return []
    if isinstance(value, str):
        return [value]
    return [str(v) for v in value]


def _model_layout(model: Any) -> tuple[int | None, tuple[int, ...] | None]:
    """``(number of actions, observation shape)`` of an SB3 model (``None`` where not Discrete / Box)."""
    from gymnasium import spaces

    action_space = getattr(model, "action_space", None)
    obs_space = getattr(model, "observation_space", None)
    n = int(action_space.n) if isinstance(action_space, spaces.Discrete) else None
    shape = tuple(int(s) for s in obs_space.shape) if isinstance(obs_space, spaces.Box) else None
    return n, shape


def _frame_stack(smc: SMC) -> int:
    """How many observations the SMC's model sees at once (``FrameStackPolicy``, else 1)."""
    from sb3_smc.training import FrameStackPolicy

    return smc.policy.n_stack if isinstance(smc.policy, FrameStackPolicy) else 1


def _check_model_layout(name: str, model: Any, action_names: Sequence[str], size: int, where: str,
                        frame_stack: int = 1) -> None:
    n, shape = _model_layout(model)
    if n != len(action_names):
        have = f"{n} actions" if n is not None else f"action space {getattr(model, 'action_space', None)}"
        raise LayoutMismatchError(
            f"SMC {name!r}: {where} has {have}, but its action names are {len(action_names)}: {list(action_names)}")
    if shape != (frame_stack * size,):
        have = f"observation shape {shape}" if shape is not None else \
            f"observation space {getattr(model, 'observation_space', None)}"
        stacked = f", {frame_stack} stacked" if frame_stack > 1 else ""
        raise LayoutMismatchError(
            f"SMC {name!r}: {where} has {have}, but its observation layout is ({frame_stack * size},) "
            f"({HAND_SIZE} window + {size - HAND_SIZE - len(action_names)} outcomes + "
            f"{len(action_names)} previous action{stacked})")


def _same_parameters(a: Any, b: Any) -> bool:
    if type(a) is not type(b):
        return False
    sa, sb = a.policy.state_dict(), b.policy.state_dict()
    return sa.keys() == sb.keys() and all(bool((sa[k] == sb[k]).all()) for k in sa)


def _same_smc(a: SMC, b: SMC) -> bool:
    """Same name, kind, children names, primitives and model parameters (or the very same object)."""
    if a is b:
        return True
    if (a.name, a.kind, a.include_primitives) != (b.name, b.kind, b.include_primitives):
        return False
    if [c.name for c in a.children] != [c.name for c in b.children]:
        return False
    if a.model is None or b.model is None:
        return a.model is b.model and a.policy is b.policy
    return _same_parameters(a.model, b.model)


# ---------------------------------------------------------------------------------------------------------------
# The library
# ---------------------------------------------------------------------------------------------------------------

class SMCLibrary(Mapping[str, SMC]):
    """A named collection of trained SMCs that saves to and loads from a directory.

    A read-only mapping ``name -> SMC`` (``library[name]``, ``name in library``, ``len``, iteration over names)
    plus :meth:`add`, :meth:`remove`, :meth:`save`, :meth:`load`, :meth:`wrap` and :meth:`env_for`.
    Children live in the same library, by name: :meth:`add` adds an SMC's missing children (recursively) before
    the SMC itself, so :attr:`names` lists children before their parents. Only SMCs with a trained
    ``RecurrentPPO``, ``TRPO`` or ``PPO`` model can be stored (scripted SMCs cannot: ``LibraryError``).
    """

    def __init__(self, smcs: Sequence[SMC] = (), path: str | os.PathLike | None = None) -> None:
        self._smcs: dict[str, SMC] = {}
        self.path: Path | None = Path(path) if path is not None else None
        """Where the library was loaded from or last saved to (the default target of :meth:`save`)."""
        self.created_with: dict[str, str] = {}
        """Package versions recorded in the loaded manifest (empty for a library not loaded from disk)."""
        for smc in smcs:
            self.add(smc)

    # ------------------------------------------------------------------------------------------ mapping

    def __getitem__(self, name: str) -> SMC:
        try:
            return self._smcs[name]
        except KeyError:
            raise UnknownSMCError(f"no SMC named {name!r} in the library{_suggest(str(name), self.names)}") from None

    def __iter__(self) -> Iterator[str]:
        return iter(self._smcs)

    def __len__(self) -> int:
        return len(self._smcs)

    def __repr__(self) -> str:
        where = f", path={str(self.path)!r}" if self.path is not None else ""
        return f"SMCLibrary({list(self._smcs)}{where})"

    @property
    def names(self) -> tuple[str, ...]:
        """Names of the SMCs, children before their parents (insertion order otherwise)."""
        return tuple(self._smcs)

    # ------------------------------------------------------------------------------------------ editing

    def add(self, smc: SMC, *, replace: bool = False) -> SMC:
        """Add ``smc`` and, first, those of its children (recursively) that are not in the library yet.

        A child whose name is already in the library must be the same SMC (the same object, or the same kind,
        children and model parameters, e.g. an SMC loaded from this library); otherwise ``LibraryError``.
        ``replace=True`` replaces an SMC of the same name (its own entry only: parents keep calling the new one
        by name). Adding an SMC that is already stored (same object or same content) changes nothing. Raises
        ``LibraryError`` for an SMC without a model (scripted), a model of another algorithm, or a model whose
        spaces do not fit the SMC's action names and observation size. Returns the stored SMC: ``smc`` itself,
        or a copy calling the library's own child objects when ``smc``'s children are equal but other objects.
        """
        if not isinstance(smc, SMC):
            raise TypeError(f"SMCLibrary.add expects an SMC, got {type(smc).__name__}")
        before = dict(self._smcs)
        try:
            return self._add(smc, replace)
        except BaseException:
            self._smcs = before  # all or nothing: no half-added tree
            raise

    def _add(self, smc: SMC, replace: bool) -> SMC:
        self._check_storable(smc)
        for child in smc.children:
            if child.name not in self._smcs:
                self._add(child, False)
            elif not _same_smc(self._smcs[child.name], child):
                raise LibraryError(
                    f"SMC {smc.name!r} calls a child {child.name!r} that differs from the SMC of that name already in "
                    f"the library (other kind, children or model parameters); add the child under another name or "
                    f"replace it first with library.add(child, replace=True)")
        existing = self._smcs.get(smc.name)
        if existing is not None and not replace:
            if _same_smc(existing, smc):
                return existing
            raise LibraryError(f"the library already has a different SMC named {smc.name!r}; pass replace=True to "
                               "replace it")
        # the stored SMC calls the library's own child objects
        stored_children = tuple(self._smcs[c.name] for c in smc.children)
        if any(a is not b for a, b in zip(stored_children, smc.children, strict=True)):
            smc = SMC(smc.name, smc.kind, smc.policy, stored_children, smc.include_primitives, dict(smc.metadata),
                      smc.model)
        self._smcs[smc.name] = smc
        if existing is not None:  # parents of a replaced SMC now call the new object
            self._relink(smc)
        return smc

    def _relink(self, new: SMC) -> None:
        for name, parent in list(self._smcs.items()):
            if any(c.name == new.name and c is not new for c in parent.children):
                children = tuple(new if c.name == new.name else c for c in parent.children)
                updated = SMC(parent.name, parent.kind, parent.policy, children, parent.include_primitives,
                              parent.metadata, parent.model)
                self._smcs[name] = updated
                self._relink(updated)

    def remove(self, name: str) -> SMC:
        """Remove and return the SMC ``name``; ``LibraryError`` if another SMC of the library calls it."""
        smc = self[name]
        users = [p.name for p in self._smcs.values() if any(c.name == name for c in p.children)]
        if users:
            raise LibraryError(f"cannot remove {name!r}: it is a child of {users}; remove those first")
        del self._smcs[name]
        return smc

    @staticmethod
    def _check_storable(smc: SMC) -> None:
        if smc.model is None:
            raise LibraryError(
                f"SMC {smc.name!r} has no model (a scripted policy: {type(smc.policy).__name__}); a library stores "
                f"only SMCs with a trained {'/'.join(ALGORITHMS)} model")
        algo = type(smc.model).__name__
        if algo not in ALGORITHMS or not isinstance(smc.model, _algorithms()[algo]):
            raise LibraryError(f"SMC {smc.name!r}: cannot store a {algo} model (supported: {', '.join(ALGORITHMS)})")
        _check_model_layout(smc.name, smc.model, smc.action_names, smc.observation_size, f"its {algo} model",
                            _frame_stack(smc))

    # ------------------------------------------------------------------------------------------ manifest

    def entry(self, name: str) -> dict[str, Any]:
        """The manifest entry of SMC ``name`` (without the ``model`` file and ``sha256`` fields :meth:`save` adds)."""
        smc = self[name]
        meta = _jsonable(smc.metadata)
        return {
            "kind": smc.kind,
            "algo": type(smc.model).__name__,
            "env_id": meta.get("env_id"),
            "datasets": _datasets(meta),
            "children": [c.name for c in smc.children],
            "include_primitives": smc.include_primitives,
            "action_names": list(smc.action_names),
            "observation": observation_layout(len(smc.children), len(smc.action_names)),
            "frame_stack": _frame_stack(smc),
            "seed": meta.get("seed"),
            "selected_update": meta.get("selected_update"),
            "training_return": meta.get("training_return"),
            "test_score": meta.get("test_score"),
            "total_timesteps": meta.get("total_timesteps"),
            "metadata": meta,
        }

    def manifest(self) -> dict[str, Any]:
        """The manifest :meth:`save` writes (model file names included, checksums not)."""
        files = _model_files(self.names)
        smcs = {}
        for name in self.names:
            entry = self.entry(name)
            smcs[name] = {"model": files[name], **entry}
        return {"format": FORMAT, "version": FORMAT_VERSION, "created_with": _versions(), "smcs": smcs}

    # ------------------------------------------------------------------------------------------ saving

    def save(self, path: str | os.PathLike | None = None) -> Path:
        """Write the library to directory ``path`` (default: :attr:`path`), atomically; returns the path.

        Everything is written into a temporary directory beside ``path`` (models first, then the manifest, each
        fsynced); only when it is complete is an existing library at ``path`` renamed aside, the new one renamed
        into place and the old one deleted. An error while writing deletes the temporary directory and leaves the
        previous library untouched. ``path`` may be missing, an empty directory or an existing library; anything
        else is refused.
        """
        if path is None:
            if self.path is None:
                raise LibraryError("SMCLibrary.save needs a path (this library was not loaded from one)")
            path = self.path
        target = Path(path).absolute()
        if target.exists():
            if not target.is_dir():
                raise LibraryError(f"cannot save an SMC library to {target}: it is a file")
            if any(target.iterdir()) and not (target / MANIFEST).is_file():
                raise LibraryError(f"refusing to replace {target}: it is a non-empty directory without {MANIFEST} "
                                   "(not an SMC library)")
        for name in self.names:  # an SMC may have been changed since it was added
            self._check_storable(self._smcs[name])
        manifest = self.manifest()
        target.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}{_SAVING}", dir=target.parent))
        try:
            (tmp / MODELS).mkdir()
            for name, entry in manifest["smcs"].items():
                file = tmp / entry["model"]
                self._smcs[name].model.save(file)
                if not file.is_file():
                    raise LibraryError(f"SMC {name!r}: saving its model did not create {file}")
                _fsync_file(file)
                entry["sha256"] = _sha256(file)
            _fsync_dir(tmp / MODELS)
            text = json.dumps(manifest, indent=2)
            with open(tmp / MANIFEST, "w", encoding="utf-8") as handle:
                handle.write(text + "\n")
                handle.flush()
                os.fsync(handle.fileno())
            _fsync_dir(tmp)
            self._swap_in(tmp, target)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        self.path = target
        self.created_with = manifest["created_with"]
        return target

    @staticmethod
    def _swap_in(tmp: Path, target: Path) -> None:
        old = None
        if target.exists():
            old = target.parent / f".{target.name}{_OLD}{uuid.uuid4().hex[:12]}"
            os.rename(target, old)
        try:
            os.rename(tmp, target)
        except BaseException:
            if old is not None:
                os.rename(old, target)
            raise
        _fsync_dir(target.parent)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)

    # ------------------------------------------------------------------------------------------ loading

    @classmethod
    def load(cls, path: str | os.PathLike) -> SMCLibrary:
        """Load and validate the library in directory ``path``.

        Checks the manifest (format, version, fields), that every child is in the library and no SMC calls itself
        (through any chain), that action names and observation sizes agree with kind/children and with each
        model's spaces, and that each model file is intact (readable zip, SHA-256 as recorded) and loads with
        its algorithm's class (``device="cpu"``). Errors are :class:`LibraryError` subclasses naming the file
        and SMC.
        """
        root = Path(path)
        manifest_path = root / MANIFEST
        if not manifest_path.is_file():
            raise ManifestError(f"no SMC library at {root}: {manifest_path} not found{_interrupted_hint(root)}")
        try:
            manifest = json.loads(manifest_path.read_text(encoding="utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError) as err:
            raise ManifestError(f"{manifest_path} is not valid JSON (corrupt or truncated?): {err}") from None
        from sb3_smc.policies import policy_from_model
        from sb3_smc.training import FrameStackPolicy

        entries = _check_manifest(manifest, manifest_path)
        order = _topological_order(entries, manifest_path)
        library = cls(path=root)
        library.created_with = dict(manifest.get("created_with") or {})
        for name in order:
            entry = entries[name]
            model = _load_model(root, name, entry)
            size = entry["observation"]["size"]
            stack = entry.get("frame_stack", 1)
            _check_model_layout(name, model, entry["action_names"], size,
                                f"the {entry['algo']} model in {root / entry['model']}", stack)
            try:
                policy = policy_from_model(model)
                if stack > 1:
                    policy = FrameStackPolicy(policy, stack, size)
            except (TypeError, ValueError) as err:
                raise CorruptModelError(
                    f"SMC {name!r}: cannot run the model in {root / entry['model']}: {err}") from err
            metadata = dict(entry.get("metadata") or {})
            children = tuple(library._smcs[c] for c in entry["children"])
            smc = SMC(name, entry["kind"], policy, children, entry["include_primitives"], metadata, model)
            library._smcs[name] = smc
        return library

    # ------------------------------------------------------------------------------------------ environments

    def wrap(self, env: Any, names: Sequence[str] | str, *, include_primitives: bool = True, **kwargs: Any) -> Any:
        """``HierarchicalSMCWrapper(env, [library[n] for n in names], include_primitives=..., **kwargs)``.

        The SMCs ``names`` become actions of ``env`` (after its signals and, unless ``include_primitives=False``,
        the four moves), for training a new higher-level policy. SMCs of either task kind may be used on either
        kind of environment (as in the paper's curricula): an SMC only moves; its signal becomes its outcome.
        ``kwargs`` go to the wrapper (``count_primitive_steps``, ``call_step_cap``).
        """
        from sb3_smc.wrapper import HierarchicalSMCWrapper

        if isinstance(names, str):
            names = [names]
        names = list(names)
        if len(set(names)) != len(names):
            duplicates = sorted({n for n in names if names.count(n) > 1})
            raise LibraryError(f"SMC names given twice: {duplicates}")
        smcs = [self[n] for n in names]
        _check_env(env)
        return HierarchicalSMCWrapper(env, smcs, include_primitives=include_primitives, **kwargs)

    def env_for(self, name: str, env: Any, **kwargs: Any) -> Any:
        """``env`` as SMC ``name`` itself sees it: wrapped with the SMC's children and ``include_primitives``.

        The result's action names and observation size are exactly the SMC's, so ``library[name].model`` or
        ``.policy`` can act on it (evaluate it, or continue training with ``model.set_env``). Raises
        :class:`LayoutMismatchError` when ``env`` is of the other task kind (its signals differ) or the layout
        does not match. ``kwargs`` go to the wrapper; ``count_primitive_steps`` and ``call_step_cap`` default to the
        values the SMC was trained with (``metadata["wrapper"]``, as :func:`sb3_smc.training.train_smc` records).
        """
        from sb3_smc.wrapper import HierarchicalSMCWrapper

        smc = self[name]
        base = _check_env(env)
        if base.kind != smc.kind:
            raise LayoutMismatchError(
                f"SMC {name!r} acts on {smc.kind} tasks (actions {list(smc.action_names)}), but the environment "
                f"{_env_label(env)} is a {base.kind} task (signals {list(SIGNALS[base.kind])}); its action layout "
                "does not fit")
        trained = smc.metadata.get("wrapper") or {}
        for key in ("count_primitive_steps", "call_step_cap"):
            if key in trained:
                kwargs.setdefault(key, trained[key])
        wrapped = HierarchicalSMCWrapper(env, smc.children, include_primitives=smc.include_primitives, **kwargs)
        shape = wrapped.observation_space.shape
        if tuple(wrapped.action_names) != smc.action_names or shape != (smc.observation_size,):
            raise LayoutMismatchError(
                f"SMC {name!r}: the wrapped environment has actions {list(wrapped.action_names)} and observation "
                f"shape {wrapped.observation_space.shape}; the SMC expects {list(smc.action_names)} and "
                f"({smc.observation_size},)")
        return wrapped


# ---------------------------------------------------------------------------------------------------------------
# Loading helpers
# ---------------------------------------------------------------------------------------------------------------

def _interrupted_hint(root: Path) -> str:
    parent = root.parent
    if not parent.is_dir():
        return ""
    saving = sorted(p for p in parent.glob(f".{root.name}{_SAVING}*") if (p / MANIFEST).is_file())
    old = sorted(p for p in parent.glob(f".{root.name}{_OLD}*") if (p / MANIFEST).is_file())
    if not saving and not old:
        return ""
    parts = []
    if saving:
        parts.append(f"a complete new library at {saving[-1]}")
    if old:
        parts.append(f"the previous library at {old[-1]}")
    return (f"; a save to this path was interrupted: found {' and '.join(parts)} (rename one to {root.name} to "
            "recover it)")


_ENTRY_FIELDS: dict[str, tuple[type, ...]] = {
    "model": (str,),
    "kind": (str,),
    "algo": (str,),
    "children": (list,),
    "include_primitives": (bool,),
    "action_names": (list,),
    "observation": (dict,),
}


def _check_manifest(manifest: Any, where: Path) -> dict[str, dict[str, Any]]:
    if not isinstance(manifest, dict):
        raise ManifestError(f"{where}: expected a JSON object, got {type(manifest).__name__}")
    if manifest.get("format") != FORMAT:
        raise ManifestError(f"{where}: not an SMC library manifest (format {manifest.get('format')!r}, expected "
                            f"{FORMAT!r})")
    version = manifest.get("version")
    if not isinstance(version, int) or isinstance(version, bool):
        raise ManifestError(f"{where}: manifest version must be an integer, got {version!r}")
    if version > FORMAT_VERSION:
        made = (manifest.get("created_with") or {}).get("sb3_smc", "a newer sb3_smc")
        raise ManifestError(f"{where}: manifest version {version} is newer than this sb3_smc reads "
                            f"(version {FORMAT_VERSION}); it was written by sb3_smc {made}: upgrade sb3_smc")
    if version != FORMAT_VERSION:
        raise ManifestError(f"{where}: incompatible manifest version {version} (this sb3_smc reads version "
                            f"{FORMAT_VERSION})")
    smcs = manifest.get("smcs")
    if not isinstance(smcs, dict):
        raise ManifestError(f"{where}: 'smcs' must be an object name -> entry, got {type(smcs).__name__}")
    for name, entry in smcs.items():
        if not isinstance(entry, dict):
            raise ManifestError(f"{where}: entry {name!r} must be an object, got {type(entry).__name__}")
        missing = [f for f in _ENTRY_FIELDS if f not in entry]
        if missing:
            raise ManifestError(f"{where}: entry {name!r} lacks the field(s) {missing}")
        for field, types in _ENTRY_FIELDS.items():
            if not isinstance(entry[field], types):
                raise ManifestError(f"{where}: entry {name!r}: {field!r} must be {types[0].__name__}, got "
                                    f"{entry[field]!r}")
        if entry["kind"] not in SIGNALS:
            raise ManifestError(f"{where}: entry {name!r}: unknown kind {entry['kind']!r} (expected one of "
                                f"{list(SIGNALS)})")
        if entry["algo"] not in ALGORITHMS:
            raise ManifestError(f"{where}: entry {name!r}: unknown algorithm {entry['algo']!r} (supported: "
                                f"{list(ALGORITHMS)})")
        model = entry["model"]
        if Path(model).is_absolute() or ".." in Path(model).parts:
            raise ManifestError(f"{where}: entry {name!r}: model path {model!r} must be relative, inside the library")
        if not all(isinstance(c, str) for c in entry["children"]):
            raise ManifestError(f"{where}: entry {name!r}: children must be names, got {entry['children']!r}")
        for field, value in (("observation.size", entry["observation"].get("size")),
                             ("frame_stack", entry.get("frame_stack", 1))):
            if not isinstance(value, int) or isinstance(value, bool) or value < 1:
                raise ManifestError(f"{where}: entry {name!r}: {field} must be a positive integer, got {value!r}")
    for name, entry in smcs.items():
        for child in entry["children"]:
            if child not in smcs:
                raise MissingChildError(
                    f"{where}: SMC {name!r} calls child {child!r}, which is not in the library"
                    f"{_suggest(child, [n for n in smcs if n != name], ' (it has no other SMC)')}")
        expected = list(smc_action_names(entry["kind"], entry["children"], entry["include_primitives"]))
        if entry["action_names"] != expected:
            raise LayoutMismatchError(
                f"{where}: SMC {name!r}: action names {entry['action_names']} do not match its kind "
                f"{entry['kind']!r}, children {entry['children']} and include_primitives="
                f"{entry['include_primitives']} (expected {expected})")
        layout = observation_layout(len(entry["children"]), len(expected))
        if entry["observation"] != layout:
            raise LayoutMismatchError(
                f"{where}: SMC {name!r}: observation {entry['observation']} does not match its children and actions "
                f"(expected {layout}: {HAND_SIZE} window + {len(entry['children'])} outcomes + {len(expected)} "
                "previous action)")
    return smcs


def _topological_order(entries: Mapping[str, Mapping[str, Any]], where: Path) -> list[str]:
    order: list[str] = []
    state: dict[str, int] = {}  # 1 visiting, 2 done

    def visit(name: str, stack: list[str]) -> None:
        if state.get(name) == 2:
            return
        if state.get(name) == 1:
            cycle = stack[stack.index(name):] + [name]
            raise LibraryError(f"{where}: SMCs call each other in a cycle: {' -> '.join(cycle)}")
        state[name] = 1
        for child in entries[name]["children"]:
            visit(child, [*stack, name])
        state[name] = 2
        order.append(name)

    for name in entries:
        visit(name, [])
    return order


def _load_model(root: Path, name: str, entry: Mapping[str, Any]) -> Any:
    file = root / entry["model"]
    if not file.is_file():
        raise CorruptModelError(f"SMC {name!r}: model file {file} is missing")
    try:
        with zipfile.ZipFile(file) as archive:
            bad = archive.testzip()
            members = set(archive.namelist())
    except (zipfile.BadZipFile, OSError, EOFError, ValueError) as err:
        raise CorruptModelError(f"SMC {name!r}: model file {file} is corrupt or truncated (not a readable zip "
                                f"archive: {err})") from None
    if bad is not None:
        raise CorruptModelError(f"SMC {name!r}: model file {file} is corrupt (member {bad!r} fails its CRC check)")
    if "data" not in members or "policy.pth" not in members:
        raise CorruptModelError(f"SMC {name!r}: model file {file} is not a Stable-Baselines3 model archive "
                                f"(members: {sorted(members)})")
    expected = entry.get("sha256")
    if expected is not None and _sha256(file) != expected:
        raise CorruptModelError(f"SMC {name!r}: model file {file} does not match the SHA-256 recorded in the "
                                "manifest (modified or corrupt since it was saved)")
    cls = _algorithms()[entry["algo"]]
    try:
        return cls.load(file, device="cpu")
    except Exception as err:  # noqa: BLE001 - SB3 raises many kinds of errors for a bad archive
        raise CorruptModelError(f"SMC {name!r}: cannot load model file {file} as {entry['algo']}: "
                                f"{type(err).__name__}: {err}") from err


def _check_env(env: Any) -> Any:
    from pixelworld_env.env import PixelWorldEnv

    base = getattr(env, "unwrapped", env)
    if not isinstance(base, PixelWorldEnv):
        raise LayoutMismatchError(f"SMCs act on PixelWorld environments; got {type(base).__name__}")
    from sb3_smc.wrapper import HierarchicalSMCWrapper

    layer = env
    while layer is not base:
        if isinstance(layer, HierarchicalSMCWrapper):
            raise LayoutMismatchError("the environment is already wrapped with SMC actions (HierarchicalSMCWrapper); "
                                      "wrap the PixelWorld environment itself")
        layer = getattr(layer, "env", base)
    return base


def _env_label(env: Any) -> str:
    spec = getattr(env, "spec", None)
    return repr(spec.id) if spec is not None and getattr(spec, "id", None) else type(env.unwrapped).__name__
