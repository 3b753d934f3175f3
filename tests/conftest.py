"""Test session set-up: one torch thread, a dataset cache and a checkpoint key that are never the user's.

The default run generates what it needs into a temporary ``PIXELWORLD_CACHE`` (removed at the end); set
``PIXELWORLD_TEST_CACHE=DIR`` to keep and reuse a cache folder between runs (never ``~/.cache/pixelworld`` unless
named explicitly). Shared helpers live in ``tests/helpers.py``.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

import pytest

from tests.helpers import require_reference

_TEMPORARY_CACHE: str | None = None


@pytest.fixture(scope="session")
def reference() -> Path:
    return require_reference()


def pytest_configure(config: pytest.Config) -> None:
    global _TEMPORARY_CACHE
    import torch

    torch.set_num_threads(1)
    chosen = os.environ.get("PIXELWORLD_TEST_CACHE")
    if chosen:
        os.environ["PIXELWORLD_CACHE"] = chosen
    else:
        _TEMPORARY_CACHE = tempfile.mkdtemp(prefix="pixelworld-test-cache-")
        os.environ["PIXELWORLD_CACHE"] = _TEMPORARY_CACHE
    # group checkpoints are signed with a key of the session's own (sb3_smc.learning.group_checkpoint)
    os.environ["SB3_SMC_CHECKPOINT_KEY"] = str(Path(tempfile.mkdtemp(prefix="sb3-smc-test-key-")) / "checkpoint.key")


def pytest_unconfigure(config: pytest.Config) -> None:
    if _TEMPORARY_CACHE is not None:
        shutil.rmtree(_TEMPORARY_CACHE, ignore_errors=True)
