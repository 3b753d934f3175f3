"""The paper's reported numbers (Hay et al., AAAI-18, Fig. 5 and text), for the report to put beside ours.

Percentages of test accuracy (classification) or success rate (bring-about): best seed, the update with the best
training return; means over the level-2 concepts of each kind.
"""

from __future__ import annotations

__all__ = ["ORIGINAL_FLAT_RUNS", "PAPER_CONCEPTS", "PAPER_COUNTS", "PAPER_MEANS", "PAPER_NOPRIM", "PAPER_TTESTS"]

PAPER_COUNTS: dict[str, int] = {"classification": 34, "bring-about": 17}
"""How many level-2 concepts the paper's means and t-tests are over."""

PAPER_MEANS: dict[str, dict[str, float]] = {
    "classification": {"cnn": 79.9, "base": 74.5, "curr": 84.9, "canon": 80.2},
    "bring-about": {"base": 52.7, "curr": 74.5, "canon": 75.0},
}
"""Mean score per method over the level-2 concepts (34 classification, 17 bring-about)."""

PAPER_NOPRIM: dict[str, dict[str, float]] = {
    "classification": {"curr": 84.9, "curr-noprim": 82.7, "canon": 80.3, "canon-noprim": 81.1},
    "bring-about": {"curr": 74.5, "curr-noprim": 71.6, "canon": 75.1, "canon-noprim": 75.1},
}
"""The role of hierarchy, with and without primitive moves (the with-primitives numbers as printed in that
paragraph of the paper)."""

PAPER_TTESTS: dict[str, dict[str, tuple[int, float, float]]] = {
    "classification": {"curr vs base": (34, 4.9, 0.00002), "canon vs base": (34, 2.3, 0.025)},
    "bring-about": {"curr vs base": (16, 4.1, 0.0008), "canon vs base": (16, 4.4, 0.0005)},
}
"""Paired t-tests across concepts: (df, t, p)."""

PAPER_CONCEPTS: dict[str, dict[str, float]] = {
    "cl_self-left-of-two-objects-vs-one": {"base": 52.6, "curr": 90.4, "canon": 89.0},
    "ba_self-in-container_from_between-potential-containers": {"base": 48.4, "curr": 82.0, "canon": 71.2},
}
"""The per-concept numbers the paper gives (the headline targets)."""

ORIGINAL_FLAT_RUNS: dict[str, tuple[float, float]] = {
    "cl_object-above-floor_vs_no-object": (55.0, 53.0),
    "cl_object-on-floor_vs_no-object": (65.0, 58.0),
    "cl_object-on-floor_vs_not-on-floor": (66.0, 60.0),
    "cl_object-on-floor_vs_not": (64.0, 58.0),
    "cl_self-between-two-objects_vs_not-between-on-floor": (79.0, 72.0),
    "cl_two-objects-on-floor_vs_not": (70.0, 62.0),
    "cl_two-objects-on-floor_vs_one": (66.0, 64.0),
    "cl_two-objects-on-floor_vs_two-objects-one-on-floor": (49.0, 45.0),
    "cl_two-objects-one-above-and-one-on-floor_vs_not": (52.0, 51.0),
    "ba_self-ontop-object_from_anywhere-on-floor": (80.0, 62.0),
    "ba_self-between-two-objects_from_not-between-on-floor": (48.0, 32.0),
    "ba_self-second_from_left_from_anywhere-on-floor": (21.0, 10.0),
    "ba_self-second_from_right_from_anywhere-on-floor": (20.0, 9.0),
    "ba_self-left-of-two-objects_from_not-left-on-floor": (100.0, 37.0),
    "ba_self-right-of-two-objects_from_not-right-on-floor": (100.0, 78.0),
}
"""The original runs' flat SMCs of the objects concepts: (best seed, mean over seeds), as the comments of the
release's ``objects2-cl-canon`` / ``objects2-ba-canon`` curriculum files record them (their "Max" and "Avg" columns;
the paper itself gives no per-concept numbers). The only per-concept reference for the flat baseline (``base``)."""
