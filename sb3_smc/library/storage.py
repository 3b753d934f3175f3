"""How an SMC library lies on disk: the manifest schema and its validation, model files and checksums, the
conversion of version-1 manifests, and the atomic save (:mod:`pixelworld_env.atomic`).

Layout::

    my-library/
        manifest.json        {"format": "sb3-smc-library", "version": 2, "created_with": {...}, "smcs": {...}}
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
from collections.abc import Callable, Collection, Mapping, Sequence
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
from sb3_smc.hyperparameters import ALGORITHM_REGISTRY
from sb3_smc.hyperparameters import ALGORITHMS as TRAINED_ALGORITHMS
from sb3_smc.library.errors import (
    CorruptModelError,
    LayoutMismatchError,
    LibraryError,
    ManifestError,
    MissingChildError,
    suggest,
)
from sb3_smc.records import (
    Budget,
    EvaluationRecord,
    RecordError,
    SignalBias,
    TaskSpec,
    TrainingRecord,
    TrainingSpec,
    WrapperSettings,
    package_versions,
    test_score_of,
)
from sb3_smc.smc import HAND_SIZE, SIGNALS, SMC, observation_size, smc_action_names

if TYPE_CHECKING:
    from stable_baselines3.common.on_policy_algorithm import OnPolicyAlgorithm

__all__ = ["ALGORITHMS", "FORMAT", "FORMAT_VERSION", "MANIFEST", "MODELS", "add_to_library", "check_manifest",
           "check_model_file", "entry_for", "interrupted_hint", "link_copy", "load_model", "model_files",
           "read_manifest", "remove_from_library", "sha256", "topological_order", "upgrade_v1", "write_library"]

FORMAT = "sb3-smc-library"
"""Value of the manifest's ``format`` field."""
FORMAT_VERSION = 2
"""Manifest version written. Version 1 (sb3-smc 0.1, a free-form ``metadata`` dict per SMC) is read through
:func:`upgrade_v1`."""
MANIFEST = "manifest.json"
MODELS = "models"
SAVING_MARKER = ".saving-"

ALGORITHMS = TRAINED_ALGORITHMS
"""Algorithms whose models a library stores (those ``train_smc`` trains; loaded with their class, ``device="cpu"``)."""


_V1_ALGORITHMS = ("RecurrentPPO", "TRPO")
"""The algorithms of sb3-smc 0.1, whose version-1 entries carry a training spec to convert."""


def algorithm_classes() -> dict[str, type[OnPolicyAlgorithm]]:
    """Algorithm name (as in the manifest's ``algo``) -> SB3 class (from
    :data:`~sb3_smc.hyperparameters.ALGORITHM_REGISTRY`)."""
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


def observation_layout(n_children: int, n_actions: int) -> dict[str, int]:
    """The manifest's ``observation``: total ``size``, then the parts in order (window, outcomes, previous action)."""
    return {"size": observation_size(n_children, n_actions), "window": HAND_SIZE, "outcomes": n_children,
            "previous_action": n_actions}


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
    from sb3_smc.policies import FrameStackPolicy

    return smc.policy.n_stack if isinstance(smc.policy, FrameStackPolicy) else 1


def check_model_layout(name: str, model: Any, action_names: Sequence[str], size: int, where: str,
                       frame_stack: int = 1) -> None:
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
                "the window, the outcomes and its previous action") if shape in ((HAND_SIZE,), (9,)) else ""
        raise LayoutMismatchError(
            f"SMC {name!r}: {where} has {have}, but its observation layout is ({frame_stack * size},) "
            f"({HAND_SIZE} window + {size - HAND_SIZE - len(action_names)} outcomes + "
            f"{len(action_names)} previous action{stacked}){bare}")


# ---------------------------------------------------------------------------------------------------------------
# Writing
# ---------------------------------------------------------------------------------------------------------------

def entry_for(smc: SMC) -> dict[str, Any]:
    """The manifest entry of ``smc`` (without the ``model`` file and ``sha256`` fields the save adds)."""
    return make_entry(smc.kind, type(smc.model).__name__, [c.name for c in smc.children], smc.include_primitives,
                      frame_stack_of(smc), smc.spec, smc.record, smc.evaluations, smc.test_score)


def make_entry(kind: str, algo: str, children: Sequence[str], include_primitives: bool, frame_stack: int,
               spec: TrainingSpec | None, record: TrainingRecord | None,
               evaluations: Sequence[EvaluationRecord] = (), test_score: float | None = None) -> dict[str, Any]:
    """A manifest entry (without ``model`` and ``sha256``).

    ``spec``, ``record`` and ``evaluations`` are the typed records; ``env_id`` ... ``total_timesteps`` repeat the
    most-used of their values for people and tools reading the manifest (they are derived, never read back).
    """
    action_names = smc_action_names(kind, children, include_primitives)
    return {
        "kind": kind,
        "algo": algo,
        "children": list(children),
        "include_primitives": include_primitives,
        "action_names": list(action_names),
        "observation": observation_layout(len(children), len(action_names)),
        "frame_stack": frame_stack,
        "spec": spec.to_dict() if spec is not None else None,
        "record": record.to_dict() if record is not None else None,
        "evaluations": [e.to_dict() for e in evaluations],
        "env_id": spec.task.env_id if spec is not None else None,
        "datasets": list(spec.task.datasets) if spec is not None else [],
        "seed": spec.seed if spec is not None else None,
        "selected_update": record.selected_update if record is not None else None,
        "training_return": record.selected_return if record is not None else None,
        "test_score": test_score,
        "total_timesteps": record.total_timesteps if record is not None else None,
    }


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
        atomic_write(tmp / MANIFEST, json.dumps(manifest, indent=2, allow_nan=False) + "\n")
        replace_directory(tmp, target)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def new_manifest(smcs: dict[str, dict[str, Any]]) -> dict[str, Any]:
    return {"format": FORMAT, "version": FORMAT_VERSION, "created_with": package_versions(), "smcs": smcs}


def _current_manifest(root: Path) -> tuple[dict[str, Any], Path]:
    """The manifest of the library in ``root`` (a new, empty one where there is none), which must be of the current
    version to be written."""
    manifest_path = root / MANIFEST
    if not manifest_path.is_file():
        return new_manifest({}), manifest_path
    manifest, _ = read_manifest(root)
    if _check_version(manifest, manifest_path) != FORMAT_VERSION:
        raise ManifestError(f"{manifest_path}: version {manifest['version']} library; convert it first "
                            "(SMCLibrary.load(path).save())")
    return manifest, manifest_path


def add_to_library(root: Path, name: str, entry: dict[str, Any], model: bytes, *, replace: bool = False) -> None:
    """Add one SMC to the library directory ``root`` without touching what is already there.

    The model file is written atomically first, then the manifest (read, the entry added, written atomically), so
    an interruption leaves the library as it was or with the SMC complete; an existing library must be of the
    current version, and ``name`` must be new. Creates the library when ``root`` has no manifest. ``replace=True``:
    ``name`` must be there already (an SMC whose model file was damaged, trained again); its model file and entry
    are replaced the same way.
    """
    manifest, manifest_path = _current_manifest(root)
    smcs = manifest["smcs"]
    if name in smcs and not replace:
        raise LibraryError(f"{manifest_path}: already has an SMC named {name!r}")
    if replace and name not in smcs:
        raise LibraryError(f"{manifest_path}: has no SMC named {name!r} to replace")
    file = smcs[name]["model"] if replace else model_file_for(name, [e["model"] for e in smcs.values()])
    atomic_write(root / file, model)
    smcs[name] = {"model": file, **entry, "sha256": hashlib.sha256(model).hexdigest()}
    atomic_write(manifest_path, json.dumps(manifest, indent=2, allow_nan=False) + "\n")


def remove_from_library(root: Path, names: Collection[str]) -> None:
    """Remove the SMCs ``names`` from the library in ``root``: the manifest first (atomically), then their model
    files. No SMC left may call one of them."""
    manifest, manifest_path = _current_manifest(root)
    smcs = manifest["smcs"]
    unknown = sorted(set(names) - set(smcs))
    if unknown:
        raise LibraryError(f"{manifest_path}: has no SMC named {unknown[0]!r}{suggest(unknown[0], list(smcs))}")
    callers = sorted(n for n, e in smcs.items() if n not in names and set(e["children"]) & set(names))
    if callers:
        raise LibraryError(f"{manifest_path}: cannot remove {sorted(names)}: {callers} call them")
    files = [smcs.pop(name)["model"] for name in names]
    atomic_write(manifest_path, json.dumps(manifest, indent=2, allow_nan=False) + "\n")
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


def read_manifest(root: Path) -> tuple[dict[str, Any], Path]:
    """The manifest of the library in ``root`` as JSON data (any version), and its path."""
    manifest_path = root / MANIFEST
    if not manifest_path.is_file():
        raise ManifestError(f"no SMC library at {root}: {manifest_path} not found{interrupted_hint(root)}")
    try:
        return json.loads(manifest_path.read_text(encoding="utf-8")), manifest_path
    except (UnicodeDecodeError, json.JSONDecodeError) as err:
        raise ManifestError(f"{manifest_path} is not valid JSON (corrupt or truncated?): {err}") from None


_ENTRY_FIELDS: dict[str, tuple[type, ...]] = {
    "model": (str,),
    "kind": (str,),
    "algo": (str,),
    "children": (list,),
    "include_primitives": (bool,),
    "action_names": (list,),
    "observation": (dict,),
}


def _check_version(manifest: Any, where: Path) -> int:
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
    if version not in (1, FORMAT_VERSION):
        raise ManifestError(f"{where}: incompatible manifest version {version} (this sb3_smc reads versions 1 and "
                            f"{FORMAT_VERSION})")
    return version


def check_manifest(manifest: Any, where: Path) -> dict[str, dict[str, Any]]:
    """Validate a manifest (a version-1 one is upgraded first, :func:`upgrade_v1`); returns its entries with
    ``spec``, ``record`` and ``evaluations`` parsed into records."""
    if _check_version(manifest, where) == 1:
        manifest = upgrade_v1(manifest, where)
    smcs = manifest.get("smcs")
    if not isinstance(smcs, dict):
        raise ManifestError(f"{where}: 'smcs' must be an object name -> entry, got {type(smcs).__name__}")
    for name, entry in smcs.items():
        _check_entry(name, entry, where)
    for name, entry in smcs.items():
        for child in entry["children"]:
            if child not in smcs:
                raise MissingChildError(
                    f"{where}: SMC {name!r} calls child {child!r}, which is not in the library"
                    f"{suggest(child, [n for n in smcs if n != name], ' (it has no other SMC)')}")
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


def _check_entry(name: str, entry: Any, where: Path) -> None:
    if not isinstance(entry, dict):
        raise ManifestError(f"{where}: entry {name!r} must be an object, got {type(entry).__name__}")
    missing = [f for f in (*_ENTRY_FIELDS, "sha256", "spec", "record", "evaluations") if f not in entry]
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
    if not isinstance(entry["sha256"], str) or not re.fullmatch(r"[0-9a-f]{64}", entry["sha256"]):
        raise ManifestError(f"{where}: entry {name!r}: 'sha256' must be the 64 hex digits of the model file's "
                            f"SHA-256, got {entry['sha256']!r}")
    model = entry["model"]
    if Path(model).is_absolute() or ".." in Path(model).parts:
        raise ManifestError(f"{where}: entry {name!r}: model path {model!r} must be relative, inside the library")
    if not all(isinstance(c, str) for c in entry["children"]):
        raise ManifestError(f"{where}: entry {name!r}: children must be names, got {entry['children']!r}")
    for field, value in (("observation.size", entry["observation"].get("size")),
                         ("frame_stack", entry.get("frame_stack", 1))):
        if not isinstance(value, int) or isinstance(value, bool) or value < 1:
            raise ManifestError(f"{where}: entry {name!r}: {field} must be a positive integer, got {value!r}")
    _parse_records(name, entry, where)


def _parse_records(name: str, entry: dict[str, Any], where: Path) -> None:
    """Replace ``entry``'s spec / record / evaluations JSON by records (``ManifestError`` naming the field)."""
    def parse(field: str, parser: Callable[[Any], Any]) -> Any:
        value = entry[field]
        if value is None or isinstance(value, TrainingSpec | TrainingRecord):
            return value
        try:
            return parser(value)
        except RecordError as err:
            raise ManifestError(f"{where}: entry {name!r}: {err}") from None

    entry["spec"] = parse("spec", lambda v: TrainingSpec.from_dict(v, "spec"))
    entry["record"] = parse("record", lambda v: TrainingRecord.from_dict(v, "record"))
    evaluations = entry["evaluations"]
    if not isinstance(evaluations, list):
        raise ManifestError(f"{where}: entry {name!r}: 'evaluations' must be a list, got {evaluations!r}")
    parsed = []
    for i, value in enumerate(evaluations):
        if isinstance(value, EvaluationRecord):
            parsed.append(value)
            continue
        try:
            parsed.append(EvaluationRecord.from_dict(value, f"evaluations[{i}]"))
        except RecordError as err:
            raise ManifestError(f"{where}: entry {name!r}: {err}") from None
    entry["evaluations"] = parsed
    _check_summary(name, entry, where)
    spec = entry["spec"]
    if spec is not None:
        found = {"kind": (spec.task.kind, entry["kind"]), "children": (list(spec.children), entry["children"]),
                 "algo": (spec.algo, entry["algo"]), "frame_stack": (spec.frame_stack, entry.get("frame_stack", 1)),
                 "include_primitives": (spec.wrapper.include_primitives, entry["include_primitives"])}
        wrong = [f"{k}: spec {a!r}, entry {b!r}" for k, (a, b) in found.items() if a != b]
        if wrong:
            raise ManifestError(f"{where}: entry {name!r}: its training spec disagrees with the entry "
                                f"({'; '.join(wrong)})")


SUMMARY_FIELDS = ("env_id", "datasets", "seed", "selected_update", "training_return", "test_score", "total_timesteps")
"""Fields of an entry that repeat values of its records (for people and tools reading the manifest)."""


def _check_summary(name: str, entry: dict[str, Any], where: Path) -> None:
    """The summary fields must say what the records say (they are never read back, so a wrong one is an error)."""
    spec, record, evaluations = entry["spec"], entry["record"], entry["evaluations"]
    derived = make_entry(entry["kind"], entry["algo"], entry["children"], entry["include_primitives"],
                         entry.get("frame_stack", 1), spec, record, evaluations, test_score_of(spec, evaluations))
    for field in SUMMARY_FIELDS:
        if field in entry and entry[field] != derived[field]:
            raise ManifestError(f"{where}: entry {name!r}: {field!r} is {entry[field]!r}, but its records say "
                                f"{derived[field]!r}")


_V1_SUMMARY_TYPES = {"env_id": (str,), "datasets": (list,), "seed": (int,), "selected_update": (int,),
                     "training_return": (int, float), "test_score": (int, float), "total_timesteps": (int,)}


def _check_v1_summary(name: str, entry: dict[str, Any], where: Path) -> None:
    for field, types in _V1_SUMMARY_TYPES.items():
        value = entry.get(field)
        if value is not None and (isinstance(value, bool) or not isinstance(value, types)):
            raise ManifestError(f"{where}: version-1 entry {name!r}: {field!r} must be "
                                f"{' or '.join(t.__name__ for t in types)} or null, got {value!r}")


def upgrade_v1(manifest: dict[str, Any], where: Path) -> dict[str, Any]:
    """A version-1 manifest (sb3-smc 0.1) as version 2: each entry's ``metadata`` becomes typed records.

    The ``metadata`` that ``train_smc`` 0.1 wrote converts completely into a :class:`TrainingSpec` and a
    :class:`TrainingRecord` (the budget's ``total_timesteps`` is the number of steps actually run, which 0.1
    recorded instead of the requested one); a ``test_score`` becomes an :class:`EvaluationRecord` of the test split
    whose ``repeats`` and ``seed`` are unknown (``None``). An entry without training metadata (a model trained
    elsewhere) gets no spec and no record; other metadata keys are dropped.
    """
    smcs = manifest.get("smcs")
    if not isinstance(smcs, dict):
        raise ManifestError(f"{where}: 'smcs' must be an object name -> entry, got {type(smcs).__name__}")
    versions = {str(k): str(v) for k, v in (manifest.get("created_with") or {}).items()}
    upgraded = {}
    for name, entry in smcs.items():
        if not isinstance(entry, dict):
            raise ManifestError(f"{where}: entry {name!r} must be an object, got {type(entry).__name__}")
        new = {k: v for k, v in entry.items() if k != "metadata" and k not in SUMMARY_FIELDS}
        meta = entry.get("metadata") or {}
        if not isinstance(meta, dict):
            raise ManifestError(f"{where}: version-1 entry {name!r}: 'metadata' must be an object, got {meta!r}")
        _check_v1_summary(name, entry, where)
        try:
            spec, record = _v1_records(name, entry, meta, versions)
            evaluations = []
            if entry.get("test_score") is not None:
                evaluations.append(EvaluationRecord(
                    smc=name, env_id=entry.get("env_id") or meta.get("env_id") or "unknown", split="test",
                    kind=entry["kind"], repeats=None, seed=None, score=entry["test_score"]).to_dict())
        except (RecordError, KeyError, TypeError) as err:
            raise ManifestError(f"{where}: version-1 entry {name!r} cannot be converted to version "
                                f"{FORMAT_VERSION} ({type(err).__name__}: {err})") from None
        new.update(spec=spec, record=record, evaluations=evaluations)
        upgraded[name] = new
    return {**manifest, "version": FORMAT_VERSION, "smcs": upgraded}


def _v1_records(name: str, entry: dict[str, Any], meta: Mapping[str, Any],
                versions: dict[str, str]) -> tuple[dict | None, dict | None]:
    if not meta.get("env_id") or "training_returns" not in meta or entry["algo"] not in _V1_ALGORITHMS:
        return None, None
    hyper = dict(meta["hyperparameters"])
    n_steps = hyper.pop("n_steps")
    hyper["policy"] = meta["policy"]
    wrapper = dict(meta["wrapper"])
    spec = TrainingSpec(
        name=name,
        task=TaskSpec(meta["env_id"], kind=entry["kind"], datasets=tuple(meta.get("datasets") or ()),
                      env_kwargs=dict(meta.get("env_kwargs") or {})),
        algo=entry["algo"], hyperparameters=hyper, seed=meta["seed"],
        budget=Budget(meta["total_timesteps"], meta["n_envs"], n_steps),
        wrapper=WrapperSettings(entry["include_primitives"], wrapper["count_primitive_steps"],
                                wrapper["call_step_cap"], wrapper["max_steps"]),
        signal_bias=SignalBias(enabled=bool(meta["signal_bias"])), frame_stack=meta.get("frame_stack", 1),
        children=tuple(entry["children"]))
    probabilities = meta.get("initial_action_probabilities")
    record = TrainingRecord(
        training_returns=tuple(meta["training_returns"]),
        success_rates=tuple(meta["training_success_rates"]),
        selected_update=meta["selected_update"], selected_return=meta["training_return"],
        total_timesteps=meta["total_timesteps"], primitive_steps=meta["primitive_steps"],
        wall_time_s=meta["wall_time_s"], action_names=tuple(meta.get("action_names") or entry["action_names"]),
        initial_action_probabilities=None if probabilities is None else tuple(probabilities),
        torch_threads=meta.get("torch_threads", 1), versions=versions)
    return spec.to_dict(), record.to_dict()


def topological_order(entries: Mapping[str, Mapping[str, Any]], where: Path) -> list[str]:
    """Entry names, children before parents; :class:`LibraryError` naming the cycle if SMCs call each other."""
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


def check_model_file(root: Path, name: str, entry: Mapping[str, Any]) -> None:
    """:class:`CorruptModelError` unless entry ``name``'s model file is there, a readable SB3 zip, with the recorded
    SHA-256."""
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
    if sha256(file) != entry["sha256"]:
        raise CorruptModelError(f"SMC {name!r}: model file {file} does not match the SHA-256 recorded in the "
                                "manifest (modified or corrupt since it was saved)")


def load_model(root: Path, name: str, entry: Mapping[str, Any]) -> Any:
    """The SB3 model of entry ``name``, after checking its file (:func:`check_model_file`)."""
    check_model_file(root, name, entry)
    file = root / entry["model"]
    algorithm = ALGORITHM_REGISTRY[entry["algo"]]
    cls = algorithm.load_class()
    try:
        model = cls.load(file, device="cpu")
    except Exception as err:  # noqa: BLE001 - SB3 raises many kinds of errors for a bad archive
        raise CorruptModelError(f"SMC {name!r}: cannot load model file {file} as {entry['algo']}: "
                                f"{type(err).__name__}: {err}") from err
    from sb3_contrib.common.recurrent.policies import RecurrentActorCriticPolicy

    if isinstance(model.policy, RecurrentActorCriticPolicy) != algorithm.recurrent:
        raise CorruptModelError(f"SMC {name!r}: the manifest says {entry['algo']}, but {file} holds a "
                                f"{type(model.policy).__name__} (a model of another algorithm)")
    return model
