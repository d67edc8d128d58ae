"""The one place that configures numba (layer 0).

``njit`` compiles with the on-disk cache. ``NUMBA_DISABLE_JIT=1`` turns every kernel into plain
Python (the tests run both ways), which is why kernels avoid numba-only constructs.

Numba keys a cached function on its own source file only, but hsgran's kernels inline functions
from other modules (the collision model into the event loop). An edit to ``contact/normal.py``
would then leave a stale compiled loop behind. So the cache lives in a directory named after a
hash of all hsgran sources (and of the data tables kernels compile in as constants): any change
to the package starts a fresh cache. A user-set
``NUMBA_CACHE_DIR`` is respected as it is.
"""

import hashlib
import os
from pathlib import Path

import numba
from numba import njit as _njit

#: Compile options shared by every kernel: on-disk cache (a cold compile costs seconds), no
#: fast-math so that results are IEEE-reproducible, and no reference counting of arrays
#: (``_nrt``: numba's runtime; see :func:`njit`).
JIT_OPTIONS = {"cache": True, "nogil": True, "_nrt": False}


#: Data files whose contents kernels compile in as constants (the effects' tables,
#: hsgran.contact.compliance and hsgran.contact.viscous): part of the cache's key like sources.
COMPILED_DATA = ("data/tangential_compliance.npz", "data/derived_viscoelastic_restitution.csv")


def _source_digest() -> str:
    """Hash of every ``.py`` file of the package and of the COMPILED_DATA (names and
    contents)."""
    root = Path(__file__).parent
    h = hashlib.sha1()
    data = [root / name for name in COMPILED_DATA if (root / name).is_file()]
    for path in sorted(root.rglob("*.py")) + data:
        h.update(str(path.relative_to(root)).encode())
        h.update(path.read_bytes())
    return h.hexdigest()[:16]


def _configure_cache() -> None:
    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    numba.config.CACHE_DIR = str(base / "hsgran" / "numba" / _source_digest())


_configure_cache()


def njit(func=None, *, allocates=False, **options):
    """``numba.njit`` with hsgran's defaults (see :data:`JIT_OPTIONS`).

    Kernels are compiled without numba's reference counting of arrays. Every array a kernel
    touches belongs to a Python caller that holds it for the whole call, so the counting is
    pure cost: numba increments and decrements (atomically, out of line) the count of every
    array passed to an inlined helper, each array of a tuple argument included, and its
    pruning pass left 28 increments and 55 decrements in the compiled event loop. They took a
    third of its time (tools/profile_loop.py; the measurements are in docs/performance.md).

    The price: such a kernel cannot create arrays, nor return an array other than one of its
    arguments (a counting caller would release it once too often); numba refuses to compile
    either. A kernel that creates arrays passes ``allocates=True`` and keeps the counting.
    tests/test_jit.py checks that runs leave the reference count of every array of the engine
    as they found it and free every array the allocating kernels create.
    """
    opts = {**JIT_OPTIONS, **options}
    if allocates:
        opts["_nrt"] = True
    if func is None:
        return lambda f: _njit(**opts)(f)
    return _njit(**opts)(func)


def _prefetch_intrinsic():
    """A compiled ``prefetch(array, i)``: a hint to the CPU to load the cache line of
    ``array[i]`` (its first element if 2-D) while other work goes on (LLVM ``llvm.prefetch``,
    read, high locality). It never faults and changes no result."""
    from llvmlite import ir
    from numba import types
    from numba.core import cgutils
    from numba.extending import intrinsic

    @intrinsic
    def prefetch(typingctx, array, index):
        if not isinstance(array, types.Array) or not isinstance(index, types.Integer):
            return None

        def codegen(context, builder, signature, args):
            aryty, idxty = signature.args
            ary = context.make_array(aryty)(context, builder, args[0])
            i = context.cast(builder, args[1], idxty, types.intp)
            zero = context.get_constant(types.intp, 0)
            ptr = cgutils.get_item_pointer2(
                context, builder, ary.data, cgutils.unpack_tuple(builder, ary.shape),
                cgutils.unpack_tuple(builder, ary.strides), aryty.layout,
                [i] + [zero] * (aryty.ndim - 1), wraparound=False)
            byte_ptr = ir.IntType(8).as_pointer()
            i32 = ir.IntType(32)
            fnty = ir.FunctionType(ir.VoidType(), [byte_ptr, i32, i32, i32])
            fn = cgutils.get_or_insert_function(builder.module, fnty, "llvm.prefetch.p0")
            builder.call(fn, [builder.bitcast(ptr, byte_ptr), i32(0), i32(3), i32(1)])
            return context.get_dummy_value()

        return types.void(array, index), codegen

    return prefetch


def _prefetch_python(array, index):
    """Plain-Python stand-in of the compiled prefetch hint (NUMBA_DISABLE_JIT=1): nothing."""


#: ``prefetch(array, i)``: ask for the cache line of ``array[i]`` ahead of its use (a hint only).
prefetch = _prefetch_python if numba.config.DISABLE_JIT else _prefetch_intrinsic()
