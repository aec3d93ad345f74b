"""A cache-line prefetch hint for numba kernels (LLVM's ``llvm.prefetch``), for gathers whose addresses are known ahead.

``prefetch_read(a, i)`` asks the CPU to bring the line of ``a[i]`` (a 1-D array, ``i`` any integer in range) into
every cache level; it changes no value and never faults, so a kernel's outputs stay bit for bit those without it.
Used by ``T_align``'s kernels (:mod:`evpose.fusion.aligned_surface_kernels`; figures in
:mod:`evpose.fusion.aligned_surface`): the selecting passes read the SP-TS's three last-timestamp maps (0.7 MB each
at 346x260) at ~13,000 patch pixels per update in patch order, the event pass the grid at each event's pixel in time
order, the marking the rows of each point's patch. Not kept there: ``_scatter_tdf``
(:mod:`evpose.fusion.aligned_field`) prefetching its TDF scratch for writing, 0.058-0.073 -> 0.070-0.077 ms per
update in a run (three alternated pairs, ``stpe+filter`` 346x260 seed 0); registration's linearisation
(:func:`~evpose.tracker.registration_kernels._linearise`) prefetching the field's rows at the projection of the point
8 on (one more projection per point), 0.294-0.295 -> 0.311-0.314 ms per update in a run (``full`` 346x260 seed 0,
three alternated pairs): the field is already in cache after the first of its ~3.5 linearisations.
"""

from __future__ import annotations

import llvmlite.binding as llvm_binding
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

_NAME = "llvm.prefetch.p0" if llvm_binding.llvm_version_info >= (15,) else "llvm.prefetch.p0i8"
"""The intrinsic's name: LLVM 15 and later mangle it for opaque pointers."""


def _prefetch_codegen(write: int):
    def codegen(context, builder, signature, args):
        aryty, indty = signature.args
        ary = context.make_array(aryty)(context, builder, args[0])
        ind = context.cast(builder, args[1], indty, types.intp)
        ptr = cgutils.get_item_pointer(context, builder, aryty, ary, [ind], wraparound=False)
        i8p = ir.IntType(8).as_pointer()
        i32 = ir.IntType(32)
        fn = cgutils.get_or_insert_function(builder.module, ir.FunctionType(ir.VoidType(), [i8p, i32, i32, i32]), _NAME)
        # (address, read 0 / write 1, locality 3 = keep in every level, data cache = 1)
        builder.call(fn, [builder.bitcast(ptr, i8p), ir.Constant(i32, write), ir.Constant(i32, 3), ir.Constant(i32, 1)])
        return context.get_dummy_value()

    return codegen


def _typed(arr, idx) -> bool:
    return isinstance(arr, types.Array) and arr.ndim == 1 and isinstance(idx, types.Integer)


@intrinsic
def prefetch_read(typingctx, arr, idx):
    """Prefetch ``arr[idx]`` (1-D array, integer index within it) for reading, keeping it in all cache levels."""
    return (types.void(arr, idx), _prefetch_codegen(0)) if _typed(arr, idx) else None


@intrinsic
def prefetch_write(typingctx, arr, idx):
    """Prefetch ``arr[idx]`` (1-D array, integer index within it) for writing, keeping it in all cache levels."""
    return (types.void(arr, idx), _prefetch_codegen(1)) if _typed(arr, idx) else None
