"""The dataset disk cache: location, round trip, no regeneration, corruption handling, atomic writes, keys."""

from __future__ import annotations

import dataclasses
import gzip
import hashlib
import json
import os
from pathlib import Path

import pytest

import pixelworld_env.datasets.cache as datasets
from pixelworld_env.datasets.cache import CacheWarning, DatasetCache, cache_dir, cache_key, load_or_generate
from pixelworld_env.generation.dataset import GeneratedDataset, generate
from pixelworld_env.generation.dataset_spec import DatasetSpec

SELF_ON_FLOOR = "?f ?x floor(f) & blue(f) & white(x) & small_blob(x) & on_top(x,f) & on_top(self,f)"
SPEC = DatasetSpec(
    name="cl_self-touches-object_tiny",
    kind="classification",
    concept="?f ?x object-on-floor(f,x) & touches(self,x)",
    generators=(("touching", SELF_ON_FLOOR + " & touches(self,x)"), ("apart", SELF_ON_FLOOR + " & ~touches(self,x)")),
    macros={"object-on-floor": "?f ?x floor(f) & on_top(x,f)", "unused": "?x white(x)"},
    num_samples=6,
)


@pytest.fixture
def cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("PIXELWORLD_CACHE", str(tmp_path))
    return tmp_path


def no_generation(*args, **kwargs):
    raise AssertionError("generate() must not be called when the cache is valid")


def same(a: GeneratedDataset, b: GeneratedDataset) -> bool:
    return a.scenes == b.scenes and a.labels == b.labels and a.generator_of == b.generator_of and a == b


def test_cache_dir_precedence(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("PIXELWORLD_CACHE", str(tmp_path / "explicit"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cache_dir() == tmp_path / "explicit"
    monkeypatch.delenv("PIXELWORLD_CACHE")
    assert cache_dir() == tmp_path / "xdg" / "pixelworld"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert cache_dir() == tmp_path / "home" / ".cache" / "pixelworld"


def test_round_trip_and_no_regeneration(cache: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    first = load_or_generate(SPEC, 3)
    files = list(cache.iterdir())
    assert [f.name for f in files] == [f"{SPEC.name}-{cache_key(SPEC, 3)[:16]}.json.gz"]
    assert same(first, generate(SPEC, 3))
    monkeypatch.setattr(datasets, "generate", no_generation)
    second = load_or_generate(SPEC, 3)
    assert same(second, first)
    assert [s.to_dict() for s in second.scenes] == [s.to_dict() for s in first.scenes]
    assert second.generator_stats == first.generator_stats and second.draws == first.draws


def test_file_is_reproducible_and_lean(cache: Path) -> None:
    dataset = generate(SPEC, 0)
    store = DatasetCache()
    path = store.save(dataset)
    blob = path.read_bytes()
    store.save(dataset)
    assert path.read_bytes() == blob
    header, payload = gzip.decompress(blob).split(b"\n", 1)
    header = json.loads(header)
    assert header["checksum"] == hashlib.sha256(payload).hexdigest() and header["count"] == 12
    assert len(json.loads(payload)["scenes"]) == 12


def test_atomic_write_leaves_no_temporary_files(cache: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    load_or_generate(SPEC)
    assert [p.suffix for p in cache.iterdir()] == [".gz"]

    def broken_replace(src, dst):
        raise OSError(28, "No space left on device")

    other = dataclasses.replace(SPEC, num_samples=5)
    monkeypatch.setattr(os, "replace", broken_replace)
    with pytest.raises(OSError):
        DatasetCache().save(generate(other))
    assert len(list(cache.iterdir())) == 1  # the temporary file was removed
    with pytest.warns(CacheWarning, match="could not write"):
        dataset = load_or_generate(other)
    assert len(dataset) == 10 and len(list(cache.iterdir())) == 1


def _rewrite(path: Path, header_change: dict | None = None, payload_change=None, fix_checksum: bool = False) -> None:
    head, payload = gzip.decompress(path.read_bytes()).split(b"\n", 1)
    header = json.loads(head)
    if payload_change is not None:
        body = json.loads(payload)
        payload_change(body)
        payload = json.dumps(body, separators=(",", ":")).encode()
    if fix_checksum:
        header["checksum"] = hashlib.sha256(payload).hexdigest()
    header.update(header_change or {})
    path.write_bytes(gzip.compress(json.dumps(header).encode() + b"\n" + payload))


def _truncate(path: Path) -> None:
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])


def _flip(path: Path) -> None:
    blob = bytearray(path.read_bytes())
    for i in range(len(blob) // 3, len(blob) // 3 + 8):
        blob[i] ^= 0xFF
    path.write_bytes(bytes(blob))


def _drop_scene(body: dict) -> None:
    for key in ("scenes", "labels", "generators"):
        body[key].pop()


def _move_self(body: dict) -> None:
    for obj in body["scenes"][0]:
        if obj[0] == "self":
            obj[2] = 40  # outside the 18-row world


CORRUPTIONS = {
    "truncated": _truncate,
    "flipped bytes": _flip,
    "empty": lambda p: p.write_bytes(b""),
    "not gzip": lambda p: p.write_bytes(b"{}\n{}"),
    "bad json": lambda p: p.write_bytes(gzip.compress(b"{not json\n[")),
    "wrong checksum": lambda p: _rewrite(p, payload_change=lambda b: b["labels"].reverse()),
    "wrong key": lambda p: _rewrite(p, {"key": "0" * 64}),
    "wrong counts": lambda p: _rewrite(p, payload_change=_drop_scene, fix_checksum=True),
    "object outside the world": lambda p: _rewrite(p, payload_change=_move_self, fix_checksum=True),
    "unknown family": lambda p: _rewrite(p, payload_change=lambda b: b["scenes"][0][1].__setitem__(4, "blobb"),
                                         fix_checksum=True),
}


@pytest.mark.parametrize("damage", list(CORRUPTIONS), ids=list(CORRUPTIONS))
def test_corrupt_file_is_warned_about_and_regenerated(cache: Path, damage: str) -> None:
    original = load_or_generate(SPEC)
    (path,) = cache.iterdir()
    CORRUPTIONS[damage](path)
    with pytest.warns(CacheWarning, match=path.name):
        again = load_or_generate(SPEC)
    assert same(again, original)
    # The file was rewritten and is trusted again.
    assert same(DatasetCache().load(SPEC), original)


def test_key_changes_with_everything_that_matters() -> None:
    base = cache_key(SPEC, 0)
    variants = [
        cache_key(SPEC, 1),
        cache_key(dataclasses.replace(SPEC, num_samples=7), 0),
        cache_key(dataclasses.replace(SPEC, concept=SPEC.concept + " & white(x)"), 0),
        cache_key(dataclasses.replace(SPEC, generators=SPEC.generators[:1]), 0),
        cache_key(dataclasses.replace(SPEC, generators=(SPEC.generators[0], ("apart", SELF_ON_FLOOR))), 0),
        cache_key(dataclasses.replace(SPEC, macros={**SPEC.macros, "object-on-floor": "?f ?x floor(f) & above(x,f)"}),
                  0),
        cache_key(dataclasses.replace(SPEC, settings={"allow_targets": True}), 0),
        cache_key(dataclasses.replace(SPEC, kind="bring-about"), 0),
        cache_key(dataclasses.replace(SPEC, padding=1), 0),
        cache_key(dataclasses.replace(SPEC, name="other"), 0),
    ]
    assert len({base, *variants}) == len(variants) + 1
    # A macro the dataset does not use does not change the key.
    assert cache_key(dataclasses.replace(SPEC, macros={**SPEC.macros, "unused": "?x blue(x)"}), 0) == base


def test_key_changes_with_generator_version(monkeypatch: pytest.MonkeyPatch) -> None:
    base = cache_key(SPEC, 0)
    monkeypatch.setattr(datasets, "GENERATOR_VERSION", datasets.GENERATOR_VERSION + 1)
    assert cache_key(SPEC, 0) != base


def test_other_seed_is_another_file(cache: Path) -> None:
    a, b = load_or_generate(SPEC, 0), load_or_generate(SPEC, 1)
    assert len(list(cache.iterdir())) == 2
    assert a.scenes != b.scenes
