"""The one place that configures numba (layer 0).

``njit`` compiles with the on-disk cache. ``NUMBA_DISABLE_JIT=1`` turns every kernel into plain
Python (the tests run both ways), which is why kernels avoid numba-only constructs.

Numba keys a cached function on its own source file only, but hsgran's kernels inline functions
from other modules (the collision model into the event loop). An edit to ``contact/normal.py``
would then leave a stale compiled loop behind. So the cache lives in a directory named after a
hash of all hsgran sources: any change to the package starts a fresh cache. A user-set
``NUMBA_CACHE_DIR`` is respected as it is.
"""

import hashlib
import os
from pathlib import Path

import numba
from numba import njit as _njit

#: Compile options shared by every kernel: on-disk cache (a cold compile costs seconds), and
#: no fast-math so that results are IEEE-reproducible.
JIT_OPTIONS = {"cache": True, "nogil": True}


def _source_digest() -> str:
    """Hash of every ``.py`` file of the package (names and contents)."""
    root = Path(__file__).parent
    h = hashlib.sha1()
    for path in sorted(root.rglob("*.py")):
        h.update(str(path.relative_to(root)).encode())
        h.update(path.read_bytes())
    return h.hexdigest()[:16]


def _configure_cache() -> None:
    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    numba.config.CACHE_DIR = str(base / "hsgran" / "numba" / _source_digest())


_configure_cache()


def njit(func=None, **options):
    """``numba.njit`` with hsgran's defaults (see :data:`JIT_OPTIONS`)."""
    opts = {**JIT_OPTIONS, **options}
    if func is None:
        return lambda f: _njit(**opts)(f)
    return _njit(**opts)(func)
