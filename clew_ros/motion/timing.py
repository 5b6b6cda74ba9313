"""Time parameterisation of a straight joint-space piece: a rest-to-rest quintic within joint limits.

Every piece between two waypoints is timed on its own and starts and ends at
rest (zero velocity and zero acceleration): the plan's path has corners, and
stopping at each waypoint keeps the executed path exactly the planned one.
Along a piece of duration ``T`` from ``q0`` to ``q1`` all joints follow one
normalised profile ``s``, so they stay on the straight segment and arrive
together::

    q(t) = q0 + s(t / T) (q1 - q0),    s(u) = 10 u^3 - 15 u^4 + 6 u^5

``s`` is the minimum-jerk (quintic) S-curve: ``s(0) = 0``, ``s(1) = 1`` and
``s'`` and ``s''`` vanish at both ends. It is exactly what
``joint_trajectory_controller`` (quintic spline interpolation) executes
between two points that carry zero velocity and zero acceleration, so a
``JointTrajectory`` of the waypoints alone is followed along the straight
segments, in the time given. Its peaks are ``max s' = 15/8`` (at ``u = 1/2``)
and ``max |s''| = 10 / sqrt(3)`` (at ``u = 1/2 -+ sqrt(3)/6``); the shortest
duration within limits ``v_i`` and ``a_i`` for a move ``d_i`` of each joint
is therefore::

    T = max_i max(15/8 |d_i| / v_i, sqrt(10 / sqrt(3) |d_i| / a_i))

Pure NumPy; no rclpy.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["PEAK_ACCELERATION", "PEAK_VELOCITY", "profile", "quintic_spline", "rest_to_rest_duration_s"]

#: Largest ``s'(u)`` of the profile (at ``u = 1/2``).
PEAK_VELOCITY = 15.0 / 8.0
#: Largest ``|s''(u)|`` of the profile (at ``u = 1/2 -+ sqrt(3)/6``).
PEAK_ACCELERATION = 10.0 / math.sqrt(3.0)


def profile(u: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(s, ds/du, d2s/du2)`` of the normalised profile at ``u`` (clipped to [0, 1]); vectorised."""
    x = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
    s = np.asarray(x**3 * (10.0 + x * (-15.0 + 6.0 * x)))
    ds = np.asarray(30.0 * x**2 * (1.0 - x) ** 2)
    dds = np.asarray(60.0 * x * (1.0 - x) * (1.0 - 2.0 * x))
    return s, ds, dds


def rest_to_rest_duration_s(
    delta_rad: np.ndarray, max_velocity_rad_s: np.ndarray | float, max_acceleration_rad_s2: np.ndarray | float
) -> float:
    """Shortest duration (s) of the profile that moves each joint by ``delta_rad`` (n,) within the limits.

    The limits are per joint, (n,) or scalars; 0 for a move of zero length.
    """
    distance = np.abs(np.asarray(delta_rad, dtype=float))
    if distance.size == 0:
        return 0.0
    by_velocity = PEAK_VELOCITY * distance / max_velocity_rad_s
    by_acceleration = np.sqrt(PEAK_ACCELERATION * distance / max_acceleration_rad_s2)
    return float(max(np.max(by_velocity), np.max(by_acceleration)))


def quintic_spline(
    times_s: np.ndarray, positions: np.ndarray, velocities: np.ndarray, accelerations: np.ndarray, t_s: np.ndarray
) -> np.ndarray:
    """Positions (N, m) at ``t_s`` (N,) of the quintic spline through timed points, as a controller runs them.

    ``times_s`` (P,) increasing, ``positions``, ``velocities`` and
    ``accelerations`` (P, m): between two points each coordinate follows the
    quintic polynomial that matches position, velocity and acceleration at
    both (``joint_trajectory_controller``'s interpolation when points carry
    all three); clamped to the first and last point outside ``times_s``.
    """
    times = np.asarray(times_s, dtype=float)
    p, v, a = (np.asarray(x, dtype=float) for x in (positions, velocities, accelerations))
    t = np.clip(np.asarray(t_s, dtype=float).reshape(-1), times[0], times[-1])
    if len(times) == 1:
        return np.repeat(p[:1], len(t), axis=0)
    k = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2)
    span = (times[k + 1] - times[k])[:, None]
    x = (t - times[k])[:, None]
    p0, v0, a0, p1, v1, a1 = p[k], v[k], a[k], p[k + 1], v[k + 1], a[k + 1]
    d = p1 - p0
    c3 = (20.0 * d - (8.0 * v1 + 12.0 * v0) * span - (3.0 * a0 - a1) * span**2) / (2.0 * span**3)
    c4 = (-30.0 * d + (14.0 * v1 + 16.0 * v0) * span + (3.0 * a0 - 2.0 * a1) * span**2) / (2.0 * span**4)
    c5 = (12.0 * d - 6.0 * (v1 + v0) * span - (a0 - a1) * span**2) / (2.0 * span**5)
    out: np.ndarray = p0 + x * (v0 + x * (0.5 * a0 + x * (c3 + x * (c4 + x * c5))))
    return out
