"""Event-camera simulator with exact ground truth (scenes, rendering, ESIM, trajectories, IMU, scenarios).

Public API::

    from evpose.sim import simulate, SimulationConfig
    result = simulate(SimulationConfig(scenario="landing", seconds=2.0, resolution=(346, 260), seed=0))
    result.recording        # Recording: events, IMU, ground truth, calibration, metadata
    result.cloud_points     # (N, 3) raw LiDAR-like cloud; result.cloud_intensity (N,) albedo
    result.edges            # (M, 2, 3) true static edges in the world frame

    from evpose.sim.scenarios import SCENARIOS   # the scenario names
    from evpose.sim.outputs import write_simulation  # recording + <stem>_cloud.ply + <stem>_edges.npz
"""

from evpose.sim.simulator import Extrinsic, SimulationConfig, SimulationResult, simulate

__all__ = ["Extrinsic", "SimulationConfig", "SimulationResult", "simulate"]
