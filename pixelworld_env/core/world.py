"""The mutable world: object positions, the state array, movement and transitive pushing.

The rules: docs/design.md, "Movement and pushing" and "Episodes and the reset".
"""

from __future__ import annotations

import numpy as np

from pixelworld_env.core import kernels
from pixelworld_env.core.constants import EMPTY, OUTSIDE, Color
from pixelworld_env.core.objects import Cell, WorldObject
from pixelworld_env.core.scene import Scene

__all__ = ["EMPTY", "MOVES", "OUTSIDE", "World"]

_self_target_free = kernels.self_target_free.py_func
"""The self-only move's rule as Python: the same source as the compiled one, without the ~0.3 µs of a call into
compiled code (8 % of a single env's step)."""

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
        objects = scene.objects
        self.moveable = tuple(o.moveable for o in objects)
        self._initial = tuple(o.position for o in objects)
        self.positions: list[Cell] = list(self._initial)
        # Fast path: only the (one-pixel) self can move, so a move succeeds iff the target cell is free.
        self.self_only = scene.self_object.cells == ((0, 0),) and sum(self.moveable) == 1
        self._self_color = int(scene.self_object.color)
        shape = (scene.height + 2, scene.width + 2)
        self.grid = np.zeros(shape, dtype=np.int8)
        self.owner = np.full(shape, OUTSIDE, dtype=np.int16)
        # the objects as the compiled physics (pixelworld_env.core.kernels) takes them
        n, most = len(objects), max(len(o.cells) for o in objects)
        self._n_objects = n
        self._cells = np.zeros((n, most, 2), dtype=np.int64)
        for i, obj in enumerate(objects):
            self._cells[i, : len(obj.cells)] = obj.cells
        self._n_cells = np.array([len(o.cells) for o in objects], dtype=np.int64)
        self._colors = np.array([int(o.color) for o in objects], dtype=np.int8)
        self._moveable = np.array(self.moveable, dtype=np.bool_)
        self._initial_array = np.array(self._initial, dtype=np.int64).reshape(n, 2)
        self._array_positions = self._initial_array.copy()
        self._plan, self._planned = np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.bool_)
        self._disjoint = np.ones(1, dtype=np.bool_)  # no two objects share a cell: a move redraws only what it moves
        self._draw()
        self._grid0, self._owner0 = self.grid.copy(), self.owner.copy()
        self._disjoint0 = bool(self._disjoint[0])
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

        ``stale_cell`` reproduces the AAAI-18 reset bug (docs/design.md, "Episodes and the reset"): a red pixel
        owned by the self is left in that cell (if it is empty) until the first successful move redraws the world.
        """
        self.positions[:] = self._initial
        if not self.self_only:  # the array the compiled pushing reads (a self-only move needs only the list)
            np.copyto(self._array_positions, self._initial_array)
        np.copyto(self.grid, self._grid0)
        np.copyto(self.owner, self._owner0)
        self._disjoint[0] = self._disjoint0
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

    def _draw(self) -> None:
        """Redraw every object at ``positions`` (:func:`pixelworld_env.core.kernels.draw_objects`)."""
        self._array_positions[:] = self.positions
        self._disjoint[0] = kernels.draw_objects(self.grid, self.owner, self._array_positions, self._cells,
                                                 self._n_cells, self._colors, self._n_objects)
        self._stale = False

    def move(self, delta: Cell) -> bool:
        """Try to move the self by ``delta``, pushing moveable objects; return whether anything moved.

        The physics is written once, in :mod:`pixelworld_env.core.kernels`, for every path (this world, the native
        vector env, the compiled SMC calls): where only the self moves,
        :func:`~pixelworld_env.core.kernels.self_target_free` decides (its Python form here: one check costs less than
        a call into compiled code); elsewhere :func:`pixelworld_env.core.kernels.push_move` plans the move (the self
        plus, transitively, every object whose pixels the planned objects would overlap after the shift; any
        immoveable object or the world's edge in the chain blocks it all) and redraws what moved.
        """
        dr, dc = delta
        me = self.self_index
        if self.self_only:
            row, col = self.positions[me]
            if not _self_target_free(self.owner, me, row + dr, col + dc):
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
        positions = self._array_positions
        if self._stale:  # the reset bug's stale pixel: a move redraws everything, which erases it
            self._disjoint[0] = False
        if not kernels.push_move(self.grid, self.owner, positions, self._cells, self._n_cells, self._colors,
                                 self._moveable, self._n_objects, me, dr, dc, self._disjoint, 0, self._plan,
                                 self._planned):
            return False
        self._stale = False
        self.positions[:] = [(r, c) for r, c in positions.tolist()]
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
