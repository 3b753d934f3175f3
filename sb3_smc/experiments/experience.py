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
hierarchical method's experience (linear in the logarithm of the experience between the points measured).
"""

from __future__ import annotations

import argparse
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
from sb3_smc.experiments.design import EXPERIENCE_METHODS, METHOD_REGISTRY

__all__ = ["EXPERIENCE_FILE", "EXPERIENCE_HEADING", "Experience", "experience_section"]

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

    @classmethod
    def merged(cls, parts: Sequence[Experience]) -> Experience | None:
        """The experience of several runs (a node in two of them must have the same uses; ``None`` for none)."""
        if not parts:
            return None
        uses: dict[str, tuple[str, ...]] = {}
        steps: dict[str, dict[int, int]] = {}
        for part in parts:
            for name, used in part.uses.items():
                if uses.setdefault(name, used) != used:
                    raise SMCError(f"node {name!r} uses {list(uses[name])} in one run and {list(used)} in another")
            for name, seeds in part.steps.items():
                steps.setdefault(name, {}).update(seeds)
        return cls(max(p.seeds for p in parts), uses, steps)

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


class ScoreTable(Protocol):
    """What the section reads of a report's :class:`~sb3_smc.experiments.tables.ResultTable`."""

    methods: list[str]
    targets: list[str]
    score: dict[tuple[str, str], float]
    kind_of: dict[str, str]

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


def _at(curve: Sequence[tuple[float, float]], experience: float) -> tuple[float, str]:
    """The flat SMC's score at ``experience`` read off its curve (points sorted by experience), and where: inside
    the measured range (interpolated in log experience), or at its nearest end."""
    if experience <= curve[0][0]:
        return curve[0][1], "below"
    if experience >= curve[-1][0]:
        return curve[-1][1], "beyond"
    for (e0, s0), (e1, s1) in zip(curve, curve[1:], strict=False):
        if e0 <= experience <= e1:
            share = (math.log(experience) - math.log(e0)) / (math.log(e1) - math.log(e0)) if e1 > e0 else 0.0
            return s0 + share * (s1 - s0), "inside"
    raise AssertionError("unreachable: the curve is sorted")


def experience_section(table: ScoreTable, experience: Experience | None) -> list[str]:
    """The report's section: per target with the flat SMC's curve, each hierarchical method's best-seed score and
    experience beside the flat SMC's score at that experience; nothing without the curve's records."""
    flats = [m for m in EXPERIENCE_METHODS if m in table.methods]
    if experience is None or len(flats) < 2:
        return []
    rows: list[str] = []
    leads: dict[str, list[float]] = {}
    for target in table.targets:
        points = [(experience.total([METHOD_REGISTRY[m].flat_node(target).name]), table.score.get((target, m)))
                  for m in flats]
        curve = sorted((e, s) for e, s in points if e and s is not None)
        if len(curve) < 2:
            continue
        for method in table.hierarchical:
            if (target, method) not in table.score:
                continue
            spent = experience.total(table.candidate_nodes(target, method))
            if spent is None:
                continue
            ours = table.score[(target, method)]
            flat, where = _at(curve, spent)
            mark = {"inside": "", "below": " (its least)", "beyond": " (its most: less experience)"}[where]
            rows.append(f"| {target} | {table.kind_of[target]} | "
                        + " / ".join(f"{100 * s:.1f} @ {_moves(e)}" for e, s in curve)
                        + f" | {method} | {100 * ours:.1f} @ {_moves(spent)} ({spent / curve[0][0]:.0f} x) | "
                        f"{100 * flat:.1f}{mark} | {100 * (ours - flat):+.1f} |")
            leads.setdefault(method, []).append(ours - flat)
    if not rows:
        return []
    summary = "; ".join(f"{m}: ahead on {sum(d > 0 for d in ds)} of {len(ds)} targets, mean lead "
                        f"{100 * sum(ds) / len(ds):+.1f} points" for m, ds in leads.items())
    return [EXPERIENCE_HEADING, "",
            f"The flat SMC at {', '.join(flats)} (best seed @ the primitive moves all its seeds trained on) and each "
            "hierarchical method's best-seed score @ its experience: the moves of all seeds of its target nodes and "
            "of every lower-level node they were built on (docs/experiments.md, \"Equal experience\"), with how many "
            "times the first point's that is; the flat SMC's score at that experience, interpolated in log "
            "experience (at the curve's end where the method's experience lies beyond it), and the method's lead.",
            "", "| target | kind | flat SMC: score @ moves | method | score @ moves | flat SMC there | lead |",
            "|---|---|---|---|---|---:|---:|", *rows, "", f"**At equal experience**: {summary}.", ""]


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
