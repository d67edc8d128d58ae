"""The one place that configures numba (layer 0).

``njit`` compiles with the on-disk cache. ``NUMBA_DISABLE_JIT=1`` turns every kernel into plain
Python (the tests run both ways), which is why kernels avoid numba-only constructs.
"""

from numba import njit as _njit

#: Compile options shared by every kernel: on-disk cache (a cold compile costs seconds), and
#: no fast-math so that results are IEEE-reproducible.
JIT_OPTIONS = {"cache": True, "nogil": True}


def njit(func=None, **options):
    """``numba.njit`` with hsgran's defaults (see :data:`JIT_OPTIONS`)."""
    opts = {**JIT_OPTIONS, **options}
    if func is None:
        return lambda f: _njit(**opts)(f)
    return _njit(**opts)(func)
