"""The mutable world: object positions, the state array, movement and transitive pushing (spec §1.6)."""

from __future__ import annotations

import numpy as np

from pixelworld_env.constants import Color
from pixelworld_env.objects import Cell, WorldObject
from pixelworld_env.scene import Scene

EMPTY = -1
OUTSIDE = -2

MOVES: dict[str, Cell] = {"DOWN": (1, 0), "RIGHT": (0, 1), "UP": (-1, 0), "LEFT": (0, -1)}
"""Row/column offsets of the four moves (row 0 is the top)."""


class World:
    """The state of one scene during an episode.

    ``grid`` is the state array of colour codes and ``owner`` the index of the object drawn in each cell, both
    padded by one ring of outside cells (colour 0, owner ``OUTSIDE``) so that the 3 x 3 window never leaves
    the array and moves off the world are blocked. ``positions`` holds each object's current position.
    """

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        self.self_index = scene.self_index
        self.moveable = tuple(o.moveable for o in scene.objects)
        self._initial = tuple(o.position for o in scene.objects)
        self.positions: list[Cell] = list(self._initial)
        # Fast path: only the (one-pixel) self can move, so a move succeeds iff the target cell is free.
        self.self_only = scene.self_object.cells == ((0, 0),) and sum(self.moveable) == 1
        self._self_color = int(scene.self_object.color)
        shape = (scene.height + 2, scene.width + 2)
        self.grid = np.zeros(shape, dtype=np.int8)
        self.owner = np.full(shape, OUTSIDE, dtype=np.int16)
        self._n_pixels = sum(len(o.cells) for o in scene.objects)
        self._disjoint: bool = True  # set by _draw: no two objects share a cell
        self._draw()
        self._grid0, self._owner0 = self.grid.copy(), self.owner.copy()
        self._disjoint0 = self._disjoint
        self._stale = False

    @property
    def self_position(self) -> Cell:
        return self.positions[self.self_index]

    @property
    def objects(self) -> tuple[WorldObject, ...]:
        """The objects at their current positions."""
        return tuple(
            obj if obj.position == pos else obj.moved_to(pos)
            for obj, pos in zip(self.scene.objects, self.positions, strict=True)
        )

    def reset(self, stale_cell: Cell | None = None) -> None:
        """Restore the scene's initial state.

        ``stale_cell`` reproduces the AAAI-18 reset bug (spec §1.8): a red pixel owned by the self is left in
        that cell (if it is empty) until the first successful move redraws the world.
        """
        self.positions[:] = self._initial
        np.copyto(self.grid, self._grid0)
        np.copyto(self.owner, self._owner0)
        self._disjoint = self._disjoint0
        self._stale = False
        if stale_cell is not None:
            r, c = stale_cell[0] + 1, stale_cell[1] + 1
            if self.owner[r, c] == EMPTY:
                self.grid[r, c] = Color.RED
                self.owner[r, c] = self.self_index
                self._stale = True

    def set_positions(self, positions: list[Cell] | tuple[Cell, ...]) -> None:
        """Put every object at the given position and redraw (no collision checks)."""
        self.positions[:] = positions
        self._draw()

    def _pixels(self, index: int) -> list[Cell]:
        row, col = self.positions[index]
        return [(row + dr, col + dc) for dr, dc in self.scene.objects[index].cells]

    def _draw(self) -> None:
        height, width = self.scene.height, self.scene.width
        self.grid[:] = 0
        self.owner[:] = OUTSIDE
        self.owner[1 : height + 1, 1 : width + 1] = EMPTY
        for i, obj in enumerate(self.scene.objects):
            for r, c in self._pixels(i):
                self.grid[r + 1, c + 1] = obj.color
                self.owner[r + 1, c + 1] = i
        self._stale = False
        # No two objects share a cell: then a move can redraw only the objects it moves (moves keep it so).
        self._disjoint = int(np.count_nonzero(self.owner >= 0)) == self._n_pixels

    def move(self, delta: Cell) -> bool:
        """Try to move the self by ``delta``, pushing moveable objects; return whether anything moved.

        The move plan is the self plus, transitively, every object whose pixels the planned objects would
        overlap after the shift. If any object in the plan is immoveable (or a planned pixel would leave the
        world) nothing moves.
        """
        dr, dc = delta
        if self.self_only:
            me = self.self_index
            row, col = self.positions[me]
            target = self.owner[row + dr + 1, col + dc + 1]
            if target != EMPTY and target != me:
                return False
            self.positions[me] = (row + dr, col + dc)
            if self._stale:
                self._draw()
            else:
                self.grid[row + 1, col + 1] = 0
                self.owner[row + 1, col + 1] = EMPTY
                self.grid[row + dr + 1, col + dc + 1] = self._self_color
                self.owner[row + dr + 1, col + dc + 1] = me
            return True
        plan = [self.self_index]
        planned = {self.self_index}
        for index in plan:  # grows while iterating: breadth-first closure of the pushed objects
            for r, c in self._pixels(index):
                other = int(self.owner[r + dr + 1, c + dc + 1])
                if other == OUTSIDE:
                    return False
                if other == EMPTY or other in planned:
                    continue
                if not self.moveable[other]:
                    return False
                planned.add(other)
                plan.append(other)
        if self._stale or not self._disjoint:
            for index in plan:
                row, col = self.positions[index]
                self.positions[index] = (row + dr, col + dc)
            self._draw()
            return True
        # the same arrays as a full redraw: erase the moved objects, then draw them at their new positions
        for index in plan:
            for r, c in self._pixels(index):
                self.grid[r + 1, c + 1] = 0
                self.owner[r + 1, c + 1] = EMPTY
        objects = self.scene.objects
        for index in plan:
            row, col = self.positions[index]
            self.positions[index] = (row + dr, col + dc)
            color = objects[index].color
            for r, c in self._pixels(index):
                self.grid[r + 1, c + 1] = color
                self.owner[r + 1, c + 1] = index
        return True

    @property
    def stale(self) -> bool:
        """Whether the reset bug's stale red pixel (``reset(stale_cell=...)``) is still drawn."""
        return self._stale

    def place_self(self, position: Cell) -> None:
        """Record the self's position after a caller moved it in ``grid`` / ``owner`` itself, exactly as
        :meth:`move` does where only the self moves (``self_only``, no stale pixel); compiled option loops do."""
        self.positions[self.self_index] = position

    def window(self) -> np.ndarray:
        """The 3 x 3 colour codes centred on the self (cells outside the world read 0)."""
        row, col = self.positions[self.self_index]
        return self.grid[row : row + 3, col : col + 3]

    def state(self) -> np.ndarray:
        """The unpadded state array (a view)."""
        return self.grid[1:-1, 1:-1]

    def current_scene(self) -> Scene:
        """The current state as a :class:`Scene`."""
        return self.scene.with_positions(self.positions)
