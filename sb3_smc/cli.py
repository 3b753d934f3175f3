"""``sb3-smc``: list curricula, train them into a library (resumable, parallel, on Ray), and inspect runs.

    sb3-smc curricula                      # every shipped curriculum: method, targets, nodes per level
    sb3-smc curricula con2-cl              # one curriculum's DAG by level (a name or a .yml file)
    sb3-smc train con2-cl --out runs/con2-cl --targets cl_self-in-container_vs_noncontainer --seeds 2
    sb3-smc status runs/con2-cl            # done, running, failed, skipped and left jobs
    sb3-smc library runs/con2-cl/library   # its SMCs: kind, children, seed, selected update, test score
    sb3-smc experiment --out runs/headline --targets cl_self-left-of-two-objects-vs-one
    sb3-smc report runs/headline           # report.md and figures/, the paper's numbers beside ours
"""

from __future__ import annotations

import argparse
import errno
import json
import shlex
import signal
import sys
import threading
import unicodedata
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from pixelworld_env.errors import PixelWorldError
from pixelworld_env.generation.dataset_spec import MAX_NUM_SAMPLES
from sb3_smc import curricula
from sb3_smc.core.hyperparameters import ALGORITHMS, DEFAULT_ALGORITHM, DEFAULT_TIMESTEPS, RECURRENT_POLICIES
from sb3_smc.curricula import trainer
from sb3_smc.curricula.format import describe
from sb3_smc.curricula.jobs import DEFAULT_REUSE, DEFAULT_SEEDS, REUSE, check_curriculum
from sb3_smc.curricula.options import BACKENDS, DEFAULT_GROUP_SIZE, LIMITS, MAX_TRAIN_WORLDS, RunOptions
from sb3_smc.curricula.run_directory import status
from sb3_smc.errors import SMCError
from sb3_smc.experiments import report, runner
from sb3_smc.experiments.design import CATEGORIES, DEFAULT_METHODS, DEFAULT_REPEATS, METHOD_REGISTRY, METHODS
from sb3_smc.learning.evaluation import MAX_REPEATS
from sb3_smc.library import LibraryError, SMCLibrary, storage
from sb3_smc.library.pretrained import pretrained_root

__all__ = ["main"]


def _curricula(args: argparse.Namespace) -> int:
    if args.name:
        curriculum = curricula.resolve_curriculum(args.name)
        check_curriculum(curriculum)  # what sb3-smc train checks, with its default settings
        print(describe(curriculum))
        return 0
    rows = [("name", "method", "targets", "nodes per level")]
    for name, curriculum in curricula.shipped_curricula().items():
        levels = " + ".join(str(len(level)) for level in curriculum.levels())
        rows.append((name, curriculum.method or "", str(len(curriculum.targets)), levels))
    _print_table(rows)
    print("\nsb3-smc curricula NAME shows one curriculum; `python -m pydoc sb3_smc.curricula.format` describes the "
          "file format (and docs/curricula.md in the repository).")
    return 0


def _run_options(args: argparse.Namespace, **more: Any) -> RunOptions:
    """The run options of ``sb3-smc train`` and ``sb3-smc experiment`` (``more``: a command's own), checked."""
    return RunOptions(seeds=args.seeds, timesteps=args.timesteps, workers=args.workers, group_size=args.group_size,
                      backend=args.backend, ray_address=args.ray_address, algo=args.algo, rnn=args.rnn,
                      lean_update=args.lean_update, train_worlds=args.train_worlds,
                      reuse_from=_reuse_from(args.reuse_from), **more)


def _train(args: argparse.Namespace) -> int:
    targets = [t for item in args.targets for t in item.split(",") if t] if args.targets else None
    options = _run_options(args, reuse=args.reuse, tensorboard=not args.no_tensorboard)
    run = trainer.train_curriculum(args.curriculum, args.out, targets=targets, options=options,
                                   accept_changes=args.accept_changes)
    print(f"library: {run.library}")
    return 1 if run.failed else 0


def _status(args: argparse.Namespace) -> int:
    state = status(args.directory)
    settings = state["settings"]
    print(f"{args.directory}: curriculum {settings['curriculum']}, {len(settings['nodes'])} nodes x "
          f"{settings['seeds']} seeds = {len(state['jobs'])} jobs")
    for key in ("done", "running", "failed", "skipped", "damaged", "left"):
        names = list(state[key])
        shown = ", ".join(names[:8]) + (", ..." if len(names) > 8 else "")
        print(f"  {key:8s} {len(names):4d}  {shown}")
    if state["damaged"]:
        for problem in state["damaged"].values():
            print(f"  {problem}")
        print(f"the command that trained {args.directory} trains them again:\n  "
              f"{_resume_command(Path(args.directory), settings)}")
    return 0


def _resume_command(directory: Path, settings: dict[str, Any]) -> str:
    """The command that resumes the run in ``directory``: an experiment's recorded command, else ``sb3-smc train``
    with the settings of ``run.json`` (its curriculum named so where it is a file; where curricula were merged, what
    to look for)."""
    try:
        command = json.loads((directory / "results.json").read_text(encoding="utf-8")).get("command")
    except (OSError, ValueError, AttributeError):
        command = None
    if isinstance(command, str):
        return command
    name = settings["curriculum"]
    shipped = curricula.shipped_curricula()
    if "+" in name and name not in shipped:  # curricula merged: an experiment, or several in Python
        return (f"the command or call that started it, with the same options (for an experiment: sb3-smc experiment "
                f"--out {shlex.quote(str(directory))} ...)")
    curriculum = name if name in shipped else f"<the curriculum file of {name!r}>"
    options = [("--out", str(directory)), ("--targets", ",".join(settings["targets"])), ("--seeds", settings["seeds"]),
               ("--timesteps", settings.get("timesteps")), ("--reuse", settings.get("reuse")),
               ("--algo", settings.get("algo")), ("--rnn", settings.get("rnn"))]
    worlds = {(settings.get("nodes", {}).get(t) or {}).get("train_worlds") for t in settings["targets"]}
    if len(worlds) == 1:
        options.append(("--train-worlds", worlds.pop()))
    return (f"sb3-smc train {curriculum}" + "".join(f" {flag} {shlex.quote(str(value))}" for flag, value in options
                                                   if value is not None)
            + (" --lean-update" if settings.get("lean_update") else ""))


def _group_size_option(p: argparse.ArgumentParser) -> None:
    """``--group-size`` of ``sb3-smc train`` and ``sb3-smc experiment``."""
    p.add_argument("--group-size", type=_count(LIMITS["group_size"]), default=DEFAULT_GROUP_SIZE,
                   help="the most seeds of a node (flat, or level 2 over flat nodes) trained together by one worker "
                        "(default "
                        f"{DEFAULT_GROUP_SIZE}; 1: one job per worker); the SMCs are the same whatever it is")


def _experiment(args: argparse.Namespace) -> int:
    methods = [m for item in args.methods.split(",") if (m := item.strip())]
    targets = [t for item in args.targets for t in item.split(",") if t] if args.targets else None
    runner.run_experiment(args.out, methods=methods, targets=targets, category=args.category, repeats=args.repeats,
                          train=not args.no_train, options=_run_options(args))
    print(f"next: sb3-smc report {shlex.quote(args.out)}")
    return 0


def _report(args: argparse.Namespace) -> int:
    for path in report.write_report(args.directories, out=args.out, trajectories=args.trajectories,
                                    behaviour=not args.no_behaviour, reruns=args.rerun):
        print(f"wrote {path}")
    return 0


def _library(args: argparse.Namespace) -> int:
    root = Path(args.directory)
    manifest, where = storage.read_manifest(root)
    entries = storage.check_manifest(manifest, where)
    storage.topological_order(entries, where)  # SMCs that call each other in a cycle: an error, as on load
    pickled = [name for name, entry in entries.items() if storage.is_pickled(entry)]
    if args.upgrade:
        if pickled and not args.trust:
            raise LibraryError(f"{root}: {len(pickled)} SMC(s) stored as pickled archives (a library written before "
                               "sb3-smc's version-5 format): converting them loads them, which runs any code their "
                               "author put in them; add --trust if you trust where the library comes from")
        SMCLibrary.load(root, trust=args.trust).save()
        manifest, where = storage.read_manifest(root)
        entries = storage.check_manifest(manifest, where)
        pickled = []
    checked = ""
    if args.check:  # every model file: there, intact, its checksum; the safe ones rebuilt and fitted to their SMC
        for name, entry in entries.items():
            storage.check_model_file(root, name, entry)
        if pickled and not args.trust:
            checked = (f", every model file checked; {len(pickled)} pickled archive(s) checked but not loaded "
                       "(loading runs their code: --trust loads them, --upgrade --trust converts them)")
        else:
            SMCLibrary.load(root, trust=args.trust)
            checked = ", every model file checked and loaded"
    elif pickled:
        checked = (f"; {len(pickled)} SMC(s) stored as pickled archives, loaded only with trust "
                   f"(sb3-smc library {shlex.quote(str(root))} --upgrade --trust converts them)")
    rows = [{"name": name, "kind": entry.kind, "algo": entry.algo, "children": list(entry.children),
             **entry.summary()} for name, entry in entries.items()]
    if args.json:
        print(json.dumps(rows, indent=1))
        return 0
    made = (manifest.get("created_with") or {}).get("sb3_smc", "an unknown sb3_smc")
    print(f"{root}: {len(rows)} SMC(s), manifest version {manifest['version']} (sb3_smc {made}){checked}")
    table = [("name", "kind", "algo", "children", "task", "seed", "update", "return", "test %")]
    for row in rows:
        number = {key: "-" if row[key] is None else row[key] for key in ("seed", "selected_update")}
        table.append((row["name"], row["kind"], row["algo"], _children_cell(row["children"]),
                      _task_cell(row["name"], row["env_id"]),
                      str(number["seed"]), str(number["selected_update"]),
                      "-" if row["training_return"] is None else f"{row['training_return']:.3f}",
                      "-" if row["test_score"] is None else f"{100 * row['test_score']:.1f}"))
    _print_table(table)
    print("task: the env id (PW-X-v0 as X; = where X is the name before its @seed); --json: every field in full")
    return 0


CHILDREN_WIDTH = 32
"""The widest children cell of ``sb3-smc library``'s table; longer lists become a count (``--json`` lists them)."""


def _children_cell(children: Sequence[str]) -> str:
    listed = ",".join(children)
    return (listed or "-") if len(listed) <= CHILDREN_WIDTH else f"{len(children)} SMC{'s' * (len(children) != 1)}"


def _task_cell(name: str, env_id: str | None) -> str:
    if env_id is None:
        return "-"
    dataset = env_id.removeprefix("PW-").removesuffix("-v0") if env_id.startswith("PW-") else env_id
    return "=" if dataset == name.rpartition("@")[0] else dataset


def _display_width(text: str) -> int:
    """The terminal columns ``text`` takes: two for a wide or full-width character (CJK), none for a combining
    mark, one for any other."""
    return sum(0 if unicodedata.combining(char) else 2 if unicodedata.east_asian_width(char) in "WF" else 1
               for char in text)


def _print_table(rows: Sequence[Sequence[str]]) -> None:
    """``rows`` in columns two spaces apart, aligned by display width (:func:`_display_width`)."""
    widths = [max(_display_width(row[i]) for row in rows) for i in range(len(rows[0]))]
    for row in rows:
        print("  ".join(cell + " " * (width - _display_width(cell)) for cell, width in zip(row, widths, strict=True))
              .rstrip())


def _learn(args: argparse.Namespace) -> int:
    from sb3_smc.fewshot import OFFERS, learn_concept
    from sb3_smc.fewshot.choice import DEFAULT_OFFERED

    offer: str | list[str] = args.offer
    if args.offer not in OFFERS and "," in args.offer:
        offer = [name for item in args.offer.split(",") if (name := item.strip())]
    settings = {"total_timesteps": args.timesteps} if args.timesteps is not None else {}
    learned = learn_concept(args.task, library=args.library or "pretrained", offer=offer,
                            train_worlds=args.train_worlds, k=args.k or DEFAULT_OFFERED, name=args.name,
                            seed=args.seed, add_to=args.add_to, log_every=None, **settings)
    smc = learned.smc
    worlds = f"{args.train_worlds} training worlds" if args.train_worlds else "every training world"
    print(f"{smc.name}: learned from {worlds} with {len(learned.offered)} SMC(s) offered"
          + (f" ({', '.join(learned.offered)})" if learned.offered else ""))
    score = smc.test_score
    print(f"test score {100 * score:.1f} % on every held-out world, 10 times each" if score is not None else "")
    if args.add_to:
        print(f"added to {args.add_to}")
    return 0


def _import_zoo(args: argparse.Namespace) -> int:
    from sb3_smc.zoo import import_zoo_model

    smc = import_zoo_model(args.run_dir, args.library, name=args.name, model_file=args.model)
    calls = f", calling {[c.name for c in smc.children]}" if smc.children else ""
    print(f"added SMC {smc.name!r} ({smc.kind}, {type(smc.model).__name__}{calls}) to {args.library}")
    return 0


def _count(limit: int) -> Callable[[str], int]:
    """The type of an option that is a count in ``[1, limit]`` (argparse reports its error with the option's name),
    checked as the command line is read: the limits are those of the run's options (:data:`LIMITS`) and
    :data:`~sb3_smc.learning.evaluation.MAX_REPEATS`."""
    def count(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be a positive integer, got {text!r}") from None
        if value < 1:
            raise argparse.ArgumentTypeError(f"must be a positive integer, got {value}")
        if value > limit:
            raise argparse.ArgumentTypeError(f"must be at most {limit:,}, got {value:,}")
        return value

    return count


def _reuse_from(value: str | None) -> Path | None:
    """``--reuse-from``: a library directory, or ``pretrained`` for the package's pretrained library."""
    if value is None:
        return None
    return pretrained_root() if value == "pretrained" else Path(value)


def _learner_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--reuse-from", default=None, metavar="LIBRARY",
                        help="copy the SMCs this library holds with the spec the run would train them with instead "
                             "of training them ('pretrained': the package's pretrained library, whose nodes' other "
                             "seeds are then not trained)")
    parser.add_argument("--algo", default=None, choices=ALGORITHMS,
                        help=f"algorithm of every SMC (default: each node's, else {DEFAULT_ALGORITHM})")
    parser.add_argument("--rnn", default=None, choices=sorted(RECURRENT_POLICIES),
                        help="recurrent cell of every SMC (recurrent algorithms; default lstm); the paper's learner "
                             "is --algo RecurrentTRPO --rnn gru")
    parser.add_argument("--lean-update", action="store_true",
                        help="update every SMC with the lean update (RecurrentPPO or RecurrentTRPO with one LSTM or "
                             "GRU layer; the same update up to float rounding, faster, not bit-identical; recorded "
                             "in run.json)")
    parser.add_argument("--train-worlds", type=_count(MAX_TRAIN_WORLDS), default=None, metavar="N",
                        help="the targets learn from the first N worlds of their training split (the nodes they use "
                             "from all of theirs; recorded in run.json); default: every world")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="sb3-smc", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("curricula", help="list the shipped curricula, or show one by level")
    p.add_argument("name", nargs="?", help="a shipped curriculum name or a curriculum .yml file")
    p.set_defaults(run=_curricula)

    p = sub.add_parser("train", help="train a curriculum into DIR/library (re-run to resume)")
    p.add_argument("curriculum", help="a shipped curriculum name or a curriculum .yml file")
    p.add_argument("--out", required=True, help="the run directory")
    p.add_argument("--targets", action="append", help="node or dataset names (comma-separated; repeatable); "
                                                      "default: the curriculum's targets")
    p.add_argument("--seeds", type=_count(LIMITS["seeds"]), default=DEFAULT_SEEDS,
                   help=f"seeds 0..N-1 per node (default {DEFAULT_SEEDS}, the paper's)")
    p.add_argument("--timesteps", type=_count(LIMITS["timesteps"]), default=None,
                   help=f"steps per job, replacing the nodes' own (default: the node's, else {DEFAULT_TIMESTEPS:,}), "
                        "times a node's budget_scale")
    p.add_argument("--reuse", choices=list(REUSE), default=DEFAULT_REUSE,
                   help="seeds of each lower-level node a caller gets (default two_best)")
    p.add_argument("--workers", type=_count(LIMITS["workers"]), default=1,
                   help="jobs in parallel (local processes or Ray tasks)")
    _group_size_option(p)
    p.add_argument("--backend", choices=BACKENDS, default=BACKENDS[0])
    p.add_argument("--ray-address", default=None, help="Ray cluster address (default: $RAY_ADDRESS)")
    _learner_arguments(p)
    p.add_argument("--no-tensorboard", action="store_true", help="write no TensorBoard logs")
    p.add_argument("--accept-changes", action="store_true",
                   help="DIR holds this run with other node settings: train the changed nodes and the nodes above "
                        "them again (it says which), keep the others' jobs")
    p.set_defaults(run=_train)

    p = sub.add_parser("experiment", help="the paper's protocol: train, evaluate, results.csv / results.json")
    p.add_argument("--out", required=True, help="the experiment directory (re-run to resume)")
    p.add_argument("--methods", default=",".join(DEFAULT_METHODS),
                   help=f"comma-separated: {', '.join(METHODS)} (default: the paper's {', '.join(DEFAULT_METHODS)}; "
                        + "; ".join(METHOD_REGISTRY[m].label for m in METHODS if m not in DEFAULT_METHODS) + ")")
    group = p.add_mutually_exclusive_group()
    group.add_argument("--targets", action="append", help="level-2 target datasets (comma-separated; repeatable)")
    group.add_argument("--category", choices=[*CATEGORIES, "all"],
                       help="the higher-level targets of a category (default: all, the paper's 51; pushable: "
                            "the 8 of the designed pushable curriculum)")
    p.add_argument("--seeds", type=_count(LIMITS["seeds"]), default=DEFAULT_SEEDS)
    p.add_argument("--timesteps", type=_count(LIMITS["timesteps"]), default=None,
                   help=f"steps per SMC (default {DEFAULT_TIMESTEPS:,})")
    p.add_argument("--repeats", type=_count(MAX_REPEATS), default=DEFAULT_REPEATS,
                   help=f"test repeats per environment (default {DEFAULT_REPEATS})")
    p.add_argument("--workers", type=_count(LIMITS["workers"]), default=1)
    _group_size_option(p)
    p.add_argument("--backend", choices=BACKENDS, default=BACKENDS[0])
    p.add_argument("--ray-address", default=None)
    p.add_argument("--no-train", action="store_true",
                   help="train nothing: evaluate and tabulate what the run has finished so far (partial results, "
                        "marked so; the run may be training meanwhile)")
    _learner_arguments(p)
    p.set_defaults(run=_experiment)

    p = sub.add_parser("report", help="report.md and figures/ from experiment directories")
    p.add_argument("directories", nargs="+")
    p.add_argument("--out", default=None, help="one report over all the directories, written into OUT (default: a "
                                               "report in each directory)")
    p.add_argument("--trajectories", default=None, help="the target of the trajectory and timeline figures "
                                                        "(default: the first target)")
    p.add_argument("--no-behaviour", action="store_true", help="skip the trajectory and timeline figures")
    p.add_argument("--rerun", action="append", default=[], metavar="DIR",
                   help="one of the directories that ran target x method pairs of the others again: its rows replace "
                        "theirs, named in the report (repeatable; needs --out)")
    p.set_defaults(run=_report)

    p = sub.add_parser("learn", help="learn a new concept from a few of its worlds with a library's SMCs as actions")
    p.add_argument("task", help="the concept's task: a PW-* id (e.g. PW-cl_self-in-container_vs_noncontainer-v0)")
    p.add_argument("--train-worlds", type=_count(MAX_NUM_SAMPLES), default=None,
                   help="train on the first N worlds of its training split (default: all of them)")
    p.add_argument("--library", action="append", default=None,
                   help="a library folder to take SMCs from, or 'pretrained' (the default); repeat for several")
    p.add_argument("--offer", default="auto",
                   help="which SMCs to offer: auto (chosen from the examples alone), all, none (a flat SMC), a "
                        "pretrained curriculum's name (e.g. search2-canon), or names separated by commas")
    p.add_argument("--k", type=_count(MAX_NUM_SAMPLES), default=None,
                   help="how many SMCs the automatic choice keeps (default 8)")
    p.add_argument("--seed", type=int, default=0, help="the training seed")
    p.add_argument("--timesteps", type=_count(LIMITS["timesteps"]), default=None,
                   help="the training budget (default: the package's)")
    p.add_argument("--add-to", default=None, help="a library folder to add the learned SMC to (created if missing)")
    p.add_argument("--name", default=None, help="the new SMC's name (default: <task>[-n<N>]@<seed>)")
    p.set_defaults(run=_learn)

    p = sub.add_parser("import-zoo", help="add a model trained by rl_zoo3 to an SMC library")
    p.add_argument("run_dir", help="the zoo's run directory, e.g. logs/trpo/PW-...-v0_1")
    p.add_argument("--library", required=True, help="the library directory (created if missing)")
    p.add_argument("--name", default=None, help="the SMC's name (default: the env id's dataset name)")
    p.add_argument("--model", choices=("final", "best"), default="final",
                   help="the zoo's final model (<env id>.zip) or its best_model.zip")
    p.set_defaults(run=_import_zoo)

    p = sub.add_parser("library", help="what an SMC library holds: one row per SMC, read from its manifest")
    p.add_argument("directory", help="the library directory (e.g. runs/con2-cl/library)")
    p.add_argument("--check", action="store_true",
                   help="also check every model file (there, its checksum, well-formed; rebuilt and fitted to its SMC "
                        "without unpickling anything; an old library's pickled archives only with --trust)")
    p.add_argument("--upgrade", action="store_true",
                   help="write the library in the current format (an old library's pickled models need --trust)")
    p.add_argument("--trust", action="store_true",
                   help="load what runs code from the files (pickled models of a library written before version 5, "
                        "classes of other modules): only for a library from a source you trust")
    p.add_argument("--json", action="store_true", help="the rows as JSON")
    p.set_defaults(run=_library)

    p = sub.add_parser("status", help="what a run directory holds: done, running, failed, skipped, left")
    p.add_argument("directory")
    p.set_defaults(run=_status)

    args = parser.parse_args(argv)
    main_thread = threading.current_thread() is threading.main_thread()  # where a handler may be set
    previous = signal.signal(signal.SIGTERM, _terminated) if main_thread else None  # as Ctrl-C: the workers end
    try:
        return args.run(args)
    except (SMCError, PixelWorldError) as err:  # bad input, said in one line; anything else is a bug: its traceback
        print(f"sb3-smc {args.command}: error: {err}", file=sys.stderr)
        return 2
    except OSError as err:  # a file of the user's: missing, not allowed, the disk full
        print(f"sb3-smc {args.command}: error: {_os_error(err)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as stop:
        print(f"\n{'terminated' if isinstance(stop, _Terminated) else 'interrupted'}: what finished is saved; run the "
              "same command again to resume", file=sys.stderr)
        return 143 if isinstance(stop, _Terminated) else 130
    finally:
        if main_thread and previous is not None:  # None: a handler set outside Python, left as it is
            signal.signal(signal.SIGTERM, previous)


class _Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the command is, so that it stops as on Ctrl-C."""


def _terminated(signum: int, frame: object) -> None:
    raise _Terminated


def _os_error(err: OSError) -> str:
    """What went wrong with a file, and what to do where it is plain."""
    where = f" ({err.filename})" if err.filename else ""
    text = f"{err.strerror or err}{where}"
    if err.errno == errno.ENOSPC:
        return (f"{text}: the disk is full. What finished is saved and the run directory is consistent (files are "
                "written whole or not at all); free some space, then run the same command again to resume")
    return text


if __name__ == "__main__":
    sys.exit(main())
