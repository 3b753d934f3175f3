"""The thread counts of a block of work (torch's and numpy's BLAS), restored afterwards."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["compute_threads"]


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
        with threadpool_limits(limits=n, user_api="blas"):
            yield
    finally:
        torch.set_num_threads(before)
