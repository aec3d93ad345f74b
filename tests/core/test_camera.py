"""CameraCalibration: projection, distortion and their inverses for both lens models."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evpose.core.camera import CameraCalibration, DistortionModel
from evpose.errors import InputError

coef = st.floats(allow_nan=False, allow_infinity=False)


def radtan(k1, k2, p1, p2, k3):
    return CameraCalibration(640, 480, 400.0, 410.0, 320.0, 240.0, DistortionModel.RADTAN, (k1, k2, p1, p2, k3))


def kb(k1, k2, k3, k4):
    return CameraCalibration(1280, 720, 700.0, 700.0, 640.0, 360.0, DistortionModel.EQUIDISTANT, (k1, k2, k3, k4))


radtan_cams = st.builds(
    radtan,
    st.floats(-0.3, 0.3), st.floats(-0.1, 0.1), st.floats(-0.005, 0.005), st.floats(-0.005, 0.005), st.floats(-0.01, 0.01),
)
kb_cams = st.builds(kb, st.floats(-0.05, 0.05), st.floats(-0.01, 0.01), st.floats(-0.005, 0.005), st.floats(-0.001, 0.001))
# Normalised coordinates inside the region where these models are monotonic (|a|,|b| <= 0.5).
normalized = st.tuples(st.floats(-0.5, 0.5), st.floats(-0.5, 0.5))


@settings(max_examples=150, deadline=None)
@given(radtan_cams, normalized)
def test_radtan_distort_then_undistort_returns_the_point(cam, ab):
    ab = np.array([ab])
    back = cam.undistort_normalized(cam.distort_normalized(ab))
    np.testing.assert_allclose(back, ab, atol=1e-9, rtol=0)


@settings(max_examples=150, deadline=None)
@given(kb_cams, normalized)
def test_equidistant_distort_then_undistort_returns_the_point(cam, ab):
    ab = np.array([ab])
    back = cam.undistort_normalized(cam.distort_normalized(ab))
    np.testing.assert_allclose(back, ab, atol=1e-9, rtol=0)


@settings(max_examples=150, deadline=None)
@given(st.one_of(radtan_cams, kb_cams), normalized, st.floats(0.2, 50.0))
def test_unproject_of_project_is_the_bearing_of_the_point(cam, ab, z):
    P = np.array([[ab[0] * z, ab[1] * z, z]])
    ray = cam.unproject(cam.project(P))
    np.testing.assert_allclose(ray, P / np.linalg.norm(P), atol=1e-9, rtol=0)


@settings(max_examples=150, deadline=None)
@given(st.one_of(radtan_cams, kb_cams), normalized)
def test_project_of_unproject_returns_the_pixel(cam, ab):
    uv = cam.project(np.array([[ab[0], ab[1], 1.0]]))
    back = cam.project(cam.unproject(uv))
    np.testing.assert_allclose(back, uv, atol=1e-9, rtol=0)


@settings(max_examples=50, deadline=None)
@given(kb_cams, st.floats(0.0, 1.3), st.floats(-np.pi, np.pi))
def test_equidistant_round_trips_wide_angles(cam, theta, phi):
    d = np.array([[np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)]])
    np.testing.assert_allclose(cam.unproject(cam.project(d)), d, atol=1e-9, rtol=0)


def test_undistort_pixels_matches_pinhole_projection_of_the_same_point():
    cam = radtan(-0.25, 0.05, 0.001, -0.002, 0.0)
    P = np.array([[0.3, -0.2, 1.5], [-0.4, 0.25, 2.0]])
    ideal = cam.without_distortion().project(P)
    np.testing.assert_allclose(cam.undistort_pixels(cam.project(P)), ideal, atol=1e-9)


def test_undistortion_table_matches_undistort_pixels():
    cam = CameraCalibration(24, 18, 20.0, 20.0, 12.0, 9.0, DistortionModel.RADTAN, (-0.2, 0.03, 0.0, 0.0, 0.0))
    table = cam.undistortion_table
    assert table.shape == (18, 24, 2)
    np.testing.assert_allclose(table[5, 7], cam.undistort_pixels(np.array([[7.0, 5.0]]))[0], atol=1e-4)


def test_points_behind_the_camera_project_to_nan():
    cam = radtan(0.0, 0.0, 0.0, 0.0, 0.0)
    assert np.isnan(cam.project(np.array([[0.0, 0.0, -1.0]]))).all()


def test_calibration_round_trips_through_dict_with_extrinsic_and_offset():
    T = np.eye(4)
    T[:3, 3] = [0.01, -0.02, 0.03]
    cam = CameraCalibration(346, 260, 300.0, 301.0, 170.0, 130.0, DistortionModel.EQUIDISTANT, (0.01, 0.002, 0.0, 0.0), T, 1234)
    back = CameraCalibration.from_dict(cam.to_dict())
    assert back.to_dict() == cam.to_dict()
    np.testing.assert_array_equal(back.T_cam_imu, T)
    assert back.time_offset_us == 1234


@pytest.mark.parametrize(
    "model, dist",
    [(DistortionModel.RADTAN, (0.1, 0.2)), (DistortionModel.EQUIDISTANT, (0.1, 0.2, 0.3, 0.4, 0.5)), (DistortionModel.NONE, (0.1,))],
)
def test_wrong_number_of_distortion_coefficients_is_an_input_error(model, dist):
    with pytest.raises(InputError, match="coefficients"):
        CameraCalibration(10, 10, 5.0, 5.0, 5.0, 5.0, model, dist)


def test_non_finite_or_non_positive_calibration_is_an_input_error():
    with pytest.raises(InputError, match="NaN"):
        CameraCalibration(10, 10, float("nan"), 5.0, 5.0, 5.0)
    with pytest.raises(InputError, match="positive"):
        CameraCalibration(0, 10, 5.0, 5.0, 5.0, 5.0)


def test_from_dict_names_the_missing_field_and_the_file():
    with pytest.raises(InputError, match="cal.json: calibration is missing the field 'fx'"):
        CameraCalibration.from_dict({"width": 1, "height": 1, "fy": 1, "cx": 0, "cy": 0}, source="cal.json")


@pytest.mark.parametrize("scale", [2.0, -1.0])
def test_extrinsic_that_is_not_a_rotation_is_an_input_error(scale):
    T = np.eye(4)
    T[0, 0] = scale  # scaled, or a reflection (det -1)
    with pytest.raises(InputError, match="T_cam_imu rotation is not a rotation matrix"):
        CameraCalibration(10, 10, 5.0, 5.0, 5.0, 5.0, T_cam_imu=T)


def test_extrinsic_with_a_projective_bottom_row_is_an_input_error():
    T = np.eye(4)
    T[3, 0] = 0.5
    with pytest.raises(InputError, match="bottom row"):
        CameraCalibration(10, 10, 5.0, 5.0, 5.0, 5.0, T_cam_imu=T)


def test_extrinsic_rotation_printed_with_four_decimals_is_accepted():
    from scipy.spatial.transform import Rotation

    T = np.eye(4)
    T[:3, :3] = np.round(Rotation.from_euler("xyz", [0.3, -0.2, 1.1]).as_matrix(), 4)
    CameraCalibration(10, 10, 5.0, 5.0, 5.0, 5.0, T_cam_imu=T)


def test_principal_point_outside_the_sensor_is_an_input_error():
    with pytest.raises(InputError, match=r"principal point \(5000, 5\) px lies outside the 10x10 sensor"):
        CameraCalibration(10, 10, 5.0, 5.0, 5000.0, 5.0)


@pytest.mark.parametrize("kwargs, message", [
    # fx=1e-300 overflowed the projection, a width of 1e9 allocated terabytes: both tracebacks.
    ({"fx": 1e-300}, r"calibration's fx=1e-300 px is not a focal length for a 346 px sensor side \(expected 0.346..346000 px\)"),
    ({"fy": 1e300}, r"calibration's fy=1e\+300 px is not a focal length for a 260 px sensor side"),
    ({"width": 1_000_000_000}, r"calibration's sensor size 1000000000x260 is beyond 65536 pixels"),
])
def test_implausible_focal_length_or_sensor_size_is_an_input_error(kwargs, message):
    args = {"width": 346, "height": 260, "fx": 247.0, "fy": 247.0, "cx": 172.5, "cy": 129.5, **kwargs}
    with pytest.raises(InputError, match=message):
        CameraCalibration(**args)


def test_extrinsic_translation_beyond_a_rig_is_an_input_error():
    T = np.eye(4)
    T[0, 3] = 1e300  # numpy's overflow warnings were printed and the tracker blamed the map
    with pytest.raises(InputError, match=r"T_cam_imu translation \[1e\+300, 0.0, 0.0\] m is beyond 100 m"):
        CameraCalibration(10, 10, 5.0, 5.0, 5.0, 5.0, T_cam_imu=T)


@pytest.mark.parametrize("field, value", [("width", 346.5), ("time_offset_us", 12.5)])
def test_from_dict_refuses_a_fractional_integer_field_instead_of_truncating_it(field, value):
    d = CameraCalibration(346, 260, 247.0, 247.0, 172.5, 129.5).to_dict()
    d[field] = value
    with pytest.raises(InputError, match=rf"cal.json: calibration's {field} {value} is not a whole number"):
        CameraCalibration.from_dict(d, source="cal.json")


@pytest.mark.parametrize("dist, message", [
    # k1 = 1e9 shrank a 55 deg field of view to 0.05 deg; the tracker then blamed the map.
    ((1e9, 0.0, 0.0, 0.0, 0.0), r"puts a pixel 129 px from the principal point 0.0459 deg off the axis, against 27.3 deg"),
    # k1 = -3 folds the image 83 px from the principal point.
    ((-3.0, 0.0, 0.0, 0.0, 0.0), r"does not invert within 129 px of the principal point .* and the image folds"),
])
def test_distortion_of_another_lens_or_unit_is_an_input_error(dist, message):
    with pytest.raises(InputError, match=message):
        CameraCalibration(346, 260, 250.0, 250.0, 173.0, 130.0, DistortionModel.RADTAN, dist)


def test_real_wide_lens_calibrations_are_accepted_even_if_they_fold_in_the_corners():
    cams = [
        # The Event Camera Dataset's DAVIS240C calibration (shapes_6dof's calib.txt): invertible over the whole sensor.
        CameraCalibration(240, 180, 199.092366542, 198.82882047, 132.192071378, 110.712660011, DistortionModel.RADTAN,
                          (-0.368436311798, 0.150947243557, -0.000296130534385, -0.000759431726241, 0.0)),
        # k1 alone at -0.3 folds 422 px from the centre: only the corners of a 640x480 sensor, beyond its 239 px disc.
        CameraCalibration(640, 480, 400.0, 400.0, 320.0, 240.0, DistortionModel.RADTAN, (-0.3, 0.0, 0.0, 0.0, 0.0)),
    ]
    for cam in cams:
        # Inside the checked disc every pixel's ray projects back onto it.
        edge = np.array([[cam.cx + 0.99 * min(cam.cx, cam.cy), cam.cy], [cam.cx, cam.cy - 0.99 * min(cam.cx, cam.cy)]])
        assert np.abs(cam.project(cam.unproject(edge)) - edge).max() < 1e-6
    ecd = cams[0]
    corners = np.array([[0.0, 0.0], [239.0, 179.0]])
    assert np.abs(ecd.project(ecd.unproject(corners)) - corners).max() < 1e-6


@pytest.mark.parametrize("offset", [10**18, -(10**18), float("nan")])
def test_a_time_offset_beyond_any_clock_is_an_input_error(offset):
    # A kalibr timeshift of 1e300 s passed, and event times plus it overflowed int64 later.
    with pytest.raises(InputError, match="calibration's time_offset_us .* is not a number of microseconds within"):
        CameraCalibration(346, 260, 247.0, 247.0, 172.5, 129.5, time_offset_us=offset)
    CameraCalibration(346, 260, 247.0, 247.0, 172.5, 129.5, time_offset_us=1_700_000_000_000_000)  # Unix time: fine


def test_from_dict_with_an_integer_beyond_the_float_range_is_malformed_not_a_traceback():
    d = CameraCalibration(346, 260, 247.0, 247.0, 172.5, 129.5).to_dict()
    d["width"] = 10**400  # json.loads reads it; float() of it was an OverflowError traceback
    with pytest.raises(InputError, match="cal.json: calibration is malformed"):
        CameraCalibration.from_dict(d, source="cal.json")
