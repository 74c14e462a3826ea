"""What numba does not offer: atomic fetch-and-add, and arrays on the stack.

:func:`fetch_add`: threads refining one batch phase take chunks of cells from a shared
counter, so a thread on a busier core simply takes fewer (which cells a thread takes
never changes the result). On an idle machine this is as fast as dealing the chunks out
round-robin; with one of the two cores also running another process, 10 % faster.

:func:`stack_array`: the lock-step labelling kernels keep per-chain sums in arrays whose
length, the number of chains, is known when compiling; on the stack they live in vector
registers, where a heap array kept them in memory (30 against 60 ns a sample at 16
chains, when the two were first compared). :func:`stack_table` is its two-dimensional
kin, ``rows`` (a constant) by ``len(like)``: the lock-step sweep keeps a cell's counts
and the running sums there (all topics by all chains), so the compiler knows no other
array aliases them.

(A software prefetch of the next word's row of the word-topic counts lived here too; once
the sampler stopped waiting on its own stores it gained nothing, on one thread or two. Nor
did one in the lock-step sweep, of the next words' rows of ``phiw``, one to six words
ahead, into L1 or L2: within the noise of a shared 2-core machine.)
They compute nothing a twin could check; the kernels using them have twins.
"""

from __future__ import annotations

from numba.core import cgutils, types
from numba.extending import intrinsic


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


@intrinsic
def stack_array(typingctx, like, dtype):
    """A 1-D array of ``len(like)`` (a tuple) items of ``dtype`` on the stack, uninitialised.

    A heap array (``np.empty``) may alias every other array, so LLVM keeps its items in
    memory; a stack array of a length known when compiling is split into registers.
    """
    if not isinstance(like, types.BaseTuple) or not isinstance(dtype, (types.DType, types.NumberClass)):
        return None
    item = dtype.dtype if isinstance(dtype, types.DType) else dtype.instance_type
    n = len(like)
    array_type = types.Array(item, 1, "C")

    def codegen(context, builder, sig, args):
        from numba.np.arrayobj import populate_array

        data_type = context.get_data_type(item)
        data = cgutils.alloca_once(builder, data_type, size=n)
        array = context.make_array(array_type)(context, builder)
        size = context.get_constant(types.intp, n)
        step = context.get_constant(types.intp, context.get_abi_sizeof(data_type))
        populate_array(array, data=data, shape=[size], strides=[step], itemsize=step, meminfo=None)
        return array._getvalue()

    return array_type(like, dtype), codegen


#: Bytes to which :func:`stack_table` aligns its rows' start (a cache line: a row of 16
#: float32 chains is then one line, and a 256-bit load never straddles two).
TABLE_ALIGN = 64


@intrinsic
def stack_table(typingctx, rows, like, dtype):
    """A C-contiguous (``rows``, ``len(like)``) array of ``dtype`` on the stack, uninitialised.

    ``rows`` must be an integer constant (a global or literal), ``like`` a tuple (its
    length known when compiling), as in :func:`stack_array`; the data start on a
    :data:`TABLE_ALIGN`-byte boundary.
    """
    if not (isinstance(rows, types.IntegerLiteral) and isinstance(like, types.BaseTuple)):
        return None
    if not isinstance(dtype, (types.DType, types.NumberClass)):
        return None
    item = dtype.dtype if isinstance(dtype, types.DType) else dtype.instance_type
    n_rows, n_cols = rows.literal_value, len(like)
    array_type = types.Array(item, 2, "C")

    def codegen(context, builder, sig, args):
        from numba.np.arrayobj import populate_array

        data_type = context.get_data_type(item)
        data = cgutils.alloca_once(builder, data_type, size=n_rows * n_cols)
        data.align = TABLE_ALIGN
        array = context.make_array(array_type)(context, builder)
        itemsize = context.get_abi_sizeof(data_type)
        size = context.get_constant
        populate_array(
            array, data=data, shape=[size(types.intp, n_rows), size(types.intp, n_cols)],
            strides=[size(types.intp, n_cols * itemsize), size(types.intp, itemsize)],
            itemsize=size(types.intp, itemsize), meminfo=None,
        )
        return array._getvalue()

    return array_type(rows, like, dtype), codegen
