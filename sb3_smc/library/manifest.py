"""The manifest of an SMC library: its schema (format, version, the entry of one SMC), validation of any version
(a version-1 manifest is upgraded first), and the order in which SMCs that call each other load.

JSON data in, JSON data (and typed records) out: reading and writing the files is :mod:`sb3_smc.library.storage`'s.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from sb3_smc.errors import SMCError
from sb3_smc.hyperparameters import ALGORITHMS as TRAINED_ALGORITHMS
from sb3_smc.layout import PIXELWORLD_LAYOUT, SIGNALS, Layout, observation_size, smc_action_names
from sb3_smc.library.errors import LayoutMismatchError, LibraryError, ManifestError, MissingChildError, suggest
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

__all__ = ["ALGORITHMS", "FORMAT", "FORMAT_VERSION", "MANIFEST", "SUMMARY_FIELDS", "check_manifest", "check_version",
           "entry_layout", "make_entry", "new_manifest", "observation_layout", "topological_order", "upgrade_v1"]

FORMAT = "sb3-smc-library"
"""Value of the manifest's ``format`` field."""
FORMAT_VERSION = 2
"""Manifest version written. Version 1 (sb3-smc 0.1, a free-form ``metadata`` dict per SMC) is read through
:func:`upgrade_v1`."""
MANIFEST = "manifest.json"
ALGORITHMS = TRAINED_ALGORITHMS
"""Algorithms whose models a library stores (those ``train_smc`` trains; loaded with their class, ``device="cpu"``)."""


_V1_ALGORITHMS = ("RecurrentPPO", "TRPO")
"""The algorithms of sb3-smc 0.1, whose version-1 entries carry a training spec to convert."""


def observation_layout(n_children: int, n_actions: int, layout: Layout = PIXELWORLD_LAYOUT) -> dict[str, int]:
    """The manifest's ``observation``: total ``size``, then the parts in order (PixelWorld's ``window`` or another
    environment's ``sensor``, outcomes, previous action)."""
    return {"size": observation_size(n_children, n_actions, layout.sensor_size), layout.sensor_name: layout.sensor_size,
            "outcomes": n_children, "previous_action": n_actions}


def entry_layout(entry: dict[str, Any]) -> Layout:
    """The environment layout of a (checked) entry: its ``layout`` field, PixelWorld's when it has none."""
    layout = entry.get("layout")
    return PIXELWORLD_LAYOUT if layout is None else Layout(layout["sensor_size"], tuple(layout["primitives"]))


def make_entry(kind: str, algo: str, children: Sequence[str], include_primitives: bool, frame_stack: int,
               spec: TrainingSpec | None, record: TrainingRecord | None,
               evaluations: Sequence[EvaluationRecord] = (), test_score: float | None = None,
               layout: Layout = PIXELWORLD_LAYOUT) -> dict[str, Any]:
    """A manifest entry (without ``model`` and ``sha256``).

    ``spec``, ``record`` and ``evaluations`` are the typed records; ``env_id`` ... ``total_timesteps`` repeat the
    most-used of their values for people and tools reading the manifest (they are derived, never read back).
    ``layout``: the environment's sensor and primitives, written as the entry's ``layout`` unless PixelWorld's.
    """
    action_names = smc_action_names(kind, children, include_primitives, layout.primitives)
    environment = ({} if layout == PIXELWORLD_LAYOUT else
                   {"layout": {"sensor_size": layout.sensor_size, "primitives": list(layout.primitives)}})
    return {
        "kind": kind,
        "algo": algo,
        "children": list(children),
        "include_primitives": include_primitives,
        "action_names": list(action_names),
        **environment,
        "observation": observation_layout(len(children), len(action_names), layout),
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


def new_manifest(smcs: dict[str, dict[str, Any]]) -> dict[str, Any]:
    return {"format": FORMAT, "version": FORMAT_VERSION, "created_with": package_versions(), "smcs": smcs}


_ENTRY_FIELDS: dict[str, tuple[type, ...]] = {
    "model": (str,),
    "kind": (str,),
    "algo": (str,),
    "children": (list,),
    "include_primitives": (bool,),
    "action_names": (list,),
    "observation": (dict,),
}


def check_version(manifest: Any, where: Path) -> int:
    """The version of ``manifest`` (1 or :data:`FORMAT_VERSION`); :class:`ManifestError` for anything else."""
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
    if check_version(manifest, where) == 1:
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
        environment = entry_layout(entry)
        other = [child for child in entry["children"] if entry_layout(smcs[child]) != environment]
        if other:
            raise LayoutMismatchError(f"{where}: SMC {name!r} ({environment}) calls {other}, which act on another "
                                      "environment layout")
        expected = list(smc_action_names(entry["kind"], entry["children"], entry["include_primitives"],
                                         environment.primitives))
        if entry["action_names"] != expected:
            raise LayoutMismatchError(
                f"{where}: SMC {name!r}: action names {entry['action_names']} do not match its kind "
                f"{entry['kind']!r}, children {entry['children']} and include_primitives="
                f"{entry['include_primitives']} (expected {expected})")
        layout = observation_layout(len(entry["children"]), len(expected), environment)
        if entry["observation"] != layout:
            raise LayoutMismatchError(
                f"{where}: SMC {name!r}: observation {entry['observation']} does not match its children and actions "
                f"(expected {layout}: {environment.describe(len(entry['children']), len(expected))})")
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
    layout = entry.get("layout")
    if layout is not None:
        if not isinstance(layout, dict) or set(layout) != {"sensor_size", "primitives"} or not isinstance(
                layout["primitives"], list):
            raise ManifestError(f"{where}: entry {name!r}: 'layout' must be {{'sensor_size': int, 'primitives': "
                                f"[names]}}, got {layout!r}")
        try:
            Layout(layout["sensor_size"], tuple(layout["primitives"]))
        except SMCError as err:
            raise ManifestError(f"{where}: entry {name!r}: layout: {err}") from None
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
                         entry.get("frame_stack", 1), spec, record, evaluations, test_score_of(spec, evaluations),
                         entry_layout(entry))
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
