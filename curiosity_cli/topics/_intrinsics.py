"""Two LLVM instructions numba does not offer: a prefetch and an atomic fetch-and-add.

- :func:`prefetch`: the sampler reads one row of the word-topic counts per word, at a
  random row of a table larger than L2; asking for the next word's row while the current
  word is sampled hides part of that miss: 0.5-1.5 % of the time per word on one thread,
  1-2 % on two, measured on the reference machine (the sampler waits more on its own
  stores than on memory). Only a hint: it never faults and changes no result.
- :func:`fetch_add`: threads refining one batch phase take chunks of cells from a shared
  counter, so a thread on a busier core simply takes fewer (which cells a thread takes
  never changes the result). On an idle machine this is as fast as dealing the chunks
  out round-robin; with one core also running another process, 10 % faster.

Neither computes anything a twin could check; the kernels using them have twins.
"""

from __future__ import annotations

from llvmlite import ir
from numba.core import cgutils, types
from numba.extending import intrinsic

# llvm.prefetch(address, rw = 0 read, locality = 3 keep in all cache levels, cache type = 1 data)
_READ, _KEEP, _DATA = 0, 3, 1


@intrinsic
def prefetch(typingctx, array, row, col):
    """Prefetch the cache line holding ``array[row, col]`` (a 2-D array, integer indices)."""
    if not (isinstance(array, types.Array) and array.ndim == 2):
        return None
    signature = types.void(array, types.intp, types.intp)

    def codegen(context, builder, sig, args):
        data, r, c = args
        r = context.cast(builder, r, sig.args[1], types.intp)
        c = context.cast(builder, c, sig.args[2], types.intp)
        view = context.make_array(sig.args[0])(context, builder, data)
        pointer = cgutils.get_item_pointer(context, builder, sig.args[0], view, [r, c])
        int32 = ir.IntType(32)
        function = cgutils.get_or_insert_function(
            builder.module, ir.FunctionType(ir.VoidType(), [pointer.type, int32, int32, int32]), "llvm.prefetch.p0"
        )
        flags = [ir.Constant(int32, flag) for flag in (_READ, _KEEP, _DATA)]
        builder.call(function, [pointer, *flags])
        return context.get_dummy_value()

    return signature, codegen


@intrinsic
def fetch_add(typingctx, array, index, value):
    """Atomically add ``value`` to ``array[index]`` (1-D int64) and return the old value."""
    if not (isinstance(array, types.Array) and array.ndim == 1 and array.dtype == types.int64):
        return None
    signature = types.int64(array, types.intp, types.int64)

    def codegen(context, builder, sig, args):
        data, i, v = args
        i = context.cast(builder, i, sig.args[1], types.intp)
        v = context.cast(builder, v, sig.args[2], types.int64)
        view = context.make_array(sig.args[0])(context, builder, data)
        pointer = cgutils.get_item_pointer(context, builder, sig.args[0], view, [i])
        return builder.atomic_rmw("add", pointer, v, "seq_cst")

    return signature, codegen
