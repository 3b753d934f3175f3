"""Shared fixtures: the reference data beside the checkout (``../shared/reference``)."""

from __future__ import annotations

import gzip
import json
import os
from pathlib import Path

import pytest

REFERENCE = Path(os.environ.get("PIXELWORLD_REFERENCE",
                                Path(__file__).resolve().parents[2] / "shared" / "reference"))
SAMPLES = REFERENCE / "aaai18_samples"


def require_reference() -> Path:
    """The reference folder, or a loud failure (never a silent skip) when it is missing."""
    if not (SAMPLES / "index.json").is_file():
        pytest.fail(
            f"reference data not found at {REFERENCE}: these tests need ../shared/reference beside the "
            "checkout (or PIXELWORLD_REFERENCE pointing at it)",
            pytrace=False,
        )
    return REFERENCE


def sample_files() -> list[Path]:
    """Every decoded dataset file (empty when the reference is missing; the tests then fail loudly)."""
    return sorted(SAMPLES.glob("*.jsonl.gz")) if SAMPLES.is_dir() else []


def read_samples(path: Path) -> tuple[dict, list[dict]]:
    """The header and the sample records of one decoded dataset file."""
    with gzip.open(path, "rt", encoding="utf-8") as handle:
        header = json.loads(handle.readline())
        return header, [json.loads(line) for line in handle]


@pytest.fixture(scope="session")
def reference() -> Path:
    return require_reference()


def pytest_configure(config: pytest.Config) -> None:
    import torch

    torch.set_num_threads(1)
