"""``SMCLibrary``: a directory of trained SMCs with a versioned manifest (the API; the disk format is
:mod:`sb3_smc.library.storage`).

Each manifest entry records how the SMC was trained and what came out (its :class:`~sb3_smc.records.TrainingSpec`,
from which its kind, algorithm and children by name are read, :class:`~sb3_smc.records.TrainingRecord` and
:class:`~sb3_smc.records.EvaluationRecord` list), plus its model file and that file's SHA-256, and the SHA-256 of the
entry's own content (the manifest has one of its whole content too). :meth:`SMCLibrary.load` validates all of it and
rebuilds every :class:`~sb3_smc.smc.smc.SMC` (children first, its policy by
:func:`sb3_smc.smc.policies.policy_from_model`); :meth:`SMCLibrary.save` writes a complete copy beside the target and
swaps it in, so an interrupted save never leaves a half-written library. Libraries of earlier versions load through
:mod:`sb3_smc.library.upgrade`. See ``docs/library.md``.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from sb3_smc.core.layout import SIGNALS
from sb3_smc.envs.factory import make_smc_env, task_base, wrap_with_smcs
from sb3_smc.errors import SMCTypeError
from sb3_smc.library import storage
from sb3_smc.library.errors import (
    CorruptModelError,
    LayoutMismatchError,
    LibraryError,
    UnknownSMCError,
    suggest,
)
from sb3_smc.library.pretrained import pretrained_names, pretrained_root
from sb3_smc.records import WrapperSettings
from sb3_smc.smc.smc import SMC, StepPolicy
from sb3_smc.tasks.task import TaskEnv, layout_of

if TYPE_CHECKING:
    import gymnasium as gym

    from sb3_smc.envs.wrapper import HierarchicalSMCWrapper

__all__ = ["SMCLibrary"]


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



class SMCLibrary(Mapping[str, SMC]):
    """A named collection of trained SMCs that saves to and loads from a directory.

    A read-only mapping ``name -> SMC`` (``library[name]``, ``name in library``, ``len``, iteration over names)
    plus :meth:`add`, :meth:`remove`, :meth:`save`, :meth:`load`, :meth:`wrap` and :meth:`env_for`.
    Children live in the same library, by name: :meth:`add` adds an SMC's missing children (recursively) before
    the SMC itself, so :attr:`names` lists children before their parents. Only SMCs with a trained
    ``RecurrentPPO``, ``RecurrentTRPO``, ``TRPO`` or ``PPO`` model can be stored (scripted SMCs cannot:
    ``LibraryError``).
    """

    def __init__(self, smcs: Sequence[SMC] = (), path: str | os.PathLike | None = None) -> None:
        self._smcs: dict[str, SMC] = {}
        self.path: Path | None = Path(path) if path is not None else None
        """Where the library was loaded from or last saved to (the default target of :meth:`save`)."""
        self.created_with: dict[str, str] = {}
        """Package versions recorded in the loaded manifest (empty for a library not loaded from disk)."""
        self._synced: dict[Path, dict[str, str]] = {}
        """By folder, the checksums of the entries this object read from or wrote to it: what it knows of it, for
        :meth:`save`'s merge."""
        for smc in smcs:
            self.add(smc)

    # ------------------------------------------------------------------------------------------ mapping

    def __getitem__(self, name: str) -> SMC:
        try:
            return self._smcs[name]
        except KeyError:
            raise UnknownSMCError(f"no SMC named {name!r} in the library{suggest(str(name), self.names)}") from None

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
        children and model parameters, e.g. an SMC loaded from this library). Adding an SMC that is already stored
        (same object or same content) changes nothing; a failed add changes nothing either (all or nothing).

        :param smc: a trained SMC (``RecurrentPPO``, ``RecurrentTRPO``, ``TRPO`` or ``PPO`` model).
        :param replace: replace an SMC of the same name (its own entry only: parents keep calling the new one by
            name); without it, a different SMC of that name is refused.
        :return: the stored SMC: ``smc`` itself, or a copy calling the library's own child objects when ``smc``'s
            children are equal but other objects.
        :raises LibraryError: an SMC without a model (scripted), a model of another algorithm, a model whose spaces
            do not fit the SMC's action names and observation size, or a child that differs from the stored one.
        """
        if not isinstance(smc, SMC):
            raise SMCTypeError(f"SMCLibrary.add expects an SMC, got {type(smc).__name__}")
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
            smc = dataclasses.replace(smc, children=stored_children)
        self._smcs[smc.name] = smc
        if existing is not None:  # parents of a replaced SMC now call the new object
            self._relink(smc)
        return smc

    def _relink(self, new: SMC) -> None:
        for name, parent in list(self._smcs.items()):
            if any(c.name == new.name and c is not new for c in parent.children):
                children = tuple(new if c.name == new.name else c for c in parent.children)
                updated = dataclasses.replace(parent, children=children)
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
                "only SMCs with a trained model")
        algo = storage.algorithm_name(smc)
        storage.check_model_layout(smc.name, smc.model, smc.action_names, smc.observation_size, f"its {algo} model",
                                   storage.frame_stack_of(smc), smc.layout)

    # ------------------------------------------------------------------------------------------ manifest

    def entry(self, name: str) -> dict[str, Any]:
        """The manifest entry of SMC ``name`` (without the ``model`` file and ``sha256`` fields :meth:`save` adds)."""
        return storage.entry_for(self[name])

    # ------------------------------------------------------------------------------------------ saving

    def save(self, path: str | os.PathLike | None = None, *, overwrite: bool = False) -> Path:
        """Write the library to a directory, in place and safely against crashes and other writers.

        Under the library's lock, each SMC's model file is written (named by the SHA-256 of its bytes, so a file is
        never rewritten), then the manifest atomically, then the files no entry names any more are deleted: an
        interrupted save leaves the previous library, a reader sees the old or the new one. SMCs another process
        added to the folder since this library read it (or that the folder held before, for a library that never
        read it) are kept: two processes that each load, add and save both keep their SMCs. An SMC this library read
        from the folder and someone else changed there since is refused (:class:`LibraryConflictError`, nothing
        written).

        :param path: the directory (default: :attr:`path`): missing, empty, or an existing library; anything else
            is refused (``LibraryError``).
        :param overwrite: make the folder hold exactly this library's SMCs, dropping the others.
        :return: the absolute path written.
        """
        if path is None:
            if self.path is None:
                raise LibraryError("SMCLibrary.save needs a path (this library was not loaded from one)")
            path = self.path
        target = Path(path).absolute()
        if target.exists():
            if not target.is_dir():
                raise LibraryError(f"cannot save an SMC library to {target}: it is a file")
            if any(p.name != storage.LOCK for p in target.iterdir()) and not (target / storage.MANIFEST).is_file():
                raise LibraryError(f"refusing to write to {target}: it is a non-empty directory without "
                                   f"{storage.MANIFEST} (not an SMC library)")
        for name in self.names:  # an SMC may have been changed since it was added
            self._check_storable(self._smcs[name])
        entries = {name: self.entry(name) for name in self.names}
        models = {name: storage.model_bytes(self._smcs[name].model, where=f"SMC {name!r}") for name in self.names}
        known = self._synced.get(target.resolve(), {})
        self._synced[target.resolve()], self.created_with = storage.save_library(target, entries, models, known,
                                                                                 overwrite=overwrite)
        self.path = target
        return target

    # ------------------------------------------------------------------------------------------ loading

    @classmethod
    def load(cls, path: str | os.PathLike, names: Sequence[str] | None = None, *, trust: bool = False) -> SMCLibrary:
        """Load and validate a saved library, running no code from it.

        Checks the manifest (format, version, the checksums of its content, fields), that every child is in the
        library and no SMC calls itself (through any chain), that action names and observation sizes agree with
        kind/children and with each model's spaces, and that each model file is intact (its SHA-256 as recorded, a
        well-formed model file) and rebuilds its model from its tensors and settings (``device="cpu"``; nothing is
        unpickled, classes come only from Stable-Baselines3, sb3-contrib, PyTorch and this package, and the learners
        this process registered, :func:`~sb3_smc.core.hyperparameters.register_algorithm`). Reads under the
        library's shared lock: a writer's save is seen whole or not at all. Symbolic links inside the folder are
        refused. See ``docs/security.md``.

        :param path: the library's directory (with its ``manifest.json``).
        :param names: load only these SMCs and their descendants; such a partial library has no default save path.
        :param trust: also load what runs code from the files: the pickled model archives of a library of version 4
            or earlier, and classes of other modules named in a model's settings. Only for a library from a source
            you trust: a forged archive runs its payload.
        :raises LibraryError: (its subclasses) naming the file and the SMC at fault; :class:`UntrustedModelError`
            for a pickled model without ``trust``.
        """
        root = Path(path)
        with storage.locked(root, exclusive=False):
            return cls._load(root, names, trust)

    @classmethod
    def _load(cls, root: Path, names: Sequence[str] | None, trust: bool) -> SMCLibrary:
        from sb3_smc.smc.policies import FrameStackPolicy, policy_from_model

        entries, created_with, manifest_path = storage.checked_entries(root)
        order = storage.topological_order(entries, manifest_path)
        if names is not None:
            wanted = _descendants(entries, names, manifest_path)
            order = [name for name in order if name in wanted]
        library = cls(path=root if names is None else None)  # a partial copy must not replace the whole library
        library.created_with = created_with
        for name in order:
            entry = entries[name]
            model = storage.load_model(root, name, entry, trust=trust)
            size, stack = entry.observation_size, entry.frame_stack
            storage.check_model_layout(name, model, entry.action_names, size,
                                       f"the {entry.algo} model in {root / entry.model}", stack, entry.layout)
            try:
                policy: StepPolicy = policy_from_model(model)
                if stack > 1:
                    policy = FrameStackPolicy(policy, stack, size)
            except (TypeError, ValueError) as err:
                raise CorruptModelError(
                    f"SMC {name!r}: cannot run the model in {root / entry.model}: {err}") from err
            children = tuple(library._smcs[c] for c in entry.children)
            if entry.spec is not None:
                smc = SMC.from_spec(entry.spec, policy, children, name=name, model=model, record=entry.record,
                                    evaluations=entry.evaluations)
            else:
                smc = SMC(name, entry.kind, policy, children, entry.include_primitives, model=model,
                          record=entry.record, evaluations=entry.evaluations, layout=entry.layout)
            library._smcs[name] = smc
        library._synced[root.resolve()] = {name: entries[name].checksum for name in order}
        return library

    @classmethod
    def pretrained(cls, curriculum: str, root: str | os.PathLike | None = None) -> SMCLibrary:
        """The pretrained lower-level SMCs shipped with the package, two best seeds of each node
        (:mod:`sb3_smc.library.pretrained`; ``docs/library.md``).

        :param curriculum: a shipped curriculum (``SMCLibrary.pretrained("search2-canon")``), or one node by its
            name (``SMCLibrary.pretrained("cl_self-touches-container_vs_corner")``: every shipped SMC loads by a
            name).
        :param root: another pretrained library (built by :func:`sb3_smc.curricula.pretrained.build_pretrained`).
        """
        path = pretrained_root() if root is None else Path(root)
        return cls.load(path, names=pretrained_names(curriculum, path))

    # ------------------------------------------------------------------------------------------ environments

    def wrap(self, env: gym.Env, names: Sequence[str] | str, *, include_primitives: bool = True,
             **kwargs: Any) -> HierarchicalSMCWrapper:
        """``env`` with the SMCs ``names`` as actions (:func:`sb3_smc.envs.factory.wrap_with_smcs`), for training a new
        higher-level policy.

        The SMCs become actions after ``env``'s signals and its primitive actions (PixelWorld's four moves). SMCs of
        either task kind may be used on either kind of environment (as in the paper's curricula): an SMC only acts;
        its signal becomes its outcome.

        :param env: a task (a PixelWorld environment or an :class:`~sb3_smc.tasks.task.SMCTask`, possibly under other
            wrappers) whose layout (sensor size, primitive actions) is the SMCs' own (else
            :class:`LayoutMismatchError`).
        :param names: the SMCs of the library to add as actions, in order (a name, or several).
        :param include_primitives: keep ``env``'s primitive actions beside the SMCs.
        :param kwargs: the other :class:`~sb3_smc.records.WrapperSettings` (``count_primitive_steps``,
            ``call_step_cap``) and ``record_cells``.
        """
        if isinstance(names, str):
            names = [names]
        names = list(names)
        if len(set(names)) != len(names):
            duplicates = sorted({n for n in names if names.count(n) > 1})
            raise LibraryError(f"SMC names given twice: {duplicates}")
        smcs = [self[n] for n in names]
        _check_layout(smcs, _check_env(env), env)
        record_cells = bool(kwargs.pop("record_cells", False))
        settings = WrapperSettings(include_primitives=include_primitives, **kwargs)
        return wrap_with_smcs(env, smcs, settings, record_cells=record_cells)

    def env_for(self, name: str, env: gym.Env, **kwargs: Any) -> HierarchicalSMCWrapper:
        """``env`` as SMC ``name`` itself sees it (:func:`sb3_smc.envs.factory.make_smc_env` with its spec and
        children).

        The result's action names and observation size are exactly the SMC's, so ``library[name].model`` or
        ``.policy`` can act on it (evaluate it, or continue training with ``model.set_env``).

        :param name: the SMC.
        :param env: a task as for :meth:`wrap`, of the SMC's kind and layout (else :class:`LayoutMismatchError`:
            the other kind's signals differ; another sensor size or primitive actions do not fit).
        :param kwargs: replace the wrapper settings of the SMC's spec (``count_primitive_steps``,
            ``call_step_cap``); ``record_cells`` goes to the wrapper.
        """
        smc = self[name]
        base = _check_env(env)
        if base.kind != smc.kind:
            raise LayoutMismatchError(
                f"SMC {name!r} acts on {smc.kind} tasks (actions {list(smc.action_names)}), but the environment "
                f"{_env_label(env)} is a {base.kind} task (signals {list(SIGNALS[base.kind])}); its action layout "
                "does not fit")
        _check_layout([smc], base, env)
        record_cells = bool(kwargs.pop("record_cells", False))
        trained = (smc.spec.wrapper if smc.spec is not None
                   else WrapperSettings(include_primitives=smc.include_primitives))
        settings = dataclasses.replace(trained, **kwargs)
        if smc.spec is not None:
            wrapped = make_smc_env(smc.spec, smc.children, env=env, wrapper=settings, record_cells=record_cells)
        else:
            wrapped = wrap_with_smcs(env, smc.children, settings, record_cells=record_cells)
        shape = wrapped.observation_space.shape
        if tuple(wrapped.action_names) != smc.action_names or shape != (smc.observation_size,):
            raise LayoutMismatchError(
                f"SMC {name!r}: the wrapped environment has actions {list(wrapped.action_names)} and observation "
                f"shape {wrapped.observation_space.shape}; the SMC expects {list(smc.action_names)} and "
                f"({smc.observation_size},)")
        return wrapped


def _descendants(entries: Mapping[str, storage.LibraryEntry], names: Sequence[str], where: Path) -> set[str]:
    seen: set[str] = set()
    stack = list(names)
    while stack:
        name = stack.pop()
        if name not in entries:
            raise UnknownSMCError(f"{where}: no SMC named {name!r}{suggest(str(name), list(entries))}")
        if name not in seen:
            seen.add(name)
            stack.extend(entries[name].children)
    return seen


def _check_env(env: gym.Env) -> TaskEnv:
    """The task under ``env`` (:func:`sb3_smc.envs.factory.task_base`); :class:`LayoutMismatchError` where there is none
    or ``env`` has SMC actions already."""
    try:
        return task_base(env)
    except (TypeError, ValueError) as err:
        raise LayoutMismatchError(str(err)) from None


def _check_layout(smcs: Sequence[SMC], task: TaskEnv, env: gym.Env) -> None:
    """:class:`LayoutMismatchError` naming the first of ``smcs`` that senses or acts otherwise than ``task`` allows."""
    layout = layout_of(task)
    for smc in smcs:
        wrong = []
        if smc.layout.sensor_size != layout.sensor_size:
            wrong.append(f"it senses {smc.layout.sensor_size} values, the task gives {layout.sensor_size}")
        if smc.layout.primitives != layout.primitives:
            wrong.append(f"its primitive actions are {list(smc.layout.primitives)}, the task's "
                         f"{list(layout.primitives)}")
        if wrong:
            raise LayoutMismatchError(f"SMC {smc.name!r} does not fit the environment {_env_label(env)}: "
                                      f"{'; '.join(wrong)} (it was trained on another environment or observation)")


def _env_label(env: gym.Env) -> str:
    spec = getattr(env, "spec", None)
    return repr(spec.id) if spec is not None and getattr(spec, "id", None) else type(env.unwrapped).__name__
