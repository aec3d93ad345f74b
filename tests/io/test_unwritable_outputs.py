"""Outputs that cannot be written (a full disk, a file size limit, a folder that takes no file, a device) are one
OutputError naming the output, leave no temporary file and leave an earlier output as it was."""

import errno
import os
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

import pytest

from evpose.errors import InputError, OutputError
from evpose.io.atomic import atomic_path, check_outputs, write_failure


def test_a_full_disk_is_one_line_naming_the_output_and_the_earlier_output_stays(tmp_path):
    out = tmp_path / "est.txt"
    out.write_text("earlier run\n")
    with pytest.raises(OutputError) as info:
        with atomic_path(out) as tmp:
            tmp.write_text("half")
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    assert str(info.value) == f"{out}: cannot write the output (No space left on device)"
    assert out.read_text() == "earlier run\n" and [p.name for p in tmp_path.iterdir()] == ["est.txt"]


@pytest.mark.parametrize("exc, reason", [
    # h5py raises HDF5's report of a failed write as an OSError (errno set, strerror the whole report) or, from close(),
    # a RuntimeError; both name the system's message.
    (OSError(28, "Can't synchronously write data (file write failed: time = Sun Dec 6 08:16:00 2026\n, filename = 'x',"
                 " file descriptor = 3, errno = 28, error message = 'No space left on device', buf = 0x1)"), "No space left on device"),
    (RuntimeError("Disable slist on flush dest failure failed (file write failed: time = Sun Dec 6 2026\n, errno = 27,"
                  " error message = 'File too large', buf = 0x1)"), "File too large"),
    (OSError(errno.EROFS, "Read-only file system"), "Read-only file system"),
    (OSError(errno.ENOENT, "No such file or directory"), None),  # e.g. an input that vanished: not the output's fault
    (ValueError("no space"), None),
])
def test_write_failures_are_told_from_other_errors(exc, reason):
    assert write_failure(exc) == reason


def test_a_folder_that_takes_no_new_file_is_one_line_not_a_traceback(tmp_path, monkeypatch):
    # /proc passes the writability check as root, and mkstemp then raised FileNotFoundError with its traceback.
    def refuse(*args, **kwargs):
        raise FileNotFoundError(errno.ENOENT, "No such file or directory")

    monkeypatch.setattr(tempfile, "mkstemp", refuse)
    with pytest.raises(OutputError, match=r"x.json: cannot create the output \(No such file or directory\)"):
        with atomic_path(tmp_path / "x.json"):
            raise AssertionError("the body must not run")


def test_a_pipe_given_as_an_output_is_refused_not_replaced(tmp_path):
    # As root, `--out /dev/full` replaced the device node with a regular file (the rename works on any name).
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    with pytest.raises(InputError, match="fifo: output exists and is not a regular file"):
        check_outputs((fifo,))
    with pytest.raises(OutputError, match="not a regular file"):
        with atomic_path(fifo):
            raise AssertionError("the body must not run")
    assert fifo.is_fifo()


_CHILD = textwrap.dedent("""
    import resource, signal, sys
    sys.path.insert(0, sys.argv[2])
    from io_factory import make_recording
    from evpose.errors import OutputError
    from evpose.io.h5 import Compression, H5WriteConfig, write_recording_h5
    rec = make_recording(n=60_000)
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit then fails with EFBIG, as on a full disk
    resource.setrlimit(resource.RLIMIT_FSIZE, (100_000, resource.RLIM_INFINITY))
    try:
        write_recording_h5(sys.argv[1], rec, H5WriteConfig(compression=Compression.NONE, chunk_events=1 << 14))
    except OutputError as exc:
        print(exc)
""")


def test_an_hdf5_recording_that_does_not_fit_is_one_error_not_a_crash(tmp_path):
    # HDF5 writes cached chunks when a dataset or the file closes: on a full disk (convert, simulate) that failed there,
    # h5py printed pages of "Exception ignored" and the process died of a segmentation fault at exit.
    out = tmp_path / "rec.h5"
    run = subprocess.run([sys.executable, "-c", _CHILD, str(out), str(Path(__file__).parent)], capture_output=True, text=True,
                         timeout=60, env={**os.environ, "PYTHONPATH": str(Path(__file__).parents[2])})
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout.strip() == f"{out}: cannot write the output (File too large)"
    assert "Exception ignored" not in run.stderr
    assert list(tmp_path.iterdir()) == []
