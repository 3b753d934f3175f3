"""Dataset generation: the readers of the original definition and experiment files, ``DatasetSpec``, the seeded
constraint search of a generator (``sampling``, ``placement``; ``csp`` for verification), the planner that checks
bring-about goals (``oracle``) and ``generate`` (``dataset``). Builds on ``core`` and ``concepts``.

The names of the old module ``pixelworld_env.generation`` (now ``dataset``) still resolve here, deprecated."""

from typing import Any

from pixelworld_env._moved import moved_name


def __getattr__(name: str) -> Any:
    return moved_name(__name__, name)
