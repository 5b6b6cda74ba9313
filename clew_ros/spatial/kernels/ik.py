"""Inverse kinematics of the tool centre point, damped least squares from many seeds (numba).

The conventions of :mod:`clew_ros.spatial.kernels.collide` (frames, joint origins and axes); the tcp rides
on frame ``tcp_frame`` at ``tcp_r``, ``tcp_t``. Each seed is iterated on its own: the pose error (position,
and rotation as the axis-angle vector of ``target @ current^T``), the geometric Jacobian, a damped
least-squares step ``J^T (J J^T + damping^2 I)^-1 e`` cut to ``max_step`` per joint, clamped to the
limits; it stops when within both tolerances or after ``iterations``.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numba
import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.kernels.collide import forward

if TYPE_CHECKING:
    from numba.core.decorators import _JITWrapper  # in numba's type stubs only

__all__ = ["solve_tcp"]

Array = NDArray[Any]

_jit = numba.njit(cache=True, nogil=True, error_model="numpy")
_leaf: _JITWrapper = numba.njit(  # type: ignore[call-overload]  # numba's stubs leave out its underscored options
    cache=True, nogil=True, error_model="numpy", _nrt=False
)


@_leaf
def _tcp(  # noqa: PLR0917
    frame_r: Array, frame_t: Array, tcp_frame: int, tcp_r: Array, tcp_t: Array, out_r: Array, out_t: Array
) -> None:
    fr = frame_r[tcp_frame]
    for a in range(3):
        out_t[a] = frame_t[tcp_frame, a] + fr[a, 0] * tcp_t[0] + fr[a, 1] * tcp_t[1] + fr[a, 2] * tcp_t[2]
        for c in range(3):
            out_r[a, c] = fr[a, 0] * tcp_r[0, c] + fr[a, 1] * tcp_r[1, c] + fr[a, 2] * tcp_r[2, c]


@_leaf
def _error(target_r: Array, target_t: Array, cur_r: Array, cur_t: Array, e: Array) -> float:
    """The 6-vector pose error into ``e`` (position m, rotation vector rad); returns the rotation angle."""
    for a in range(3):
        e[a] = target_t[a] - cur_t[a]
    # m = target @ cur^T
    m00 = target_r[0, 0] * cur_r[0, 0] + target_r[0, 1] * cur_r[0, 1] + target_r[0, 2] * cur_r[0, 2]
    m11 = target_r[1, 0] * cur_r[1, 0] + target_r[1, 1] * cur_r[1, 1] + target_r[1, 2] * cur_r[1, 2]
    m22 = target_r[2, 0] * cur_r[2, 0] + target_r[2, 1] * cur_r[2, 1] + target_r[2, 2] * cur_r[2, 2]
    m21 = target_r[2, 0] * cur_r[1, 0] + target_r[2, 1] * cur_r[1, 1] + target_r[2, 2] * cur_r[1, 2]
    m12 = target_r[1, 0] * cur_r[2, 0] + target_r[1, 1] * cur_r[2, 1] + target_r[1, 2] * cur_r[2, 2]
    m02 = target_r[0, 0] * cur_r[2, 0] + target_r[0, 1] * cur_r[2, 1] + target_r[0, 2] * cur_r[2, 2]
    m20 = target_r[2, 0] * cur_r[0, 0] + target_r[2, 1] * cur_r[0, 1] + target_r[2, 2] * cur_r[0, 2]
    m10 = target_r[1, 0] * cur_r[0, 0] + target_r[1, 1] * cur_r[0, 1] + target_r[1, 2] * cur_r[0, 2]
    m01 = target_r[0, 0] * cur_r[1, 0] + target_r[0, 1] * cur_r[1, 1] + target_r[0, 2] * cur_r[1, 2]
    vx, vy, vz = m21 - m12, m02 - m20, m10 - m01
    sin2 = math.sqrt(vx * vx + vy * vy + vz * vz)  # 2 sin(angle)
    angle = math.atan2(sin2, m00 + m11 + m22 - 1.0)
    if sin2 < 1e-12:
        if angle < 1.0:  # no rotation left
            e[3], e[4], e[5] = 0.0, 0.0, 0.0
            return angle
        # a half turn: the axis from the diagonal; any sign
        ax = math.sqrt(max((m00 + 1.0) / 2.0, 0.0))
        ay = math.sqrt(max((m11 + 1.0) / 2.0, 0.0))
        az = math.sqrt(max((m22 + 1.0) / 2.0, 0.0))
        e[3], e[4], e[5] = angle * ax, angle * ay, angle * az
        return angle
    scale = angle / sin2
    e[3], e[4], e[5] = vx * scale, vy * scale, vz * scale
    return angle


@_leaf
def _solve6(a: Array, b: Array, x: Array) -> None:
    """``x`` = ``a^-1 b`` for a symmetric positive definite 6x6 ``a`` (Cholesky, in place on ``a``)."""
    for i in range(6):
        for j in range(i + 1):
            total = a[i, j]
            for k in range(j):
                total -= a[i, k] * a[j, k]
            if i == j:
                a[i, i] = math.sqrt(max(total, 1e-300))
            else:
                a[i, j] = total / a[j, j]
    for i in range(6):  # L y = b
        total = b[i]
        for k in range(i):
            total -= a[i, k] * x[k]
        x[i] = total / a[i, i]
    for i in range(5, -1, -1):  # L^T x = y
        total = x[i]
        for k in range(i + 1, 6):
            total -= a[k, i] * x[k]
        x[i] = total / a[i, i]


@_jit
def solve_tcp(  # noqa: PLR0917
    seeds: Array,
    target_r: Array,
    target_t: Array,
    lower: Array,
    upper: Array,
    base_r: Array,
    base_t: Array,
    org_r: Array,
    org_t: Array,
    axes: Array,
    prismatic: Array,
    tcp_frame: int,
    tcp_r: Array,
    tcp_t: Array,
    iterations: int,
    damping: float,
    max_step: float,
    position_tolerance: float,
    angle_tolerance: float,
    out: Array,
    converged: Array,
) -> None:
    """From each row of ``seeds`` (S, n): ``out[s]`` the joint values reached, ``converged[s]`` whether the
    tcp is then within ``position_tolerance`` (m) and ``angle_tolerance`` (rad) of the target."""
    n = seeds.shape[1]
    frame_r = np.empty((n + 1, 3, 3))
    frame_t = np.empty((n + 1, 3))
    cur_r = np.empty((3, 3))
    cur_t = np.empty(3)
    e = np.empty(6)
    jac = np.zeros((6, n))
    jjt = np.empty((6, 6))
    y = np.empty(6)
    q = np.empty(n)
    for s in range(seeds.shape[0]):
        q[:] = seeds[s]
        converged[s] = False
        for _ in range(iterations + 1):
            forward(q, base_r, base_t, org_r, org_t, axes, prismatic, frame_r, frame_t)
            _tcp(frame_r, frame_t, tcp_frame, tcp_r, tcp_t, cur_r, cur_t)
            angle = _error(target_r, target_t, cur_r, cur_t, e)
            if math.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]) <= position_tolerance and angle <= angle_tolerance:
                converged[s] = True
                break
            for j in range(n):  # the geometric Jacobian; joints past the tcp's frame do not move it
                fr = frame_r[j + 1]
                z0 = fr[0, 0] * axes[j, 0] + fr[0, 1] * axes[j, 1] + fr[0, 2] * axes[j, 2]
                z1 = fr[1, 0] * axes[j, 0] + fr[1, 1] * axes[j, 1] + fr[1, 2] * axes[j, 2]
                z2 = fr[2, 0] * axes[j, 0] + fr[2, 1] * axes[j, 1] + fr[2, 2] * axes[j, 2]
                if j >= tcp_frame:
                    z0, z1, z2 = 0.0, 0.0, 0.0
                if prismatic[j]:
                    jac[0, j], jac[1, j], jac[2, j] = z0, z1, z2
                    jac[3, j], jac[4, j], jac[5, j] = 0.0, 0.0, 0.0
                else:
                    rx = cur_t[0] - frame_t[j + 1, 0]
                    ry = cur_t[1] - frame_t[j + 1, 1]
                    rz = cur_t[2] - frame_t[j + 1, 2]
                    jac[0, j], jac[1, j], jac[2, j] = z1 * rz - z2 * ry, z2 * rx - z0 * rz, z0 * ry - z1 * rx
                    jac[3, j], jac[4, j], jac[5, j] = z0, z1, z2
            for a in range(6):
                for c in range(6):
                    total = damping * damping if a == c else 0.0
                    for j in range(n):
                        total += jac[a, j] * jac[c, j]
                    jjt[a, c] = total
            _solve6(jjt, e, y)
            for j in range(n):
                step = 0.0
                for a in range(6):
                    step += jac[a, j] * y[a]
                step = min(max(step, -max_step), max_step)
                q[j] = min(max(q[j] + step, lower[j]), upper[j])
        out[s] = q
