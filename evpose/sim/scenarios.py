"""Named scenarios: a scene, its conditions, a flight and the sensor settings that go with them.

The landing variants follow the EV-Pose robustness study (speed classes slow
< 2 m/s, moderate 2-4 m/s, fast > 4 m/s; fast rotation > 30 deg/s; HDR;
flicker; dynamic objects; heavy noise; ground texture).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from evpose.sim.esim import EsimConfig
from evpose.sim.noise import NoiseConfig
from evpose.sim.scene_library import SceneName, SceneOptions
from evpose.sim.trajectories import TrajectoryConfig, TrajectoryShape


@dataclass(frozen=True)
class Scenario:
    """Everything that distinguishes one scenario from another."""

    name: str
    description: str
    scene: SceneName = SceneName.LANDING
    options: SceneOptions = field(default_factory=SceneOptions)
    trajectory: TrajectoryConfig = field(default_factory=TrajectoryConfig)
    esim: EsimConfig = field(default_factory=EsimConfig)
    noise: NoiseConfig = field(default_factory=NoiseConfig)


_MODERATE = TrajectoryConfig(speed_m_s=3.0)

SCENARIOS: dict[str, Scenario] = {
    s.name: s
    for s in [
        Scenario("landing", "square spiral descending onto the pad at 3 m/s (moderate)", trajectory=_MODERATE),
        Scenario("landing_slow", "square spiral at 1.5 m/s (slow)", trajectory=replace(_MODERATE, speed_m_s=1.5)),
        Scenario("landing_fast", "square spiral at 6 m/s (fast)", trajectory=replace(_MODERATE, speed_m_s=6.0)),
        Scenario("landing_rotation", "square spiral at 3 m/s with a 90 deg/s yaw (fast rotation)", trajectory=replace(_MODERATE, yaw_rate_deg_s=90.0)),
        Scenario(
            "indoor",
            "room loop at 1.2 m/s, camera looking at walls and furniture",
            scene=SceneName.INDOOR,
            trajectory=TrajectoryConfig(shape=TrajectoryShape.ROOM_LOOP, speed_m_s=1.2, tilt_amplitude_deg=3.0, bob_amplitude_m=0.05),
        ),
        Scenario("landing_hdr", "a building and a crate 15x brighter whose light switches off at 1 s, one of each 20x darker", options=SceneOptions(hdr=True), trajectory=_MODERATE),
        Scenario("landing_flicker", "crates and a building lit by a light flickering at 50 Hz", options=SceneOptions(flicker_hz=50.0), trajectory=_MODERATE),
        Scenario("landing_dynamic", "a rotating fan and two walking people-sized boxes, absent from the map", options=SceneOptions(dynamic=True), trajectory=_MODERATE),
        Scenario("landing_noisy", "heavy background activity (5 Hz/pixel) and 20 hot pixels", trajectory=_MODERATE, noise=NoiseConfig(background_rate_hz=5.0, hot_pixels=20)),
        Scenario("landing_texture", "fine ground texture (5 cm cells) creating events on no map contour", options=SceneOptions(ground_texture=True), trajectory=_MODERATE),
    ]
}
