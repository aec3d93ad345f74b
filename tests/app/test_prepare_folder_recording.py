"""``evpose app --prepare`` on a folder recording (an ECD folder) fills the disk cache like a file recording does:
the cache keys a folder by its files' names and bytes."""

from evpose.io.ecd import write_ecd_folder
from evpose.io.map_ply import write_contour_map


def test_prepare_fills_the_cache_for_an_ecd_folder_and_a_second_call_finds_it(tmp_path, capsys, squares_scene):
    # Until session 30 a folder had no bytes to key on: "the disk cache is off: there is nothing to prepare into".
    from evpose.cli.main import run

    rec, cmap = squares_scene
    folder = tmp_path / "squares_ecd"
    write_ecd_folder(folder, rec)
    map_path = tmp_path / "squares_map.ply"
    write_contour_map(map_path, cmap)
    args = ["app", "--prepare", str(folder), "--map", str(map_path), "--cache-dir", str(tmp_path / "cache")]
    assert run(args) == 0
    assert "computed in" in capsys.readouterr().out
    assert run(args) == 0
    assert "already in the disk cache" in capsys.readouterr().out
    (folder / "events.txt").write_text((folder / "events.txt").read_text() + "")  # same bytes, new mtime: same entry
    assert run(args) == 0
    assert "already in the disk cache" in capsys.readouterr().out
