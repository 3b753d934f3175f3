"""``compute_threads``: a block of work with n torch threads and n BLAS threads for numpy, the caller's restored."""

from __future__ import annotations

import pytest
import torch
from threadpoolctl import threadpool_info

from sb3_smc.common.threads import compute_threads


def _blas_threads() -> list[int]:
    return [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]


def test_compute_threads_sets_torch_and_blas_and_restores_them() -> None:
    import numpy  # noqa: F401  (loads numpy's BLAS)

    torch_before, blas_before = torch.get_num_threads(), _blas_threads()
    assert blas_before  # numpy's BLAS is seen
    with compute_threads(1):
        assert torch.get_num_threads() == 1 and set(_blas_threads()) == {1}
    assert torch.get_num_threads() == torch_before and _blas_threads() == blas_before
    with pytest.raises(RuntimeError, match="inside"), compute_threads(1):
        raise RuntimeError("inside")
    assert torch.get_num_threads() == torch_before and _blas_threads() == blas_before


def test_blas_threads_limits_numpys_blas() -> None:
    import numpy as np

    from sb3_smc.common.threads import blas_threads

    def numpys() -> list[int]:
        return [pool["num_threads"] for pool in threadpool_info()
                if pool["user_api"] == "blas" and "numpy" in pool["filepath"]]

    before = numpys()
    assert before and np.ones((2, 2)) @ np.ones((2, 2)) is not None
    with blas_threads(1):
        assert numpys() == [1] * len(before)
    assert numpys() == before
