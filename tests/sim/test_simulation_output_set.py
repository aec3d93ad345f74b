"""write_simulation: the recording, the raw cloud and the true edges appear together, or none of them."""

import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tracker"))
from tracker_synthetic import generate  # noqa: E402

import evpose.sim.outputs as outputs  # noqa: E402


@pytest.fixture(scope="module")
def result():
    rec, _, _ = generate(duration_s=0.05, seed=1)
    rng = np.random.default_rng(0)
    return SimpleNamespace(recording=rec, cloud_points=rng.random((50, 3)), cloud_intensity=rng.random(50),
                           edges=rng.random((4, 2, 3)), albedo_edges=np.zeros((0, 2, 3)), files=None)


def test_simulation_outputs_appear_together(tmp_path, result):
    paths = outputs.write_simulation(result, tmp_path / "sim.h5")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sim.h5", "sim_cloud.ply", "sim_edges.npz"]
    assert result.files == paths


def test_simulation_interrupted_before_its_edges_leaves_no_recording_or_cloud(tmp_path, result, monkeypatch):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(outputs, "write_edges_npz", interrupted)
    with pytest.raises(KeyboardInterrupt):
        outputs.write_simulation(result, tmp_path / "sim.h5")
    assert list(tmp_path.iterdir()) == []
