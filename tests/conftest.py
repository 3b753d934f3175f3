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


# Hypothesis profiles (tests/test_fuzz.py and any other property test), chosen by HYPOTHESIS_PROFILE: "default" (the
# normal run: 100 examples a test, derandomized so that every run tests the same ones, nothing stored) or "nightly"
# (2000 examples, new ones each run, no deadline; failures kept in .hypothesis/, which Hypothesis git-ignores, and
# replayed first next time). A failure prints its @reproduce_failure blob either way.
try:
    from hypothesis import HealthCheck, settings
except ImportError:  # hypothesis is a test extra: without it the property tests fail to import, nothing else
    pass
else:
    settings.register_profile("default", max_examples=100, deadline=5000, derandomize=True, database=None,
                              print_blob=True, suppress_health_check=[HealthCheck.too_slow])
    settings.register_profile("nightly", max_examples=2000, deadline=None, derandomize=False, print_blob=True,
                              suppress_health_check=[HealthCheck.too_slow])
    settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "default"))
