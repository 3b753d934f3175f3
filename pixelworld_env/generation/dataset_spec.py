"""What determines a generated dataset besides its seed: :class:`DatasetSpec` (its concept, generators, macros,
settings, quota and world size), read from the catalog or from definition files."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from pixelworld_env.concepts import parse
from pixelworld_env.core.constants import FLOOR_HEIGHT, HEIGHT, PADDING, WIDTH
from pixelworld_env.core.kinds import KINDS, task_kind
from pixelworld_env.core.objects import check_world_size
from pixelworld_env.errors import PixelWorldError, PixelWorldTypeError
from pixelworld_env.validation import check_bool, check_count, check_int

__all__ = ["MAX_NUM_SAMPLES", "SUPPORTED_SETTINGS", "DatasetSpec"]

SUPPORTED_SETTINGS = frozenset({"allow_targets", "allow_pushable"})
"""The settings a dataset may have, each a bool (``True`` / ``False``, in YAML ``true`` / ``false``)."""
MAX_NUM_SAMPLES = 100_000
"""The most scenes of a quota (``num_samples``; the benchmark's is 50): generation draws until the quota is full, so
a larger one is refused when the spec is made."""


@dataclass(frozen=True)
class DatasetSpec:
    """Everything that determines a generated dataset (besides the seed).

    ``generators`` are ``(name, logic)`` pairs; ``macros`` is the merged concept + generator table
    used to expand both the concept and the generators. ``num_samples`` is the quota per label for
    classification (50 + 50) and the total for bring-about (50), an int in ``[1, MAX_NUM_SAMPLES]``. The world is
    ``height`` x ``width`` cells with the frame (ints, at most ``MAX_WORLD_CELLS`` cells), the floor's top row is
    ``height - floor_height``, and generated objects keep ``padding`` cells from the border (docs/design.md, "The
    constraint problem and the sampler"). ``settings`` maps names of :data:`SUPPORTED_SETTINGS` to bools. Every field
    is checked when the spec is made (a string for a number, a float for a count, ``"false"`` for ``False`` are
    errors naming the field).
    """

    name: str
    kind: str
    concept: str
    generators: tuple[tuple[str, str], ...]
    macros: Mapping[str, str] = field(default_factory=dict)
    settings: Mapping[str, Any] = field(default_factory=dict)
    num_samples: int = 50
    height: int = HEIGHT
    width: int = WIDTH
    floor_height: int = FLOOR_HEIGHT
    padding: int = PADDING

    def __post_init__(self) -> None:
        kind = {"bringabout": "bring-about", "bring_about": "bring-about"}.get(self.kind, self.kind)
        if kind not in KINDS:
            raise PixelWorldError(f"dataset {self.name!r}: kind must be one of {KINDS}, got {self.kind!r}")
        object.__setattr__(self, "kind", kind)
        generators = tuple((str(name), str(logic)) for name, logic in self.generators)
        if not generators:
            raise PixelWorldError(f"dataset {self.name!r} has no generators")
        object.__setattr__(self, "generators", generators)
        object.__setattr__(self, "macros", dict(self.macros))
        where = f"dataset {self.name!r}"
        settings = self.settings or {}
        if not isinstance(settings, Mapping):
            raise PixelWorldTypeError(f"{where}: settings must be a mapping of names to bools, got {settings!r} "
                                      f"({type(settings).__name__})")
        unknown = sorted(set(settings) - SUPPORTED_SETTINGS, key=str)
        if unknown:
            raise PixelWorldError(f"{where}: unsupported settings {unknown}; supported: {sorted(SUPPORTED_SETTINGS)}")
        object.__setattr__(self, "settings", {key: check_bool(value, f"{where}: setting {key!r}")
                                              for key, value in settings.items()})
        object.__setattr__(self, "num_samples", check_count(self.num_samples, f"{where}: num_samples", MAX_NUM_SAMPLES,
                                                            "pixelworld_env.generation.dataset_spec.MAX_NUM_SAMPLES"))
        height, width = check_world_size(self.height, self.width, where)
        object.__setattr__(self, "height", height)
        object.__setattr__(self, "width", width)
        object.__setattr__(self, "floor_height", check_int(self.floor_height, f"{where}: floor_height"))
        object.__setattr__(self, "padding", check_int(self.padding, f"{where}: padding"))
        if self.height < 3 or self.width < 3 or self.padding < 0 or not 0 < self.floor_height < self.height:
            raise PixelWorldError(f"{where}: bad world size {self.height} x {self.width} "
                                  f"(floor_height {self.floor_height}, padding {self.padding})")

    def __hash__(self) -> int:  # equal specs hash equally (the mappings are left out)
        return hash((self.name, self.kind, self.concept, self.generators, self.num_samples, self.height, self.width,
                     self.floor_height, self.padding))

    @property
    def allow_targets(self) -> bool:
        return self.settings.get("allow_targets", False)

    @property
    def allow_pushable(self) -> bool:
        return self.settings.get("allow_pushable", False)

    @property
    def size(self) -> int:
        """The number of scenes of the dataset (``2 * num_samples`` for the kinds with labels: that many of each)."""
        return 2 * self.num_samples if task_kind(self.kind).label is not None else self.num_samples

    def used_macros(self) -> dict[str, str]:
        """The macros reachable from the concept and the generators (name -> logic), sorted by name."""
        used: dict[str, str] = {}
        todo = [self.concept, *(logic for _, logic in self.generators)]
        while todo:
            expression = parse(todo.pop())
            for clause in (*expression.positives, *(c for g in expression.negations for c in g)):
                if clause.name in self.macros and clause.name not in used:
                    used[clause.name] = self.macros[clause.name]
                    todo.append(self.macros[clause.name])
        return dict(sorted(used.items()))
