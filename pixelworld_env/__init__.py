"""PixelWorld: 2-D pixel worlds generated from a concept language, served as Gymnasium environments."""

from importlib import metadata as _metadata

try:
    __version__ = _metadata.version("sb3-smc")
    """The installed distribution's version (pyproject.toml's), shared by ``pixelworld_env`` and ``sb3_smc``."""
except _metadata.PackageNotFoundError:  # a checkout on sys.path, not installed
    __version__ = "unknown"


from pixelworld_env.concepts import (
    ArityError,
    Concept,
    ConceptError,
    ConceptSyntaxError,
    NegatedMacroError,
    UndeclaredVariableError,
    UnknownPredicateError,
    holds,
    parse,
)
from pixelworld_env.core.constants import HEIGHT, WIDTH, Color, ObjectClass
from pixelworld_env.core.objects import WorldObject
from pixelworld_env.core.scene import Scene
from pixelworld_env.datasets.loading import Dataset, load_dataset
from pixelworld_env.envs.env import PixelWorldEnv
from pixelworld_env.envs.registration import make_env, register_envs, register_worlds
from pixelworld_env.errors import PixelWorldError

register_envs()

__all__ = [
    "__version__",
    "HEIGHT",
    "WIDTH",
    "ArityError",
    "Color",
    "Concept",
    "ConceptError",
    "ConceptSyntaxError",
    "Dataset",
    "NegatedMacroError",
    "ObjectClass",
    "PixelWorldEnv",
    "PixelWorldError",
    "Scene",
    "UndeclaredVariableError",
    "UnknownPredicateError",
    "WorldObject",
    "holds",
    "load_dataset",
    "make_env",
    "parse",
    "register_worlds",
]
