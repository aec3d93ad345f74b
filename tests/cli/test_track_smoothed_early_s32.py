"""--smoothed with a mode or fusion it cannot replay is refused before the recording and the map are read."""

from __future__ import annotations

import pytest

from evpose.cli.main import run


@pytest.mark.parametrize("flags, names", [(["--mode", "stpe"], "stpe / factor_graph"), (["--fusion", "ekf"], "full / ekf"),
                                          (["--fusion", "imu_only", "--smoothed-lag", "8"], "full / imu_only")])
def test_smoothed_with_another_mode_or_backend_is_refused_before_reading_anything(tmp_path, capsys, flags, names):
    rec, cmap = tmp_path / "rec.h5", tmp_path / "map.ply"
    rec.write_bytes(b"not read")  # reading these would be another error
    cmap.write_bytes(b"not read")
    code = run(["track", str(rec), "--map", str(cmap), "--out", str(tmp_path / "e.txt"), "--smoothed", str(tmp_path / "s.txt"),
                "--no-progress", *flags])
    assert code == 2
    assert capsys.readouterr().err == f"evpose track: error: --smoothed needs --mode full with the factor_graph fusion, not {names}\n"


def test_smoothed_mode_from_the_config_file_is_checked_as_early(tmp_path, capsys):
    rec, cmap, cfg = tmp_path / "rec.h5", tmp_path / "map.ply", tmp_path / "cfg.yaml"
    rec.write_bytes(b"not read")
    cmap.write_bytes(b"not read")
    cfg.write_text("fusion: {backend: ekf}\n")
    code = run(["track", str(rec), "--map", str(cmap), "--out", str(tmp_path / "e.txt"), "--smoothed", str(tmp_path / "s.txt"),
                "--config", str(cfg)])
    assert code == 2 and "not full / ekf" in capsys.readouterr().err
