"""Concept evaluation: the plain depth-first search next to forward checking, on concepts with many variables.

Scenes of 50 single-pixel objects (plus the self) at random cells; each concept is tested once with the plain
search (variables bound in declaration order, clauses checked when their last variable is bound) and once with the
forward-checking search that ``Concept.holds`` uses from three variables besides the self. Both give the same
answer (``tests/test_concepts.py`` checks it on random concepts).

Run: ``python benchmarks/bench_concepts.py``.
"""

from __future__ import annotations

import random
import time

from pixelworld_env.concepts import Concept
from pixelworld_env.core.scene import Scene

CASES = {
    "5 variables, a chain false at its last clause":
        "?a ?b ?c ?d ?e left_of(a,b) & left_of(b,c) & left_of(c,d) & left_of(d,e) & touches(e,a)",
    "5 variables, a chain that holds":
        "?a ?b ?c ?d ?e left_of(a,b) & left_of(b,c) & left_of(c,d) & left_of(d,e)",
    "4 variables, a cycle of touches (false)":
        "?a ?b ?c ?d touches(a,b) & touches(b,c) & touches(c,d) & touches(d,a) & left_of(a,c)",
    "3 variables anchored at the self":
        "?a ?b ?c near(self,a) & above(a,b) & left_of(b,c) & ~touches(c,self)",
}


def scene_with(n_objects: int, seed: int) -> Scene:
    rng = random.Random(seed)
    letters = [chr(x) for x in range(ord("a"), ord("z") + 1)] + [chr(x) for x in range(ord("A"), ord("Z") + 1)
                                                                  if chr(x) != "S"]
    grid = [["."] * 33 for _ in range(13)]
    for k, (r, c) in enumerate(rng.sample([(r, c) for r in range(13) for c in range(33)], n_objects + 1)):
        grid[r][c] = "S" if k == 0 else letters[k - 1]
    return Scene.from_ascii("#" * 35 + "\n" + "\n".join("#" + "".join(row) + "#" for row in grid) + "\n" + "#" * 35)


def timed(call) -> tuple[bool, float]:
    start = time.perf_counter()
    result = call()
    return result, time.perf_counter() - start


def main() -> None:
    scene = scene_with(50, seed=0)
    print(f"\nscene: {len(scene.objects) - 1} objects besides the frame\n")
    print("| concept | answer | plain search (s) | forward checking (s) | speed-up |")
    print("|---|---|---:|---:|---:|")
    for label, text in CASES.items():
        concept = Concept(text, {})
        evaluator = concept.self_evaluator(scene.objects, scene.floor_row)
        evaluator.domains[0] = [next(o for o in scene.objects if o.is_self)]
        domains, ctx = evaluator.domains, evaluator.ctx
        plain, t_plain = timed(lambda c=concept, d=domains, x=ctx: c._search(0, d, [], x))
        forward, t_forward = timed(lambda c=concept, d=domains, x=ctx: c._forward(d, [None] * len(d), set(), x))
        assert plain == forward, label
        print(f"| {label} | {plain} | {t_plain:.3f} | {t_forward:.4f} | {t_plain / max(t_forward, 1e-6):,.0f}x |")


if __name__ == "__main__":
    main()
