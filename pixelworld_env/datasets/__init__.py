"""The benchmark's datasets: the catalog of the release (``catalog``, over ``pixelworld_env/data/catalog.json``),
the disk cache of generated datasets (``cache``) and ``load_dataset`` (``loading``). Builds on ``generation``.

The names of the old module ``pixelworld_env.datasets`` (now ``cache``) still resolve here, deprecated."""

from typing import Any

from pixelworld_env._moved import moved_name


def __getattr__(name: str) -> Any:
    return moved_name(__name__, name)
