"""Curricula designed by sb3-smc (not in the AAAI-18 release): the pushable curriculum of the paper's Fig. 3 / 5c.

The paper names an 11-concept, 6-level *pushable* curriculum leading to ``cl_pushable-floor-pixel_vs_unpushable``
but never released it. Its datasets are defined in
``pixelworld_env/data/definitions/pushable.datasets`` (category ``pushable`` of the catalog); the hierarchy is
:data:`PUSHABLE`. A node's level is one more than the highest level it uses (level 1: flat;
``Curriculum.levels()``). Torch-free.

Why this order (docs/curricula.md): the levels follow how much of a classification the initial state gives away
without acting. Level 1's check is decided by the agent's first 3 x 3 view; levels 2-3 are decided by the full
initial grid but not by the agent's view (it must walk and climb to look); at levels 5-6 not even the full grid
decides, because pushable and immoveable pixels look the same: the agent must push and then look. The bring-about
nodes are the behaviours the classifiers above them call: walk to the pixel, climb on it, push it against the
reference object.
"""

from __future__ import annotations

from typing import NamedTuple

from sb3_smc.curricula.format import Curriculum, Node

__all__ = ["PUSHABLE", "PUSHABLE_TOP", "DesignedNode", "designed_curricula"]

class DesignedNode(NamedTuple):
    """A node of a designed curriculum: the datasets whose SMCs it calls and what it asks, in one line."""

    uses: tuple[str, ...]
    summary: str


PUSHABLE: dict[str, DesignedNode] = {
    # level 1
    "ba_self-left-touches-pixel_from_left-on-floor": DesignedNode(
        (), "walk right along the floor until touching the white pixel (pushable or not)"),
    "ba_self-ontop-pixel_from_left-touches-on-floor": DesignedNode(
        (), "from beside the pixel, climb on top of it (up, then over; walking into it pushes a pushable one)"),
    "cl_self-ontop-pixel_touches-reference_vs_apart": DesignedNode(
        (), "standing on an immoveable pixel: does the reference object touch it? (visible in the first view)"),
    # level 2
    "ba_self-ontop-pixel_from_left-on-floor": DesignedNode(
        ("ba_self-left-touches-pixel_from_left-on-floor", "ba_self-ontop-pixel_from_left-touches-on-floor"),
        "from farther left, get on top of the pixel: walk to it, then climb"),
    "cl_pixel-touches-reference_vs_apart_from_left-touches": DesignedNode(
        ("ba_self-ontop-pixel_from_left-touches-on-floor", "cl_self-ontop-pixel_touches-reference_vs_apart"),
        "beside an immoveable pixel: does the reference touch it? (out of view: climb on the pixel and look)"),
    # level 3
    "cl_pixel-touches-reference_vs_apart_from_left-on-floor": DesignedNode(
        ("ba_self-ontop-pixel_from_left-on-floor", "cl_self-ontop-pixel_touches-reference_vs_apart"),
        "the same question from anywhere left of the pixel: walk, climb, look"),
    # level 4
    "ba_pixel-touches-reference_from_left-touches-pushable": DesignedNode(
        ("cl_pixel-touches-reference_vs_apart_from_left-on-floor",),
        "beside a pushable pixel: push it right until it touches the reference object"),
    "ba_pixel-touches-reference_from_left-on-floor-pushable": DesignedNode(
        ("ba_self-left-touches-pixel_from_left-on-floor", "cl_pixel-touches-reference_vs_apart_from_left-on-floor"),
        "from farther left: walk to the pushable pixel and push it against the reference"),
    # level 5
    "cl_pushable-pixel_vs_unpushable_from_left-touches-one-gap": DesignedNode(
        ("ba_pixel-touches-reference_from_left-touches-pushable",
         "cl_pixel-touches-reference_vs_apart_from_left-touches"),
        "beside the pixel, one cell from the reference: is it pushable? (push once, then check the contact)"),
    "cl_pushable-pixel_vs_unpushable_from_left-on-floor": DesignedNode(
        ("ba_pixel-touches-reference_from_left-on-floor-pushable",
         "cl_pixel-touches-reference_vs_apart_from_left-on-floor"),
        "from anywhere left, the reference any distance away: is the pixel pushable? (push, then check)"),
    # level 6
    "cl_pushable-floor-pixel_vs_unpushable": DesignedNode(
        ("cl_pushable-pixel_vs_unpushable_from_left-on-floor",
         "ba_pixel-touches-reference_from_left-on-floor-pushable",
         "cl_pixel-touches-reference_vs_apart_from_left-on-floor"),
        "the paper's top concept: is the pixel lying on the floor pushable? (with a floating distractor)"),
}
"""Dataset -> its node: the datasets whose SMCs it calls (the pushable curriculum's DAG) and a one-line summary."""
PUSHABLE_TOP = "cl_pushable-floor-pixel_vs_unpushable"


def _node_name(dataset: str) -> str:
    return dataset if not PUSHABLE[dataset].uses else f"pushable/{dataset}"


def designed_curricula() -> dict[str, Curriculum]:
    """The designed curricula as shipped (name -> curriculum): ``pushable`` (method smc-curr; its targets are every
    node above level 1, so ``sb3-smc experiment --category pushable`` compares each with cnn and base)."""
    nodes = tuple(Node(_node_name(d), d, tuple(_node_name(u) for u in node.uses)) for d, node in PUSHABLE.items())
    targets = tuple(_node_name(d) for d, node in PUSHABLE.items() if node.uses)
    description = ("smc-curr: the pushable curriculum (paper Fig. 3 / 5c), designed by sb3-smc: 11 concepts over "
                   "6 levels leading to cl_pushable-floor-pixel_vs_unpushable (docs/curricula.md)")
    return {"pushable": Curriculum(name="pushable", nodes=nodes, targets=targets, method="smc-curr",
                                   description=description, source="shipped curriculum 'pushable'")}
