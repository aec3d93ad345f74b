"""The MCI generator's batched homographies and numba depth fit equal the per-slice / numpy code they replaced, bit for bit."""
import numpy as np
from scipy.spatial.transform import Rotation

from evpose.slam.mci import fit_average_depth, se3_homographies

K = np.array([[190.0, 0.0, 173.0], [0.0, 190.0, 130.0], [0.0, 0.0, 1.0]])


def _se3_homographies_ref(K, omega, velocity, depth, dts):
    Ki = np.linalg.inv(K)
    out = np.empty((len(dts), 3, 3))
    e3 = np.array([0.0, 0.0, 1.0])
    inv_depth = 1.0 / max(depth, 1e-6)
    for k, dt in enumerate(dts):
        R = Rotation.from_rotvec(np.asarray(omega) * dt).as_matrix().T
        t = -R @ (np.asarray(velocity) * dt)
        out[k] = K @ (R + np.outer(t, e3) * inv_depth) @ Ki
    return out


def _fit_average_depth_ref(K, omega, velocity, ref, cur, seconds):
    if len(ref) < 3 or np.linalg.norm(velocity) < 1e-12 or seconds <= 0:
        return None
    Ki = np.linalg.inv(K)
    R = Rotation.from_rotvec(np.asarray(omega) * seconds).as_matrix().T
    t = -R @ (np.asarray(velocity) * seconds)
    a = np.c_[ref, np.ones(len(ref))] @ (K @ R @ Ki).T
    b = K @ t

    def best(ws):
        q = a[None, :, :] + ws[:, None, None] * b[None, None, :]
        with np.errstate(divide="ignore", invalid="ignore"):
            uv = q[..., :2] / q[..., 2:3]
            err = np.median(np.linalg.norm(uv - cur[None], axis=2), axis=1)
        err = np.where(np.isfinite(err), err, np.inf)
        return int(np.argmin(err)), err

    grid = np.geomspace(1e-3, 1e3, 241)
    k, err = best(grid)
    if not np.isfinite(err[k]):
        return None
    fine = np.linspace(grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)], 101)
    k2, _ = best(fine)
    return float(1.0 / fine[k2])


def test_se3_homographies_equal_per_slice_products():
    rng = np.random.default_rng(0)
    for _ in range(300):
        args = (K, rng.normal(size=3) * rng.choice([0.0, 0.01, 1.0, 10.0]), rng.normal(size=3) * rng.choice([0.0, 0.01, 1.0, 10.0]),
                float(rng.uniform(0.0, 10.0)), (rng.random(int(rng.integers(1, 40))) - 0.3) * 0.1)
        np.testing.assert_array_equal(se3_homographies(*args), _se3_homographies_ref(*args))


def test_fit_average_depth_equals_numpy_median_search():
    rng = np.random.default_rng(1)
    found = 0
    for i in range(400):
        n = int(rng.integers(0, 60))
        ref = rng.random((n, 2)) * [346.0, 260.0]
        cur = (ref + rng.normal(size=(n, 2)) * rng.choice([0.1, 1.0, 10.0])).astype(rng.choice([np.float32, np.float64]))
        if n and i % 10 == 0:
            cur[rng.integers(n)] = np.nan
        args = (K, rng.normal(size=3) * rng.choice([0.0, 0.1, 3.0]), rng.normal(size=3) * rng.choice([0.0, 1e-3, 1.0, 30.0]), ref, cur,
                float(rng.choice([0.0, 0.02, 0.1])))
        got, want = fit_average_depth(*args), _fit_average_depth_ref(*args)
        assert got == want or (got is None and want is None)
        found += want is not None
    assert found > 50
