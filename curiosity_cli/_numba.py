"""The one place that sets numba flags: every kernel module decorates with :func:`njit`.

Importing this module imports numba, so only kernel modules import it, and they are
imported inside the public functions that need them (``curiosity --help`` stays instant).
"""

from __future__ import annotations

import numba

# cache: compile once per machine, not once per process (the CLI runs many short processes).
# nogil: kernels may run in threads. error_model="numpy": no ZeroDivisionError checks in loops.
_FLAGS = dict(cache=True, nogil=True, error_model="numpy")


def njit(*args, **overrides):
    """``numba.njit`` with the project's flags; use as ``@njit`` or ``@njit(parallel=True)``."""
    if args and callable(args[0]):
        return numba.njit(**_FLAGS)(args[0])
    return numba.njit(*args, **{**_FLAGS, **overrides})
