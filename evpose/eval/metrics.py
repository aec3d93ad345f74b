"""ATE / ARE / RTE / RRE of an estimated trajectory against ground truth, computed by evo.

Everything numerical is evo's: association (``evo.core.sync``), Umeyama alignment
(``PoseTrajectory3D.align``) and the APE/RPE metrics, called in the same order as
the ``evo_ape`` / ``evo_rpe`` command-line tools, so the figures equal theirs on the
same files (tested against the CLIs).

Definitions (the EV-Pose paper's four metrics):

- **ATE**: APE, translation part, metres.
- **ARE**: APE, rotation angle of ``inv(T_gt) T_est``, degrees.
- **RTE**: RPE, translation part of the relative-motion error between poses
  ``delta`` apart (default: consecutive poses, i.e. 1 frame at the estimation
  rate), metres.
- **RRE**: RPE, rotation angle of the same relative error, degrees.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

import numpy as np

from evpose.core.trajectory import Trajectory
from evpose.errors import InputError


class Alignment(str, enum.Enum):
    """How the estimate is aligned to ground truth before measuring (evo's Umeyama)."""

    SE3 = "se3"
    """Rotation + translation (``evo_ape -a``)."""
    SIM3 = "sim3"
    """Rotation + translation + scale (``evo_ape -a -s``), for monocular SLAM."""
    NONE = "none"
    """Compare as is: estimate and ground truth share the world frame (map-based tracking)."""


class DeltaUnit(str, enum.Enum):
    """Unit of the RPE pose spacing ``delta`` (evo supports these four)."""

    FRAMES = "frames"
    METERS = "meters"
    DEGREES = "degrees"
    RADIANS = "radians"


@dataclass(frozen=True)
class EvalConfig:
    """How trajectories are associated, aligned and compared."""

    align: Alignment = Alignment.SE3
    """Alignment applied to the estimate before all four metrics."""
    max_time_diff_s: float = 0.01
    """Largest timestamp difference for associating an estimate pose with a ground-truth pose, seconds (evo's ``--t_max_diff``)."""
    time_offset_s: float = 0.0
    """Constant offset added to the estimate's timestamps for association, seconds (evo's ``--t_offset``)."""
    rpe_delta: float = 1.0
    """Spacing of the pose pairs RTE/RRE compare, in ``rpe_delta_unit`` (1 frame = consecutive estimates)."""
    rpe_delta_unit: DeltaUnit = DeltaUnit.FRAMES
    """Unit of ``rpe_delta``."""
    rpe_all_pairs: bool = False
    """Use every pose pair ``delta`` apart (overlapping); by default pairs are consecutive and disjoint, as evo's default."""
    min_poses: int = 3
    """Fewest associated poses accepted; fewer is an input error, poses."""


STAT_NAMES = ("mean", "median", "rmse", "max", "min", "std")


def error_stats(errors: np.ndarray) -> dict[str, float]:
    """mean / median / RMSE / max / min / std of per-pose errors (evo's definitions) plus the count ``n``."""
    e = np.asarray(errors, dtype=np.float64)
    if e.size == 0:
        return {"n": 0}
    return {
        "mean": float(np.mean(e)),
        "median": float(np.median(e)),
        "rmse": float(np.sqrt(np.mean(e**2))),
        "max": float(np.max(e)),
        "min": float(np.min(e)),
        "std": float(np.std(e)),
        "n": int(e.size),
    }


@dataclass
class EvalResult:
    """The four metrics plus the per-pose errors and aligned trajectories behind them."""

    ate: dict[str, float]
    """APE translation statistics, metres."""
    are: dict[str, float]
    """APE rotation-angle statistics, degrees."""
    rte: dict[str, float]
    """RPE translation statistics, metres."""
    rre: dict[str, float]
    """RPE rotation-angle statistics, degrees."""
    config: EvalConfig
    n_estimate: int
    """Poses in the estimate before association."""
    n_reference: int
    """Poses in the ground truth before association."""
    n_associated: int
    """Pose pairs after association."""
    timestamps_s: np.ndarray
    """Associated timestamps (estimate clock), seconds, (N,)."""
    ate_errors: np.ndarray
    """Per associated pose, metres, (N,)."""
    are_errors: np.ndarray
    """Per associated pose, degrees, (N,)."""
    rpe_index: np.ndarray
    """Index (into the associated poses) of the second pose of each RPE pair, (M,)."""
    rte_errors: np.ndarray
    """Per RPE pair, metres, (M,)."""
    rre_errors: np.ndarray
    """Per RPE pair, degrees, (M,)."""
    ref_positions: np.ndarray
    """Associated ground-truth positions, metres, (N, 3)."""
    est_positions: np.ndarray
    """Associated, aligned estimate positions, metres, (N, 3)."""
    alignment: np.ndarray = field(default_factory=lambda: np.eye(4))
    """Sim(3) matrix applied to the estimate, (4, 4); identity for ``Alignment.NONE``."""
    scale: float = 1.0
    """Scale of the alignment (1 unless Sim(3))."""

    def summary(self) -> dict:
        """JSON-able figures (no per-pose arrays)."""
        return {
            "ate_m": self.ate,
            "are_deg": self.are,
            "rte_m": self.rte,
            "rre_deg": self.rre,
            "align": self.config.align.value,
            "rpe_delta": self.config.rpe_delta,
            "rpe_delta_unit": self.config.rpe_delta_unit.value,
            "rpe_all_pairs": self.config.rpe_all_pairs,
            "max_time_diff_s": self.config.max_time_diff_s,
            "poses_estimate": self.n_estimate,
            "poses_reference": self.n_reference,
            "poses_associated": self.n_associated,
            "alignment_sim3": self.alignment.tolist(),
            "scale": self.scale,
        }


def to_evo(traj: Trajectory, name: str = ""):
    """A ``PoseTrajectory3D`` (timestamps in seconds, quaternions w-first) from our Trajectory."""
    from evo.core.trajectory import PoseTrajectory3D

    q = traj.quat_xyzw
    return PoseTrajectory3D(
        positions_xyz=np.array(traj.position, dtype=np.float64),
        orientations_quat_wxyz=np.column_stack([q[:, 3], q[:, 0], q[:, 1], q[:, 2]]),
        timestamps=traj.t.astype(np.float64) / 1e6,
        meta={"name": name} if name else None,
    )


def _span(t: np.ndarray) -> str:
    return f"{t[0]:.6f}..{t[-1]:.6f} s"


def _check_inputs(est, ref, config: EvalConfig, est_name: str | None, ref_name: str | None) -> None:
    te = est.timestamps + config.time_offset_s
    tr = ref.timestamps
    tol = config.max_time_diff_s
    if te[-1] < tr[0] - tol or te[0] > tr[-1] + tol:
        raise InputError(est_name, f"trajectory ({_span(te)}) does not overlap in time with the ground truth ({_span(tr)})")


def evaluate(est: Trajectory, ref: Trajectory, config: EvalConfig = EvalConfig(), est_name: str | None = None, ref_name: str | None = None) -> EvalResult:
    """Associate, align and measure ``est`` against ``ref`` exactly as ``evo_ape``/``evo_rpe`` do.

    ``est_name``/``ref_name`` (usually file paths) appear in error messages.
    Raises :class:`InputError` when the trajectories do not overlap in time or
    fewer than ``config.min_poses`` poses associate.
    """
    from evo.core import metrics, sync
    from evo.core.filters import FilterException

    # evo cannot even hold an empty trajectory, so these checks come first.
    if len(est) == 0:
        raise InputError(est_name, "estimated trajectory has no poses")
    if len(ref) == 0:
        raise InputError(ref_name, "ground truth has no poses")
    traj_est = to_evo(est, "estimate")
    traj_ref = to_evo(ref, "reference")
    _check_inputs(traj_est, traj_ref, config, est_name, ref_name)
    try:
        # Same argument order as evo_ape: reference first, estimate second.
        traj_ref, traj_est = sync.associate_trajectories(traj_ref, traj_est, max_diff=config.max_time_diff_s, offset_2=config.time_offset_s)
    except sync.SyncException:
        raise InputError(est_name, f"no pose within {config.max_time_diff_s} s of a ground-truth pose (trajectories do not associate)") from None
    n = traj_est.num_poses
    if n < config.min_poses:
        if len(ref) < config.min_poses:  # reported against the estimate's file before
            raise InputError(ref_name, f"the ground truth has only {len(ref)} pose{'' if len(ref) == 1 else 's'} (need at least {config.min_poses})")
        raise InputError(est_name, f"only {n} {'pose associates' if n == 1 else 'poses associate'} with the ground truth (need at least {config.min_poses})")

    alignment = np.eye(4)
    scale = 1.0
    if config.align is not Alignment.NONE:
        correct_scale = config.align is Alignment.SIM3
        try:
            r, t, s = traj_est.align(traj_ref, correct_scale=correct_scale)
        except Exception as exc:  # evo raises GeometryException on degenerate point sets
            raise InputError(est_name, f"cannot align to the ground truth ({exc})") from None
        alignment[:3, :3] = s * r
        alignment[:3, 3] = t
        scale = float(s)

    data = (traj_ref, traj_est)
    ate = metrics.APE(metrics.PoseRelation.translation_part)
    ate.process_data(data)
    are = metrics.APE(metrics.PoseRelation.rotation_angle_deg)
    are.process_data(data)

    unit = {
        DeltaUnit.FRAMES: metrics.Unit.frames,
        DeltaUnit.METERS: metrics.Unit.meters,
        DeltaUnit.DEGREES: metrics.Unit.degrees,
        DeltaUnit.RADIANS: metrics.Unit.radians,
    }[config.rpe_delta_unit]
    delta = int(config.rpe_delta) if unit is metrics.Unit.frames else float(config.rpe_delta)
    try:
        rte = metrics.RPE(metrics.PoseRelation.translation_part, delta, unit, all_pairs=config.rpe_all_pairs)
        rte.process_data(data)
        rre = metrics.RPE(metrics.PoseRelation.rotation_angle_deg, delta, unit, all_pairs=config.rpe_all_pairs)
        rre.process_data(data)
        rpe_index = np.asarray(rte.delta_ids, dtype=np.int64)
        rte_err, rre_err = np.asarray(rte.error, dtype=np.float64), np.asarray(rre.error, dtype=np.float64)
    except (FilterException, metrics.MetricsException):
        # Too short for the requested delta: APE still stands, RPE is empty.
        rpe_index = np.zeros(0, np.int64)
        rte_err = rre_err = np.zeros(0)

    return EvalResult(
        ate=error_stats(ate.error),
        are=error_stats(are.error),
        rte=error_stats(rte_err),
        rre=error_stats(rre_err),
        config=config,
        n_estimate=len(est),
        n_reference=len(ref),
        n_associated=n,
        timestamps_s=np.array(traj_est.timestamps, dtype=np.float64),
        ate_errors=np.asarray(ate.error, dtype=np.float64),
        are_errors=np.asarray(are.error, dtype=np.float64),
        rpe_index=rpe_index,
        rte_errors=rte_err,
        rre_errors=rre_err,
        ref_positions=np.array(traj_ref.positions_xyz),
        est_positions=np.array(traj_est.positions_xyz),
        alignment=alignment,
        scale=scale,
    )

