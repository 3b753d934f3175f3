"""Rendering of PixelWorld states as RGB images, and the window of ``render_mode="human"`` (docs/design.md,
"Rendering")."""

from __future__ import annotations

import os
import sys
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.error import DependencyNotInstalled

from pixelworld_env.core.constants import Color

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


HUMAN_CELL_SIZE = 20
"""Pixels per cell in the ``render_mode="human"`` window (700 x 360 for the catalog's 18 x 35 grid)."""
HEADLESS_DRIVERS = ("offscreen", "dummy")
"""SDL video drivers that draw without showing anything: what SDL falls back to on a machine without a display."""


def _no_display() -> bool:
    """Linux without a display variable and without a chosen SDL video driver."""
    return (sys.platform.startswith("linux") and not os.environ.get("SDL_VIDEODRIVER")
            and not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"))


def init_display() -> None:
    """``pygame.display.init()``; where :func:`_no_display`, with the driver SDL would fall back to (``offscreen``)
    chosen for this call only, so that SDL does not probe Wayland and X11 first (which prints "XDG_RUNTIME_DIR is
    invalid or not set" to stderr)."""
    import pygame

    headless = _no_display()
    if headless:
        os.environ["SDL_VIDEODRIVER"] = "offscreen"
    try:
        pygame.display.init()
    finally:
        if headless:
            del os.environ["SDL_VIDEODRIVER"]


def check_display() -> None:
    """Check that ``render_mode="human"`` can draw here, and warn where its window cannot be seen.

    ``DependencyNotInstalled`` without pygame (the ``render`` extra); ``RuntimeError`` where pygame has no video
    driver at all (one chosen with ``SDL_VIDEODRIVER`` that cannot start). On a machine without a display SDL falls
    back to an invisible driver (``offscreen``): the frames are drawn and nothing is shown, with a warning, so that
    headless tests and Gymnasium's ``check_env`` (which builds every mode of ``metadata["render_modes"]``) pass, as
    they do for Gymnasium's and Minigrid's environments. ``SDL_VIDEODRIVER=dummy`` (or ``offscreen``) chooses that
    on purpose, without the warning.
    """
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
    try:
        import pygame
    except ImportError:
        raise DependencyNotInstalled('render_mode="human" draws in a pygame window, and pygame is not installed: '
                                     'pip install "sb3-smc[render]" (or use render_mode="rgb_array")') from None
    displays = f"DISPLAY={os.environ.get('DISPLAY')!r}, WAYLAND_DISPLAY={os.environ.get('WAYLAND_DISPLAY')!r}"
    chosen = os.environ.get("SDL_VIDEODRIVER", "")
    try:
        init_display()
    except pygame.error as error:
        raise RuntimeError(f'render_mode="human" draws in a pygame window, and pygame has no video driver here '
                           f"({error}; SDL_VIDEODRIVER={os.environ.get('SDL_VIDEODRIVER')!r}, {displays}): "
                           "run it where a screen is attached (or forwarded), set SDL_VIDEODRIVER=dummy to draw "
                           'without one, or use render_mode="rgb_array"') from None
    driver = pygame.display.get_driver()
    if driver in HEADLESS_DRIVERS and driver not in chosen:
        gym.logger.warn(f'render_mode="human": pygame finds no display here (video driver: {driver}; {displays}), '
                        "so the window is drawn off screen and nothing is shown; set SDL_VIDEODRIVER=dummy to do "
                        'that without this warning, or use render_mode="rgb_array"')


class Window:
    """The window of ``render_mode="human"``: a pygame display showing each frame at up to ``fps`` frames per
    second, opened at the first frame (call :func:`check_display` first)."""

    def __init__(self, title: str, fps: int) -> None:
        self.title = title
        self.fps = fps
        self._screen: Any = None
        self._clock: Any = None

    def show(self, frame: np.ndarray) -> None:
        """Draw ``frame`` (``(height, width, 3)`` uint8) in the window."""
        import pygame

        if self._screen is None:
            init_display()
            self._screen = pygame.display.set_mode((frame.shape[1], frame.shape[0]))
            pygame.display.set_caption(self.title)
            self._clock = pygame.time.Clock()
        pygame.surfarray.blit_array(self._screen, frame.swapaxes(0, 1))
        pygame.event.pump()
        pygame.display.flip()
        self._clock.tick(self.fps)

    def close(self) -> None:
        """Close the window (the next frame opens a new one)."""
        if self._screen is not None:
            import pygame

            pygame.display.quit()
            self._screen = self._clock = None
