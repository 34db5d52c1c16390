"""The compiled kernels' switch: numba's ``njit`` (cached on disk), or plain Python; and the
BLAS threads of a computation (:func:`blas_threads`).

Where numba cannot be imported, or with the environment variable ``GEAROPT_JIT=0``,
:data:`ENABLED` is False and :func:`compiled` hands functions back as they are: the same
kernels run as plain Python (slow: for checks, not for studies).
"""

from __future__ import annotations

import functools
import os

from threadpoolctl import ThreadpoolController

try:  # pragma: no cover - depends on the installed extras
    import numba
except ImportError:  # pragma: no cover
    numba = None

__all__ = ["ENABLED", "blas_threads", "compiled", "compiled_here"]

ENABLED = numba is not None and os.environ.get("GEAROPT_JIT", "1") != "0"

#: every kernel :func:`compiled` made in this process (what :func:`compiled_here` counts)
_KERNELS = []


def compiled(func=None, *, inline=False):
    """``func`` compiled (cached on disk) when the kernels are enabled, else as it is;
    ``inline``: inlined into its callers (point evaluations that take tuples of tables, where
    a call boundary would cost more than the evaluation)."""
    if func is None:
        return lambda f: compiled(f, inline=inline)
    if not ENABLED:
        return func
    options = {"inline": "always"} if inline else {}
    kernel = numba.njit(cache=True, nogil=True, error_model="numpy", **options)(func)
    _KERNELS.append(kernel)
    return kernel


def compiled_here() -> int:
    """How many kernel signatures this process compiled rather than loaded from numba's disk
    cache (numba's ``Dispatcher.stats``): nonzero after a first use, after an install or a
    change of a kernel's source; 0 without the kernels."""
    return sum(len(kernel.stats.cache_misses) for kernel in _KERNELS)


@functools.cache
def _controller() -> ThreadpoolController:
    return ThreadpoolController()


def blas_threads(limit: int):
    """A context limiting the BLAS libraries to ``limit`` threads (threadpoolctl's controller,
    made once: the libraries are scanned at the first call, not at every one)."""
    return _controller().limit(limits=limit, user_api="blas")
