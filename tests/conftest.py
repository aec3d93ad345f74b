"""Shared fixtures. Numba caches go to a per-run folder so a clean clone compiles once.

Simulated recordings (session-scoped, generated once per test run):

``sim_landing_small``
    :class:`evpose.sim.SimulationResult` of ``SimulationConfig(scenario="landing",
    seconds=1.0, resolution=(240, 180), seed=0)``: the moderate (3 m/s) landing
    spiral with the default sensor noise (threshold spread, background
    activity, noisy biased IMU at 500 Hz), ground truth at 1 kHz, identity
    camera-IMU extrinsic, no lens distortion. About 0.17 M events; 15-50 s to
    generate on the shared 2-core machine, then cached across sessions under
    ``<pytest tmp root>/evpose-sim-cache`` (keyed by the config and the
    simulator's source, so editing ``evpose/sim`` regenerates it).
    ``.recording`` is the in-memory :class:`~evpose.core.recording.Recording`;
    ``.cloud_points``/``.cloud_intensity`` the raw LiDAR-like cloud;
    ``.edges`` the true static edges (M, 2, 3) in the world frame;
    ``.files`` the same data as files in the cache folder (read-only for tests):
    ``{"recording": .../landing_small.h5, "cloud": .../landing_small_cloud.ply,
    "edges": .../landing_small_edges.npz}``.
"""

from __future__ import annotations

import evpose  # noqa: F401  first, before numpy: the suite runs on the BLAS kernels evpose pins (evpose.blas_kernels)

import signal

import pytest

# A run started in the background of a non-interactive shell (`make test &`, a CI script's `cmd &`) inherits SIGINT
# ignored, so the tests that send themselves a Ctrl+C saw nothing and failed (session 32). Such a run could not be
# interrupted from a terminal anyway; the suite runs as from an interactive one, and so do the commands it starts.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

SIM_LANDING_SMALL = dict(scenario="landing", seconds=1.0, resolution=(240, 180), seed=0)


def sim_cache_dir(tmp_path_factory):
    """Simulation cache shared by pytest sessions: the parent of pytest's per-session tmp dirs."""
    return tmp_path_factory.getbasetemp().parent / "evpose-sim-cache"


@pytest.fixture(scope="session")
def sim_landing_small(tmp_path_factory):
    """A 1 s, 240x180 simulated landing (see the module docstring); its files are under ``.files``."""
    from evpose.sim import SimulationConfig
    from evpose.sim.cache import load_or_simulate

    return load_or_simulate(SimulationConfig(**SIM_LANDING_SMALL), sim_cache_dir(tmp_path_factory), stem="landing_small")
