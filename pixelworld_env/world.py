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
    the array and moves off the world are blocked.
    """

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        self.objects: list[WorldObject] = list(scene.objects)
        self.self_index = scene.self_index
        self.moveable = np.array([o.moveable for o in scene.objects], dtype=bool)
        me = scene.self_object
        # Fast path: only the (one-pixel) self can move, so a move succeeds iff the target cell is free.
        self.self_only = me.cells == ((0, 0),) and int(self.moveable.sum()) == 1
        self.grid = np.zeros((scene.height + 2, scene.width + 2), dtype=np.int8)
        self.owner = np.full((scene.height + 2, scene.width + 2), OUTSIDE, dtype=np.int16)
        self.reset()

    @property
    def self_position(self) -> Cell:
        return self.objects[self.self_index].position

    def reset(self, stale_cell: Cell | None = None) -> None:
        """Restore the scene's initial state.

        ``stale_cell`` reproduces the AAAI-18 reset bug (spec §1.8): a red pixel owned by the self is left in
        that cell (if it is empty) until the first successful move redraws the world.
        """
        self.objects = list(self.scene.objects)
        self._redraw()
        if stale_cell is not None:
            r, c = stale_cell[0] + 1, stale_cell[1] + 1
            if self.owner[r, c] == EMPTY:
                self.grid[r, c] = Color.RED
                self.owner[r, c] = self.self_index
        self._stale = stale_cell is not None

    def _redraw(self) -> None:
        height, width = self.scene.height, self.scene.width
        self.grid[:] = 0
        self.owner[:] = OUTSIDE
        self.owner[1 : height + 1, 1 : width + 1] = EMPTY
        for i, obj in enumerate(self.objects):
            for r, c in obj.pixels:
                if 0 <= r < height and 0 <= c < width:
                    self.grid[r + 1, c + 1] = obj.color
                    self.owner[r + 1, c + 1] = i
        self._stale = False

    def move(self, delta: Cell) -> bool:
        """Try to move the self by ``delta``, pushing moveable objects; return whether anything moved.

        The move plan is the self plus, transitively, every object whose pixels the planned objects would
        overlap after the shift. If any object in the plan is immoveable (or a planned pixel would leave the
        world) nothing moves.
        """
        dr, dc = delta
        if self.self_only:
            row, col = self.objects[self.self_index].position
            target = self.owner[row + dr + 1, col + dc + 1]
            if target != EMPTY and target != self.self_index:
                return False
            if self._stale:
                self._redraw_self_only((row + dr, col + dc))
            else:
                self.grid[row + 1, col + 1] = 0
                self.owner[row + 1, col + 1] = EMPTY
                self.grid[row + dr + 1, col + dc + 1] = self.objects[self.self_index].color
                self.owner[row + dr + 1, col + dc + 1] = self.self_index
                self.objects[self.self_index] = self.objects[self.self_index].moved_to((row + dr, col + dc))
            return True
        plan = [self.self_index]
        planned = {self.self_index}
        for index in plan:  # grows while iterating: breadth-first closure of the pushed objects
            for r, c in self.objects[index].pixels:
                other = int(self.owner[r + dr + 1, c + dc + 1])
                if other == OUTSIDE:
                    return False
                if other == EMPTY or other in planned:
                    continue
                if not self.moveable[other]:
                    return False
                planned.add(other)
                plan.append(other)
        for index in plan:
            row, col = self.objects[index].position
            self.objects[index] = self.objects[index].moved_to((row + dr, col + dc))
        self._redraw()
        return True

    def _redraw_self_only(self, position: Cell) -> None:
        self.objects[self.self_index] = self.objects[self.self_index].moved_to(position)
        self._redraw()

    def window(self) -> np.ndarray:
        """The 3 x 3 colour codes centred on the self (cells outside the world read 0)."""
        row, col = self.objects[self.self_index].position
        return self.grid[row : row + 3, col : col + 3]

    def state(self) -> np.ndarray:
        """The unpadded state array (a view)."""
        return self.grid[1:-1, 1:-1]

    def current_scene(self) -> Scene:
        """The current state as a :class:`Scene`."""
        return self.scene.with_positions([o.position for o in self.objects])
