"""The pushable curriculum's datasets (designed by sb3-smc; docs/catalog.md): generation and labels, pushing
physics under every generator, and the same pixels for pushable and immoveable floor pixels.

Solvability of every bring-about scene (a plan that pushes, executed in the environment) is checked for every
registered id in tests/test_registration.py, these included.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pixelworld_env import Scene
from pixelworld_env.core.constants import MOVEABLE_CLASSES, ObjectClass
from pixelworld_env.core.world import MOVES, World
from pixelworld_env.datasets import catalog
from pixelworld_env.datasets.cache import load_or_generate
from pixelworld_env.datasets.loading import dataset_spec
from tests.helpers import import_benchmark
from tests.test_generation import check_dataset

PUSHABLE = sorted(n for n in catalog.dataset_names() if catalog.dataset(n).category == "pushable")
RIGHT = MOVES["RIGHT"]


def _dataset(name: str):
    return load_or_generate(dataset_spec(name), 0)


def _floor_pixel(scene: Scene) -> int:
    (index,) = [i for i, o in enumerate(scene.objects) if o.family == "pixel" and not o.is_self]
    return index


def _reference(scene: Scene) -> int | None:
    floor_row = scene.floor_row
    found = [i for i, o in enumerate(scene.objects) if o.family == "small_blob"
             and o.position[0] + o.size[0] == floor_row]
    return found[0] if found else None


def test_eleven_datasets_with_allow_pushable() -> None:
    assert len(PUSHABLE) == 11
    assert {catalog.dataset(n).kind for n in PUSHABLE} == {"classification", "bring-about"}


@pytest.mark.parametrize("name", PUSHABLE)
def test_generated_scenes_are_valid_and_labelled_by_the_concept(name: str) -> None:
    ds = _dataset(name)
    check_dataset(ds)  # sizes, quotas, generator and concept truth, padding, no overlap
    pixels = [ds.scenes[i].objects[_floor_pixel(ds.scenes[i])] for i in range(len(ds.scenes))]
    assert all(p.color == 1 and p.position[0] == ds.scenes[0].floor_row - 1 for p in pixels)  # white, on the floor
    assert all(o.pushable == (o.cls in MOVEABLE_CLASSES and not o.is_self) for s in ds.scenes for o in s.objects)
    floor = [o for s in ds.scenes for o in s.objects if o.family == "floor_shape"]
    assert floor and not any(o.pushable for o in floor)
    if "pushable" in catalog.dataset(name).concept:  # levels 5-6: both kinds of pixel, half and half
        assert sorted({p.pushable for p in pixels}) == [False, True]
        assert [p.pushable for p in pixels] == [bool(label) for label in ds.labels]


@pytest.mark.parametrize("name", [n for n in PUSHABLE if "from_left" in n or "pushable-floor" in n])
def test_walking_right_pushes_exactly_the_pushable_pixel(name: str) -> None:
    """Under every generator whose self stands on the floor left of the pixel: walking right moves the self up to
    the pixel; a pushable pixel then moves with it, one cell per step, until it touches the reference object (or
    the frame), and every push after that is blocked; an immoveable pixel never moves."""
    for scene in _dataset(name).scenes:
        world = World(scene)
        p, r, me = _floor_pixel(scene), _reference(scene), scene.objects.index(scene.self_object)
        pixel_start = world.positions[p]
        others = {i: world.positions[i] for i in range(len(scene.objects)) if i not in (p, me)}
        for _ in range(scene.width):
            world.move(RIGHT)
        (row, col), (self_row, self_col) = world.positions[p], world.positions[me]
        assert row == pixel_start[0] and (self_row, self_col) == (row, col - 1)  # self left-touching the pixel
        if scene.objects[p].pushable:
            reference_row = [c for rr, c in world.objects[r].pixels if rr == row] if r is not None else []
            stop = min(reference_row) - 1 if reference_row else scene.width - 2
            assert col == stop and col > pixel_start[1]
        else:
            assert (row, col) == pixel_start
        assert {i: world.positions[i] for i in others} == others  # nothing else moved
        assert not world.move(RIGHT)  # blocked now


def test_pushes_against_the_frame_chains_and_immoveable_objects() -> None:
    chain = Scene.from_ascii("""
#########
#.......#
#.SAB...#
#=======#
#.......#
#########
""")
    world = World(chain)
    a, b = (chain.objects.index(o) for o in chain.objects if o.pushable)
    assert world.move(RIGHT) and world.move(RIGHT) and world.move(RIGHT)  # the self pushes A, A pushes B
    assert world.positions[b][1] == 7 and world.positions[a][1] == 6  # B next to the frame (column 8)
    assert not world.move(RIGHT)  # B against the frame: the whole chain is blocked
    blocked = Scene.from_ascii("""
#########
#.......#
#.SAa...#
#=======#
#.......#
#########
""")
    world = World(blocked)
    before = list(world.positions)
    assert not world.move(RIGHT) and world.positions == before  # A against an immoveable pixel


def test_a_move_redraws_the_same_arrays_as_a_full_redraw() -> None:
    """Moves that push redraw only the moved objects: after every move of random walks in every pushable dataset
    (and in a scene with a pushable multi-pixel object), the state and owner arrays equal a full redraw."""
    scenes = [scene for name in PUSHABLE for scene in _dataset(name).scenes[:6]]
    scenes.append(Scene.from_ascii("""
##########
#........#
#.S.AA...#
#...AA.B.#
#========#
#........#
##########
"""))
    rng = np.random.default_rng(0)
    pushes = 0
    for scene in scenes:
        world = World(scene)
        for delta in rng.choice(list(MOVES.values()), size=60, p=[0.1, 0.6, 0.2, 0.1]):  # mostly towards P
            before = list(world.positions)
            world.move(tuple(delta))
            moved = [i for i, (a, b) in enumerate(zip(before, world.positions, strict=True)) if a != b]
            pushes += len(set(moved) - {world.self_index})
            grid, owner = world.grid.copy(), world.owner.copy()
            world.set_positions(list(world.positions))  # the full redraw
            np.testing.assert_array_equal(world.grid, grid)
            np.testing.assert_array_equal(world.owner, owner)
    assert pushes > 20  # the walks did push (32 pushes)


@pytest.mark.parametrize("name", ["cl_pushable-pixel_vs_unpushable_from_left-touches-one-gap",
                                  "cl_pushable-pixel_vs_unpushable_from_left-on-floor",
                                  "cl_pushable-floor-pixel_vs_unpushable"])
def test_pushable_and_immoveable_pixels_are_the_same_pixels(name: str) -> None:
    """What a passive observer gets (the initial state array, the CNN's input) does not change when the floor
    pixel's pushability is flipped: at levels 5-6 the label is not in the initial grid."""
    from sb3_smc.experiments.cnn import encode

    for scene in _dataset(name).scenes[:20]:
        p = _floor_pixel(scene)
        pixel = scene.objects[p]
        flipped_pixel = dataclasses.replace(pixel, pushable=not pixel.pushable,
                                            cls=ObjectClass.IMMOVEABLE if pixel.pushable else ObjectClass.BASIC)
        flipped = dataclasses.replace(scene, objects=(*scene.objects[:p], flipped_pixel, *scene.objects[p + 1:]))
        if name.endswith("one-gap"):  # the self touches the pixel: one push tells the two worlds apart
            assert World(flipped).move(RIGHT) != World(scene).move(RIGHT)
        grids = [World(scene).state().copy(), World(flipped).state().copy()]
        np.testing.assert_array_equal(grids[0], grids[1])
        np.testing.assert_array_equal(*encode(grids))


def test_only_level_1_is_decided_by_the_agents_first_view() -> None:
    """The order of the levels, measured (benchmarks/pushable_levels.py, docs/curricula.md): a lookup table from
    the first 3 x 3 view to the label answers level 1 and no higher classification (measured: 1.00, then 0.56,
    0.50, 0.50, 0.50, 0.50)."""
    module = import_benchmark("pushable_levels")
    classification = [n for n in PUSHABLE if catalog.dataset(n).kind == "classification"]
    accuracy = {n: module.first_view_accuracy(n) for n in classification}
    assert accuracy.pop("cl_self-ontop-pixel_touches-reference_vs_apart") >= 0.95
    assert len(accuracy) == 5 and all(value <= 0.65 for value in accuracy.values()), accuracy


def test_the_papers_protocol_estimate_leaves_the_designed_curriculum_out() -> None:
    """benchmarks/bench_curriculum.py counts the paper's protocol (docs/benchmarks.md: 101 flat nodes, 166 smc-curr
    and 102 smc-canon entries with their noprim variants, x 5 seeds), not the pushable curriculum beside it."""
    module = import_benchmark("bench_curriculum")
    assert "pushable" not in module.paper_curricula()
    assert module.protocol_jobs() == {"flat": 505, "curr": 830, "canon": 510}


def test_the_reset_bugs_stale_pixel_in_a_pushing_world() -> None:
    """A stale self pixel (the AAAI-18 reset bug) in a world with a pushable object: a blocked move keeps it, the
    first move that succeeds redraws the world without it (as in a world where only the self moves)."""
    scene = Scene.from_ascii("""
#########
#.......#
#..SA...#
#=======#
#.......#
#########
""")
    world = World(scene)
    world.move(RIGHT)  # pushes A
    start = world.self_position
    world.reset(stale_cell=(1, 1))
    assert world.stale and world.grid[2, 2] != 0 and world.owner[2, 2] == world.self_index
    assert not world.move(MOVES["DOWN"])  # the floor: blocked, the stale pixel stays
    assert world.stale and world.owner[2, 2] == world.self_index
    assert world.move(RIGHT) and not world.stale  # pushes A again, redraws everything
    assert world.self_position == (start[0], start[1]) and world.owner[2, 2] < 0
    grid, owner = world.grid.copy(), world.owner.copy()
    world.set_positions(list(world.positions))
    np.testing.assert_array_equal(world.grid, grid)
    np.testing.assert_array_equal(world.owner, owner)
