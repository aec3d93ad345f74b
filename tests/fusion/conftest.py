"""Fixtures of the fusion tests: a camera with a non-trivial camera-IMU extrinsic."""

import pytest

from evpose.core.camera import CameraCalibration
from evpose.fusion.synthetic import default_T_cam_imu


@pytest.fixture
def calibration():
    return CameraCalibration(346, 260, 300.0, 300.0, 172.5, 129.5, T_cam_imu=default_T_cam_imu())
