"""BLAS threading control for the small-matrix hot paths.

Simulation and estimation multiply many small matrices. Multi-threaded BLAS only adds
contention there (measured 20× slower with two OpenBLAS threads on two loaded cores), so these
paths run with one BLAS thread; parallelism comes from running independent work in processes.
"""

from __future__ import annotations

import scipy.linalg  # noqa: F401  (loads scipy's own BLAS, so the controller sees it)
from threadpoolctl import ThreadpoolController

_CONTROLLER = ThreadpoolController()


def single_threaded():
    """Context manager limiting every loaded BLAS library to one thread."""
    return _CONTROLLER.limit(limits=1, user_api="blas")
