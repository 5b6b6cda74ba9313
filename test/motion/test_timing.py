"""The rest-to-rest quintic that times each piece of ~/trajectory (no ROS graph needed)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clew_ros.motion.timing import PEAK_ACCELERATION, PEAK_VELOCITY, profile, quintic_spline, rest_to_rest_duration_s

U = np.linspace(0.0, 1.0, 100_001)


def test_profile_goes_from_rest_to_rest() -> None:
    s, ds, dds = profile(np.array([0.0, 1.0]))
    assert s.tolist() == [0.0, 1.0]
    assert ds.tolist() == [0.0, 0.0]
    assert dds.tolist() == [0.0, 0.0]
    s, ds, dds = profile(U)
    assert np.all(np.diff(s) > 0)  # monotonic: never goes back along the segment
    assert s[50_000] == pytest.approx(0.5)
    # derivatives agree with finite differences of s
    h = U[1] - U[0]
    assert np.allclose(np.gradient(s, h)[1:-1], ds[1:-1], atol=1e-6)
    assert np.allclose(np.gradient(ds, h)[1:-1], dds[1:-1], atol=1e-5)
    # clipped outside [0, 1]
    assert profile(-1.0)[0] == 0.0
    assert profile(2.0)[0] == 1.0


def test_profile_peaks() -> None:
    _, ds, dds = profile(U)
    assert ds.max() == pytest.approx(PEAK_VELOCITY, rel=1e-9)
    assert np.abs(dds).max() == pytest.approx(PEAK_ACCELERATION, rel=1e-8)
    assert profile(0.5 - math.sqrt(3) / 6)[2] == pytest.approx(PEAK_ACCELERATION)
    assert profile(0.5 + math.sqrt(3) / 6)[2] == pytest.approx(-PEAK_ACCELERATION)


@pytest.mark.parametrize(
    ("delta", "v", "a", "bound"),
    [
        ([3.0, -1.0], 1.0, 2.0, "velocity"),  # long move: the velocity limit binds
        ([0.01, 0.005], 1.0, 2.0, "acceleration"),  # short move: the acceleration limit binds
        ([1.0, 1.0], [1.0, 0.25], [100.0, 100.0], "velocity"),  # per joint: the slow joint binds
        ([0.1, 0.1], [10.0, 10.0], [5.0, 0.5], "acceleration"),
    ],
)
def test_duration_is_the_shortest_within_the_limits(delta, v, a, bound: str) -> None:
    delta, v, a = np.asarray(delta), np.broadcast_to(v, 2), np.broadcast_to(a, 2)
    duration = rest_to_rest_duration_s(delta, v, a)
    _, ds, dds = profile(U)
    peak_v = np.max(np.abs(ds[:, None] * delta / duration), axis=0)
    peak_a = np.max(np.abs(dds[:, None] * delta / duration**2), axis=0)
    assert np.all(peak_v <= v * (1 + 1e-9))
    assert np.all(peak_a <= a * (1 + 1e-9))
    # and the binding limit is reached: no shorter duration would do
    reached = peak_v / v if bound == "velocity" else peak_a / a
    assert np.max(reached) == pytest.approx(1.0, rel=1e-6)


def test_a_zero_move_takes_no_time() -> None:
    assert rest_to_rest_duration_s(np.zeros(3), 1.0, 1.0) == 0.0


def test_quintic_spline_matches_the_points_and_a_quintic() -> None:
    rng = np.random.default_rng(0)
    times = np.array([0.0, 0.7, 1.5, 1.6])
    p, v, a = rng.normal(size=(4, 3)), rng.normal(size=(4, 3)), rng.normal(size=(4, 3))
    assert np.allclose(quintic_spline(times, p, v, a, times), p)
    # slopes and curvatures at the knots: one-sided second-order finite differences inside each interval
    h = 1e-5
    for k in range(3):
        t0, t1 = times[k], times[k + 1]
        q = quintic_spline(times, p, v, a, t0 + h * np.arange(4))
        assert np.allclose((-3 * q[0] + 4 * q[1] - q[2]) / (2 * h), v[k], atol=1e-4)
        assert np.allclose((2 * q[0] - 5 * q[1] + 4 * q[2] - q[3]) / h**2, a[k], atol=2e-2)
        q = quintic_spline(times, p, v, a, t1 - h * np.arange(4))
        assert np.allclose((3 * q[0] - 4 * q[1] + q[2]) / (2 * h), v[k + 1], atol=1e-4)
        assert np.allclose((2 * q[0] - 5 * q[1] + 4 * q[2] - q[3]) / h**2, a[k + 1], atol=2e-2)
    # points at rest: the spline is the rest-to-rest profile, every coordinate in step
    zeros = np.zeros((2, 2))
    ends = np.array([[0.0, 1.0], [2.0, -1.0]])
    t = np.linspace(0.0, 3.0, 31)
    s = profile(t / 3.0)[0]
    expected = ends[0] + s[:, None] * (ends[1] - ends[0])
    assert np.allclose(quintic_spline(np.array([0.0, 3.0]), ends, zeros, zeros, t), expected, atol=1e-12)
