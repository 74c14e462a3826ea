"""The one place that sets numba flags: every kernel module decorates with :func:`njit`.

Importing this module imports numba, so only kernel modules import it, and they are
imported inside the public functions that need them (``curiosity --help`` stays instant).

Compiled kernels are cached on disk (the CLI runs many short processes). Numba checks a
cached kernel against its own source file only, not against the kernels it calls in other
files, so after an edit or an update it could run stale machine code. The cache therefore
lives in a folder named by a hash of every kernel source (the package's private
``_*.py`` modules): any change to them starts a fresh cache. ``NUMBA_CACHE_DIR`` set by
the user wins.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

from curiosity_cli.paths import user_cache

_PACKAGE = Path(__file__).resolve().parent


def kernel_sources_hash(package: Path = _PACKAGE) -> str:
    """A hash of every private module (``_*.py``, not dunder files) below ``package``."""
    digest = hashlib.sha256()
    for path in sorted(package.rglob("_*.py")):
        if not path.name.startswith("__"):
            digest.update(path.relative_to(package).as_posix().encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()[:16]


def cache_dir() -> Path:
    """Where this version of the kernels is cached: ``numba-<hash>`` in the user cache (:func:`curiosity_cli.paths.user_cache`)."""
    return user_cache() / f"numba-{kernel_sources_hash()}"


if "NUMBA_CACHE_DIR" not in os.environ:
    os.environ["NUMBA_CACHE_DIR"] = str(cache_dir())
# LLVM's SLP vectoriser, which numba turns off by default: the lock-step labelling kernels
# (_chain_kernels.py) step over many chains at once and only become vector code with it.
# It left the single-chain sampler's speed unchanged (docs/PERFORMANCE.md).
os.environ.setdefault("NUMBA_SLP_VECTORIZE", "1")
# numba-cuda warns of a launch too small to fill the GPU: a colour of a small map is one,
# by design, and labelling shows library warnings to the user
os.environ.setdefault("NUMBA_CUDA_LOW_OCCUPANCY_WARNINGS", "0")

import numba  # noqa: E402  (after the cache folder is chosen)
import numba.core.config  # noqa: E402

# numba reads its settings when first imported, which may have happened before this module
numba.core.config.reload_config()

# cache: compile once per machine, not once per process (the CLI runs many short processes).
# nogil: kernels may run in threads. error_model="numpy": no ZeroDivisionError checks in loops.
_FLAGS = dict(cache=True, nogil=True, error_model="numpy")


def njit(*args, **overrides):
    """``numba.njit`` with the project's flags; use as ``@njit`` or ``@njit(parallel=True)``."""
    if args and callable(args[0]):
        return numba.njit(**_FLAGS)(args[0])
    return numba.njit(*args, **{**_FLAGS, **overrides})


def import_cuda():
    """``numba.cuda`` (numba-cuda, the optional extra ``curiosity-cli[cuda]``), importable with numpy 2.5.

    numba-cuda up to at least 0.30 registers an implementation of ``np.row_stack``, which
    numpy 2.5 removed, and so fails to import there (``docs/PERFORMANCE.md``);
    ``np.row_stack`` is ``np.vstack`` under its old name, given back for the import.

    Raises
    ------
    ImportError
        numba-cuda is not installed (numba's own deprecated CUDA target, which numba
        still ships, is not used: it is not what the kernels were checked with).
    """
    import importlib.util

    import numpy as np

    if importlib.util.find_spec("numba_cuda") is None:
        raise ImportError("numba-cuda is not installed")
    if not hasattr(np, "row_stack"):
        np.row_stack = np.vstack
    from numba import cuda

    if getattr(cuda, "implementation", None) != "NVIDIA":
        raise ImportError(f"numba.cuda is numba's {getattr(cuda, 'implementation', 'built-in')} target, not numba-cuda")
    return cuda
