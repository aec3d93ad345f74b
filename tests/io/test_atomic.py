"""atomic_path: all-or-nothing outputs that never replace an input."""

import pytest

from evpose.errors import InputError
from evpose.io.atomic import atomic_path


def test_output_appears_only_on_success(tmp_path):
    with pytest.raises(RuntimeError):
        with atomic_path(tmp_path / "out.txt") as tmp:
            tmp.write_text("half")
            raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []
    with atomic_path(tmp_path / "out.txt") as tmp:
        tmp.write_text("done")
    assert (tmp_path / "out.txt").read_text() == "done"


def test_refuses_to_replace_an_input(tmp_path):
    f = tmp_path / "in.txt"
    f.write_text("keep")
    with pytest.raises(InputError, match="refusing to overwrite an input"):
        with atomic_path(f, inputs=(f,)):
            pass
    assert f.read_text() == "keep"


def test_folders_are_replaced_whole(tmp_path):
    with atomic_path(tmp_path / "d", is_dir=True) as tmp:
        (tmp / "a").write_text("1")
    with atomic_path(tmp_path / "d", is_dir=True) as tmp:
        (tmp / "b").write_text("2")
    assert sorted(p.name for p in (tmp_path / "d").iterdir()) == ["b"]


def test_file_output_onto_an_existing_folder_is_refused_up_front(tmp_path):
    (tmp_path / "d").mkdir()
    with pytest.raises(InputError, match="output is an existing folder; give a file name"):
        with atomic_path(tmp_path / "d"):
            raise AssertionError("the body must not run")


def test_output_under_a_file_names_the_file_in_the_way(tmp_path):
    (tmp_path / "f.txt").write_text("x")
    with pytest.raises(InputError, match=r"f.txt is a file, not a folder"):
        with atomic_path(tmp_path / "f.txt" / "sub" / "out.txt"):
            pass


def test_check_outputs_refuses_inputs_folders_and_files_in_the_way_before_any_work(tmp_path):
    from evpose.io.atomic import check_outputs

    src = tmp_path / "in.txt"
    src.write_text("keep")
    (tmp_path / "d").mkdir()
    with pytest.raises(InputError, match="refusing to overwrite an input"):
        check_outputs((tmp_path / "x.txt", tmp_path / "sub" / ".." / "in.txt"), inputs=(src,))
    with pytest.raises(InputError, match="existing folder"):
        check_outputs((tmp_path / "d",))
    with pytest.raises(InputError, match="output folder exists and is a file"):
        check_outputs((), folders=(src,))
    check_outputs((None, tmp_path / "new" / "deeper" / "o.txt"), inputs=(src, None), folders=(tmp_path / "d", None))
    assert src.read_text() == "keep" and not (tmp_path / "new").exists()


def test_files_an_ecd_folder_is_read_from_are_never_replaced(tmp_path):
    from evpose.io.atomic import check_outputs

    ecd = tmp_path / "ecd"
    ecd.mkdir()
    events = ecd / "events.txt"
    events.write_text("keep")
    (ecd / "rec.h5").write_text("an earlier conversion")
    with pytest.raises(InputError, match="events.txt: refusing to overwrite a file the input recording .*ecd is read from"):
        check_outputs((events,), inputs=(ecd,))
    with pytest.raises(InputError, match="refusing to overwrite a file the input recording"):
        with atomic_path(events, inputs=(ecd,)) as tmp:
            tmp.write_text("replaced")
    assert events.read_text() == "keep"
    with atomic_path(ecd / "rec.h5", inputs=(ecd,)) as tmp:  # not read by the recording: replaced as any output
        tmp.write_text("converted again")
    assert (ecd / "rec.h5").read_text() == "converted again"


def test_sibling_files_an_event_h5_is_read_from_are_never_replaced(tmp_path):
    from evpose.core.events import EventArray
    from evpose.io.atomic import check_outputs
    from evpose.io.event_h5 import write_event_h5

    write_event_h5(tmp_path / "seq-events_left.h5", EventArray.from_arrays([1, 2], [0, 0], [0, 0], [1, 0]))
    (tmp_path / "mocap_data.txt").write_text("keep")
    with pytest.raises(InputError, match="mocap_data.txt: refusing to overwrite a file the input recording"):
        check_outputs((tmp_path / "mocap_data.txt",), inputs=(tmp_path / "seq-events_left.h5",))
    check_outputs((tmp_path / "est.txt",), inputs=(tmp_path / "seq-events_left.h5",))


def test_the_same_path_for_two_outputs_is_refused(tmp_path):
    from evpose.io.atomic import check_outputs

    with pytest.raises(InputError, match="a.txt: given for two outputs"):
        check_outputs((tmp_path / "a.txt", tmp_path / "d" / ".." / "a.txt"))
    with pytest.raises(InputError, match="given for two outputs"):
        check_outputs((tmp_path / "o",), folders=(tmp_path / "o",))
    check_outputs((tmp_path / "a.txt", None, None, tmp_path / "b.txt"))


def test_same_name_yields_the_output_name_inside_a_temporary_folder_that_never_stays(tmp_path):
    with atomic_path(tmp_path / "bag", is_dir=True, same_name=True) as tmp:
        assert tmp.name == "bag" and not tmp.exists()
        tmp.mkdir()
        (tmp / "bag.db3").write_text("x")
    assert [p.name for p in tmp_path.iterdir()] == ["bag"] and (tmp_path / "bag" / "bag.db3").read_text() == "x"
    with pytest.raises(RuntimeError):
        with atomic_path(tmp_path / "other.bag", same_name=True) as tmp:
            tmp.write_text("half")
            raise RuntimeError
    assert [p.name for p in tmp_path.iterdir()] == ["bag"]
