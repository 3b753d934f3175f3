"""The manifest of an SMC library: its schema (format, version, the entry of one SMC), its validation, and the order
in which SMCs that call each other load. Manifests of earlier versions are converted on read
(:mod:`sb3_smc.library.upgrade`).

An entry stores each fact once (since version 3): the model file and its checksum, the SMC's training ``spec``, its
training ``record`` and its ``evaluations``. What the SMC is (kind, algorithm, children, primitives, frame stacking,
environment layout) is read from the spec; only an SMC without one (trained elsewhere, e.g. imported from rl_zoo3)
says it in an ``smc`` field instead. Summaries (action names, observation size, seed, test score ...) are derived
on read (:class:`LibraryEntry`). Version 4 adds checksums of the manifest's own content, written by :func:`seal`
and verified on read by :func:`unseal`: ``entry_sha256`` in each entry, ``manifest_sha256`` for the whole.

JSON data in, JSON data (and typed records) out: reading and writing the files is :mod:`sb3_smc.library.storage`'s.
"""

from __future__ import annotations

import functools
import hashlib
import json
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from sb3_smc.core.dag import CycleError, children_first
from sb3_smc.core.hyperparameters import ALGORITHM_REGISTRY
from sb3_smc.core.layout import PIXELWORLD_LAYOUT, SIGNALS, Layout, observation_size, smc_action_names
from sb3_smc.core.names import name_problem
from sb3_smc.errors import SMCError
from sb3_smc.library.errors import LayoutMismatchError, LibraryError, ManifestError, MissingChildError, suggest
from sb3_smc.records import (
    EvaluationRecord,
    RecordError,
    TrainingRecord,
    TrainingSpec,
    package_versions,
    test_score_of,
)

__all__ = ["ENTRY_CHECKSUM", "FORMAT", "FORMAT_VERSION", "MANIFEST", "MANIFEST_CHECKSUM", "MODELS",
           "SUMMARY_FIELDS", "LibraryEntry", "check_entries", "check_version", "content_sha256", "entry_checksum",
           "entry_json", "layout_json", "model_path", "new_manifest", "seal", "topological_order", "unseal"]

FORMAT = "sb3-smc-library"
"""Value of the manifest's ``format`` field."""
FORMAT_VERSION = 6
"""Manifest version written. Versions 1 (sb3-smc 0.1), 2 (each entry repeating its spec's facts and summaries), 3
(no checksums of the manifest's content) and 4 (pickled SB3 archives as model files) are read through
:mod:`sb3_smc.library.upgrade`. Version 5 names content-addressed model files that load without unpickling
(:mod:`sb3_smc.library.model_file`); an entry of an earlier library converted on read may still name a pickled
``.zip`` archive until the library is saved again with ``trust=True``. Version 6 is version 5 that may hold SMCs of
every kind of PixelWorld's table (``bring-about-or-cannot`` besides the two of version 5): a reader of version 5
refuses it by its version, with "upgrade sb3_smc", rather than at an SMC of a kind it does not know."""
MANIFEST = "manifest.json"
MODELS = "models"
"""The folder of a library's model files."""

ENTRY_CHECKSUM = "entry_sha256"
"""The field of a version-4 entry holding the SHA-256 of its name and content (:func:`seal`)."""
MANIFEST_CHECKSUM = "manifest_sha256"
"""The field of a version-4 manifest holding the SHA-256 of its whole content (:func:`seal`)."""
ENTRY_FIELDS = ("model", "sha256", "spec", "record", "evaluations")
"""The fields of every entry (its checksum aside); an SMC without a spec has an ``smc`` field too
(:data:`SMC_FIELDS`)."""
SMC_FIELDS: dict[str, tuple[type, ...]] = {"kind": (str,), "algo": (str,), "children": (list,),
                                           "include_primitives": (bool,), "frame_stack": (int,)}
"""What an entry without a spec says in its ``smc`` field (plus ``layout`` for another environment's SMC)."""
SUMMARY_FIELDS = ("env_id", "datasets", "seed", "selected_update", "training_return", "test_score", "total_timesteps")
"""The values of :meth:`LibraryEntry.summary` read from the records (version 2 also stored them in each entry)."""


def layout_json(layout: Layout) -> dict[str, Any]:
    """A layout as JSON (``sensor_size``, ``primitives``)."""
    return {"sensor_size": layout.sensor_size, "primitives": list(layout.primitives)}


@dataclass(frozen=True)
class LibraryEntry:
    """One checked entry of a manifest: the model file, what the SMC is (read from its spec where it has one) and its
    records."""

    model: str
    sha256: str
    kind: str
    algo: str
    children: tuple[str, ...]
    include_primitives: bool
    frame_stack: int
    layout: Layout
    spec: TrainingSpec | None
    record: TrainingRecord | None
    evaluations: tuple[EvaluationRecord, ...]
    checksum: str = ""
    """The entry's checksum (:func:`entry_checksum`): who saves the library compares it with the one on disk."""

    @property
    def action_names(self) -> tuple[str, ...]:
        return smc_action_names(self.kind, self.children, self.include_primitives, self.layout.primitives)

    @property
    def observation_size(self) -> int:
        """Length of one observation (before frame stacking)."""
        return observation_size(len(self.children), len(self.action_names), self.layout.sensor_size)

    @property
    def observation(self) -> dict[str, int]:
        """The parts of an observation in order: total ``size``, PixelWorld's ``window`` (another environment's
        ``sensor``), ``outcomes``, ``previous_action``."""
        return {"size": self.observation_size, self.layout.sensor_name: self.layout.sensor_size,
                "outcomes": len(self.children), "previous_action": len(self.action_names)}

    def summary(self) -> dict[str, Any]:
        """The most-used values of the records (:data:`SUMMARY_FIELDS`; ``None`` where there is no record)."""
        spec, record = self.spec, self.record
        return {"env_id": spec.task.env_id if spec is not None else None,
                "datasets": list(spec.task.datasets) if spec is not None else [],
                "seed": spec.seed if spec is not None else None,
                "selected_update": record.selected_update if record is not None else None,
                "training_return": record.selected_return if record is not None else None,
                "test_score": test_score_of(spec, self.evaluations),
                "total_timesteps": record.total_timesteps if record is not None else None}


def entry_json(name: str, algo: str, frame_stack: int, spec: TrainingSpec | None, record: TrainingRecord | None,
               evaluations: tuple[EvaluationRecord, ...] = (), *, kind: str | None = None,
               children: tuple[str, ...] = (), include_primitives: bool = True,
               layout: Layout = PIXELWORLD_LAYOUT) -> dict[str, Any]:
    """An entry of the current version (without ``model`` and ``sha256``, which the save adds, and the checksum of its
    content, which :func:`seal` adds).

    With a ``spec``, the model's ``algo`` and ``frame_stack`` must be the spec's (:class:`LibraryError` otherwise: a
    model the manifest would describe wrongly is never written); without one, ``kind``, ``children``,
    ``include_primitives`` and ``layout`` say what the SMC is.
    """
    entry: dict[str, Any] = {"spec": spec.to_dict() if spec is not None else None,
                             "record": record.to_dict() if record is not None else None,
                             "evaluations": [e.to_dict() for e in evaluations]}
    if spec is not None:
        wrong = [f"{field}: spec {a!r}, model {b!r}" for field, a, b in
                 (("algo", spec.algo, algo), ("frame_stack", spec.frame_stack, frame_stack)) if a != b]
        if wrong:
            raise LibraryError(f"SMC {name!r}: its training spec does not describe its model ({'; '.join(wrong)})")
        return entry
    if kind is None:
        raise LibraryError(f"SMC {name!r}: an entry without a training spec needs the SMC's kind")
    smc = {"kind": kind, "algo": algo, "children": list(children), "include_primitives": include_primitives,
           "frame_stack": frame_stack}
    if layout != PIXELWORLD_LAYOUT:
        smc["layout"] = layout_json(layout)
    return {**entry, "smc": smc}


def new_manifest(smcs: dict[str, dict[str, Any]]) -> dict[str, Any]:
    return {"format": FORMAT, "version": FORMAT_VERSION, "created_with": package_versions(), "smcs": smcs}


_SHA256 = re.compile(r"[0-9a-f]{64}")
_MODEL = re.compile(rf"{MODELS}/([0-9a-f]{{64}})\.safetensors")
_PICKLED_MODEL = re.compile(rf"{MODELS}/[A-Za-z0-9][A-Za-z0-9_.+=@-]{{0,120}}\.zip")
"""The model file of an entry: ``models/<its SHA-256>.safetensors``, or an old library's pickled archive
``models/<safe name>.zip`` (loaded only with trust)."""


def model_path(sha256: str) -> str:
    """The manifest path of the model file whose bytes have this SHA-256."""
    return f"{MODELS}/{sha256}.safetensors"


def _canonical(value: Any) -> str:
    """JSON data's canonical text: keys sorted, no spaces (what :func:`content_sha256` hashes)."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), ensure_ascii=False)


def content_sha256(value: Any) -> str:
    """The SHA-256 of JSON data's content, whatever its layout in a file (its canonical form: keys sorted, no
    spaces)."""
    return hashlib.sha256(_canonical(value).encode("utf-8")).hexdigest()


def _without(data: dict[str, Any], field: str) -> dict[str, Any]:
    return {key: value for key, value in data.items() if key != field}


def _entry_sha256(name: str, entry: dict[str, Any]) -> str:
    return content_sha256([name, _without(entry, ENTRY_CHECKSUM)])


def entry_checksum(name: str, entry: dict[str, Any]) -> str:
    """The checksum :func:`seal` writes for entry ``name`` (JSON data, without its own checksum): equal checksums,
    equal entries (model file included)."""
    return _entry_sha256(name, entry)


def seal(manifest: dict[str, Any], known: dict[str, tuple[str, str]] | None = None) -> dict[str, Any]:
    """``manifest`` with the checksums of its own content, as it is written: in each entry ``entry_sha256`` (of the
    SMC's name and every other field of its entry), and ``manifest_sha256`` (of everything else, the entries'
    checksums included). Checksums ``manifest`` holds already are replaced.

    ``known``: by name, what was computed before for entries unchanged since (the caller's word): the entry's
    checksum and the canonical text of the sealed entry; those missing are computed and added to it. The whole
    manifest's canonical text is joined from the entries' texts, so an add to a library of hundreds of SMCs
    serializes only its own entry (the same text as ``content_sha256`` of the whole: tested)."""
    known = {} if known is None else known
    for name, entry in manifest["smcs"].items():
        if name not in known:
            checksum = _entry_sha256(name, entry)
            known[name] = checksum, _canonical({**_without(entry, ENTRY_CHECKSUM), ENTRY_CHECKSUM: checksum})
    smcs = {name: {**_without(entry, ENTRY_CHECKSUM), ENTRY_CHECKSUM: known[name][0]}
            for name, entry in manifest["smcs"].items()}
    content = {**_without(manifest, MANIFEST_CHECKSUM), "smcs": smcs}
    entries = "{" + ",".join(f"{_canonical(name)}:{known[name][1]}" for name in sorted(smcs)) + "}"
    text = "{" + ",".join(f"{_canonical(key)}:{entries if key == 'smcs' else _canonical(content[key])}"
                          for key in sorted(content)) + "}"
    return {**content, MANIFEST_CHECKSUM: hashlib.sha256(text.encode("utf-8")).hexdigest()}


def unseal(manifest: dict[str, Any], where: Path) -> dict[str, Any]:
    """A manifest of version 4 or later without its checksums, after checking that its content is what
    :func:`seal` wrote (:class:`ManifestError` naming the file and the SMC whose entry changed, or saying that
    something outside the entries did)."""
    fix = ("edited by hand or damaged since sb3_smc wrote it; restore it, or write an edit meant to be kept with "
           "sb3_smc.library.storage.write_manifest")
    smcs = manifest.get("smcs")
    if not isinstance(smcs, dict):
        raise ManifestError(f"{where}: 'smcs' must be an object name -> entry, got {type(smcs).__name__}")
    entries = {}
    for name, entry in smcs.items():
        if not isinstance(entry, dict):
            raise ManifestError(f"{where}: entry {name!r} must be an object, got {type(entry).__name__}")
        recorded = entry.get(ENTRY_CHECKSUM)
        if not isinstance(recorded, str) or not _SHA256.fullmatch(recorded):
            raise ManifestError(f"{where}: entry {name!r}: {ENTRY_CHECKSUM!r} must be the 64 hex digits of the "
                                f"SHA-256 of the entry's content (version {FORMAT_VERSION}), got {recorded!r}")
        if recorded != _entry_sha256(name, entry):
            raise ManifestError(f"{where}: the entry of SMC {name!r} does not match its {ENTRY_CHECKSUM!r}: {fix}")
        entries[name] = _without(entry, ENTRY_CHECKSUM)
    recorded = manifest.get(MANIFEST_CHECKSUM)
    if not isinstance(recorded, str) or not _SHA256.fullmatch(recorded):
        raise ManifestError(f"{where}: {MANIFEST_CHECKSUM!r} must be the 64 hex digits of the SHA-256 of the "
                            f"manifest's content (version {FORMAT_VERSION}), got {recorded!r}")
    if recorded != content_sha256(_without(manifest, MANIFEST_CHECKSUM)):
        raise ManifestError(f"{where}: the manifest does not match its {MANIFEST_CHECKSUM!r} outside the SMC entries "
                            f"(its created_with changed, or a whole entry was added or removed): {fix}")
    return {**_without(manifest, MANIFEST_CHECKSUM), "smcs": entries}


def check_version(manifest: Any, where: Path) -> int:
    """The version of ``manifest`` (1 to :data:`FORMAT_VERSION`); :class:`ManifestError` for anything else."""
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
    if version < 1:
        raise ManifestError(f"{where}: incompatible manifest version {version} (this sb3_smc reads versions 1 to "
                            f"{FORMAT_VERSION})")
    return version


def check_entries(manifest: dict[str, Any], where: Path) -> dict[str, LibraryEntry]:
    """The entries of a manifest of the current version, checked and with their records parsed (one of an earlier
    version is converted first: :func:`sb3_smc.library.storage.check_manifest`)."""
    smcs = manifest.get("smcs")
    if not isinstance(smcs, dict):
        raise ManifestError(f"{where}: 'smcs' must be an object name -> entry, got {type(smcs).__name__}")
    for name in smcs:
        problem = name_problem(name)
        if problem is not None:
            raise ManifestError(f"{where}: SMC {name!r} is not a name: {problem}")
    entries = {name: parse_entry(name, entry, where) for name, entry in smcs.items()}
    for name, entry in entries.items():
        for child in entry.children:
            if child not in entries:
                raise MissingChildError(
                    f"{where}: SMC {name!r} calls child {child!r}, which is not in the library"
                    f"{suggest(child, [n for n in entries if n != name], ' (it has no other SMC)')}")
        other = [child for child in entry.children if entries[child].layout != entry.layout]
        if other:
            raise LayoutMismatchError(f"{where}: SMC {name!r} ({entry.layout}) calls {other}, which act on another "
                                      "environment layout")
    return entries


def parse_entry(name: str, entry: Any, where: Path) -> LibraryEntry:
    """One entry of the current version (its checksum verified and removed: :func:`unseal`), checked
    (:class:`ManifestError` naming the entry and the field)."""
    if not isinstance(entry, dict):
        raise ManifestError(f"{where}: entry {name!r} must be an object, got {type(entry).__name__}")
    missing = [f for f in ENTRY_FIELDS if f not in entry]
    if missing:
        raise ManifestError(f"{where}: entry {name!r} lacks the field(s) {missing}")
    unknown = sorted(set(entry) - {*ENTRY_FIELDS, "smc"})
    if unknown:
        spec_says = " (since version 3 an entry reads what the SMC is from its spec)" if entry["spec"] is not None \
            else ""
        raise ManifestError(f"{where}: entry {name!r}: unknown field(s) {unknown}{spec_says}; an entry has "
                            f"{list(ENTRY_FIELDS)}, and 'smc' when it has no spec")
    if not isinstance(entry["sha256"], str) or not _SHA256.fullmatch(entry["sha256"]):
        raise ManifestError(f"{where}: entry {name!r}: 'sha256' must be the 64 hex digits of the model file's "
                            f"SHA-256, got {entry['sha256']!r}")
    model = entry["model"]
    if not isinstance(model, str) or Path(model).is_absolute() or ".." in Path(model).parts:
        raise ManifestError(f"{where}: entry {name!r}: model path {model!r} must be relative, inside the library")
    addressed = _MODEL.fullmatch(model)
    if addressed is None and not _PICKLED_MODEL.fullmatch(model):
        raise ManifestError(f"{where}: entry {name!r}: model path {model!r} must be {MODELS}/<its SHA-256>.safetensors "
                            f"(or an old library's {MODELS}/<name>.zip)")
    if addressed is not None and addressed.group(1) != entry["sha256"]:
        raise ManifestError(f"{where}: entry {name!r}: model file {model!r} is not named by its recorded SHA-256 "
                            f"{entry['sha256']!r}")
    spec, record, evaluations = _parse_records(name, entry, where)
    if spec is None:
        smc = entry.get("smc")
        if smc is None:
            raise ManifestError(f"{where}: entry {name!r} has no spec and no 'smc' field saying what the SMC is")
        kind, algo, children, include_primitives, frame_stack, layout = _parse_smc(name, smc, where)
    else:
        if "smc" in entry:
            raise ManifestError(f"{where}: entry {name!r}: an entry with a spec has no 'smc' field (what the SMC "
                                "is is read from its spec)")
        if spec.task.kind is None:
            raise ManifestError(f"{where}: entry {name!r}: spec.task.kind is null (a trained SMC's spec names the "
                                "kind of its task)")
        kind, algo, children, frame_stack = spec.task.kind, spec.algo, spec.children, spec.frame_stack
        include_primitives, layout = spec.wrapper.include_primitives, spec.task.smc_layout
    return LibraryEntry(model, entry["sha256"], kind, algo, children, include_primitives, frame_stack, layout, spec,
                        record, evaluations, entry_checksum(name, entry))


def _parse_smc(name: str, smc: Any, where: Path) -> tuple[str, str, tuple[str, ...], bool, int, Layout]:
    if not isinstance(smc, dict):
        raise ManifestError(f"{where}: entry {name!r}: 'smc' must be an object, got {smc!r}")
    missing = [f for f in SMC_FIELDS if f not in smc]
    unknown = sorted(set(smc) - {*SMC_FIELDS, "layout"})
    if missing or unknown:
        raise ManifestError(f"{where}: entry {name!r}: 'smc' " + (f"lacks {missing}" if missing else
                                                                   f"has unknown field(s) {unknown}"))
    for field, types in SMC_FIELDS.items():
        if not isinstance(smc[field], types) or (types == (int,) and isinstance(smc[field], bool)):
            raise ManifestError(f"{where}: entry {name!r}: smc.{field} must be {types[0].__name__}, got "
                                f"{smc[field]!r}")
    if smc["kind"] not in SIGNALS:
        raise ManifestError(f"{where}: entry {name!r}: unknown kind {smc['kind']!r} (expected one of "
                            f"{list(SIGNALS)})")
    if smc["algo"] not in ALGORITHM_REGISTRY:
        raise ManifestError(f"{where}: entry {name!r}: unknown algorithm {smc['algo']!r} (supported: "
                            f"{list(ALGORITHM_REGISTRY)})")
    children = smc["children"]
    if not all(isinstance(c, str) for c in children) or len(set(children)) != len(children):
        raise ManifestError(f"{where}: entry {name!r}: smc.children must be distinct names, got {children!r}")
    if smc["frame_stack"] < 1:
        raise ManifestError(f"{where}: entry {name!r}: smc.frame_stack must be a positive integer, got "
                            f"{smc['frame_stack']!r}")
    return (smc["kind"], smc["algo"], tuple(children), smc["include_primitives"], smc["frame_stack"],
            parse_layout(name, smc.get("layout"), where))


def parse_layout(name: str, layout: Any, where: Path) -> Layout:
    """An entry's ``layout`` JSON (``None``: PixelWorld's) as a :class:`~sb3_smc.core.layout.Layout`."""
    if layout is None:
        return PIXELWORLD_LAYOUT
    if not isinstance(layout, dict) or set(layout) != {"sensor_size", "primitives"} or not isinstance(
            layout["primitives"], list):
        raise ManifestError(f"{where}: entry {name!r}: 'layout' must be {{'sensor_size': int, 'primitives': "
                            f"[names]}}, got {layout!r}")
    try:
        return Layout(layout["sensor_size"], tuple(layout["primitives"]))
    except SMCError as err:
        raise ManifestError(f"{where}: entry {name!r}: layout: {err}") from None


def _parse_records(name: str, entry: dict[str, Any], where: Path) -> tuple[TrainingSpec | None,
                                                                          TrainingRecord | None,
                                                                          tuple[EvaluationRecord, ...]]:
    """The entry's spec, record and evaluations as records (``ManifestError`` naming the field)."""
    def parse(value: Any, parser: Callable[[Any], Any]) -> Any:
        try:
            return parser(value)
        except RecordError as err:
            raise ManifestError(f"{where}: entry {name!r}: {err}") from None

    spec = None if entry["spec"] is None else parse(entry["spec"], lambda v: TrainingSpec.from_dict(v, "spec"))
    record = (None if entry["record"] is None else
              parse(entry["record"], lambda v: TrainingRecord.from_dict(v, "record")))
    evaluations = entry["evaluations"]
    if not isinstance(evaluations, list):
        raise ManifestError(f"{where}: entry {name!r}: 'evaluations' must be a list, got {evaluations!r}")
    return spec, record, tuple(parse(value, functools.partial(EvaluationRecord.from_dict, where=f"evaluations[{i}]"))
                               for i, value in enumerate(evaluations))


def topological_order(entries: Mapping[str, LibraryEntry], where: Path) -> list[str]:
    """Entry names, children before parents; :class:`LibraryError` naming the cycle if SMCs call each other."""
    try:
        return children_first({name: entry.children for name, entry in entries.items()})
    except CycleError as err:
        raise LibraryError(f"{where}: SMCs call each other in a cycle: {err}") from None
