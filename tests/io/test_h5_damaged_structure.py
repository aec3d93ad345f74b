"""HDF5 files damaged in their structure (object headers, symbol tables, local heaps: the first KiBs) are one
InputError naming the file, never h5py's KeyError or RuntimeError out of a plain ``name in file``."""

import numpy as np
import pytest

from io_factory import make_recording
from evpose.errors import InputError
from evpose.io.event_h5 import write_event_h5
from evpose.io.h5 import write_recording_h5
from evpose.io.open import open_recording


@pytest.mark.parametrize("kind", ["evpose", "event"])
def test_zeros_or_noise_over_the_structure_are_one_input_error(tmp_path, kind):
    # Session 30's fuzzing: 66 of 640 damaged copies of a recording were tracebacks ("KeyError: 'Unable to
    # synchronously open object (bad object header version number)'", "RuntimeError: ... (bad symbol table node
    # signature)") out of info, convert and track.
    rec = make_recording(n=2000, duration_us=200_000)
    src = tmp_path / "src.h5"
    if kind == "evpose":
        write_recording_h5(src, rec)
    else:
        write_event_h5(src, rec.events)
    data = src.read_bytes()
    path = tmp_path / "rec.h5"
    messages = []
    for at in range(0, min(len(data), 8192), 256):
        for noise in (False, True):
            damaged = bytearray(data)
            damaged[at:at + 256] = np.random.default_rng(at).integers(0, 256, 256, dtype=np.uint8).tobytes() if noise else bytes(256)
            path.write_bytes(bytes(damaged))
            try:
                open_recording(path, *(() if kind == "evpose" else (240, 180)))
            except InputError as exc:
                messages.append(str(exc))
    assert all(m.startswith(str(path)) and "\n" not in m for m in messages)
    assert any("the file's HDF5 structure is damaged (" in m for m in messages)
