"""Where the flat SMC's curve of experience must go on: the targets that need its next point (``base-x16``,
``base-x64``, :data:`~sb3_smc.experiments.design.EXPERIENCE_METHODS`). Torch-free.

Beyond its last point, the flat SMC is read at its best point (:mod:`sb3_smc.experiments.experience`): it had less
experience than the curriculum it is set against, so a curriculum that leads it there may lead only for that. A
target needs the curve's next point (``method``, from the points below it) when

* some hierarchical method's experience there lies beyond the curve, and that method scores above the flat SMC's
  best point;
* the flat SMC has not converged at its last point: a seed ran its whole budget (a seed that stopped early, at the
  largest return, would stop at the same move with a larger budget: training is the same up to there);
* the point is not measured there yet, the curve's last point is the point just below ``method``, and, where the
  curve was already extended beyond :data:`FIRST`, its last extension still raised the flat SMC's score (it still
  rises).

``python -m sb3_smc.experiments.extension METHOD DIR...`` prints the ``sb3-smc experiment`` selection of those
targets (``--methods METHOD --targets ...``; nothing where none needs it) from the complete directories of the whole
table (``tools/paper_table.sh`` runs it for its categories ``experience-x16`` and ``experience-x64``).
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

from sb3_smc.errors import SMCError
from sb3_smc.experiments.design import EXPERIENCE_METHODS, METHOD_REGISTRY
from sb3_smc.experiments.experience import ExperienceSource, ScoreTable, at_experience

__all__ = ["FIRST", "main", "needs_point"]

FIRST = EXPERIENCE_METHODS[:2]
"""The points every target's curve has (1 and 4 x the budget); each later one is an extension."""


def needs_point(table: ScoreTable, experience: ExperienceSource, method: str, timesteps: int) -> list[str]:
    """The targets whose flat SMC's curve needs the point ``method`` (module docstring), from the points below it;
    ``timesteps``: the runs' budget (a flat method's budget is its factor times it)."""
    if method not in EXPERIENCE_METHODS[len(FIRST):]:
        raise SMCError(f"the curve's next point is one of {list(EXPERIENCE_METHODS[len(FIRST):])}, not {method!r}")
    below = EXPERIENCE_METHODS[:EXPERIENCE_METHODS.index(method)]
    found = at_experience(table, experience, below)
    out = []
    for target in table.targets:
        beyond = [(m, at) for (t, m), at in found.items() if t == target and at.where == "beyond"]
        if not beyond or (target, method) in table.score:  # measured already
            continue
        curve = beyond[0][1].curve
        best = max(table.score[(target, flat)] for _, flat in curve)
        last = curve[-1][1]
        if last != below[-1] or not any(table.score[(target, m)] > best for m, _ in beyond):
            continue
        if len(curve) > len(FIRST) and not table.score[(target, last)] > table.score[(target, curve[-2][1])]:
            continue  # extended already, and no longer rising
        if not _converged(experience, target, last, timesteps):
            out.append(target)
    return out


def _converged(experience: ExperienceSource, target: str, flat: str, timesteps: int) -> bool:
    """Whether every seed of the flat SMC ``flat`` on ``target`` stopped before its budget."""
    run = experience.of(target, flat)
    if run is None:
        return False
    recorded = run.steps.get(METHOD_REGISTRY[flat].flat_node(target).name, {})
    budget = METHOD_REGISTRY[flat].budget_factor * timesteps
    return len(recorded) >= run.seeds and all(steps < budget for steps in recorded.values())


def main(argv: Sequence[str] | None = None) -> None:
    from sb3_smc.experiments.report import read_table  # the report's reading of directories (matplotlib: on use)
    from sb3_smc.experiments.runner import read_results

    parser = argparse.ArgumentParser(prog="python -m sb3_smc.experiments.extension",
                                     description="Print the sb3-smc experiment selection (--methods METHOD --targets "
                                                 "...) of the targets whose flat SMC's curve of experience needs the "
                                                 "point METHOD; nothing where none does.")
    parser.add_argument("method", choices=EXPERIENCE_METHODS[len(FIRST):])
    parser.add_argument("directories", nargs="+", help="complete experiment directories (with experience.json)")
    parser.add_argument("--rerun", action="append", default=[], metavar="DIR",
                        help="one of the directories that ran pairs of the others again: its rows replace theirs")
    args = parser.parse_args(argv)
    budgets = {read_results(Path(d))["settings"]["timesteps"] for d in args.directories}
    if len(budgets) != 1:
        raise SystemExit(f"the directories ran with different budgets {sorted(budgets)}: the curve needs one")
    table, experience = read_table(args.directories, reruns=args.rerun)
    if experience is None:
        raise SystemExit("none of the directories has an experience.json: no curve to extend")
    targets = needs_point(table, experience, args.method, budgets.pop())
    if targets:
        print("--methods", args.method, "--targets", ",".join(targets))


if __name__ == "__main__":
    main()
