"""Manifests of earlier versions, converted on read to the current one (:mod:`sb3_smc.library.manifest`).

- Version 1 (sb3-smc 0.1): a free-form ``metadata`` dict per SMC, converted into typed records
  (:func:`upgrade_v1`).
- Version 2: each entry also repeated what its spec says (kind, algorithm, children, primitives, frame stacking,
  environment layout), its action names and observation layout, and seven summary fields, all cross-checked on read.
  :func:`upgrade_v2` runs those checks (a version-2 file that contradicts itself is still an error) and keeps what
  version 3 stores.
- Version 4: the content of version 5 (its checksums verified), but its model files are pickled SB3 archives
  (``models/<name>.zip``), which load only with ``trust=True``; saving the library writes them in version 5's format.
- Version 3: the content of version 4 without its checksums (:func:`sb3_smc.library.manifest.seal`), which are
  written with it the next time it is written.
- Version 5: the content of version 6, whose SMCs may also be of the ``bring-about-or-cannot`` kind; read as it is.

JSON in, JSON out; saving a loaded library (``SMCLibrary.load(path).save()``) writes the current version.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from sb3_smc.core.hyperparameters import ALGORITHMS
from sb3_smc.library.errors import LayoutMismatchError, ManifestError
from sb3_smc.library.manifest import (
    ENTRY_FIELDS,
    FORMAT_VERSION,
    SMC_FIELDS,
    SUMMARY_FIELDS,
    LibraryEntry,
    check_version,
    parse_entry,
    parse_layout,
    unseal,
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
)

__all__ = ["dropped_fields", "upgrade", "upgrade_v1", "upgrade_v2"]


def upgrade(manifest: Any, where: Path) -> dict[str, Any]:
    """``manifest`` (JSON) as the current version without its checksums: one of the current version checked against
    them (:func:`~sb3_smc.library.manifest.unseal`), an older one converted step by step."""
    version = check_version(manifest, where)
    if version >= 4:
        return {**unseal(manifest, where), "version": FORMAT_VERSION}
    if version == 1:
        manifest = upgrade_v1(manifest, where)
        version = 2
    if version == 2:
        manifest = upgrade_v2(manifest, where)
    return {**manifest, "version": FORMAT_VERSION}


# ---------------------------------------------------------------------------------------------------------------
# Version 2
# ---------------------------------------------------------------------------------------------------------------

_V2_FIELDS: dict[str, tuple[type, ...]] = {
    "model": (str,), "kind": (str,), "algo": (str,), "children": (list,), "include_primitives": (bool,),
    "action_names": (list,), "observation": (dict,),
}


_V2_ENTRY = {*_V2_FIELDS, "sha256", "spec", "record", "evaluations", "frame_stack", "layout", *SUMMARY_FIELDS}
"""Every field version 2 wrote in an entry."""


def dropped_fields(manifest: dict[str, Any]) -> dict[str, list[str]]:
    """Entry name -> the fields of a version-2 entry that are none of version 2's own (a user's additions, which the
    conversion to version 3 does not keep)."""
    smcs = manifest.get("smcs")
    if not isinstance(smcs, dict):
        return {}
    return {name: extra for name, entry in smcs.items()
            if isinstance(entry, dict) and (extra := sorted(set(entry) - _V2_ENTRY))}


def upgrade_v2(manifest: dict[str, Any], where: Path) -> dict[str, Any]:
    """A version-2 manifest as version 3, after checking that each entry's repeated fields say what its records
    say (:class:`ManifestError` / :class:`LayoutMismatchError` naming the entry and field otherwise)."""
    smcs = manifest.get("smcs")
    if not isinstance(smcs, dict):
        raise ManifestError(f"{where}: 'smcs' must be an object name -> entry, got {type(smcs).__name__}")
    upgraded = {}
    for name, entry in smcs.items():
        _check_v2_fields(name, entry, where)
        new = {field: copy.deepcopy(entry[field]) for field in ENTRY_FIELDS}
        if entry["spec"] is None:
            new["smc"] = {field: entry.get(field, 1) for field in SMC_FIELDS}
            if entry.get("layout") is not None:
                new["smc"]["layout"] = entry["layout"]
        checked = parse_entry(name, new, where)
        _check_v2_agreement(name, entry, checked, where)
        upgraded[name] = new
    return {**manifest, "version": 3, "smcs": upgraded}


def _check_v2_fields(name: str, entry: Any, where: Path) -> None:
    if not isinstance(entry, dict):
        raise ManifestError(f"{where}: entry {name!r} must be an object, got {type(entry).__name__}")
    missing = [f for f in (*_V2_FIELDS, "sha256", "spec", "record", "evaluations") if f not in entry]
    if missing:
        raise ManifestError(f"{where}: entry {name!r} lacks the field(s) {missing}")
    for field, types in _V2_FIELDS.items():
        if not isinstance(entry[field], types):
            raise ManifestError(f"{where}: entry {name!r}: {field!r} must be {types[0].__name__}, got "
                                f"{entry[field]!r}")
    if entry["algo"] not in ALGORITHMS:
        raise ManifestError(f"{where}: entry {name!r}: unknown algorithm {entry['algo']!r} (supported: "
                            f"{list(ALGORITHMS)})")
    for field, value in (("observation.size", entry["observation"].get("size")),
                         ("frame_stack", entry.get("frame_stack", 1))):
        if not isinstance(value, int) or isinstance(value, bool) or value < 1:
            raise ManifestError(f"{where}: entry {name!r}: {field} must be a positive integer, got {value!r}")


def _check_v2_agreement(name: str, entry: dict[str, Any], checked: LibraryEntry, where: Path) -> None:
    """The facts a version-2 entry repeats must be those of its records (they were never read back)."""
    layout = parse_layout(name, entry.get("layout"), where)
    if checked.spec is not None:
        found = {"kind": (checked.kind, entry["kind"]), "children": (list(checked.children), entry["children"]),
                 "algo": (checked.algo, entry["algo"]), "frame_stack": (checked.frame_stack,
                                                                         entry.get("frame_stack", 1)),
                 "include_primitives": (checked.include_primitives, entry["include_primitives"])}
        wrong = [f"{k}: spec {a!r}, entry {b!r}" for k, (a, b) in found.items() if a != b]
        if checked.layout != layout:
            wrong.append(f"layout: spec {checked.layout}, entry {layout}")
        if wrong:
            raise ManifestError(f"{where}: entry {name!r}: its training spec disagrees with the entry "
                                f"({'; '.join(wrong)})")
    if entry["action_names"] != list(checked.action_names):
        raise LayoutMismatchError(
            f"{where}: SMC {name!r}: action names {entry['action_names']} do not match its kind "
            f"{checked.kind!r}, children {list(checked.children)} and include_primitives="
            f"{checked.include_primitives} (expected {list(checked.action_names)})")
    if entry["observation"] != checked.observation:
        raise LayoutMismatchError(
            f"{where}: SMC {name!r}: observation {entry['observation']} does not match its children and actions "
            f"(expected {checked.observation}: "
            f"{checked.layout.describe(len(checked.children), len(checked.action_names))})")
    summary = checked.summary()
    for field in SUMMARY_FIELDS:
        if field in entry and entry[field] != summary[field]:
            raise ManifestError(f"{where}: entry {name!r}: {field!r} is {entry[field]!r}, but its records say "
                                f"{summary[field]!r}")


# ---------------------------------------------------------------------------------------------------------------
# Version 1
# ---------------------------------------------------------------------------------------------------------------

_V1_ALGORITHMS = ("RecurrentPPO", "TRPO")
"""The algorithms of sb3-smc 0.1, whose version-1 entries carry a training spec to convert."""

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
                    kind=entry["kind"], repeats=None, evaluation_seed=None, score=entry["test_score"]).to_dict())
        except (RecordError, KeyError, TypeError) as err:
            raise ManifestError(f"{where}: version-1 entry {name!r} cannot be converted ({type(err).__name__}: "
                                f"{err})") from None
        new.update(spec=spec, record=record, evaluations=evaluations)
        upgraded[name] = new
    return {**manifest, "version": 2, "smcs": upgraded}


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
