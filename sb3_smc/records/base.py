"""The base of the typed records: the round trip through dicts and JSON, and the checks of their fields (each
error names the field). Torch-free, like every module of :mod:`sb3_smc.records`."""

from __future__ import annotations

import dataclasses
import json
import math
import platform
from collections.abc import Mapping, Sequence
from importlib import metadata as importlib_metadata
from typing import Any, ClassVar, TypeVar

from pixelworld_env.validation import as_integer
from sb3_smc.core.hyperparameters import encode_value
from sb3_smc.errors import SMCError

__all__ = ["Record", "RecordError", "package_versions"]

R = TypeVar("R", bound="Record")


class RecordError(SMCError):
    """A record's field is missing, unknown, or of the wrong type or value (the message names it)."""


def package_versions() -> dict[str, str]:
    """Versions of the packages that decide a training result (and of Python)."""

    def version(dist: str) -> str:
        try:
            return importlib_metadata.version(dist)
        except importlib_metadata.PackageNotFoundError:
            return "unknown"

    return {"sb3_smc": version("sb3-smc"), "stable_baselines3": version("stable-baselines3"),
            "sb3_contrib": version("sb3-contrib"), "torch": version("torch"), "gymnasium": version("gymnasium"),
            "numpy": version("numpy"), "python": platform.python_version()}


# ---------------------------------------------------------------------------------------------------------------
# Field checks
# ---------------------------------------------------------------------------------------------------------------

def int_field(value: Any, where: str, minimum: int | None = None, maximum: int | None = None) -> int:
    number = as_integer(value)  # the package's one integer rule (bools and floats are not integers)
    if number is None:
        raise RecordError(f"{where} must be an integer, got {value!r}")
    if minimum is not None and number < minimum:
        raise RecordError(f"{where} must be >= {minimum}, got {number}")
    if maximum is not None and number > maximum:
        raise RecordError(f"{where} must be at most {maximum:,}, got {number:,}")
    return number


def float_field(value: Any, where: str, allow_nan: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) and not (
            type(value).__module__ == "numpy" and hasattr(value, "dtype") and value.dtype.kind in "iuf"):
        raise RecordError(f"{where} must be a number, got {value!r}")
    value = float(value)
    if math.isnan(value) and not allow_nan or math.isinf(value):
        raise RecordError(f"{where} must be a finite number, got {value}")
    return value


def bool_field(value: Any, where: str) -> bool:
    if not isinstance(value, bool):
        raise RecordError(f"{where} must be true or false, got {value!r}")
    return value


def str_field(value: Any, where: str, choices: Sequence[str] | None = None) -> str:
    if not isinstance(value, str) or not value:
        raise RecordError(f"{where} must be a non-empty string, got {value!r}")
    if choices is not None and value not in choices:
        raise RecordError(f"{where} must be one of {tuple(choices)}, got {value!r}")
    return value


def names_field(value: Any, where: str) -> tuple[str, ...]:
    if isinstance(value, str) or not isinstance(value, Sequence):
        raise RecordError(f"{where} must be a list of names, got {value!r}")
    return tuple(str_field(v, f"{where}[{i}]") for i, v in enumerate(value))


def mapping_field(value: Any, where: str) -> dict[str, Any]:
    if not isinstance(value, Mapping):
        raise RecordError(f"{where} must be a mapping, got {value!r}")
    try:
        return {str(k): encode_value(v, f"{where}.{k}") for k, v in value.items()}
    except ValueError as err:
        raise RecordError(str(err)) from None


def set_field(obj: Any, name: str, value: Any) -> None:
    object.__setattr__(obj, name, value)


def nan_to_none(values: Sequence[float]) -> list[float | None]:
    return [None if math.isnan(v) else v for v in values]


def none_to_nan(values: Any, where: str) -> tuple[float, ...]:
    if isinstance(values, str) or not isinstance(values, Sequence):
        raise RecordError(f"{where} must be a list of numbers, got {values!r}")
    return tuple(math.nan if v is None else float_field(v, f"{where}[{i}]", allow_nan=True)
                 for i, v in enumerate(values))


# ---------------------------------------------------------------------------------------------------------------
# Base: dict / JSON round trip
# ---------------------------------------------------------------------------------------------------------------

class Record:
    """``to_dict`` / ``from_dict`` / JSON for the frozen dataclasses below (nested records by field type)."""

    _nested: ClassVar[dict[str, type[Record]]] = {}

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):  # type: ignore[arg-type]
            value = getattr(self, f.name)
            if isinstance(value, Record):
                value = value.to_dict()
            elif isinstance(value, tuple):
                value = list(value)
            elif isinstance(value, dict):
                value = json.loads(json.dumps(value))
            out[f.name] = value
        return out

    @classmethod
    def from_dict(cls: type[R], data: Any, where: str | None = None) -> R:
        where = where or cls.__name__
        if not isinstance(data, Mapping):
            raise RecordError(f"{where}: expected a mapping, got {type(data).__name__}")
        fields = {f.name: f for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
        unknown = sorted(set(data) - set(fields))
        if unknown:
            raise RecordError(f"{where}: unknown field(s) {unknown} (expected {sorted(fields)})")
        required = [n for n, f in fields.items()
                    if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING]
        missing = [n for n in required if n not in data]
        if missing:
            raise RecordError(f"{where}: missing field(s) {missing}")
        kwargs = {}
        for name, value in data.items():
            nested = cls._nested.get(name)
            kwargs[name] = nested.from_dict(value, f"{where}.{name}") if nested is not None else value
        try:
            return cls(**kwargs)
        except RecordError as err:
            raise RecordError(f"{where}: {err}") from None

    def __eq__(self, other: object) -> bool:
        # by JSON form: NaN returns (null in JSON) compare equal, which field-wise float comparison would not
        if type(other) is not type(self):
            return NotImplemented
        return self.to_dict() == other.to_dict()  # type: ignore[attr-defined]

    __hash__ = None  # type: ignore[assignment]  # records hold dicts

    def to_json(self, **kwargs: Any) -> str:
        return json.dumps(self.to_dict(), allow_nan=False, **kwargs)

    @classmethod
    def from_json(cls: type[R], text: str, where: str | None = None) -> R:
        try:
            data = json.loads(text)
        except json.JSONDecodeError as err:
            raise RecordError(f"{where or cls.__name__}: not valid JSON: {err}") from None
        return cls.from_dict(data, where)


