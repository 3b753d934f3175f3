"""Equal experience: the primitive moves the SMCs behind a score trained on, and the flat SMC's score at a
curriculum's experience.

A flat SMC's score after its budget and a curriculum's are not scores at equal experience: a curriculum's target
SMCs call lower-level SMCs that trained for budgets of their own, and a call makes many moves. :class:`Experience`
holds what a run directory records of it (``run.json``: every node and the nodes it uses; the library's manifest:
each trained SMC's record with its ``primitive_steps``), kept beside the run's other records as ``experience.json``
(``python -m sb3_smc.experiments.experience RUN_DIR [--out FILE]``). :meth:`Experience.total` is the experience of
a set of nodes: the moves every seed of them and of every lower-level node they were built on trained on, each node
once (a run trains all of a node's seeds to pick the best ones, so all of them count). A node with records for only
some of its seeds (the pretrained library keeps the two best of five) counts as their mean times the run's seeds.

:func:`experience_section` sets each hierarchical method's best-seed score beside the flat SMC's at 1, 4 and 16 times
its budget (:data:`~sb3_smc.experiments.design.EXPERIENCE_METHODS`), the flat SMC's score read off its curve at the
hierarchical method's experience (linear in the logarithm of the experience between the points measured). That score
is a weighted sum of the flat methods' scores (:func:`at_experience`), so the bootstrap replicates of those scores
give it replicates too (:func:`blends`, named :func:`flat_at`): each method's mean lead gets an interval, and the
claims table judges the paper's "curr above base" at equal experience (:mod:`sb3_smc.experiments.claims`).
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

from pixelworld_env.atomic import atomic_write
from sb3_smc.core.dag import reachable
from sb3_smc.curricula.jobs import JobId
from sb3_smc.curricula.run_directory import read_json
from sb3_smc.errors import SMCError
from sb3_smc.experiments.bootstrap import Replicates
from sb3_smc.experiments.design import EXPERIENCE_METHODS, METHOD_REGISTRY
from sb3_smc.experiments.statistics import CEILING, NEAR, ceiling_wins, method_test, ttest_text, wins

__all__ = ["EXPERIENCE_FILE", "EXPERIENCE_HEADING", "AtExperience", "Experience", "ExperienceSource", "Experiences",
           "at_experience", "blends", "experience_section", "flat_at"]

EXPERIENCE_FILE = "experience.json"
"""The file of a run directory's (or its kept records') :class:`Experience`."""
EXPERIENCE_HEADING = "## Equal experience: the flat SMC at a curriculum's experience"
FORMAT = "sb3-smc-experience"


@dataclass(frozen=True)
class Experience:
    """The primitive moves each trained SMC of one or more runs made in training, and the nodes each node uses."""

    seeds: int
    """The seeds of each node in the run(s)."""
    uses: dict[str, tuple[str, ...]] = field(default_factory=dict)
    """Each node's lower-level nodes (its SMC actions)."""
    steps: dict[str, dict[int, int]] = field(default_factory=dict)
    """Each node's trained seeds and their primitive moves (``TrainingRecord.primitive_steps``)."""

    @classmethod
    def from_run(cls, directory: str | Path) -> Experience:
        """Read a run directory's ``run.json`` and its library's ``manifest.json``."""
        root = Path(directory)
        settings = _json(root / "run.json", "a run's settings (sb3-smc train / experiment)")
        manifest = _json(root / "library" / "manifest.json", "the run's SMC library")
        try:
            uses = {name: tuple(node["uses"]) for name, node in settings["nodes"].items()}
            seeds = int(settings["seeds"])
            steps: dict[str, dict[int, int]] = {}
            for name, entry in manifest["smcs"].items():
                job, record = JobId.of(name), entry.get("record") or {}
                if job is not None and record.get("primitive_steps") is not None:
                    steps.setdefault(job.node, {})[job.seed] = int(record["primitive_steps"])
        except (KeyError, TypeError, ValueError, AttributeError) as err:
            raise SMCError(f"{root}: run.json or library/manifest.json lacks what experience needs "
                           f"({type(err).__name__}: {err})") from None
        return cls(seeds, uses, steps)

    def to_dict(self) -> dict[str, Any]:
        return {"format": FORMAT, "version": 1, "seeds": self.seeds,
                "nodes": {name: {"uses": list(self.uses.get(name, ())),
                                 "primitive_steps": {str(s): n for s, n in sorted(self.steps.get(name, {}).items())}}
                          for name in sorted(set(self.uses) | set(self.steps))}}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], where: str = "experience") -> Experience:
        if data.get("format") != FORMAT or data.get("version") != 1:
            raise SMCError(f"{where}: not an {FORMAT} file of version 1 (format {data.get('format')!r}, version "
                           f"{data.get('version')!r})")
        try:
            nodes = data["nodes"]
            return cls(int(data["seeds"]), {n: tuple(v["uses"]) for n, v in nodes.items()},
                       {n: {int(s): int(k) for s, k in v["primitive_steps"].items()} for n, v in nodes.items()
                        if v["primitive_steps"]})
        except (KeyError, TypeError, ValueError, AttributeError) as err:
            raise SMCError(f"{where}: malformed ({type(err).__name__}: {err})") from None

    def save(self, path: str | Path) -> Path:
        """Write ``experience.json`` (write, then rename)."""
        return atomic_write(Path(path), json.dumps(self.to_dict(), indent=1) + "\n")

    @classmethod
    def load(cls, path: str | Path) -> Experience:
        return cls.from_dict(_json(Path(path), f"an {FORMAT} file"), str(path))

    def of(self, target: str, method: str) -> Experience:
        """The experience ``method``'s score on ``target`` was trained with: this one run's."""
        return self

    def closure(self, nodes: Iterable[str]) -> set[str]:
        """``nodes`` and every node they use, at any depth."""
        return reachable(nodes, lambda name: self.uses.get(name, ()))

    def node_total(self, name: str) -> float | None:
        """The moves of all of a node's seeds (their mean times :attr:`seeds` where only some were recorded);
        ``None`` without any record of it."""
        recorded = self.steps.get(name)
        if not recorded:
            return None
        return float(sum(recorded.values())) if len(recorded) >= self.seeds else \
            sum(recorded.values()) / len(recorded) * self.seeds

    def total(self, nodes: Collection[str]) -> float | None:
        """The experience of ``nodes``: the moves of every seed of them and of every node below them, each node
        once; ``None`` where any of them has no record."""
        totals = [self.node_total(name) for name in self.closure(nodes)]
        return None if not totals or any(t is None for t in totals) else float(sum(t for t in totals if t))


@dataclass(frozen=True)
class Experiences:
    """The experience of several runs, each with the (target, method) scores it reported: a score's experience is
    counted in the run that trained it. Two runs may hold SMCs of one node name trained apart (lower-level nodes one
    run reused from the pretrained library, two of five seeds, and another trained again), so their records are not
    merged."""

    runs: tuple[tuple[Experience, frozenset[tuple[str, str]]], ...]

    def of(self, target: str, method: str) -> Experience | None:
        """The experience of the run that reported ``method`` on ``target`` (``None``: no run with records did)."""
        return next((experience for experience, pairs in self.runs if (target, method) in pairs), None)


ExperienceSource = Experience | Experiences
"""One run's experience (every score's), or several runs' (:class:`Experiences`)."""


class ScoreTable(Protocol):
    """What the section reads of a report's :class:`~sb3_smc.experiments.tables.ResultTable`."""

    methods: list[str]
    targets: list[str]
    score: dict[tuple[str, str], float]
    kind_of: dict[str, str]
    unfinished: frozenset[tuple[str, str]]

    @property
    def replicates(self) -> Replicates: ...

    @property
    def hierarchical(self) -> list[str]: ...

    def candidate_nodes(self, target: str, method: str) -> set[str]: ...


def _json(path: Path, holds: str) -> Any:
    """:func:`~sb3_smc.curricula.run_directory.read_json`, and a clear error for a missing file."""
    if not path.is_file():
        raise SMCError(f"{path} does not exist; it should hold {holds}")
    return read_json(path, holds)


def _moves(count: float) -> str:
    """A count of moves: millions to one decimal (thousands below 100,000)."""
    return f"{count / 1e6:.1f}M" if count >= 100_000 else f"{count / 1e3:.1f}k"


def _weights(curve: Sequence[tuple[float, str]], spent: float,
             score: Mapping[str, float]) -> tuple[tuple[tuple[str, float], ...], str]:
    """The flat SMC's score at the experience ``spent`` as weights on its curve's points ((experience, method),
    sorted by experience), and where it lies: inside the measured range (interpolated in log experience), below it
    (its first point), or beyond it (its best point, by ``score``: a flat SMC whose curve fell at its last point, or
    that converged, is read at the most it reached, never less)."""
    if spent <= curve[0][0]:
        return ((curve[0][1], 1.0),), "below"
    if spent >= curve[-1][0]:
        best = max(range(len(curve)), key=lambda i: (score[curve[i][1]], i))  # ties: the later point
        return ((curve[best][1], 1.0),), "beyond"
    for (e0, m0), (e1, m1) in itertools.pairwise(curve):
        if e0 <= spent <= e1:
            share = (math.log(spent) - math.log(e0)) / (math.log(e1) - math.log(e0)) if e1 > e0 else 0.0
            return ((m0, 1.0 - share), (m1, share)), "inside"
    raise AssertionError("unreachable: the curve is sorted")


def flat_at(method: str) -> str:
    """The name of the flat SMC's score at ``method``'s experience (a blend of the flat methods' scores)."""
    return f"base@{method}"


@dataclass(frozen=True)
class AtExperience:
    """A hierarchical method's experience on a target, the flat SMC's curve there and its score at that experience
    as weights on the curve's points."""

    spent: float
    curve: tuple[tuple[float, str], ...]
    """(experience, flat method) for each point of the curve, by experience."""
    weights: tuple[tuple[str, float], ...]
    where: str
    """``inside`` the curve's range, ``below`` it (the flat SMC's score at its first point) or ``beyond`` it (at its
    best point)."""


def _spent(experience: ExperienceSource, target: str, method: str, nodes: Collection[str]) -> float | None:
    """The experience of ``nodes`` in the run that reported ``method`` on ``target`` (``None``: not recorded)."""
    run = experience.of(target, method)
    return run.total(nodes) if run is not None else None


def at_experience(table: ScoreTable, experience: ExperienceSource | None,
                  curve_of: Collection[str] = EXPERIENCE_METHODS) -> dict[tuple[str, str], AtExperience]:
    """(target, hierarchical method) -> where its experience falls on the flat SMC's curve (of the flat methods
    ``curve_of``, default every one that ran), for every target with at least two points of the curve and every
    method whose experience is recorded there."""
    flats = [m for m in EXPERIENCE_METHODS if m in table.methods and m in curve_of]
    if experience is None or len(flats) < 2:
        return {}
    found: dict[tuple[str, str], AtExperience] = {}
    for target in table.targets:
        points = [(_spent(experience, target, m, [METHOD_REGISTRY[m].flat_node(target).name]), m) for m in flats
                  if (target, m) in table.score]
        curve = tuple(sorted(((e, m) for e, m in points if e), key=lambda p: (p[0], flats.index(p[1]))))
        if len(curve) < 2:
            continue
        for method in table.hierarchical:
            spent = _spent(experience, target, method, table.candidate_nodes(target, method)) \
                if (target, method) in table.score else None
            if spent is not None:
                found[(target, method)] = AtExperience(spent, curve, *_weights(
                    curve, spent, {m: table.score[(target, m)] for _, m in curve}))
    return found


def blends(found: Mapping[tuple[str, str], AtExperience]) -> dict[str, dict[str, tuple[tuple[str, float], ...]]]:
    """:meth:`~sb3_smc.experiments.bootstrap.Replicates.blended`'s argument: the flat SMC's score at each method's
    experience (:func:`flat_at`) on each target."""
    out: dict[str, dict[str, tuple[tuple[str, float], ...]]] = {}
    for (target, method), at in found.items():
        out.setdefault(flat_at(method), {})[target] = at.weights
    return out


def experience_section(table: ScoreTable, experience: ExperienceSource | None) -> list[str]:
    """The report's section: per target with the flat SMC's curve, each hierarchical method's best-seed score and
    experience beside the flat SMC's score at that experience, and per method its lead with a bootstrap interval and
    a paired t-test; nothing without the curve's records."""
    found = at_experience(table, experience)
    if not found:
        return []
    replicates = table.replicates.blended(blends(found))
    rows: list[str] = []
    for (target, method), at in found.items():
        ours, flat = table.score[(target, method)], replicates.estimate[(target, flat_at(method))]
        mark = {"inside": "", "below": " (its least)", "beyond": " (its best point: less experience)"}[at.where]
        rows.append(f"| {target} | {table.kind_of[target]} | "
                    + " / ".join(f"{100 * table.score[(target, m)]:.1f} @ {_moves(e)}" for e, m in at.curve)
                    + f" | {method} | {100 * ours:.1f} @ {_moves(at.spent)} ({at.spent / at.curve[0][0]:.0f} x) | "
                    f"{100 * flat:.1f}{mark} | {100 * (ours - flat):+.1f} |")
    summary = []
    for method in [m for m in table.hierarchical if any(k == m for _, k in found)]:
        targets = sorted(t for t, m in found if m == method)
        blend = flat_at(method)
        lead = replicates.gap(targets, method, blend, concepts=True)
        ahead, _ = wins(replicates.estimate, targets, [method], blend)
        at_ceiling = ceiling_wins(replicates.estimate, targets, [method], blend)
        _, test = method_test(replicates.estimate, targets, method, blend)
        short = sum(found[(t, method)].where == "beyond" for t in targets)
        remarks = [f"{at_ceiling} of them at the ceiling"] * bool(at_ceiling) \
            + [f"on {short} the flat SMC's curve ends below its experience"] * bool(short)
        summary.append(f"{method}: ahead on {ahead} of {len(targets)} targets"
                       + (f" ({'; '.join(remarks)})" if remarks else "") + ", mean lead "
                       f"{100 * lead.estimate:+.1f} points [{100 * lead.low:+.1f}, {100 * lead.high:+.1f}]"
                       + (f", {ttest_text(test)}" if test is not None else "")
                       + (" (partial)" if any((t, method) in table.unfinished for t in targets) else ""))
    return [EXPERIENCE_HEADING, "",
            f"The flat SMC at {', '.join(m for m in EXPERIENCE_METHODS if m in table.methods)} (best seed @ the "
            "primitive moves all its seeds trained on) and each hierarchical method's best-seed score @ its "
            "experience: the moves of all seeds of its target nodes and of every lower-level node they were built on "
            "(docs/experiments.md, \"Equal experience\"), with how many times the first point's that is; the flat "
            "SMC's score at that experience, interpolated in log experience (at the curve's end where the method's "
            "experience lies beyond it), and the method's lead. Per method: on how many targets it leads (those at "
            f"the ceiling counted apart: the winner at {100 * CEILING:.0f} % or more, by {100 * NEAR:.0f} points or "
            "less), its mean lead with a 95 % bootstrap interval over the targets, seeds and test worlds, and the "
            "paired t-test across the targets.",
            "", "| target | kind | flat SMC: score @ moves | method | score @ moves | flat SMC there | lead |",
            "|---|---|---|---|---|---:|---:|", *rows, "", f"**At equal experience**: {'; '.join(summary)}.", ""]


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m sb3_smc.experiments.experience",
                                     description="Write a run directory's experience.json (the primitive moves of "
                                                 "every trained SMC, and the nodes each node uses).")
    parser.add_argument("run", help="a run directory of sb3-smc train / experiment (with run.json and library/)")
    parser.add_argument("--out", help=f"the file to write (default: RUN/{EXPERIENCE_FILE})")
    args = parser.parse_args(argv)
    path = Experience.from_run(args.run).save(Path(args.out) if args.out else Path(args.run) / EXPERIENCE_FILE)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
