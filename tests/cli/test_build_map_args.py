"""``evpose build-map``: flag values are checked like config-file values, before the cloud is read."""

from __future__ import annotations

import pytest

from evpose.cli.main import run


@pytest.mark.parametrize("args, message", [
    (["--voxel", "-1"], "voxel_m: -1.0 is outside the allowed range 0.0..0.2 m"),
    (["--k", "0"], "k_neighbours: 0 is outside the allowed range 6..100 points"),
    (["--spacing", "nan"], "contour_spacing_m: expected a finite number, got nan"),
    (["--viewpoint", "nan", "0", "0"], "viewpoint: expected a finite number, got nan"),
])
def test_bad_flag_values_are_one_line_errors_and_write_nothing(tmp_path, capsys, args, message):
    # --k 0 and --spacing nan were tracebacks; --voxel -1 and a NaN viewpoint ran and wrote a map.
    cloud = tmp_path / "cloud.ply"
    cloud.write_text("not read: the flags are refused first")
    out = tmp_path / "map.ply"
    assert run(["build-map", str(cloud), "--out", str(out), "--quiet", *args]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
    assert not out.exists()
