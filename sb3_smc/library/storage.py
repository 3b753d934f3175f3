"""How an SMC library lies on disk: reading and writing the manifest file, model files and checksums, adding and
removing SMCs in place, under a lock. The manifest's schema and validation (and the checksums of its content) are
:mod:`sb3_smc.library.manifest`'s; its names that callers use through this module (``topological_order``,
``FORMAT`` ...) are re-exported here; :func:`check_manifest` reads a manifest of any version (the conversions:
:mod:`sb3_smc.library.upgrade`); a model file's layout is :mod:`sb3_smc.library.model_file`'s.

Layout::

    my-library/
        manifest.json        {"format": "sb3-smc-library", "version": 6, "created_with": {...}, "smcs": {...},
                              "manifest_sha256": ...}
        models/<sha256>.safetensors   one model per SMC, named by the SHA-256 of its bytes (never rewritten)
        .lock                the lock of its writers and readers

Model files are content-addressed and written before the manifest that names them, which is replaced atomically; a
file no entry names any more is deleted after that. Writers hold an exclusive lock (``fcntl.flock`` on ``.lock``),
readers a shared one, so a reader sees one manifest and the files it names. A library of version 4 or earlier holds
SB3 ``model.save`` archives (``models/<name>.zip``), which pickle: they load only with ``trust=True``.

Nothing here knows about :class:`~sb3_smc.library.SMCLibrary` beyond the SMCs it is given.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import shutil
import zipfile
from collections.abc import Collection, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pixelworld_env.atomic import OLD_MARKER, atomic_write
from sb3_smc.core.hyperparameters import ALGORITHM_REGISTRY, algorithm_of
from sb3_smc.core.layout import HAND_SIZE, PIXELWORLD_LAYOUT, Layout
from sb3_smc.errors import SMCError
from sb3_smc.library.errors import (
    CorruptModelError,
    LayoutMismatchError,
    LibraryConflictError,
    LibraryError,
    ManifestError,
    UnreadableFileError,
    UntrustedModelError,
    suggest,
)
from sb3_smc.library.files import LOCK, locked, read_inside
from sb3_smc.library.manifest import (
    FORMAT,
    FORMAT_VERSION,
    MANIFEST,
    MODELS,
    SUMMARY_FIELDS,
    LibraryEntry,
    check_entries,
    check_version,
    entry_checksum,
    entry_json,
    model_path,
    new_manifest,
    parse_entry,
    seal,
    topological_order,
)
from sb3_smc.library.model_file import MAX_MODEL_BYTES, check_model_bytes, decode_model, encode_model
from sb3_smc.library.upgrade import dropped_fields, upgrade
from sb3_smc.records import package_versions
from sb3_smc.smc.smc import SMC

if TYPE_CHECKING:
    from stable_baselines3.common.base_class import BaseAlgorithm

__all__ = ["FORMAT", "FORMAT_VERSION", "LOCK", "MANIFEST", "MAX_MANIFEST_BYTES", "MODELS",
           "SUMMARY_FIELDS", "LibraryEntry", "add_to_library", "check_manifest", "check_model_file", "checked_entries",
           "entry_for", "entry_json", "interrupted_hint", "is_pickled", "link_copy", "load_model", "locked",
           "manifest_text", "model_bytes", "new_manifest", "read_manifest", "remove_from_library", "save_library",
           "sha256", "topological_order", "write_manifest"]

MAX_MANIFEST_BYTES = 256 * 2**20
"""The largest manifest read (256 MiB; the package's pretrained library's is about 1 MB)."""


def algorithm_name(smc: SMC) -> str:
    """The registry's name of the algorithm of ``smc``'s model (:func:`~sb3_smc.core.hyperparameters.algorithm_of`:
    only that algorithm's class is imported); :class:`LibraryError` for a model of none, or where the class of the
    one it can be cannot be imported."""
    try:
        algo = algorithm_of(type(smc.model))
    except SMCError as err:
        raise LibraryError(f"SMC {smc.name!r}: {err}") from err
    if algo is None:
        raise LibraryError(f"SMC {smc.name!r}: cannot store a {type(smc.model).__name__} model (supported: "
                           f"{', '.join(ALGORITHM_REGISTRY)}; sb3_smc.register_algorithm adds a learner)")
    return algo


def sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


# ---------------------------------------------------------------------------------------------------------------
# Model layout
# ---------------------------------------------------------------------------------------------------------------

def model_layout(model: Any) -> tuple[int | None, tuple[int, ...] | None]:
    """``(number of actions, observation shape)`` of an SB3 model (``None`` where not Discrete / Box)."""
    from gymnasium import spaces

    action_space = getattr(model, "action_space", None)
    obs_space = getattr(model, "observation_space", None)
    n = int(action_space.n) if isinstance(action_space, spaces.Discrete) else None
    shape = tuple(int(s) for s in obs_space.shape) if isinstance(obs_space, spaces.Box) else None
    return n, shape


def frame_stack_of(smc: SMC) -> int:
    """How many observations the SMC's model sees at once (``FrameStackPolicy``, else 1)."""
    from sb3_smc.smc.policies import FrameStackPolicy

    return smc.policy.n_stack if isinstance(smc.policy, FrameStackPolicy) else 1


def check_model_layout(name: str, model: Any, action_names: Sequence[str], size: int, where: str,
                       frame_stack: int = 1, layout: Layout = PIXELWORLD_LAYOUT) -> None:
    """:class:`LayoutMismatchError` unless the model's spaces fit the action names and observation size."""
    n, shape = model_layout(model)
    if n != len(action_names):
        have = f"{n} actions" if n is not None else f"action space {getattr(model, 'action_space', None)}"
        raise LayoutMismatchError(
            f"SMC {name!r}: {where} has {have}, but its action names are {len(action_names)}: {list(action_names)}")
    if shape != (frame_stack * size,):
        have = f"observation shape {shape}" if shape is not None else \
            f"observation space {getattr(model, 'observation_space', None)}"
        stacked = f", {frame_stack} stacked" if frame_stack > 1 else ""
        bare = (" — the bare PixelWorld observation: the model was trained without HierarchicalSMCWrapper (e.g. by "
                "rl_zoo3 without -conf sb3_smc.zoo.<algo>); train it inside sb3_smc.zoo.smc_env so that it sees "
                "the window, the outcomes and its previous action") if layout == PIXELWORLD_LAYOUT and shape in (
                    (HAND_SIZE,), (9,)) else ""
        n_outcomes = size - layout.sensor_size - len(action_names)
        raise LayoutMismatchError(
            f"SMC {name!r}: {where} has {have}, but its observation layout is ({frame_stack * size},) "
            f"({layout.describe(n_outcomes, len(action_names))}{stacked}){bare}")


# ---------------------------------------------------------------------------------------------------------------
# Writing
# ---------------------------------------------------------------------------------------------------------------

def entry_for(smc: SMC) -> dict[str, Any]:
    """The manifest entry of ``smc`` (without the ``model`` file and ``sha256`` fields the save adds)."""
    return entry_json(smc.name, algorithm_name(smc), frame_stack_of(smc), smc.spec, smc.record, smc.evaluations,
                      kind=smc.kind, children=tuple(c.name for c in smc.children),
                      include_primitives=smc.include_primitives, layout=smc.layout)


def model_bytes(model: Any, *, compact: bool = False, where: str = "model") -> bytes:
    """The bytes of ``model``'s file (:func:`sb3_smc.library.model_file.encode_model`); ``compact``: without the
    optimiser's running state (the pretrained library's)."""
    return encode_model(model, optimizer_state=not compact, where=where)


def _collect_garbage(root: Path, manifest: Mapping[str, Any]) -> None:
    """Delete the files of ``root/models`` that no entry of ``manifest`` names (the caller holds the lock)."""
    folder = root / MODELS
    if not folder.is_dir():
        return
    named = {Path(entry["model"]).name for entry in manifest["smcs"].values()}
    for file in folder.iterdir():
        if file.name not in named and (file.is_file() or file.is_symlink()):
            file.unlink(missing_ok=True)


def _write_model(root: Path, data: bytes, digest: str) -> None:
    """Write a model file content-addressed (``digest``: the SHA-256 of ``data``), kept where a file of that name
    holds those bytes."""
    file = root / model_path(digest)
    if file.is_symlink() or not file.is_file() or sha256(file) != digest:
        file.unlink(missing_ok=True)
        atomic_write(file, data)


def save_library(target: Path, entries: Mapping[str, dict[str, Any]], models: Mapping[str, bytes],
                 known: Mapping[str, str], *, overwrite: bool = False) -> tuple[dict[str, str], dict[str, str]]:
    """Write SMCs to the library in ``target`` under its lock: their model files (content-addressed), then the
    manifest (atomically), then delete the files no entry names.

    ``entries``: by name, each SMC's entry without ``model`` and ``sha256``; ``models``: its model's bytes;
    ``known``: the checksums of the entries the caller read from or wrote to ``target`` before (its view of it).
    An SMC on disk that the caller never knew (another process added it, or the folder held a library the caller did
    not load) is kept, unless ``overwrite``; one the caller knew is the caller's to keep, replace or drop, unless it
    changed on disk since: then, and where a kept SMC would lose a child or two SMCs share a name with different
    content, :class:`LibraryConflictError`, and nothing is written. Returns the checksums of the entries written and
    the manifest's ``created_with``."""
    with locked(target, exclusive=True):
        manifest_path = target / MANIFEST
        old = read_manifest(target)[0] if manifest_path.is_file() else None
        if old is not None and check_version(old, manifest_path) == 1:  # its conversion would drop metadata
            if not overwrite and not set(old.get("smcs") or {}) <= set(known):
                raise ManifestError(f"{manifest_path}: version-1 library (sb3-smc 0.1) holding SMCs this library did "
                                    "not read; convert it first: SMCLibrary.load(path, trust=True).save()")
            disk, disk_entries = new_manifest({}), dict[str, LibraryEntry]()  # the caller read every SMC of it
        else:
            disk, disk_entries, manifest_path = _current_manifest(target)
        digests = {name: hashlib.sha256(models[name]).hexdigest() for name in entries}
        ours = {name: json.loads(json.dumps({"model": model_path(digests[name]), **entry, "sha256": digests[name]}))
                for name, entry in entries.items()}
        checksums = {name: entry_checksum(name, entry) for name, entry in ours.items()}
        merged = dict(ours)
        if not overwrite:
            for name, entry in disk["smcs"].items():
                on_disk = disk_entries[name].checksum
                if name in known:
                    if on_disk != known[name] and checksums.get(name) != on_disk:
                        raise LibraryConflictError(
                            f"{manifest_path}: SMC {name!r} was changed by another writer since this library was "
                            "loaded; nothing was saved: load the library again and repeat the change")
                elif name in ours:
                    if checksums[name] != on_disk:
                        raise LibraryConflictError(
                            f"{manifest_path}: another writer added a different SMC named {name!r}; nothing was "
                            "saved: load the library again, or save under another name")
                else:
                    merged[name] = entry
            lost = sorted((name, child) for name in merged for child in _children(merged[name]) if child not in merged)
            if lost:
                raise LibraryConflictError(
                    f"{manifest_path}: SMC {lost[0][0]!r} (kept from the library on disk) calls {lost[0][1]!r}, which "
                    "this save removes; nothing was saved: load the library again")
        for name in ours:
            _write_model(target, models[name], digests[name])
        manifest = new_manifest(merged)
        write_manifest(manifest_path, manifest)
        _collect_garbage(target, manifest)
    return checksums, manifest["created_with"]


def _children(entry: Mapping[str, Any]) -> list[str]:
    """The children an entry (JSON) names, from its spec or its ``smc`` field."""
    spec, smc = entry.get("spec"), entry.get("smc")
    return list((spec or {}).get("children") or (smc or {}).get("children") or [])


def _indented(value: Any, level: int) -> str:
    """``value`` as ``json.dumps(..., indent=2)`` writes it ``level`` levels deep in a document."""
    return json.dumps(value, indent=2, allow_nan=False).replace("\n", "\n" + "  " * level)


def manifest_text(sealed: dict[str, Any], texts: dict[str, str] | None = None) -> str:
    """``json.dumps(sealed, indent=2)`` of a sealed manifest, character for character (tested), from its entries
    written one by one. ``texts``: entries' texts written before, by name, for entries unchanged since (the caller's
    word); those missing are written and added to it. ``json.dumps`` with an indent runs in pure Python: a manifest of
    575 entries takes 0.2 s, so adding an SMC writes only its own entry."""
    texts = {} if texts is None else texts
    parts = []
    for key, value in sealed.items():
        if key == "smcs" and value:
            for name, entry in value.items():
                if name not in texts:
                    texts[name] = _indented(entry, 2)
            body = "{\n" + ",\n".join(f"    {json.dumps(name)}: {texts[name]}" for name in value) + "\n  }"
        else:
            body = _indented(value, 1)
        parts.append(f"  {json.dumps(key)}: {body}")
    return "{\n" + ",\n".join(parts) + "\n}" if parts else "{}"


def write_manifest(path: Path, manifest: dict[str, Any], known: dict[str, tuple[str, str]] | None = None,
                   texts: dict[str, str] | None = None) -> bytes:
    """Write ``manifest`` (JSON data of the current version) to ``path`` atomically, with the checksums of its content
    (:func:`~sb3_smc.library.manifest.seal`; those it holds are replaced). Every manifest is written here; so is a
    deliberate edit by hand that a library is to load. ``known`` / ``texts``: the checksums and canonical texts
    (:func:`~sb3_smc.library.manifest.seal`'s) and the written texts of unchanged entries (:func:`add_to_library`'s),
    completed there. Returns the bytes written."""
    data = (manifest_text(seal(manifest, known), texts) + "\n").encode("utf-8")
    atomic_write(path, data)
    return data


_KEPT = 4
"""How many manifests a process keeps, checked (:func:`checked_entries`) and as last added to (:func:`add_to_library`):
the latest ones."""


def _keep(cache: dict[Any, Any], key: Any, value: Any) -> None:
    """``cache[key] = value`` as the latest entry, the oldest dropped beyond :data:`_KEPT`."""
    cache.pop(key, None)
    while len(cache) >= _KEPT:
        del cache[next(iter(cache))]
    cache[key] = value

_ADDED: dict[str, tuple[str, dict[str, Any], dict[str, tuple[str, str]], dict[str, str]]] = {}
"""Per manifest path, what :func:`add_to_library` last wrote there in this process: the SHA-256 of the file's bytes,
the manifest without its checksums, and its entries' checksums with canonical texts, and written texts."""


def _manifest_to_add_to(root: Path) -> tuple[dict[str, Any], dict[str, tuple[str, str]], dict[str, str], Path]:
    """What :func:`add_to_library` adds to: the manifest of the library in ``root`` as the current version without its
    checksums (:func:`_current_manifest`: checked), and its entries' checksums and texts where known. While the file
    holds the bytes this process's last add wrote there, that add's manifest is taken as it is (a run adding its SMCs
    one by one reads and checks its manifest once, not at every add)."""
    manifest_path = root / MANIFEST
    if manifest_path.is_file():
        added = _ADDED.get(str(manifest_path.resolve()))
        if added is not None and added[0] == hashlib.sha256(_manifest_bytes(root)[0]).hexdigest():
            return {**added[1], "smcs": dict(added[1]["smcs"])}, dict(added[2]), dict(added[3]), manifest_path
    manifest, _, manifest_path = _current_manifest(root)
    return manifest, {}, {}, manifest_path


def _current_manifest(root: Path) -> tuple[dict[str, Any], dict[str, LibraryEntry], Path]:
    """The manifest of the library in ``root`` as the current version (its checksums verified and removed), its
    checked entries, and its path; a new, empty manifest where there is none.

    A version-2 or -3 library is converted (the next write stores it as the current version; for version 2
    ``created_with`` then says who converted it), unless a version-2 entry holds fields of its own that the
    conversion would drop; a version-1 library is refused (its conversion drops metadata): :class:`ManifestError`
    saying how to convert it.
    """
    manifest_path = root / MANIFEST
    if not manifest_path.is_file():
        return new_manifest({}), {}, manifest_path
    manifest = read_manifest(root)[0]
    version = check_version(manifest, manifest_path)
    if version == 1:
        raise ManifestError(f"{manifest_path}: version-1 library (sb3-smc 0.1); convert it first: "
                            "SMCLibrary.load(path, trust=True).save() writes it in the current version")
    if version == 2:
        extra = dropped_fields(manifest)
        if extra:
            shown = "; ".join(f"entry {name!r}: {fields}" for name, fields in extra.items())
            raise ManifestError(f"{manifest_path}: version-{version} library whose entries hold fields that writing "
                                f"it as version {FORMAT_VERSION} would drop ({shown}); move them elsewhere first")
        manifest = {**manifest, "created_with": package_versions()}
    manifest = upgrade(manifest, manifest_path)
    return manifest, check_entries(manifest, manifest_path), manifest_path


def add_to_library(root: Path, name: str, entry: dict[str, Any], model: bytes, *, replace: bool = False) -> None:
    """Add one SMC to the library directory ``root`` without touching what is already there, under the library's
    lock (:func:`locked`): two processes adding at once both get their SMCs in.

    The model file is written first (content-addressed), then the manifest (read, the entry added, written
    atomically), so an interruption leaves the library as it was or with the SMC complete; a version-2 to -4 library
    is written as the current version (:func:`_current_manifest`), and ``name`` must be new. Creates the library when
    ``root`` has no manifest. ``replace=True``: ``name`` must be there already (an SMC whose model file was damaged,
    trained again); its entry is replaced, and its old model file deleted where no other entry names it.
    """
    with locked(root, exclusive=True):
        manifest, known, texts, manifest_path = _manifest_to_add_to(root)
        smcs = manifest["smcs"]
        if name in smcs and not replace:
            raise LibraryError(f"{manifest_path}: already has an SMC named {name!r}")
        if replace and name not in smcs:
            raise LibraryError(f"{manifest_path}: has no SMC named {name!r} to replace")
        algo = ((entry.get("spec") or entry.get("smc") or {}).get("algo"))
        check_model_bytes(model, str(algo), f"SMC {name!r}: the model to add")
        digest = hashlib.sha256(model).hexdigest()
        new = json.loads(json.dumps({"model": model_path(digest), **entry, "sha256": digest}))
        checked = parse_entry(name, new, manifest_path)  # the entry is checked before anything is written
        missing = [child for child in checked.children if child not in smcs]
        if missing:
            raise LibraryError(f"{manifest_path}: SMC {name!r} calls {missing}, which the library does not hold")
        _write_model(root, model, digest)
        smcs[name] = new
        known.pop(name, None)
        texts.pop(name, None)
        data = write_manifest(manifest_path, manifest, known, texts)
        if replace:
            _collect_garbage(root, manifest)
        key = str(manifest_path.resolve())
        _keep(_ADDED, key, (hashlib.sha256(data).hexdigest(), manifest, known, texts))


def remove_from_library(root: Path, names: Collection[str]) -> None:
    """Remove the SMCs ``names`` from the library in ``root``, under its lock: the manifest first (atomically), then
    the model files no entry names any more. No SMC left may call one of them."""
    if isinstance(names, str):
        raise LibraryError(f"remove_from_library takes a collection of SMC names, not the string {names!r}")
    names = set(names)
    with locked(root, exclusive=True):
        manifest, entries, manifest_path = _current_manifest(root)
        smcs = manifest["smcs"]
        unknown = sorted(names - set(smcs))
        if unknown:
            raise LibraryError(f"{manifest_path}: has no SMC named {unknown[0]!r}{suggest(unknown[0], list(smcs))}")
        callers = sorted(n for n, e in entries.items() if n not in names and set(e.children) & set(names))
        if callers:
            raise LibraryError(f"{manifest_path}: cannot remove {sorted(names)}: {callers} call them")
        for name in names:
            smcs.pop(name)
        write_manifest(manifest_path, manifest)
        _collect_garbage(root, manifest)


def link_copy(root: Path, target: Path) -> None:
    """A copy of the library directory ``root`` at the new path ``target``, its files hard-linked where the file
    system allows (a library's files are replaced by renames, never rewritten in place), else copied."""
    def link(source: str, destination: str) -> None:
        try:
            os.link(source, destination)
        except OSError:
            shutil.copy2(source, destination)

    with locked(root, exclusive=False):  # a writer's save is copied whole or not at all
        shutil.copytree(root, target, copy_function=link, ignore=shutil.ignore_patterns(LOCK, "*.tmp"))


# ---------------------------------------------------------------------------------------------------------------
# Reading
# ---------------------------------------------------------------------------------------------------------------

def interrupted_hint(root: Path) -> str:
    """Where the complete previous copy of ``root`` is when a replacement of the whole folder
    (:func:`pixelworld_env.atomic.replace_directory`, e.g. by ``build_pretrained``) was interrupted ("" otherwise)."""
    parent = root.parent
    if not parent.is_dir():
        return ""
    old = sorted(p for p in parent.glob(f".{root.name}{OLD_MARKER}*") if (p / MANIFEST).is_file())
    if not old:
        return ""
    return (f"; a replacement of this folder was interrupted: found the previous library at {old[-1]} (rename it to "
            f"{root.name} to recover it)")


def check_manifest(manifest: Any, where: Path) -> dict[str, LibraryEntry]:
    """The entries of a manifest of any version (one of the current version checked against its checksums, an
    earlier one converted: :func:`sb3_smc.library.upgrade.upgrade`), checked and with their records parsed."""
    return check_entries(upgrade(manifest, where), where)


def _manifest_bytes(root: Path) -> tuple[bytes, Path]:
    manifest_path = root / MANIFEST
    try:
        return read_inside(root, MANIFEST, MAX_MANIFEST_BYTES, "the manifest"), manifest_path
    except FileNotFoundError:
        raise ManifestError(f"no SMC library at {root}: {manifest_path} not found{interrupted_hint(root)}") from None
    except LibraryError as err:
        raise ManifestError(str(err)) from None


def _parse_manifest(data: bytes, manifest_path: Path) -> dict[str, Any]:
    try:
        return json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as err:
        raise ManifestError(f"{manifest_path} is not valid JSON (corrupt or truncated?): {err}") from None
    except (ValueError, RecursionError) as err:  # an integer of thousands of digits; JSON nested beyond reading
        raise ManifestError(f"{manifest_path} is not a manifest this package reads ({type(err).__name__}: "
                            f"{str(err)[:200]})") from None


def read_manifest(root: Path) -> tuple[dict[str, Any], Path]:
    """The manifest of the library in ``root`` as JSON data (any version), and its path."""
    data, manifest_path = _manifest_bytes(root)
    return _parse_manifest(data, manifest_path), manifest_path


_CHECKED: dict[tuple[str, str], tuple[dict[str, LibraryEntry], dict[str, Any]]] = {}
"""The manifests :func:`checked_entries` keeps checked, by path and the SHA-256 of their bytes (the latest ones)."""


def checked_entries(root: Path) -> tuple[dict[str, LibraryEntry], dict[str, Any], Path]:
    """The checked entries of the library in ``root`` (:func:`check_manifest` of :func:`read_manifest`), its
    ``created_with`` and the manifest's path. A process keeps the last few by the manifest's path and the SHA-256 of
    its bytes, so loading SMCs one at a time from a large library that does not change meanwhile (an experiment's
    evaluations) parses and checks it once: checking 575 entries takes most of a second, and
    hashing the file a few milliseconds. The entries are immutable records; the dicts returned are the caller's."""
    data, manifest_path = _manifest_bytes(root)
    key = (str(manifest_path.resolve()), hashlib.sha256(data).hexdigest())
    if key not in _CHECKED:
        manifest = _parse_manifest(data, manifest_path)
        entries = check_manifest(manifest, manifest_path)
        created_with = manifest.get("created_with") or {}
        if not isinstance(created_with, dict) or not all(isinstance(v, str) for v in created_with.values()):
            raise ManifestError(f"{manifest_path}: 'created_with' must map package names to versions, got "
                                f"{created_with!r:.200}")
        _keep(_CHECKED, key, (entries, dict(created_with)))
    entries, created_with = _CHECKED[key]
    return dict(entries), dict(created_with), manifest_path


MAX_ARCHIVE_BYTES = 1 * 2**30
"""The most an old (pickled) model archive may unpack to, its members' declared sizes added (1 GiB)."""


def check_model_file(root: Path, name: str, entry: LibraryEntry) -> bytes:
    """The bytes of entry ``name``'s model file, after checking that it is there, with the recorded SHA-256, and a
    well-formed model file (:func:`~sb3_smc.library.model_file.check_model_bytes`; an old ``.zip`` archive: a
    readable SB3 zip within :data:`MAX_ARCHIVE_BYTES`) — without unpickling or building anything
    (:class:`CorruptModelError` otherwise)."""
    file = root / entry.model
    where = f"SMC {name!r}: model file {file}"
    try:
        data = read_inside(root, entry.model, MAX_MODEL_BYTES if not is_pickled(entry) else MAX_ARCHIVE_BYTES,
                            "model file")
    except FileNotFoundError:
        raise CorruptModelError(f"SMC {name!r}: model file {file} is missing") from None
    except UnreadableFileError as err:  # there, but not readable: not damaged
        raise UnreadableFileError(f"SMC {name!r}: {err}") from None
    except LibraryError as err:
        raise CorruptModelError(f"SMC {name!r}: {err}") from None
    if hashlib.sha256(data).hexdigest() != entry.sha256:
        raise CorruptModelError(f"{where} does not match the SHA-256 recorded in the manifest (modified or corrupt "
                                "since it was saved)")
    if not is_pickled(entry):
        check_model_bytes(data, entry.algo, where)
        return data
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            infos = archive.infolist()
            unpacked = sum(info.file_size for info in infos)
            if unpacked > MAX_ARCHIVE_BYTES:
                raise CorruptModelError(f"{where} unpacks to {unpacked} bytes, more than a model archive may "
                                        f"({MAX_ARCHIVE_BYTES})")
            bad = archive.testzip()
            members = {info.filename for info in infos}
    except (zipfile.BadZipFile, EOFError, ValueError) as err:
        raise CorruptModelError(f"{where} is corrupt or truncated (not a readable zip archive: {err})") from None
    if bad is not None:
        raise CorruptModelError(f"{where} is corrupt (member {bad!r} fails its CRC check)")
    if "data" not in members or "policy.pth" not in members:
        raise CorruptModelError(f"{where} is not a Stable-Baselines3 model archive (members: {sorted(members)})")
    return data


def is_pickled(entry: LibraryEntry) -> bool:
    """Whether the entry's model file is an SB3 ``model.save`` archive (a library of version 4 or earlier), whose
    loading unpickles, so runs code from the file."""
    return entry.model.endswith(".zip")


def load_model(root: Path, name: str, entry: LibraryEntry, *, trust: bool = False) -> BaseAlgorithm:
    """The SB3 model of entry ``name``, after checking its file (:func:`check_model_file`), rebuilt from its tensors
    and settings (:func:`~sb3_smc.library.model_file.decode_model`); nothing of the file is unpickled.

    An old pickled archive (:func:`is_pickled`) loads only with ``trust=True`` (:class:`UntrustedModelError`
    otherwise): loading it runs whatever code its author put in it. ``trust`` also lets a model file name classes of
    any module (importing a module runs its code)."""
    data = check_model_file(root, name, entry)
    file = root / entry.model
    if not is_pickled(entry):
        return decode_model(data, entry.algo, f"SMC {name!r}: model file {file}", trust=trust)
    if not trust:
        raise UntrustedModelError(
            f"SMC {name!r}: {file} is a pickled Stable-Baselines3 archive (a library written before sb3-smc's "
            "version-5 format); loading it runs any code its author put in it. If you trust where this library "
            "comes from, load it with trust=True (sb3-smc library DIR --upgrade --trust converts it to the safe "
            "format); otherwise ask for a version-5 copy")
    algorithm = ALGORITHM_REGISTRY[entry.algo]
    try:
        cls = algorithm.load_class()
    except SMCError as err:
        raise LibraryError(f"SMC {name!r}: {err}") from err
    try:
        model = cls.load(io.BytesIO(data), device="cpu")
    except Exception as err:  # noqa: BLE001 - SB3 raises many kinds of errors for a bad archive
        raise CorruptModelError(f"SMC {name!r}: cannot load model file {file} as {entry.algo}: "
                                f"{type(err).__name__}: {err}") from err
    from sb3_contrib.common.recurrent.policies import RecurrentActorCriticPolicy

    if isinstance(model.policy, RecurrentActorCriticPolicy) != algorithm.recurrent:
        raise CorruptModelError(f"SMC {name!r}: the manifest says {entry.algo}, but {file} holds a "
                                f"{type(model.policy).__name__} (a model of another algorithm)")
    return model
