"""The native loop of :mod:`evpose.cli.interrupt_watchdog` (a numba cfunc calling libc directly, so it runs without
the GIL and its compiled code can be cached: C functions reached through ctypes pointers cannot be)."""

from __future__ import annotations

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

READ_AT, INT_MSG_AT, TERM_MSG_AT, PATHS_AT, SIZE = 128, 256, 512, 1024, 1 << 16
"""Layout of the block shared with :mod:`evpose.cli.interrupt_watchdog` (here: numba compiles globals in as constants
and keys its cache on this file only). int64 slots 0-5: the pipe's read end, the grace period (us), done, held, the
lengths of the SIGINT / SIGTERM lines; then at these byte offsets the byte read, the two lines, and the temporary
paths (NUL-separated, a double NUL ends them)."""
_I64, _I32, _VP = ir.IntType(64), ir.IntType(32), ir.IntType(8).as_pointer()


def _codegen(name, ret, args):
    """Lowering of a call to libc's ``name``: int64 arguments passed as ``args`` ("i" int, "l" size_t / ssize_t,
    "p" address), its result (``ret``: "i", "l" or "v" void) as an int64."""
    llargs = [{"i": _I32, "l": _I64, "p": _VP}[a] for a in args]
    llret = {"i": _I32, "l": _I64, "v": ir.VoidType()}[ret]

    def codegen(context, builder, signature, values):
        fn = cgutils.get_or_insert_function(builder.module, ir.FunctionType(llret, llargs), name)
        conv = {_I32: lambda v: builder.trunc(v, _I32), _I64: lambda v: v, _VP: lambda v: builder.inttoptr(v, _VP)}
        out = builder.call(fn, [conv[t](v) for v, t in zip(values, llargs)])
        if ret == "v":
            return ir.Constant(_I64, 0)
        return builder.sext(out, _I64) if ret == "i" else out

    return codegen


def _libc1(name, ret, args):
    """A one-argument libc function callable from the kernel (intrinsics take no ``*args``)."""

    @intrinsic
    def call(typingctx, a):
        return types.int64(types.int64), _codegen(name, ret, args)
    return call


def _libc3(name, ret, args):
    """A three-argument libc function callable from the kernel."""

    @intrinsic
    def call(typingctx, a, b, c):
        return types.int64(types.int64, types.int64, types.int64), _codegen(name, ret, args)
    return call


_read3 = _libc3("read", "l", "ipl")
_write3 = _libc3("write", "l", "ipl")
_unlink = _libc1("unlink", "i", "p")
_rmdir = _libc1("rmdir", "i", "p")
_usleep = _libc1("usleep", "i", "i")
_exit = _libc1("_exit", "v", "i")


@intrinsic
def _address(typingctx, ptr):
    """A pointer's address as an int64 (libc's arguments are addresses in the block)."""

    def codegen(context, builder, signature, values):
        return builder.ptrtoint(values[0], _I64)
    return types.int64(types.voidptr), codegen


@numba.cfunc(types.voidptr(types.voidptr), cache=True)
def watch(arg):
    """The thread's body (``arg``: the shared block): read a signal number from the wakeup pipe; for SIGINT / SIGTERM
    wait the grace period (in 50 ms sleeps: usleep may refuse a second or more), then, unless disarmed, delete the
    temporaries, print the line and exit with 128 + the signal."""
    st = numba.carray(arg, SIZE // 8, np.int64)
    raw = numba.carray(arg, SIZE, np.uint8)
    base = _address(arg)
    while True:
        if _read3(st[0], base + READ_AT, 1) <= 0:
            _usleep(100000)  # EINTR (or a closed pipe): never spin
            continue
        sig = np.int64(raw[READ_AT])
        if sig != 2 and sig != 15:
            continue
        if st[2] != 0:
            continue
        waited = 0
        while waited < st[1] and st[2] == 0:
            _usleep(50000)
            waited += 50000
        while st[3] != 0:
            _usleep(20000)
        if st[2] != 0:
            continue
        i = PATHS_AT
        while i < SIZE - 1 and raw[i] != 0:
            j = i
            while j < SIZE - 1 and raw[j] != 0:
                j += 1
            if _unlink(base + i) != 0:
                _rmdir(base + i)
            i = j + 1
        if sig == 2:
            _write3(2, base + INT_MSG_AT, st[4])
        else:
            _write3(2, base + TERM_MSG_AT, st[5])
        _exit(128 + sig)
    return arg
