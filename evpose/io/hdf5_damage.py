"""What HDF5 itself says is wrong with a file: unwritten chunks, and damage the library reports as an exception.

Shared by every HDF5 reader (evpose recordings, event-only h5 files), so a damaged file gets the same one-line
error whichever reader meets it.
"""

from __future__ import annotations

import h5py


def unwritten_problem(ds: h5py.Dataset) -> str | None:
    """What is missing if ``ds`` declares more values than its file stores, else None. A writer that sized its datasets
    first and stopped (or a crafted file) leaves unwritten chunks, which read as zeros: one declaring 10**13 IMU
    samples in a 1.5 MB file ended in numpy's "Unable to allocate 72.8 TiB" traceback, and smaller ones could fill the
    memory. Exact and cheap: HDF5 counts the chunks it allocated."""
    if ds.size == 0:
        return None
    if ds.chunks is None:
        stored, needed = ds.id.get_storage_size(), ds.nbytes
        return None if stored >= needed else f"stores {stored} of its {needed} bytes"
    expected = 1
    for size, chunk in zip(ds.shape, ds.chunks):
        expected *= -(-size // chunk)
    got = ds.id.get_num_chunks()
    return None if got >= expected else f"has {got} of its {expected} chunks written"


def hdf5_damage(exc: BaseException) -> str | None:
    """What the HDF5 library found damaged, if ``exc`` is h5py's report of it (else None): a damaged object header,
    symbol table or local heap comes out of a plain ``name in file``, ``file[name]`` or a dataset's chunk count as a
    KeyError, RuntimeError, OSError or ValueError reading "Unable to <action> (<what is damaged>)" (the low-level
    API's: "Can't <action> (...)"). 256 bytes of zeros or noise in a recording's first 6 KiB ended in those tracebacks
    in every command (session 30's fuzzing, /tmp/s30/fuzz30/: 66 of 640 damaged copies of an evpose and an event h5)."""
    if not isinstance(exc, (KeyError, RuntimeError, OSError, ValueError)) or not exc.args:
        return None
    text = str(exc.args[0])
    if not text.startswith(("Unable to", "Can't ")):  # the high-level API's phrasing, and the low-level one's (get_num_chunks)
        return None
    inner = text[text.find("(") + 1: text.rfind(")")] if text.endswith(")") and "(" in text else text
    return inner or text
