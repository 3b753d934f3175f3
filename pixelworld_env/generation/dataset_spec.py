"""What determines a generated dataset besides its seed: :class:`DatasetSpec` (its concept, generators, macros,
settings, quota and world size), read from the catalog or from definition files."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from pixelworld_env.concepts import parse
from pixelworld_env.core.constants import FLOOR_HEIGHT, HEIGHT, PADDING, WIDTH
from pixelworld_env.errors import PixelWorldError

__all__ = ["KINDS", "SUPPORTED_SETTINGS", "DatasetSpec"]

KINDS = ("classification", "bring-about")
SUPPORTED_SETTINGS = frozenset({"allow_targets", "allow_pushable"})


@dataclass(frozen=True)
class DatasetSpec:
    """Everything that determines a generated dataset (besides the seed).

    ``generators`` are ``(name, logic)`` pairs; ``macros`` is the merged concept + generator table
    used to expand both the concept and the generators. ``num_samples`` is the quota per label for
    classification (50 + 50) and the total for bring-about (50). The world is ``height`` x ``width``
    cells with the frame, the floor's top row is ``height - floor_height``, and generated objects keep
    ``padding`` cells from the border (docs/design.md, "The constraint problem and the sampler").
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
        object.__setattr__(self, "settings", dict(self.settings or {}))
        unknown = sorted(set(self.settings) - SUPPORTED_SETTINGS)
        if unknown:
            raise PixelWorldError(f"dataset {self.name!r}: unsupported settings {unknown}; supported: "
                                  f"{sorted(SUPPORTED_SETTINGS)}")
        if self.num_samples < 1:
            raise PixelWorldError(f"dataset {self.name!r}: num_samples must be >= 1, got {self.num_samples}")
        if self.height < 3 or self.width < 3 or self.padding < 0 or not 0 < self.floor_height < self.height:
            raise PixelWorldError(f"dataset {self.name!r}: bad world size {self.height} x {self.width} "
                                  f"(floor_height {self.floor_height}, padding {self.padding})")

    def __hash__(self) -> int:  # equal specs hash equally (the mappings are left out)
        return hash((self.name, self.kind, self.concept, self.generators, self.num_samples, self.height, self.width,
                     self.floor_height, self.padding))

    @property
    def allow_targets(self) -> bool:
        return bool(self.settings.get("allow_targets", False))

    @property
    def allow_pushable(self) -> bool:
        return bool(self.settings.get("allow_pushable", False))

    @property
    def size(self) -> int:
        """The number of scenes of the dataset (``2 * num_samples`` for classification)."""
        return 2 * self.num_samples if self.kind == "classification" else self.num_samples

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
