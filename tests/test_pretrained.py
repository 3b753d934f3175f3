"""The pretrained library: built from a run's library (two best seeds of each lower-level node, evaluated, compact
models with the trained weights), loaded by curriculum name and put on an environment as actions."""

from __future__ import annotations

import json
import shutil

import gymnasium as gym
import pytest
import torch
from safetensors import safe_open

import pixelworld_env  # noqa: F401
from sb3_smc.curricula import Curriculum, Node
from sb3_smc.curricula.pretrained import build_pretrained, compact_model, lower_level
from sb3_smc.curricula.run_directory import status
from sb3_smc.curricula.shipped import shipped_curricula
from sb3_smc.curricula.trainer import rank_seeds, train_curriculum
from sb3_smc.library import FORMAT_VERSION, LibraryError, SMCLibrary, UntrustedModelError, storage
from sb3_smc.library.errors import ManifestError
from sb3_smc.library.pretrained import INDEX, pretrained_curricula, pretrained_index, pretrained_names, pretrained_root
from tests.helpers import sb3_smc_cli

LEFT, RIGHT = "cl_self-in-left-corner_vs_on-hline", "cl_self-in-right-corner_vs_on-hline"
TARGET = "ba_self-in-target-container_from_nontarget-container"


def _tensor_names(path) -> set[str]:
    """The names of the tensors in a model file (safetensors)."""
    with safe_open(path, framework="pt") as handle:
        return set(handle.keys())


def _model_file(library, name: str):
    """The model file of SMC ``name`` in the library folder ``library``, as its manifest names it."""
    return library / json.loads((library / "manifest.json").read_text())["smcs"][name]["model"]


def test_build_and_load_a_pretrained_library(tmp_path):
    tiny = Curriculum("tiny", (Node(LEFT, LEFT), Node(RIGHT, RIGHT), Node("top", TARGET, (LEFT, RIGHT))), ("top",))
    run = tmp_path / "run"
    train_curriculum(tiny, run, targets=[LEFT, RIGHT], seeds=3, timesteps=256, progress=False)
    trained = SMCLibrary.load(run / "library")
    out = build_pretrained([run], [tiny], tmp_path / "pretrained", repeats=1)
    library = SMCLibrary.load(out)
    for node in (LEFT, RIGHT):  # the two best seeds by the trainer's ranking, evaluated on the test split
        best = rank_seeds({s: trained[f"{node}@{s}"].record for s in range(3)})[:2]
        assert sorted(n for n in library.names if n.startswith(node)) == sorted(f"{node}@{s}" for s in best)
    for name in library.names:
        smc, original = library[name], trained[name]
        assert smc.test_score is not None and smc.spec == original.spec and smc.record == original.record
        ours, theirs = smc.model.policy.state_dict(), original.model.policy.state_dict()
        assert all(torch.equal(ours[k], theirs[k]) for k in theirs)  # the trained weights, exactly
        model_file, full = _model_file(out, name), _model_file(run / "library", name)
        assert model_file.name == f"{storage.sha256(model_file)}.safetensors"
        compact, whole = _tensor_names(model_file), _tensor_names(full)
        assert any(key.startswith("policy.optimizer/state/") for key in whole)  # the run's: the optimiser's state
        assert compact == {key for key in whole if not key.startswith("policy.optimizer/state/")}  # none of it here
        assert model_file.read_bytes() == compact_model(full.read_bytes())
        assert model_file.stat().st_size < 0.6 * full.stat().st_size
    # a rebuild replaces a node's entries by its best seeds (an extra seed in the library does not survive)
    best_names = sorted(library.names)
    worst = next(f"{LEFT}@{s}" for s in range(3) if f"{LEFT}@{s}" not in library)
    library.add(trained[worst])
    library.save()
    assert len(SMCLibrary.load(out)) == 5
    build_pretrained([run], [tiny], out, repeats=1)
    assert sorted(SMCLibrary.load(out).names) == best_names
    # refused: a run that lacks seeds of a node (the ranking needs all), an out that is not a library
    partial = tmp_path / "partial"
    shutil.copytree(run, partial)
    held = SMCLibrary.load(partial / "library")
    held.remove(f"{RIGHT}@0")
    held.save()
    with pytest.raises(LibraryError, match=f"node '{RIGHT}': .* holds 2 of the run's 3 seeds"):
        build_pretrained([partial], [tiny], tmp_path / "elsewhere", repeats=1)
    # ... unless only its finished nodes are wanted (a run still going): the curriculum is not listed until whole
    finished = build_pretrained([partial], [tiny], tmp_path / "finished", repeats=1, finished_only=True)
    index = json.loads((finished / INDEX).read_text())
    assert sorted(index["nodes"]) == [LEFT] and index["curricula"] == {} and index["seeds"] == {LEFT: 3}
    assert sorted(SMCLibrary.load(finished).names) == sorted(n for n in best_names if n.startswith(LEFT))
    # what a build does not replace is kept byte for byte (a rebuild adds no new copies of unchanged models), and so
    # is a node whose best seeds it holds with the same specs (a run that copied them, or trained them again)
    whole = {p.name: p.read_bytes() for p in (out / "models").iterdir()}
    manifest = (out / "manifest.json").read_bytes()
    build_pretrained([partial], [tiny], out, repeats=1, finished_only=True)  # LEFT's best seeds: held alike
    after = {p.name: p.read_bytes() for p in (out / "models").iterdir()}
    assert after == whole and (out / "manifest.json").read_bytes() == manifest
    build_pretrained([partial], [tiny], out, repeats=2, finished_only=True)  # tested otherwise: LEFT tested again
    again = SMCLibrary.load(out)
    assert {e.repeats for n in again.names if n.startswith(LEFT) for e in again[n].evaluations} == {2}
    assert {e.repeats for n in again.names if n.startswith(RIGHT) for e in again[n].evaluations} == {1}
    assert pretrained_curricula(out) == ["tiny"]
    (tmp_path / "notes").mkdir()
    (tmp_path / "notes" / "keep.txt").write_text("mine")
    with pytest.raises(LibraryError, match="refusing to write the pretrained library"):
        build_pretrained([run], [tiny], tmp_path / "notes", repeats=1)
    assert (tmp_path / "notes" / "keep.txt").read_text() == "mine"
    library = SMCLibrary.load(out)
    # an out of pickled models (a library written before version 5) is rebuilt only with trust, then as version 5
    old = tmp_path / "old"
    shutil.copytree(out, old)
    manifest = json.loads((old / "manifest.json").read_text())
    for name, entry in manifest["smcs"].items():
        (old / entry["model"]).unlink()
        library[name].model.save(old / "models" / f"{name}.zip")
        entry.update(model=f"models/{name}.zip", sha256=storage.sha256(old / "models" / f"{name}.zip"))
    storage.write_manifest(old / "manifest.json", {**manifest, "version": 4})
    pickled = (old / "manifest.json").read_bytes()
    with pytest.raises(UntrustedModelError, match=r"\.zip is a pickled Stable-Baselines3 archive"):
        build_pretrained([run], [tiny], old, repeats=1)
    assert (old / "manifest.json").read_bytes() == pickled
    build_pretrained([run], [tiny], old, repeats=1, trust=True)
    converted = SMCLibrary.load(old)
    assert sorted(converted.names) == best_names
    assert json.loads((old / "manifest.json").read_text())["version"] == FORMAT_VERSION
    assert sorted(p.name for p in (old / "models").iterdir()) == sorted(_model_file(old, n).name for n in best_names)
    for name in best_names:
        assert not any(key.startswith("policy.optimizer/state/") for key in _tensor_names(_model_file(old, name)))
        assert converted[name].digest == library[name].digest
    # loaded by curriculum name from a library root (the package's by default) and used as actions
    assert pretrained_curricula(out) == ["tiny"]  # no shipped curriculum has all its lower-level nodes here
    assert SMCLibrary.pretrained("tiny", out).names == library.names == tuple(pretrained_names("tiny", out))
    with pytest.raises(LibraryError, match="no pretrained SMCs for curriculum 'tinyy'; did you mean 'tiny'"):
        SMCLibrary.pretrained("tinyy", out)
    index = json.loads((out / INDEX).read_text())
    index["nodes"][LEFT].append(f"{LEFT}@9")
    (out / INDEX).write_text(json.dumps(index))
    with pytest.raises(ManifestError, match=f"names SMCs that are not in the library: \\['{LEFT}@9'\\]"):
        SMCLibrary.pretrained("tiny", out)
    env = library.wrap(gym.make(f"PW-{TARGET}-v0"), library.names)
    assert list(env.action_names)[-4:] == [f"SMC:{name}" for name in library.names]
    env.reset(seed=0)
    *_, info = env.step(env.action_names.index(f"SMC:{library.names[0]}"))
    assert info["smc_calls"]  # the pretrained SMC ran as an action


def test_a_run_reuses_what_a_library_holds_instead_of_training_it(tmp_path):
    """From a pretrained library a fresh run copies the two best seeds of each lower-level node (their other seed is
    not trained) and trains only what is left; its top SMCs are those of the run the library came from, bit for bit.
    From a whole run library it copies every job it holds with the spec it would train it with."""
    tiny = Curriculum("tiny", (Node(LEFT, LEFT), Node(RIGHT, RIGHT), Node("top", TARGET, (LEFT, RIGHT))), ("top",))
    first = tmp_path / "first"
    train_curriculum(tiny, first, seeds=3, timesteps=256, progress=False)
    out = build_pretrained([first], [tiny], tmp_path / "pretrained", repeats=1)
    assert json.loads((out / INDEX).read_text())["seeds"] == {LEFT: 3, RIGHT: 3}
    lines: list[str] = []
    again = train_curriculum(tiny, tmp_path / "again", seeds=3, timesteps=256, printer=lines.append,
                             reuse_from=out)
    assert lines[0].startswith("tiny: 3 nodes x 3 seeds = 9 jobs (6 already done, 2 of them skipped)")
    assert len(again.rows) == 4 + 3  # the 4 copied jobs and the 3 of "top", the only ones trained
    trained, reused = SMCLibrary.load(first / "library"), SMCLibrary.load(again.library)
    pretrained = SMCLibrary.load(out)
    assert sorted(n for n in reused.names if not n.startswith("top")) == sorted(pretrained.names)
    assert status(tmp_path / "again")["skipped"] == sorted(set(trained.names) - set(reused.names))
    for name in (f"top@{seed}" for seed in range(3)):
        assert reused[name].spec == trained[name].spec and reused[name].record.training_returns == \
            trained[name].record.training_returns
        ours, theirs = reused[name].model.policy.state_dict(), trained[name].model.policy.state_dict()
        assert all(torch.equal(ours[k], theirs[k]) for k in theirs)
    lines.clear()
    copied = train_curriculum(tiny, tmp_path / "copied", seeds=3, timesteps=256, printer=lines.append,
                              reuse_from=first / "library")
    assert lines[0].startswith("tiny: 3 nodes x 3 seeds = 9 jobs (9 already done)")
    assert sorted(SMCLibrary.load(copied.library).names) == sorted(trained.names)
    with pytest.raises(LibraryError, match="no SMC library at"):
        train_curriculum(tiny, tmp_path / "never", seeds=3, timesteps=256, progress=False,
                         reuse_from=tmp_path / "nowhere")
    assert not (tmp_path / "never").exists()  # refused before anything was written
    (tmp_path / "tiny.yml").write_text(f"curriculum: tiny\nnodes:\n  - name: {LEFT}\n    task: {LEFT}\n"
                                       f"  - name: {RIGHT}\n    task: {RIGHT}\n  - name: top\n    task: {TARGET}\n"
                                       f"    uses: [{LEFT}, {RIGHT}]\ntargets: [top]\n")
    code, stdout, err = sb3_smc_cli("train", str(tmp_path / "tiny.yml"), "--out", str(tmp_path / "cli"), "--seeds",
                                    "3", "--timesteps", "256", "--no-tensorboard", "--reuse-from", str(out))
    assert code == 0, err
    assert "9 jobs (6 already done, 2 of them skipped)" in stdout


def test_reuse_on_a_run_whose_finished_target_needs_nothing_more(tmp_path):
    """A resumed run whose target is finished (its jobs skipped, as an experiment skips evaluated targets) leaves
    that target's children out of the plan; reusing a library then copies only for the nodes still to train (this
    once raised KeyError on the children left out)."""
    tiny = Curriculum("tiny", (Node(LEFT, LEFT), Node(RIGHT, RIGHT), Node("top", TARGET, (LEFT, RIGHT)),
                               Node("flat", TARGET)), ("top", "flat"))
    first = tmp_path / "first"
    train_curriculum(tiny, first, seeds=2, timesteps=256, targets=[LEFT, RIGHT], progress=False)
    lines: list[str] = []
    run = train_curriculum(tiny, tmp_path / "again", seeds=2, timesteps=256, printer=lines.append,
                           skip=["top@0", "top@1"], reuse_from=first / "library")
    assert lines[0].startswith("tiny: 2 nodes x 2 seeds = 4 jobs (2 already done, 2 of them skipped)")
    assert sorted(SMCLibrary.load(run.library).names) == ["flat@0", "flat@1"]


def test_the_shipped_pretrained_library():
    """What the package ships: every listed curriculum loads by name, with a test score per SMC; its index says
    what the shipped curricula say."""
    shipped = pretrained_curricula()
    assert "search2-canon" in shipped and "con2-cl-canon" in shipped
    index = json.loads((pretrained_root() / INDEX).read_text())
    held = {name.rpartition("@")[0] for name in SMCLibrary.pretrained("search2-canon").names} | set(index["nodes"])
    complete = {name: lower_level(c) for name, c in shipped_curricula().items()
                if lower_level(c) and set(lower_level(c)) <= held}  # every shipped curriculum it has all nodes of
    assert index["curricula"] == complete and sorted(complete) == sorted(shipped)
    partial = {name: lower_level(c) for name, c in shipped_curricula().items()
               if set(lower_level(c)) & held and name not in complete}  # for the error that refuses them
    assert index["partial"] == partial and "con2-cl" in partial
    for curriculum in shipped:  # two seeds of each lower-level node (names from the manifest: no model loaded)
        nodes = {name.rpartition("@")[0] for name in pretrained_names(curriculum)}
        assert len(pretrained_names(curriculum)) == 2 * len(nodes)
    library = SMCLibrary.pretrained("search2-canon")  # loaded and checked (checksums, layouts) like any library
    assert list(library.names) == pretrained_names("search2-canon") and len(library) == 26
    assert all(smc.test_score is not None and smc.spec is not None and smc.record is not None
               for smc in library.values())
    with pytest.raises(LibraryError, match="did you mean 'search2-canon'"):
        SMCLibrary.pretrained("search2-canonn")


def test_every_shipped_smc_loads_by_a_name():
    """Every SMC the package ships loads by a ``SMCLibrary.pretrained`` name: a pretrained curriculum's, or its
    node's (``cl_self-touches-container_vs_corner`` is called by ``con2-cl`` only); ``con2-cl``, of whose lower level
    the library holds part, is refused with what is missing and the names that load."""
    index = json.loads((pretrained_root() / INDEX).read_text())
    shipped = json.loads((pretrained_root() / "manifest.json").read_text())["smcs"]
    reached = {n for name in [*index["curricula"], *index["nodes"]] for n in pretrained_names(name)}
    assert reached == set(shipped)
    node = "cl_self-touches-container_vs_corner"
    assert not any(node in nodes for nodes in index["curricula"].values())  # no pretrained curriculum calls it
    library = SMCLibrary.pretrained(node)
    assert sorted(library.names) == [f"{node}@1", f"{node}@2"] and all(s.test_score for s in library.values())
    with pytest.raises(LibraryError) as refused:
        SMCLibrary.pretrained("con2-cl")
    message = str(refused.value)
    assert message.startswith("no pretrained SMCs for curriculum 'con2-cl': the pretrained library holds 14 of its "
                              "19 lower-level nodes, not all (missing: ba_self-on-hline_from_directly-above, ")
    assert "held: cl_self-in-left-corner_vs_on-hline, " in message
    assert f"{node}); pretrained curricula: con2-ba, " in message
    with pytest.raises(LibraryError, match="no pretrained SMCs for curriculum 'nothing-like-it'; pretrained "
                                           "curricula: con2-ba, .*; or one of the 45 nodes it holds by name"):
        SMCLibrary.pretrained("nothing-like-it")


def test_a_library_indexed_before_partial_curricula_were_listed_still_loads(tmp_path):
    """An index without ``partial`` (built before it was written) loads as one with none: a curriculum held in part
    is then refused as one it does not know, with the names that load."""
    copy = tmp_path / "pretrained"
    shutil.copytree(pretrained_root(), copy)
    index = json.loads((copy / INDEX).read_text())
    del index["partial"]
    (copy / INDEX).write_text(json.dumps(index))
    assert pretrained_index(copy)["partial"] == {} and pretrained_names("search2-canon", copy)
    with pytest.raises(LibraryError, match="no pretrained SMCs for curriculum 'con2-cl'; did you mean 'con2-ba'"):
        pretrained_names("con2-cl", copy)
    index["partial"] = {"con2-cl": "all of them"}
    (copy / INDEX).write_text(json.dumps(index))
    with pytest.raises(ManifestError, match="'partial': {name: \\[nodes\\]}"):
        pretrained_index(copy)


def test_a_rebuild_from_a_lean_run_replaces_the_stock_smcs(tmp_path):
    """The same specs trained with the other update are other SMCs: a rebuild from a lean run does not keep the
    stock SMCs the library holds (nor the other way round)."""
    tiny = Curriculum("tiny", (Node(LEFT, LEFT), Node(RIGHT, RIGHT), Node("top", TARGET, (LEFT, RIGHT))), ("top",))
    stock, lean = tmp_path / "stock", tmp_path / "lean"
    train_curriculum(tiny, stock, targets=[LEFT], seeds=2, timesteps=4000, progress=False)
    train_curriculum(tiny, lean, targets=[LEFT], seeds=2, timesteps=4000, lean_update=True, progress=False)
    out = build_pretrained([stock], [tiny], tmp_path / "pretrained", repeats=1, finished_only=True)
    assert not any(SMCLibrary.load(out)[name].record.lean_update for name in SMCLibrary.load(out).names)
    build_pretrained([lean], [tiny], out, repeats=1, finished_only=True)
    rebuilt = SMCLibrary.load(out)
    assert rebuilt.names and all(rebuilt[name].record.lean_update for name in rebuilt.names)
