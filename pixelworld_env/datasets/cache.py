"""Disk cache of generated datasets.

``load_or_generate(spec, seed)`` returns the cached dataset when a valid cache file exists and otherwise
generates it (:func:`pixelworld_env.generation.dataset.generate`) and writes the file.

* Location: ``$PIXELWORLD_CACHE`` if set, else ``$XDG_CACHE_HOME/pixelworld``, else
  ``~/.cache/pixelworld`` (:func:`cache_dir`).
* Key: the SHA-256 of a canonical JSON document of everything that affects the result — the spec's
  name, kind, concept and generator logic, the macros they actually use (after following macro
  references), settings, ``num_samples``, world size, floor height and padding, the seed,
  :data:`~pixelworld_env.generation.dataset.GENERATOR_VERSION`, this file format's version and the shape
  library parameters (:func:`cache_key`).
* File: ``<cache>/<name>-<first 16 hex digits of the key>.json.gz``, gzip (fixed mtime, so the bytes
  are reproducible) of two lines: a JSON header ``{"format", "key", "name", "seed", "count",
  "checksum"}`` and the JSON payload whose SHA-256 is ``checksum``. The payload holds
  ``generator_names`` (those of the spec, in order), ``labels``, ``generators`` (each scene's index into
  ``generator_names``), the generation ``stats`` and the ``scenes``. Each scene is a list of objects in
  scene order, each object ``[class, colour, row, col, family, shape_idx, flags]`` (``flags``: 1
  pushable, 2 target), the frame ``["frame", colour]``; an object's cells are its library template
  ``shape_idx mod family size``. This is a lean form of :meth:`Scene.to_dict` (which spells out every
  cell): reading the catalog's 9,150 scenes through ``Scene.from_dict`` costs ~0.5 ms a scene (~5 s in
  all); this format loads the whole catalog in ~0.8 s, ~0.17 MB on disk.
* Writes are atomic (:func:`pixelworld_env.atomic.atomic_write`): a temporary file in the same folder, ``fsync``,
  then ``os.replace``.
* Reads trust nothing: a file that is not valid gzip or JSON, has another key, fails its checksum, or
  whose counts, labels or objects do not fit the spec is reported with a :class:`CacheWarning` naming
  the file, and the dataset is generated again (and the file rewritten).
"""

from __future__ import annotations

import dataclasses
import gzip
import hashlib
import json
import os
import re
import warnings
import zlib
from pathlib import Path
from typing import Any

from pixelworld_env.atomic import atomic_write
from pixelworld_env.core.kinds import task_kind
from pixelworld_env.core.objects import WorldObject, frame_object
from pixelworld_env.core.scene import Scene
from pixelworld_env.core.shapes import LibraryParams
from pixelworld_env.generation.dataset import GENERATOR_VERSION, GeneratedDataset, GeneratorStats, generate
from pixelworld_env.generation.dataset_spec import DatasetSpec
from pixelworld_env.generation.placement import library_object
from pixelworld_env.validation import check_seed

__all__ = [
    "CACHE_ENV",
    "FORMAT_VERSION",
    "CacheWarning",
    "DatasetCache",
    "cache_dir",
    "cache_key",
    "load_or_generate",
]

CACHE_ENV = "PIXELWORLD_CACHE"
FORMAT_VERSION = 1
_PUSHABLE, _TARGET = 1, 2


class CacheWarning(UserWarning):
    """A cache file was unusable (corrupt, truncated, stale) and is being regenerated."""


class _Corrupt(Exception):
    """Internal: why a cache file cannot be trusted."""


def cache_dir() -> Path:
    """``$PIXELWORLD_CACHE``, else ``$XDG_CACHE_HOME/pixelworld``, else ``~/.cache/pixelworld``."""
    explicit = os.environ.get(CACHE_ENV)
    if explicit:
        return Path(explicit).expanduser()
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg).expanduser() if xdg else Path.home() / ".cache"
    return base / "pixelworld"


def _key_document(spec: DatasetSpec, seed: int) -> dict[str, Any]:
    return {
        "format": FORMAT_VERSION,
        "generator_version": GENERATOR_VERSION,
        "name": spec.name,
        "kind": spec.kind,
        "concept": spec.concept,
        "generators": [list(pair) for pair in spec.generators],
        "macros": spec.used_macros(),
        "settings": dict(spec.settings),
        "num_samples": spec.num_samples,
        "world": [spec.height, spec.width, spec.floor_height, spec.padding],
        "seed": int(seed),
        "shape_library": dataclasses.asdict(LibraryParams()),
    }


def cache_key(spec: DatasetSpec, seed: int = 0) -> str:
    """The SHA-256 (hex) identifying the dataset ``spec`` generates with ``seed``."""
    text = json.dumps(_key_document(spec, seed), sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()


_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")


# ---------------------------------------------------------------------------------------------- codec


def _encode_object(obj: WorldObject) -> list[Any]:
    if obj.is_frame:
        return ["frame", int(obj.color)]
    flags = (_PUSHABLE if obj.pushable else 0) | (_TARGET if obj.is_target else 0)
    return [obj.cls.value, int(obj.color), obj.position[0], obj.position[1], obj.family, obj.shape_idx, flags]


def _encode(dataset: GeneratedDataset) -> bytes:
    index = {name: i for i, (name, _) in enumerate(dataset.spec.generators)}
    payload = {
        "generator_names": list(index),
        "labels": list(dataset.labels),
        "generators": [index[g] for g in dataset.generator_of],
        "stats": {
            "draws": dataset.draws, "duplicates": dataset.duplicates, "filtered": dataset.filtered,
            "generators": [[s.name, s.samples, s.kept, s.duplicates, s.rejected, s.search_steps, s.restarts]
                           for s in dataset.generator_stats],
        },
        "scenes": [[_encode_object(o) for o in scene.objects] for scene in dataset.scenes],
    }
    return json.dumps(payload, separators=(",", ":")).encode()


class _Decoder:
    def __init__(self, height: int, width: int) -> None:
        self.height, self.width = height, width
        self.objects: dict[tuple, WorldObject] = {}

    def object(self, raw: list[Any]) -> WorldObject:
        key = tuple(raw)
        obj = self.objects.get(key)
        if obj is None:
            obj = self.objects[key] = self._build(raw)
        return obj

    def _build(self, raw: list[Any]) -> WorldObject:
        if raw[0] == "frame" and len(raw) == 2:
            frame = frame_object(self.height, self.width)
            return frame if raw[1] == frame.color else dataclasses.replace(frame, color=int(raw[1]))
        cls, color, row, col, family, shape_idx, flags = raw
        if not all(isinstance(v, int) for v in (color, row, col, shape_idx, flags)) or not isinstance(family, str):
            raise _Corrupt(f"malformed object {raw}")
        obj = library_object(family, shape_idx, color, (row, col), is_self=cls == "self",
                             is_target=bool(flags & _TARGET), pushable=bool(flags & _PUSHABLE))
        if obj.cls.value != cls:
            raise _Corrupt(f"object {raw} has class {cls!r}, expected {obj.cls.value!r}")
        return obj


def _decode(spec: DatasetSpec, seed: int, payload: dict[str, Any]) -> GeneratedDataset:
    labels, generators, scenes_raw = payload["labels"], payload["generators"], payload["scenes"]
    if not (len(labels) == len(generators) == len(scenes_raw) == spec.size):
        raise _Corrupt(f"{len(scenes_raw)} scenes, {len(labels)} labels and {len(generators)} generator entries; "
                       f"expected {spec.size} of each")
    if task_kind(spec.kind).label is not None:
        if sorted(set(labels)) != [0, 1] or labels.count(1) != spec.num_samples:
            raise _Corrupt(f"labels are not {spec.num_samples} positive and {spec.num_samples} negative")
    elif set(labels) != {1}:
        raise _Corrupt(f"{spec.kind} labels must all be 1")
    names = [name for name, _ in spec.generators]
    if payload["generator_names"] != names:
        raise _Corrupt(f"generator names {payload['generator_names']} differ from the spec's {names}")
    if not all(isinstance(g, int) and 0 <= g < len(names) for g in generators):
        raise _Corrupt("generator index out of range")
    decoder = _Decoder(spec.height, spec.width)
    scenes = tuple(Scene(height=spec.height, width=spec.width, objects=tuple(decoder.object(o) for o in raw))
                   for raw in scenes_raw)
    stats = payload["stats"]
    generator_stats = tuple(GeneratorStats(*entry) for entry in stats["generators"])
    return GeneratedDataset(
        spec=spec, seed=seed, scenes=scenes, labels=tuple(int(v) for v in labels),
        generator_of=tuple(names[g] for g in generators), draws=int(stats["draws"]),
        duplicates=int(stats["duplicates"]), filtered=int(stats["filtered"]), generator_stats=generator_stats,
    )


# ---------------------------------------------------------------------------------------------- cache


class DatasetCache:
    """A folder of cached datasets (default: :func:`cache_dir` at the time of each call)."""

    def __init__(self, directory: str | Path | None = None) -> None:
        self._directory = Path(directory) if directory is not None else None

    @property
    def directory(self) -> Path:
        return self._directory if self._directory is not None else cache_dir()

    def path(self, spec: DatasetSpec, seed: int = 0) -> Path:
        """Where the dataset of ``spec`` and ``seed`` is (or would be) cached."""
        name = _UNSAFE.sub("_", spec.name)[:150] or "dataset"
        return self.directory / f"{name}-{cache_key(spec, seed)[:16]}.json.gz"

    def load(self, spec: DatasetSpec, seed: int = 0) -> GeneratedDataset | None:
        """The cached dataset, or None when there is no file or it cannot be trusted (with a warning)."""
        path = self.path(spec, seed)
        try:
            blob = path.read_bytes()
        except FileNotFoundError:
            return None
        except OSError as exc:
            warnings.warn(f"pixelworld dataset cache file {path} cannot be read ({exc.strerror}); regenerating it",
                          CacheWarning, stacklevel=3)
            return None
        try:
            return self._parse(blob, spec, seed)
        except (_Corrupt, OSError, EOFError, zlib.error, ValueError, KeyError, TypeError, IndexError) as exc:
            reason = str(exc) or type(exc).__name__
            warnings.warn(f"pixelworld dataset cache file {path} is unusable ({reason}); regenerating it",
                          CacheWarning, stacklevel=3)
            return None

    @staticmethod
    def _parse(blob: bytes, spec: DatasetSpec, seed: int) -> GeneratedDataset:
        try:
            data = gzip.decompress(blob)
        except (OSError, EOFError, zlib.error) as exc:
            raise _Corrupt(f"not a complete gzip file: {exc}") from None
        head, sep, payload = data.partition(b"\n")
        if not sep:
            raise _Corrupt("no payload after the header line")
        try:
            header = json.loads(head)
        except ValueError as exc:
            raise _Corrupt(f"bad header JSON: {exc}") from None
        if not isinstance(header, dict) or header.get("format") != FORMAT_VERSION:
            raise _Corrupt(f"unknown format {header.get('format') if isinstance(header, dict) else header!r}")
        if header.get("key") != cache_key(spec, seed):
            raise _Corrupt("the file's key does not match the spec and seed")
        if header.get("checksum") != hashlib.sha256(payload).hexdigest():
            raise _Corrupt("checksum mismatch")
        if header.get("count") != spec.size:
            raise _Corrupt(f"header count {header.get('count')} != {spec.size}")
        try:
            body = json.loads(payload)
        except ValueError as exc:
            raise _Corrupt(f"bad payload JSON: {exc}") from None
        return _decode(spec, seed, body)

    def save(self, dataset: GeneratedDataset) -> Path:
        """Write ``dataset`` atomically; returns the file's path."""
        spec = dataset.spec
        path = self.path(spec, dataset.seed)
        payload = _encode(dataset)
        header = {"format": FORMAT_VERSION, "key": cache_key(spec, dataset.seed), "name": spec.name,
                  "seed": dataset.seed, "count": len(dataset.scenes), "checksum": hashlib.sha256(payload).hexdigest()}
        blob = gzip.compress(json.dumps(header, sort_keys=True).encode() + b"\n" + payload, compresslevel=6, mtime=0)
        atomic_write(path, blob)
        return path

    def load_or_generate(self, spec: DatasetSpec, seed: int = 0) -> GeneratedDataset:
        """The cached dataset, or a freshly generated one (then cached; a write failure only warns)."""
        seed = check_seed(seed)
        cached = self.load(spec, seed)
        if cached is not None:
            return cached
        dataset = generate(spec, seed)
        try:
            self.save(dataset)
        except OSError as exc:
            warnings.warn(f"pixelworld could not write the dataset cache in {self.directory} ({exc}); "
                          "continuing without caching", CacheWarning, stacklevel=2)
        return dataset


def load_or_generate(spec: DatasetSpec, seed: int = 0) -> GeneratedDataset:
    """The dataset of ``spec`` and ``seed`` from the cache (:func:`cache_dir`), generated on a miss."""
    return DatasetCache().load_or_generate(spec, seed)
