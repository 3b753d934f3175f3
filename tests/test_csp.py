"""The python-constraint statement of the generator CSP agrees with the fast sampler and the original data."""

from __future__ import annotations

import pytest

from pixelworld_env.core.scene import Scene
from pixelworld_env.datasets import catalog
from pixelworld_env.datasets.cache import load_or_generate
from pixelworld_env.datasets.loading import dataset_spec
from pixelworld_env.generation.csp import sample_generator, satisfies_generator
from tests.helpers import read_samples, samples_folder

pytestmark = pytest.mark.reference  # reads the original data: the reference, or the fixture

DATASETS = [
    "cl_self-in-container_vs_noncontainer",
    "ba_self-in-container_from_directly-above",
    "cl_self-between-two-objects_vs_not-between-on-floor",
    "ba_self-touches-target_from_left-on-floor_with_left-nontarget",
    "ba_self-left-touches-object_from_left-on-floor_with_distraction",
]


@pytest.mark.parametrize("name", DATASETS)
def test_generated_scenes_solve_the_python_constraint_csp(name: str) -> None:
    info = catalog.dataset(name)
    generated = load_or_generate(dataset_spec(name), 0)
    targets = bool(info.settings.get("allow_targets"))
    for scene, generator in list(zip(generated.scenes, generated.generator_of, strict=True))[:20]:
        assert satisfies_generator(scene, catalog.generators()[generator], allow_targets=targets)


def test_original_samples_solve_the_csp_and_moved_selves_do_not() -> None:
    header, samples = read_samples(samples_folder() / "ba_self-in-container_from_directly-above.jsonl.gz")
    logic = catalog.generators()[header["definition"]["generators"][0]["name"]]
    for sample in samples[:20]:
        scene = Scene.from_dict(sample)
        assert satisfies_generator(scene, logic)
        me = scene.self_index
        lowered = scene.with_positions([(14, 1) if i == me else o.position for i, o in enumerate(scene.objects)])
        assert not satisfies_generator(lowered, logic)  # on the floor, not above a container


def test_python_constraint_samples_a_small_generator() -> None:
    logic = catalog.generators()["bfaw-self-on-floor"]
    scenes = [sample_generator(logic, seed=s) for s in range(3)]
    assert all(s is not None and satisfies_generator(s, logic) for s in scenes)
    assert scenes[0] == sample_generator(logic, seed=0)
    assert len({s.self_object.position for s in scenes}) > 1
    assert sample_generator("?x container(x) & noncontainer(x)", seed=0) is None


def test_each_unary_predicate_reads_only_what_the_table_says() -> None:
    """The CSP constrains a unary predicate over the attributes its PredicateSpec names (``reads``): changing any
    other attribute of an object must not change its truth (a predicate that read more would be pruned wrongly)."""
    import itertools

    from pixelworld_env.concepts.predicates import PREDICATES, EvalContext
    from pixelworld_env.core.shapes import FAMILIES
    from pixelworld_env.generation.placement import library_object

    ctx = EvalContext(floor_row=15)
    base = {"shape": "pixel", "shape_idx": 0, "color": 2, "is_target": False, "x": 3, "y": 4}
    variants = {"shape": list(FAMILIES)[:8], "shape_idx": [0, 1, 3], "color": [1, 2, 5], "is_target": [False, True],
                "x": [2, 9], "y": [3, 12]}
    checked = 0
    for name, spec in PREDICATES.items():
        if spec.arity != 1 or spec.reads is None:
            continue
        fixed = [a for a in base if a not in spec.reads]
        for read_values in itertools.product(*(variants[a] for a in spec.reads)):
            values = {**base, **dict(zip(spec.reads, read_values, strict=True))}
            answers = set()
            for attribute in fixed:
                for value in variants[attribute]:
                    v = {**values, attribute: value}
                    obj = library_object(v["shape"], v["shape_idx"], v["color"], (v["y"], v["x"]),
                                         is_target=v["is_target"])
                    answers.add(bool(spec.fn(obj, ctx)))
            assert len(answers) == 1, (name, values)
            checked += 1
    assert checked > 100
