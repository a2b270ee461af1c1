"""How many BLAS threads the solver uses (threadpoolctl).

The solver's products are many and small (a belief against a few hundred vectors, a chunk of beliefs
against a table), so a threaded BLAS spends more time waking and synchronising its threads than
multiplying; on a loaded machine the threads also wait for cores. One thread is faster until the products
are large. Order of precedence: the solver's ``blas_threads``; a thread count the user set in the
environment (OMP_NUM_THREADS and the like: left as it is); else :func:`automatic_threads`.
"""
from __future__ import annotations

import os
from contextlib import contextmanager, nullcontext
from typing import Iterator

from .tables import Tables

__all__ = ["BLAS_VARIABLES", "THREADED_STATES", "automatic_threads", "blas_threads", "limited_blas"]

BLAS_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS",
                  "VECLIB_MAXIMUM_THREADS")
# States from which the BLAS gets every core: on 2 cores, one thread was faster for the pen (39 and 69 states,
# up to 4x), chains of 5 to 7 parts (65 to 1,957 states, 3x to 6x) and about even at 6,872 states (complete
# graph of 6 parts); bench/README.md.
THREADED_STATES = 10_000


def automatic_threads(m: Tables) -> int:
    """The BLAS thread count for the model of ``m``: one below ``THREADED_STATES`` states, else the
    cores this process may use. Cost: O(1)."""
    if m.S < THREADED_STATES:
        return 1
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def blas_threads(m: Tables, requested: int | None = None) -> int | None:
    """The BLAS thread count to impose while solving ``m`` (None: leave the BLAS as it is): ``requested``
    if given, else None when the environment sets one (module docstring), else :func:`automatic_threads`."""
    if requested is not None:
        return requested
    if any(os.environ.get(variable) for variable in BLAS_VARIABLES):
        return None
    return automatic_threads(m)


@contextmanager
def limited_blas(threads: int | None) -> Iterator[None]:
    """Limit the BLAS libraries loaded in this process to ``threads`` threads inside the block (None: no
    change). Without threadpoolctl (FreeCAD's own Python may lack it) the BLAS is left as it is."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:
        threadpool_limits = None
    with nullcontext() if threads is None or threadpool_limits is None else \
            threadpool_limits(limits=threads, user_api="blas"):
        yield
