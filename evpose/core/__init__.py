"""Core data types and pure maths; depends on numpy/scipy/numba only."""

from evpose.core.camera import CameraCalibration, DistortionModel
from evpose.core.events import EventArray
from evpose.core.imu import ImuSamples
from evpose.core.recording import Recording
from evpose.core.trajectory import Trajectory

__all__ = [
    "CameraCalibration",
    "DistortionModel",
    "EventArray",
    "ImuSamples",
    "Recording",
    "Trajectory",
]
