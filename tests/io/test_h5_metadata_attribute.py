"""The evpose HDF5 ``metadata`` attribute must be a JSON object; an empty list is no exception."""

import h5py
import pytest

from io_factory import make_recording
from evpose.io.h5 import H5FormatError, read_recording_h5, write_recording_h5


@pytest.mark.parametrize("raw, kind", [("[]", "list"), ("[1]", "list"), ('""', "str"), ("0", "int")])
def test_metadata_that_is_not_an_object_is_named(tmp_path, raw, kind):
    # `or {}` read the falsy ones ([] , "", 0) as no metadata at all, silently; [1] was refused.
    path = tmp_path / "r.h5"
    write_recording_h5(path, make_recording(n=100, duration_us=10_000))
    with h5py.File(path, "r+") as f:
        f.attrs["metadata"] = raw
    with pytest.raises(H5FormatError) as info:
        read_recording_h5(path)
    assert str(info.value) == f"{path}: attribute 'metadata' is a JSON {kind}, expected an object"
