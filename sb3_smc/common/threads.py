"""The thread counts of a block of work (torch's and numpy's BLAS), restored afterwards."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from functools import cache
from typing import Any

__all__ = ["blas_threads", "compute_threads"]


@cache
def _blas() -> Any:
    """The BLAS libraries loaded at the first call (numpy's among them, numpy being imported with this package),
    found once: a limit on them then costs tens of microseconds, not the hundreds of a new search."""
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


@contextmanager
def blas_threads(n: int = 1) -> Iterator[None]:
    """Run the block with ``n`` BLAS threads for numpy, the caller's count restored afterwards (cheap enough for
    every update; libraries loaded after the first call, such as scipy's, are not limited)."""
    with _blas().limit(limits=n, user_api="blas"):
        yield


@contextmanager
def compute_threads(n: int = 1) -> Iterator[None]:
    """Run the block with ``n`` torch threads and ``n`` BLAS threads for numpy (one each per process is the measured
    setting here: a worker beside others gains nothing from more, and numpy's OpenBLAS would otherwise take every
    core for the lean update's matrix products), and give the caller its own counts back afterwards, also when the
    block raises."""
    import torch
    from threadpoolctl import threadpool_limits

    before = torch.get_num_threads()
    torch.set_num_threads(n)
    try:
        with threadpool_limits(limits=n, user_api="blas"):  # every BLAS loaded by now
            yield
    finally:
        torch.set_num_threads(before)
