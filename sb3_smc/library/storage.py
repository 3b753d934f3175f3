"""How an SMC library lies on disk: reading and writing the manifest file, model files and checksums, adding and
removing SMCs in place, and the atomic save (:mod:`pixelworld_env.atomic`). The manifest's schema and validation
(and the checksums of its content) are :mod:`sb3_smc.library.manifest`'s; its names that callers use
through this module (``topological_order``, ``FORMAT`` ...) are re-exported here; :func:`check_manifest` reads a
manifest of any version (the conversions: :mod:`sb3_smc.library.upgrade`).

Layout::

    my-library/
        manifest.json        {"format": "sb3-smc-library", "version": 4, "created_with": {...}, "smcs": {...},
                              "manifest_sha256": ...}
        models/<name>.zip    one SB3 ``model.save`` archive per SMC

Nothing here knows about :class:`~sb3_smc.library.SMCLibrary` beyond the SMCs it is given.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import zipfile
from collections.abc import Collection, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pixelworld_env.atomic import (
    OLD_MARKER,
    atomic_write,
    fsync_dir,
    fsync_file,
    make_temporary_directory,
    replace_directory,
)
from sb3_smc.core.hyperparameters import ALGORITHM_REGISTRY
from sb3_smc.core.layout import HAND_SIZE, PIXELWORLD_LAYOUT, Layout
from sb3_smc.library.errors import CorruptModelError, LayoutMismatchError, LibraryError, ManifestError, suggest
from sb3_smc.library.manifest import (
    ALGORITHMS,
    FORMAT,
    FORMAT_VERSION,
    MANIFEST,
    SUMMARY_FIELDS,
    LibraryEntry,
    check_entries,
    check_version,
    entry_json,
    new_manifest,
    seal,
    topological_order,
)
from sb3_smc.library.upgrade import dropped_fields, upgrade
from sb3_smc.records import package_versions
from sb3_smc.smc.smc import SMC

if TYPE_CHECKING:
    from stable_baselines3.common.base_class import BaseAlgorithm
    from stable_baselines3.common.on_policy_algorithm import OnPolicyAlgorithm

__all__ = ["ALGORITHMS", "FORMAT", "FORMAT_VERSION", "MANIFEST", "MODELS", "SUMMARY_FIELDS", "LibraryEntry",
           "add_to_library", "check_manifest", "check_model_file", "checked_entries", "entry_for", "entry_json",
           "interrupted_hint", "link_copy", "load_model", "manifest_text", "model_files", "new_manifest",
           "read_manifest", "remove_from_library", "sha256", "topological_order", "write_library", "write_manifest"]

MODELS = "models"
SAVING_MARKER = ".saving-"


def algorithm_classes() -> dict[str, type[OnPolicyAlgorithm]]:
    """Algorithm name (as in the manifest's ``algo``) -> SB3 class (from
    :data:`~sb3_smc.core.hyperparameters.ALGORITHM_REGISTRY`)."""
    return {name: algo.load_class() for name, algo in ALGORITHM_REGISTRY.items()}


def sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


_SAFE = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.+=@-]*")


def model_files(names: Sequence[str]) -> dict[str, str]:
    """``name -> "models/<stem>.zip"``: the name itself when it is a safe file name, else a cleaned name + hash."""
    files: dict[str, str] = {}
    for name in names:
        files[name] = model_file_for(name, list(files.values()))
    return files


def model_file_for(name: str, taken: Sequence[str]) -> str:
    """The model file of a new SMC ``name`` in a library whose model files are ``taken``: the name itself when it is
    a safe file name not taken (case-insensitively), else a cleaned name + hash."""
    used = {Path(f).stem.casefold() for f in taken}
    stem = name
    if not _SAFE.fullmatch(name) or len(name) > 100 or name.casefold() in used:
        cleaned = re.sub(r"[^A-Za-z0-9_.+=@-]", "_", name)[:80].lstrip("._") or "smc"
        stem = f"{cleaned}-{hashlib.sha256(name.encode()).hexdigest()[:10]}"
    return f"{MODELS}/{stem}.zip"


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
    return entry_json(smc.name, type(smc.model).__name__, frame_stack_of(smc), smc.spec, smc.record, smc.evaluations,
                      kind=smc.kind, children=tuple(c.name for c in smc.children),
                      include_primitives=smc.include_primitives, layout=smc.layout)


def write_library(target: Path, smcs: Mapping[str, SMC], manifest: dict[str, Any]) -> None:
    """Write ``manifest`` and the models of ``smcs`` to directory ``target``, atomically.

    Everything goes into a temporary directory beside ``target`` (models first, then the manifest, each fsynced);
    only when it is complete does :func:`pixelworld_env.atomic.replace_directory` swap it in. An error while writing
    deletes the temporary directory and leaves the previous library untouched.
    """
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = make_temporary_directory(target.parent, f".{target.name}{SAVING_MARKER}")
    try:
        (tmp / MODELS).mkdir()
        for name, entry in manifest["smcs"].items():
            file = tmp / entry["model"]
            smcs[name].model.save(file)
            if not file.is_file():
                raise LibraryError(f"SMC {name!r}: saving its model did not create {file}")
            fsync_file(file)
            entry["sha256"] = sha256(file)
        fsync_dir(tmp / MODELS)
        write_manifest(tmp / MANIFEST, manifest)
        replace_directory(tmp, target)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


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
        if added is not None and added[0] == hashlib.sha256(manifest_path.read_bytes()).hexdigest():
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
                            "SMCLibrary.load(path).save() writes it in the current version")
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
    """Add one SMC to the library directory ``root`` without touching what is already there.

    The model file is written atomically first, then the manifest (read, the entry added, written atomically), so
    an interruption leaves the library as it was or with the SMC complete; a version-2 or -3 library is written as
    the current version (:func:`_current_manifest`), and ``name`` must be new. Creates the library when ``root`` has no
    manifest. ``replace=True``: ``name`` must be there already (an SMC whose model file was damaged, trained
    again); its model file and entry are replaced the same way.
    """
    manifest, known, texts, manifest_path = _manifest_to_add_to(root)
    smcs = manifest["smcs"]
    if name in smcs and not replace:
        raise LibraryError(f"{manifest_path}: already has an SMC named {name!r}")
    if replace and name not in smcs:
        raise LibraryError(f"{manifest_path}: has no SMC named {name!r} to replace")
    file = smcs[name]["model"] if replace else model_file_for(name, [e["model"] for e in smcs.values()])
    atomic_write(root / file, model)
    smcs[name] = json.loads(json.dumps({"model": file, **entry, "sha256": hashlib.sha256(model).hexdigest()}))
    known.pop(name, None)
    texts.pop(name, None)
    data = write_manifest(manifest_path, manifest, known, texts)
    key = str(manifest_path.resolve())
    _keep(_ADDED, key, (hashlib.sha256(data).hexdigest(), manifest, known, texts))


def remove_from_library(root: Path, names: Collection[str]) -> None:
    """Remove the SMCs ``names`` from the library in ``root``: the manifest first (atomically), then their model
    files. No SMC left may call one of them."""
    manifest, entries, manifest_path = _current_manifest(root)
    smcs = manifest["smcs"]
    unknown = sorted(set(names) - set(smcs))
    if unknown:
        raise LibraryError(f"{manifest_path}: has no SMC named {unknown[0]!r}{suggest(unknown[0], list(smcs))}")
    callers = sorted(n for n, e in entries.items() if n not in names and set(e.children) & set(names))
    if callers:
        raise LibraryError(f"{manifest_path}: cannot remove {sorted(names)}: {callers} call them")
    files = [smcs.pop(name)["model"] for name in names]
    write_manifest(manifest_path, manifest)
    for file in files:
        (root / file).unlink(missing_ok=True)


def link_copy(root: Path, target: Path) -> None:
    """A copy of the library directory ``root`` at the new path ``target``, its files hard-linked where the file
    system allows (a library's files are replaced by renames, never rewritten in place), else copied."""
    def link(source: str, destination: str) -> None:
        try:
            os.link(source, destination)
        except OSError:
            shutil.copy2(source, destination)

    shutil.copytree(root, target, copy_function=link)


# ---------------------------------------------------------------------------------------------------------------
# Reading
# ---------------------------------------------------------------------------------------------------------------

def interrupted_hint(root: Path) -> str:
    """Where the complete copies of an interrupted save of ``root`` are, if any ("" otherwise)."""
    parent = root.parent
    if not parent.is_dir():
        return ""
    saving = sorted(p for p in parent.glob(f".{root.name}{SAVING_MARKER}*") if (p / MANIFEST).is_file())
    old = sorted(p for p in parent.glob(f".{root.name}{OLD_MARKER}*") if (p / MANIFEST).is_file())
    if not saving and not old:
        return ""
    parts = []
    if saving:
        parts.append(f"a complete new library at {saving[-1]}")
    if old:
        parts.append(f"the previous library at {old[-1]}")
    return (f"; a save to this path was interrupted: found {' and '.join(parts)} (rename one to {root.name} to "
            "recover it)")


def check_manifest(manifest: Any, where: Path) -> dict[str, LibraryEntry]:
    """The entries of a manifest of any version (one of the current version checked against its checksums, an
    earlier one converted: :func:`sb3_smc.library.upgrade.upgrade`), checked and with their records parsed."""
    return check_entries(upgrade(manifest, where), where)


def _manifest_bytes(root: Path) -> tuple[bytes, Path]:
    manifest_path = root / MANIFEST
    if not manifest_path.is_file():
        raise ManifestError(f"no SMC library at {root}: {manifest_path} not found{interrupted_hint(root)}")
    return manifest_path.read_bytes(), manifest_path


def _parse_manifest(data: bytes, manifest_path: Path) -> dict[str, Any]:
    try:
        return json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as err:
        raise ManifestError(f"{manifest_path} is not valid JSON (corrupt or truncated?): {err}") from None


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
        _keep(_CHECKED, key, (check_manifest(manifest, manifest_path), dict(manifest.get("created_with") or {})))
    entries, created_with = _CHECKED[key]
    return dict(entries), dict(created_with), manifest_path


def check_model_file(root: Path, name: str, entry: LibraryEntry) -> None:
    """:class:`CorruptModelError` unless entry ``name``'s model file is there, a readable SB3 zip, with the recorded
    SHA-256."""
    file = root / entry.model
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
    if sha256(file) != entry.sha256:
        raise CorruptModelError(f"SMC {name!r}: model file {file} does not match the SHA-256 recorded in the "
                                "manifest (modified or corrupt since it was saved)")


def load_model(root: Path, name: str, entry: LibraryEntry) -> BaseAlgorithm:
    """The SB3 model of entry ``name``, after checking its file (:func:`check_model_file`)."""
    check_model_file(root, name, entry)
    file = root / entry.model
    algorithm = ALGORITHM_REGISTRY[entry.algo]
    cls = algorithm.load_class()
    try:
        model = cls.load(file, device="cpu")
    except Exception as err:  # noqa: BLE001 - SB3 raises many kinds of errors for a bad archive
        raise CorruptModelError(f"SMC {name!r}: cannot load model file {file} as {entry.algo}: "
                                f"{type(err).__name__}: {err}") from err
    from sb3_contrib.common.recurrent.policies import RecurrentActorCriticPolicy

    if isinstance(model.policy, RecurrentActorCriticPolicy) != algorithm.recurrent:
        raise CorruptModelError(f"SMC {name!r}: the manifest says {entry.algo}, but {file} holds a "
                                f"{type(model.policy).__name__} (a model of another algorithm)")
    return model
