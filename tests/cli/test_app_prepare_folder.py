"""``evpose app --prepare`` on a folder recording says why it cannot, naming the folder."""

import pytest


@pytest.mark.parametrize("kind", ["ecd", "ros2"])
def test_prepare_on_a_folder_recording_names_it_in_one_line(tmp_path, capsys, kind):
    # The disk cache keys a recording by its file's bytes: an ECD folder or ROS2 bag ended in "the disk cache is
    # off: there is nothing to prepare into" (--no-disk-cache was not given), naming no file.
    from evpose.cli.main import run

    folder = tmp_path / kind
    folder.mkdir()
    (folder / ("events.txt" if kind == "ecd" else "metadata.yaml")).write_text("not read\n")
    cloud = tmp_path / "map.ply"
    cloud.write_text("not read\n")
    assert run(["app", "--prepare", str(folder), "--map", str(cloud), "--cache-dir", str(tmp_path / "cache")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert f"{folder}: is a folder (an ECD recording or a ROS2 bag), and --prepare caches file recordings only" in err
