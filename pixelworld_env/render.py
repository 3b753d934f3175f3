"""Rendering of PixelWorld states as RGB images (spec §1.9)."""

from __future__ import annotations

import numpy as np

from pixelworld_env.constants import Color

PALETTE = np.zeros((len(Color), 3), dtype=np.uint8)
PALETTE[Color.EMPTY] = (0, 0, 0)
PALETTE[Color.WHITE] = (235, 235, 235)
PALETTE[Color.RED] = (220, 30, 30)
PALETTE[Color.BLUE] = (40, 90, 230)
PALETTE[Color.GREEN] = (40, 180, 60)
PALETTE[Color.YELLOW] = (240, 210, 40)
PALETTE[Color.MAGENTA] = (200, 50, 200)
PALETTE[Color.PURPLE] = (90, 60, 160)  # the frame: distinct from the blue floor
PALETTE[Color.ORANGE] = (245, 140, 30)


WINDOW_OUTLINE = (255, 230, 0)


def rgb_image(state: np.ndarray, cell_size: int = 10, window: tuple[int, int] | None = None) -> np.ndarray:
    """An ``(H * cell_size, W * cell_size, 3)`` uint8 image of a colour-code array.

    ``window`` (the self's cell) outlines the 3 x 3 window the agent observes.
    """
    image = PALETTE[state.astype(np.intp)]
    image = np.repeat(np.repeat(image, cell_size, axis=0), cell_size, axis=1)
    if window is not None:
        height, width = image.shape[:2]
        top, left = max((window[0] - 1) * cell_size, 0), max((window[1] - 1) * cell_size, 0)
        bottom, right = min((window[0] + 2) * cell_size, height) - 1, min((window[1] + 2) * cell_size, width) - 1
        image[top, left : right + 1] = WINDOW_OUTLINE
        image[bottom, left : right + 1] = WINDOW_OUTLINE
        image[top : bottom + 1, left] = WINDOW_OUTLINE
        image[top : bottom + 1, right] = WINDOW_OUTLINE
    return image
