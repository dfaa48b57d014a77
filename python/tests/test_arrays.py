"""numpy inputs: accepted layouts, zero-copy views, and clear TypeError/ValueError otherwise."""

from __future__ import annotations

import numpy as np
import pytest

import slam_mms

T0 = 1_700_000_000_000_000_000


@pytest.fixture()
def system():
    return slam_mms.MappingSystem(slam_mms.Options())


def _points(n=100, dtype=np.float32, cols=3):
    rng = np.random.default_rng(0)
    return (rng.normal(size=(n, cols)) * 10).astype(dtype)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("cols", [3, 4])
def test_scan_accepts_float32_float64_n3_n4(dtype, cols):
    p = _points(dtype=dtype, cols=cols)
    times = np.linspace(0, 0.1, len(p), dtype=dtype)
    scan = slam_mms.Scan(p, T0, T0 + 100_000_000, times=times)
    assert len(scan) == len(p)
    np.testing.assert_array_equal(scan.points, p[:, :3].astype(np.float32))
    np.testing.assert_array_equal(scan.times, times.astype(np.float32))
    expected_i = p[:, 3].astype(np.float32) if cols == 4 else np.zeros(len(p), np.float32)
    np.testing.assert_array_equal(scan.intensities, expected_i)


def test_strided_and_fortran_inputs_are_read_correctly():
    big = _points(n=200, cols=6)
    strided = big[::2, 1:4]  # non-contiguous rows and a column offset
    fortran = np.asfortranarray(_points(n=50))
    for p in (strided, fortran):
        scan = slam_mms.Scan(p, T0, T0 + 1)
        np.testing.assert_array_equal(scan.points, p)


def test_scan_arrays_are_views_on_the_scan():
    scan = slam_mms.Scan(_points(), T0, T0 + 1)
    a, b = scan.points, scan.points
    assert np.shares_memory(a, b)  # both views onto the scan's own memory, no copy
    a[0, 0] = 123.0
    assert scan.points[0, 0] == 123.0
    assert a.base is not None  # keeps the scan alive
    del scan
    assert a[0, 0] == 123.0


@pytest.mark.parametrize("bad", [np.zeros((10, 3), np.int32), np.zeros((10, 3), np.float16),
                                 np.zeros((10, 3), np.complex64)])
def test_wrong_dtype_is_type_error(system, bad):
    with pytest.raises(TypeError, match="points: expected dtype float32 or float64"):
        system.add_scan(bad, T0, T0 + 1)


def test_not_an_array_is_type_error(system):
    with pytest.raises(TypeError, match="points: expected a numpy array, got list"):
        system.add_scan([[0.0, 0.0, 0.0]], T0, T0 + 1)


@pytest.mark.parametrize("shape", [(10,), (10, 2), (10, 5), (2, 10, 3)])
def test_wrong_shape_is_value_error(system, shape):
    with pytest.raises(ValueError, match=r"points: expected shape \(N, 3\) or \(N, 4\)"):
        system.add_scan(np.zeros(shape, np.float32), T0, T0 + 1)


def test_times_and_intensities_checked(system):
    p = _points()
    with pytest.raises(ValueError, match=r"times: expected shape \(100,\)"):
        system.add_scan(p, T0, T0 + 1, times=np.zeros(99, np.float32))
    with pytest.raises(TypeError, match="intensities: expected dtype"):
        system.add_scan(p, T0, T0 + 1, intensities=np.zeros(100, np.int64))
    with pytest.raises(ValueError, match="intensities given twice"):
        system.add_scan(_points(cols=4), T0, T0 + 1, intensities=np.zeros(100, np.float32))
    with pytest.raises(ValueError, match="stamp_end_ns .* is before stamp_start_ns"):
        system.add_scan(p, T0, T0 - 1)


def test_imu_array_shapes(system):
    with pytest.raises(ValueError, match=r"samples \(N, 6\)"):
        system.add_imu_array(np.arange(3, dtype=np.int64), np.zeros((3, 7)))


def test_trajectory_from_tum_array():
    tum = np.array([[1.0, 0, 0, 0, 0, 0, 0, 1], [2.0, 1, 0, 0, 0, 0, 0, 1]])
    t = slam_mms.Trajectory(tum)
    np.testing.assert_array_equal(t.tum, tum)
    np.testing.assert_array_equal(t.stamps_ns, [1_000_000_000, 2_000_000_000])
    assert t.path_length_m() == pytest.approx(1.0)
    with pytest.raises(ValueError, match=r"tum: expected shape \(N, 8\)"):
        slam_mms.Trajectory(np.zeros((2, 7)))
    with pytest.raises(ValueError, match="is not after the previous one"):
        slam_mms.Trajectory(tum[::-1].copy())
