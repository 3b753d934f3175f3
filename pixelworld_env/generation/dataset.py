"""Dataset generation: generators sampled as constraint problems, filtered by a concept (docs/design.md,
"Dataset generation").

A generator is a concept expression whose variables (plus ``self``) each become one object. Its objects
are sampled from a constraint problem: per term a shape family, a ``shape_idx`` (0..49, template =
``shape_idx mod family size``), a colour, a target flag and a position, subject to the generator's
positive clauses, a global no-overlap constraint and the frame / padding bounds. Negated groups are
checked by rejection on the finished assignment (:mod:`pixelworld_env.generation.sampling`: the search;
:mod:`pixelworld_env.generation.placement`: where each object may go). :func:`generate` then draws from the generators
(uniformly at random), drops duplicates, labels each scene with the dataset's concept and fills the
label quotas (classification), keeps only scenes in which the goal does not hold (bring-about), or keeps scenes in
which the goal does not hold and fills the quotas of worlds where it can be brought about and where it cannot, as
the exhaustive search over the world's moves decides (bring-about-or-cannot: 50/50, certified;
:func:`pixelworld_env.generation.oracle.can_bring_about`).

Determinism: only Python's :class:`random.Random` with integer seeds (portable) and integer arithmetic
are used. The generator choice and the final shuffle use ``random.Random(seed)``; each generator has
its own stream ``random.Random(int(sha256(f"{seed}:{generator name}")[:16], 16))`` — unlike the
original, where every generator stream started from the same seed, but like it in that the same
generator with the same seed gives the same sequence in every dataset that uses it.
"""

from __future__ import annotations

import hashlib
import math
import random
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from pixelworld_env.concepts import Concept, ConceptError
from pixelworld_env.core.kinds import task_kind
from pixelworld_env.core.objects import frame_object
from pixelworld_env.core.scene import Scene
from pixelworld_env.errors import PixelWorldError
from pixelworld_env.generation.dataset_spec import MAX_NUM_SAMPLES, DatasetSpec
from pixelworld_env.generation.oracle import ReachabilityLimit, can_bring_about, goal_reachable
from pixelworld_env.generation.sampling import GenerationError, GeneratorSampler
from pixelworld_env.validation import check_count, check_seed

__all__ = ["GENERATOR_VERSION", "MAX_DRAWS", "GeneratedDataset", "GeneratorStats", "generate", "split"]

GENERATOR_VERSION = 2  # 2: bring-about scenes whose goal cannot be reached are dropped
"""Bump whenever a change of this module, :mod:`~pixelworld_env.generation.sampling`,
:mod:`~pixelworld_env.generation.placement`, :mod:`~pixelworld_env.generation.dataset_spec` or of a predicate's
entry (its function or its :class:`~pixelworld_env.concepts.predicates.GenerationFacts`) can change generated
datasets (part of the cache key)."""
DRAWS_PER_SAMPLE = 200
"""Default draw budget of :func:`generate`: this many draws per sample of the quota (``num_samples``)."""
MAX_DRAWS = DRAWS_PER_SAMPLE * MAX_NUM_SAMPLES
"""The most draws :func:`generate` takes (``max_draws``, 20,000,000): the default budget of the largest quota; a larger
budget is refused before the first draw."""


@dataclass(frozen=True)
class GeneratorStats:
    """What one generator did during :func:`generate`.

    ``samples``: solutions delivered (each one a draw); ``kept``: of those, scenes in the dataset;
    ``duplicates``: delivered scenes identical to an earlier one; ``rejected``: complete assignments
    rejected by a negated group; ``search_steps`` and ``restarts``: search effort.
    """

    name: str
    samples: int = 0
    kept: int = 0
    duplicates: int = 0
    rejected: int = 0
    search_steps: int = 0
    restarts: int = 0


@dataclass(frozen=True)
class GeneratedDataset:
    """A generated dataset: scenes (objects in term order, frame last), labels and provenance.

    Bring-about labels are all 1; bring-about-or-cannot labels say whether the goal can be brought about (1) or
    not (0). ``generator_of[i]`` names the generator that produced scene ``i``.
    ``draws`` counts generator samples taken, ``duplicates`` those identical to an earlier sample, and
    ``filtered`` those dropped by the concept filter (bring-about: goal already true; classification:
    label quota already full; bring-about-or-cannot: either); ``unreachable`` counts bring-about scenes dropped
    because no sequence of moves reaches the goal (:func:`pixelworld_env.generation.oracle.goal_reachable`), and
    bring-about-or-cannot scenes the exhaustive search could not decide within its limit.
    """

    spec: DatasetSpec
    seed: int
    scenes: tuple[Scene, ...]
    labels: tuple[int, ...]
    generator_of: tuple[str, ...]
    draws: int = 0
    duplicates: int = 0
    filtered: int = 0
    unreachable: int = 0
    generator_stats: tuple[GeneratorStats, ...] = ()

    def __len__(self) -> int:
        return len(self.scenes)

    @property
    def name(self) -> str:
        return self.spec.name

    @property
    def kind(self) -> str:
        return self.spec.kind

    __hash__ = None  # type: ignore[assignment]


def _stream_seed(seed: int, generator: str) -> int:
    return int(hashlib.sha256(f"{seed}:{generator}".encode()).hexdigest()[:16], 16)


# ---------------------------------------------------------------------------------------------- datasets


def generate(spec: DatasetSpec, seed: int = 0, *, max_draws: int | None = None,
             progress: Callable[[int, int, int], None] | None = None) -> GeneratedDataset:
    """Generate dataset ``spec`` with ``seed`` (docs/design.md, "Generation algorithm").

    Each draw picks a generator uniformly with ``random.Random(seed)`` and takes its next sample (each
    generator has its own seeded stream); a scene identical to an earlier one (same objects, including
    ``shape_idx``) is counted as a duplicate and skipped. Classification keeps a scene if the quota
    (``num_samples``) of its label, the concept's truth, is not full and stops when both are full;
    bring-about keeps only scenes in which the concept does not hold but can be made to hold by moving (a
    breadth-first search over moves), until ``num_samples``, all labelled 1. The kept scenes are listed
    negatives first, then positives (each in the order they were drawn) and shuffled with the same
    ``random.Random(seed)`` stream.

    ``max_draws`` (default ``DRAWS_PER_SAMPLE * num_samples``, at most :data:`MAX_DRAWS`) bounds the draws;
    reaching it, or an unsatisfiable generator, raises :class:`GenerationError`. ``progress(kept, target, draws)`` is
    called after every kept scene.
    """
    seed = check_seed(seed)
    if max_draws is None:
        max_draws = DRAWS_PER_SAMPLE * spec.num_samples
    max_draws = check_count(max_draws, "max_draws", MAX_DRAWS, "pixelworld_env.generation.dataset.MAX_DRAWS")
    try:
        concept = Concept(spec.concept, spec.macros)
    except ConceptError as exc:
        raise GenerationError(f"dataset {spec.name!r}: concept: {exc}") from exc
    kept: dict[int, list[tuple[Scene, int]]] = {0: [], 1: []}
    try:
        samplers = [GeneratorSampler(name, logic, spec, _stream_seed(seed, name)) for name, logic in spec.generators]
    except GenerationError as exc:
        raise GenerationError(f"{exc} (before the first draw; kept {_counts(spec, kept)})") from None
    chooser = random.Random(seed)
    frame = frame_object(spec.height, spec.width)
    kind = task_kind(spec.kind)
    quota = spec.num_samples
    seen: set[tuple] = set()
    draws = duplicates = filtered = unreachable = 0
    per_kept = [0] * len(samplers)
    per_dup = [0] * len(samplers)
    target = spec.size

    def total() -> int:
        return len(kept[0]) + len(kept[1])

    while total() < target:
        if draws >= max_draws:
            raise _quota_error(spec, samplers, kept, draws, duplicates, filtered, unreachable)
        draws += 1
        g = chooser.randrange(len(samplers))
        sampler = samplers[g]
        try:
            objects = sampler.sample()
        except GenerationError as exc:
            raise GenerationError(f"{exc} (after {draws - 1} draws; kept {_counts(spec, kept)})") from None
        key = tuple((o.family, o.shape_idx, o.color, o.position, o.is_target, o.pushable) for o in objects)
        if key in seen:
            duplicates += 1
            per_dup[g] += 1
            continue
        seen.add(key)
        scene = Scene(height=spec.height, width=spec.width, objects=(*objects, frame))
        truth = concept.holds(scene)
        if kind.label is not None:
            if kind.tracks_goal and truth:  # bring-about-or-cannot: the goal must not hold at the start
                filtered += 1
                continue
            if kind.label == "label":
                label = int(truth)
            else:  # "possible": decided by the exhaustive search; a world it cannot decide is not kept
                try:
                    label = int(can_bring_about(concept, scene))
                except ReachabilityLimit:
                    unreachable += 1
                    continue
            if len(kept[label]) >= quota:
                filtered += 1
                continue
        else:
            if truth:
                filtered += 1
                continue
            if not goal_reachable(scene, concept):
                unreachable += 1
                continue
            label = 1
        kept[label].append((scene, g))
        per_kept[g] += 1
        if progress is not None:
            progress(total(), target, draws)

    ordered = [(scene, label, g) for label in (0, 1) for scene, g in kept[label]]
    chooser.shuffle(ordered)
    stats = tuple(
        GeneratorStats(name=s.name, samples=s.samples, kept=per_kept[i], duplicates=per_dup[i], rejected=s.rejected,
                       search_steps=s.search_steps, restarts=s.restarts)
        for i, s in enumerate(samplers)
    )
    return GeneratedDataset(
        spec=spec, seed=seed, scenes=tuple(s for s, _, _ in ordered), labels=tuple(lab for _, lab, _ in ordered),
        generator_of=tuple(spec.generators[g][0] for _, _, g in ordered), draws=draws, duplicates=duplicates,
        filtered=filtered, unreachable=unreachable, generator_stats=stats,
    )


def _counts(spec: DatasetSpec, kept: Mapping[int, list]) -> str:
    if task_kind(spec.kind).label is not None:
        return f"{len(kept[1])} positive and {len(kept[0])} negative of {spec.num_samples} each"
    return f"{len(kept[1])} of {spec.num_samples} scenes in which the goal does not hold"


def _quota_error(spec: DatasetSpec, samplers: Iterable[GeneratorSampler], kept: Mapping[int, list], draws: int,
                 duplicates: int, filtered: int, unreachable: int) -> GenerationError:
    names = ", ".join(repr(s.name) for s in samplers)
    return GenerationError(
        f"dataset {spec.name!r} (generators {names}) reached only {_counts(spec, kept)} within {draws} draws "
        f"({duplicates} duplicates, {filtered} dropped by the concept filter or a full quota, {unreachable} "
        "with an unreachable goal)"
    )


# ---------------------------------------------------------------------------------------------- split


def split(labels: Sequence[int], test_fraction: float = 0.5,
          seed: int = 521) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """A stratified train/test split: ``(train indices, test indices)``, each sorted.

    Scheme (deterministic, numpy only): the test set has ``ceil(test_fraction * n)`` items (the sklearn
    rule); it is divided among the labels proportionally to their counts (floor of each share, the rest
    to the largest remainders, ties to the smaller label). Each label's indices are permuted with one
    legacy ``numpy.random.RandomState(seed)`` stream (labels in increasing order) and the first ones go
    to the test set. Classification 50+50 -> 50/50 with 25+25 each; bring-about 50 -> 25/25.
    """
    if not 0.0 < test_fraction < 1.0:
        raise PixelWorldError(f"test_fraction must lie strictly between 0 and 1, got {test_fraction}")
    labels = [int(v) for v in labels]
    n = len(labels)
    if n < 2:
        raise PixelWorldError(f"need at least 2 samples to split, got {n}")
    classes = sorted(set(labels))
    members = {c: [i for i, v in enumerate(labels) if v == c] for c in classes}
    n_test = min(n - 1, max(1, math.ceil(test_fraction * n)))
    shares = {c: n_test * len(members[c]) for c in classes}  # share * n (integer arithmetic)
    alloc = {c: shares[c] // n for c in classes}
    rest = n_test - sum(alloc.values())
    for c in sorted(classes, key=lambda c: (-(shares[c] % n), c))[:rest]:
        alloc[c] += 1
    rng = np.random.RandomState(seed)
    test: list[int] = []
    for c in classes:
        perm = rng.permutation(len(members[c]))
        test.extend(members[c][int(p)] for p in perm[:alloc[c]])
    test_set = set(test)
    return tuple(i for i in range(n) if i not in test_set), tuple(sorted(test_set))
