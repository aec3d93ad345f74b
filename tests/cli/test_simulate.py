"""``evpose simulate``: outputs that cannot be written are refused before any simulation, with one line and exit 2."""

from evpose.cli.main import run


def test_out_onto_a_folder_of_other_files_is_refused_and_the_files_kept(tmp_path, capsys):
    data = tmp_path / "data"
    data.mkdir()
    (data / "flight.h5").write_text("keep")
    assert run(["simulate", "--scenario", "landing", "--out", str(data), "--seconds", "0.05", "--resolution", "64x48", "--no-cloud"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"evpose simulate: error: {data}: refusing to replace a folder that is not an ECD recording (it holds 'flight.h5');"
                   " give a new folder name, or a path ending in .h5"]
    assert (data / "flight.h5").read_text() == "keep" and sorted(p.name for p in data.iterdir()) == ["flight.h5"]
