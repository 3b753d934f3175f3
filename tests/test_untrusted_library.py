"""Libraries, checkpoints and run folders from someone else: loading runs no code, names stay inside their folders,
concurrent writers lose nothing and readers are never fooled (docs/security.md)."""

from __future__ import annotations

import dataclasses
import io
import json
import multiprocessing
import os
import pickle
import zipfile
from pathlib import Path

import pytest

from sb3_smc.library import (
    CorruptModelError,
    LibraryConflictError,
    LibraryError,
    ManifestError,
    SMCLibrary,
    UntrustedModelError,
    storage,
)
from sb3_smc.smc.smc import SMC
from tests.helpers import sb3_smc_cli

NAMES = ("cl_self-in-left-corner_vs_on-hline@0", "cl_self-in-left-corner_vs_on-hline@1",
         "cl_self-in-right-corner_vs_on-hline@0")


@pytest.fixture(scope="module")
def pretrained() -> SMCLibrary:
    return SMCLibrary.pretrained("search2-canon")


def _renamed(smc: SMC, name: str) -> SMC:
    assert smc.spec is not None
    spec = dataclasses.replace(smc.spec, name=name)
    return dataclasses.replace(smc, name=name, spec=spec,
                               evaluations=tuple(dataclasses.replace(e, smc=name) for e in smc.evaluations))


class _Payload:
    """Unpickling it creates a marker file: what a forged model would do, harmlessly."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return (Path.touch, (self.marker,))


def _forged_v4_library(source: Path, target: Path, marker: Path) -> Path:
    """A version-4 library whose one model archive's ``data`` member carries a pickled payload, its checksums
    recomputed: what the checksums cannot stop (a forgery, not damage)."""
    import base64

    entries = storage.checked_entries(source)[0]
    name = next(iter(entries))
    raw = json.loads((source / storage.MANIFEST).read_text())
    entry = {k: v for k, v in raw["smcs"][name].items() if k != "entry_sha256"}
    payload = base64.b64encode(pickle.dumps(_Payload(marker))).decode()
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        archive.writestr("data", json.dumps({"policy_class": {":type:": "x", ":serialized:": payload}}))
        archive.writestr("policy.pth", b"")
    (target / "models").mkdir(parents=True)
    (target / "models" / f"{name}.zip").write_bytes(buffer.getvalue())
    entry["model"], entry["sha256"] = f"models/{name}.zip", storage.sha256(target / "models" / f"{name}.zip")
    manifest = {"format": raw["format"], "version": 4, "created_with": raw["created_with"], "smcs": {name: entry}}
    storage.write_manifest(target / storage.MANIFEST, manifest)
    return target


def test_a_forged_old_library_runs_no_code_on_load_or_check(pretrained, tmp_path):
    """The forged pickle never runs: ``load`` without trust refuses it naming the file and the risk, and
    ``sb3-smc library DIR --check`` verifies the archive without unpickling it."""
    source = SMCLibrary([pretrained[NAMES[0]]]).save(tmp_path / "source")
    marker = tmp_path / "payload-ran"
    forged = _forged_v4_library(source, tmp_path / "forged", marker)
    with pytest.raises(UntrustedModelError, match=r"pickled Stable-Baselines3 archive .* runs any code .*trust=True"):
        SMCLibrary.load(forged)
    code, out, err = sb3_smc_cli("library", str(forged), "--check")
    assert not marker.exists(), "the payload ran"
    assert code == 0, err
    assert "1 pickled archive(s) checked but not loaded" in out
    code, out, err = sb3_smc_cli("library", str(forged), "--upgrade")
    assert code == 2 and "add --trust if you trust where the library comes from" in err
    assert not marker.exists()


def test_an_old_library_converts_with_trust_and_then_loads_without(pretrained, tmp_path):
    """``trust=True`` loads a library of pickled archives; saving it writes version 5, which loads without trust
    to the same weights, the archives gone."""
    import torch

    old = tmp_path / "old"
    (old / "models").mkdir(parents=True)
    smc = pretrained[NAMES[0]]
    smc.model.save(old / "models" / "a.zip")
    entry = {"model": "models/a.zip", **storage.entry_for(smc), "sha256": storage.sha256(old / "models" / "a.zip")}
    manifest = {**storage.new_manifest({NAMES[0]: entry}), "version": 4}
    storage.write_manifest(old / storage.MANIFEST, manifest)
    with pytest.raises(UntrustedModelError):
        SMCLibrary.load(old)
    SMCLibrary.load(old, trust=True).save()
    assert [p.suffix for p in (old / "models").iterdir()] == [".safetensors"]
    again = SMCLibrary.load(old)[NAMES[0]].model.policy.state_dict()
    for key, value in smc.model.policy.state_dict().items():
        assert torch.equal(value, again[key])


def test_a_class_outside_the_safe_modules_is_not_imported(pretrained, tmp_path):
    """A model file naming another module's class is refused without importing it."""
    from safetensors.torch import load, save

    from sb3_smc.library.model_file import METADATA_KEY, decode_model

    data = storage.model_bytes(pretrained[NAMES[0]].model)
    size = int.from_bytes(data[:8], "little")
    metadata = json.loads(json.loads(data[8:8 + size])["__metadata__"][METADATA_KEY])
    metadata["policy_class"] = "antigravity.Fly"
    forged = save(load(data), metadata={METADATA_KEY: json.dumps(metadata)})
    with pytest.raises(CorruptModelError, match=r"'antigravity.Fly' is not from a module loaded without trust"):
        decode_model(forged, "RecurrentPPO", "forged")
    assert "antigravity" not in __import__("sys").modules


def test_symbolic_links_inside_a_library_are_refused(pretrained, tmp_path):
    """A model file or manifest that is a link (to anywhere) is refused, naming it."""
    library = SMCLibrary([pretrained[NAMES[0]]]).save(tmp_path / "lib")
    entry = next(iter(storage.checked_entries(library)[0].values()))
    model = library / entry.model
    outside = tmp_path / "outside.bin"
    model.rename(outside)
    model.symlink_to(outside)
    with pytest.raises(CorruptModelError, match=r"is a symbolic link"):
        SMCLibrary.load(library)
    manifest = library / storage.MANIFEST
    manifest.rename(tmp_path / "manifest.json")
    manifest.symlink_to(tmp_path / "manifest.json")
    with pytest.raises(ManifestError, match=r"is a symbolic link"):
        SMCLibrary.load(library)


def test_names_with_paths_are_refused_where_they_enter(pretrained, tmp_path):
    """An SMC, a manifest entry or a curriculum node named ``../x`` is refused before anything is written; the
    trainer never removes a folder outside its run (``DIR/tensorboard/<name>@<seed>_*``)."""
    from sb3_smc.errors import SMCError

    with pytest.raises(SMCError, match=r"SMC name '\.\./precious' is not a name: its part '\.\.' starts with '\.'"):
        _renamed(pretrained[NAMES[0]], "../precious")
    library = SMCLibrary([pretrained[NAMES[0]]]).save(tmp_path / "lib")
    raw = json.loads((library / storage.MANIFEST).read_text())
    raw["smcs"] = {"../../x": next(iter(raw["smcs"].values()))}
    storage.write_manifest(library / storage.MANIFEST, raw)
    with pytest.raises(ManifestError, match=r"SMC '\.\./\.\./x' is not a name"):
        SMCLibrary.load(library)
    precious = tmp_path / "precious@0_data"
    precious.mkdir()
    curriculum = tmp_path / "evil.yml"
    curriculum.write_text("curriculum: evil\nnodes:\n  - name: ../../precious\n"
                          "    task: cl_self-in-container_vs_noncontainer\n")
    code, _, err = sb3_smc_cli("train", str(curriculum), "--out", str(tmp_path / "run" / "a" / "b"), "--seeds", "1")
    assert code == 2 and "node '../../precious' is not a name" in err
    assert precious.is_dir() and not (tmp_path / "run").exists()


def _load_add_save(root: str, name: str, source: str, barrier) -> None:
    library = SMCLibrary.load(root)
    smc = SMCLibrary.load(source, names=[NAMES[0]])[NAMES[0]]
    library.add(_renamed(smc, name))
    barrier.wait()  # both have read the library before either saves
    library.save()


def _add_many(root: str, prefix: str, source: str, count: int) -> None:
    smc = SMCLibrary.load(source, names=[NAMES[0]])[NAMES[0]]
    for i in range(count):
        renamed = _renamed(smc, f"{prefix}{i}")
        storage.add_to_library(Path(root), renamed.name, storage.entry_for(renamed),
                               storage.model_bytes(renamed.model))


def _processes(target, arguments) -> None:
    context = multiprocessing.get_context("fork")
    workers = [context.Process(target=target, args=a) for a in arguments]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join(120)
        assert worker.exitcode == 0


def test_two_writers_both_keep_their_smcs(pretrained, tmp_path):
    """Two processes that load one library, each add an SMC and save both keep theirs (the second merges what the
    first added); two that each add 6 SMCs one by one leave all 12, and no model file that no entry names."""
    source = str(SMCLibrary([pretrained[NAMES[0]]]).save(tmp_path / "source"))
    root = SMCLibrary([pretrained[NAMES[1]]]).save(tmp_path / "shared")
    barrier = multiprocessing.get_context("fork").Barrier(2)
    _processes(_load_add_save, [(str(root), "first", source, barrier), (str(root), "second", source, barrier)])
    assert set(SMCLibrary.load(root).names) == {NAMES[1], "first", "second"}
    many = tmp_path / "many"
    _processes(_add_many, [(str(many), "a", source, 6), (str(many), "b", source, 6)])
    entries = storage.checked_entries(many)[0]
    assert len(entries) == 12
    named = {Path(entry.model).name for entry in entries.values()}
    assert {p.name for p in (many / "models").iterdir()} == named


def test_a_change_to_an_smc_both_writers_hold_is_refused(pretrained, tmp_path):
    """A writer that finds an SMC it read changed by another since refuses to save (nothing written);
    ``overwrite=True`` makes the folder exactly this library."""
    root = SMCLibrary([pretrained[NAMES[0]], pretrained[NAMES[1]]]).save(tmp_path / "lib")
    first, second = SMCLibrary.load(root), SMCLibrary.load(root)
    first.add(_renamed(pretrained[NAMES[2]], NAMES[0]), replace=True)
    first.save()
    before = (root / storage.MANIFEST).read_bytes()
    second.add(_renamed(pretrained[NAMES[1]], NAMES[0]), replace=True)
    with pytest.raises(LibraryConflictError, match=r"was changed by another writer since this library was loaded"):
        second.save()
    assert (root / storage.MANIFEST).read_bytes() == before
    SMCLibrary([pretrained[NAMES[2]]]).save(root, overwrite=True)
    assert SMCLibrary.load(root).names == (NAMES[2],)


def _save_repeatedly(root: str, source: str, rounds: int) -> None:
    smcs = SMCLibrary.load(source)
    for i in range(rounds):
        library = SMCLibrary.load(root)
        name = f"extra{i % 2}"
        if name in library:
            library.remove(name)
        library.add(_renamed(smcs[NAMES[i % 2]], name))
        library.save()


def test_a_reader_never_sees_a_half_written_library(pretrained, tmp_path):
    """A reader loading while a writer saves again and again always gets a whole library (no false
    CorruptModelError, no FileNotFoundError)."""
    source = str(SMCLibrary([pretrained[NAMES[0]], pretrained[NAMES[1]]]).save(tmp_path / "source"))
    root = SMCLibrary([pretrained[NAMES[0]]]).save(tmp_path / "lib")
    writer = multiprocessing.get_context("fork").Process(target=_save_repeatedly, args=(str(root), source, 20))
    writer.start()
    loads = 0
    while writer.is_alive() or loads < 5:
        library = SMCLibrary.load(root)
        assert NAMES[0] in library and len(library) in (1, 2, 3)
        loads += 1
    writer.join()
    assert writer.exitcode == 0 and loads >= 5


def test_an_old_archive_that_unpacks_to_too_much_is_refused_before_it_is_read(pretrained, tmp_path):
    """A small zip whose ``data`` member declares more than an archive may unpack to is refused, even with trust."""
    old = tmp_path / "old"
    (old / "models").mkdir(parents=True)
    archive = old / "models" / "a.zip"
    with zipfile.ZipFile(archive, "w", zipfile.ZIP_DEFLATED) as out:
        with out.open("data", "w", force_zip64=True) as handle:
            block = b"\0" * 2**20
            for _ in range(storage.MAX_ARCHIVE_BYTES // len(block) + 1):
                handle.write(block)
        out.writestr("policy.pth", b"")
    assert archive.stat().st_size < 4 * 2**20
    smc = pretrained[NAMES[0]]
    entry = {"model": "models/a.zip", **storage.entry_for(smc), "sha256": storage.sha256(archive)}
    storage.write_manifest(old / storage.MANIFEST, {**storage.new_manifest({NAMES[0]: entry}), "version": 4})
    with pytest.raises(CorruptModelError, match=r"unpacks to \d+ bytes, more than a model archive may"):
        SMCLibrary.load(old, trust=True)


def test_a_checkpoint_not_signed_with_the_users_key_is_never_unpickled(tmp_path):
    """A planted group checkpoint (a pickle with a payload, unsigned or signed with another key) is reported and
    removed, its payload never run; one this user signed loads."""
    from sb3_smc.learning.group_checkpoint import MAGIC, GroupCheckpoint, checkpoint_key
    from sb3_smc.records import TrainingSpec

    spec = TrainingSpec.create("PW-cl_self-in-left-corner_vs_on-hline-v0", total_timesteps=2000, name="x@0")
    lines: list[str] = []
    checkpoint = GroupCheckpoint(tmp_path, [spec], [], every=0, settings={}, printer=lines.append)
    marker = tmp_path / "payload-ran"
    for planted in (pickle.dumps(_Payload(marker)), MAGIC + os.urandom(32) + pickle.dumps(_Payload(marker))):
        checkpoint.path.write_bytes(planted)
        assert checkpoint.load() is None
        assert not marker.exists() and not checkpoint.path.exists()
    assert "not a signed checkpoint" in lines[0] and "not this user's key" in lines[1]
    checkpoint.save({"state": [1, 2, 3]})
    assert checkpoint.load() == {"state": [1, 2, 3]} and len(checkpoint_key()) == 32


def test_library_errors_stay_within_the_package(tmp_path):
    """Reading a folder that is no library, or one whose manifest cannot be read, is a LibraryError."""
    with pytest.raises(ManifestError, match=r"no SMC library at"):
        SMCLibrary.load(tmp_path)
    (tmp_path / storage.MANIFEST).mkdir()
    with pytest.raises(LibraryError, match=r"is not a regular file"):
        SMCLibrary.load(tmp_path)


@pytest.mark.parametrize("name", ["cl_self-in-left-corner_vs_on-hline@0",
                                  "ba_self-away-left-of-object_from_left-touches-on-floor@0"])
def test_the_converted_pretrained_library_reproduces_its_records(name):
    """The shipped library, converted to version 5 from pickled archives, gives each SMC's recorded test evaluation
    again, world by world (the same weights, bit for bit, through the same numpy actor)."""
    from sb3_smc.learning.evaluation import evaluate

    smc = SMCLibrary.pretrained(name.split("@")[0])[name]
    (recorded,) = [e for e in smc.evaluations if e.split == "test" and e.repeats == 10 and e.evaluation_seed == 0]
    again = evaluate(smc, repeats=10, seed=0, record_cells=False)
    assert (again.score, tuple(again.scores)) == (recorded.score, tuple(recorded.environment_scores))


def test_threads_of_one_process_take_turns_on_a_library(pretrained, tmp_path):
    """``flock`` is per process: threads adding SMCs to one library at once each get theirs in."""
    import threading

    root = tmp_path / "lib"
    smc = pretrained[NAMES[0]]

    def add(prefix: str) -> None:
        for i in range(4):
            renamed = _renamed(smc, f"{prefix}{i}")
            storage.add_to_library(root, renamed.name, storage.entry_for(renamed), storage.model_bytes(renamed.model))

    threads = [threading.Thread(target=add, args=(p,)) for p in ("a", "b", "c")]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert len(storage.checked_entries(root)[0]) == 12


def test_a_script_of_a_safe_package_is_not_imported_without_trust():
    """A model file naming a class of ``sb3_smc.zoo.__main__`` (a script: it writes files when imported) is refused
    before the import: without trust only modules already imported, or those that define models' classes, are
    looked in."""
    import sys

    from sb3_smc.core.hyperparameters import decode_value
    from sb3_smc.errors import SMCError

    for path in ("sb3_smc.zoo.__main__.X", "sb3_smc.curricula.__main__.X", "sb3_smc.zoo.record_video.X"):
        with pytest.raises(SMCError, match=r"is not imported yet"):
            decode_value({"__class__": path}, "policy_class", trust=False)
        assert path.rpartition(".")[0] not in sys.modules


def test_an_entry_that_calls_a_missing_child_is_refused_before_it_is_added(pretrained, tmp_path):
    smc = pretrained[NAMES[0]]
    entry = storage.entry_for(smc)
    entry["spec"] = {**entry["spec"], "children": ["nobody@0"]}
    with pytest.raises(LibraryError, match=r"calls \['nobody@0'\], which the library does not hold"):
        storage.add_to_library(tmp_path / "lib", "x@0", entry, storage.model_bytes(smc.model))
    assert not (tmp_path / "lib" / storage.MANIFEST).exists()
    with pytest.raises(LibraryError, match=r"not the string"):
        storage.remove_from_library(tmp_path / "lib", "x@0")
