"""One thread for the numerical libraries (OpenBLAS, OpenMP, MKL) of a process or its children: their linear algebra
here is small (solves of a few unknowns, QR of N x 6), where more threads only wait, spinning, and several processes
with several threads each oversubscribe the cores. A count the user set is kept."""
from __future__ import annotations

import contextlib
import os

#: the variables the numerical libraries read their thread count from when they load
BLAS_THREAD_VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


@contextlib.contextmanager
def one_thread_environment():
    """Each of :data:`BLAS_THREAD_VARS` the user did not set is 1 inside the block (for the libraries loaded there,
    and the processes started there); the environment is as it was after. Yields whether the user set any."""
    saved = {v: os.environ.get(v) for v in BLAS_THREAD_VARS}
    for var in BLAS_THREAD_VARS:
        os.environ.setdefault(var, "1")
    try:
        yield any(v is not None for v in saved.values())
    finally:
        for var, value in saved.items():
            if value is None:
                os.environ.pop(var, None)
            else:
                os.environ[var] = value
