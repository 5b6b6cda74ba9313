"""Kinematics of the planar chain, compiled: forward kinematics (one tip, every joint) and the inverse
kinematics of one tool point per row (damped least squares within the joint limits)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from clew_ros.planar.kernel.jit import _jit, _leaf
from clew_ros.planar.kernel.packed import Chain, Solving, _arg, plain

_TWO_PI = 2.0 * math.pi
#: Limits at least this far apart (rad) let a joint turn all the way round (worlds write +-3.14159, just inside
#: pi): inverse kinematics takes such a joint past one limit to the same angle a turn short of the other.
FULL_TURN_RAD = _TWO_PI - 1e-3


@_leaf
def _forward(q: np.ndarray, base: np.ndarray, lengths: np.ndarray, links: np.ndarray) -> tuple[float, float, float]:
    """Forward kinematics of configuration ``q (n,)``: the links as segments ``links (n, 2, 2)``
    (world frame), and the end-effector frame ``(x, y, theta)``."""
    x, y, phi = base[0], base[1], 0.0
    for i in range(lengths.shape[0]):
        phi += q[i]
        nx, ny = x + lengths[i] * math.cos(phi), y + lengths[i] * math.sin(phi)
        links[i, 0, 0], links[i, 0, 1], links[i, 1, 0], links[i, 1, 1] = x, y, nx, ny
        x, y = nx, ny
    return x, y, phi


@_jit
def _chain(q: np.ndarray, base: np.ndarray, lengths: np.ndarray, points: np.ndarray, tips: np.ndarray) -> None:
    """Joint positions ``points (B, n + 1, 2)`` and end-effector frames ``tips (B, 3)`` of ``q (B, n)``."""
    links = np.empty((lengths.shape[0], 2, 2))
    for b in range(q.shape[0]):
        tips[b, 0], tips[b, 1], tips[b, 2] = _forward(q[b], base, lengths, links)
        points[b, 0, 0], points[b, 0, 1] = base[0], base[1]
        for i in range(lengths.shape[0]):
            points[b, i + 1, 0], points[b, i + 1, 1] = links[i, 1, 0], links[i, 1, 1]


@_leaf
def _within_limits(angle: float, lower: float, upper: float, full_turns: bool) -> float:
    """``angle`` stopped at the limits; but with ``full_turns``, on a joint that turns all the way round
    (:data:`FULL_TURN_RAD`), past one limit it goes on a turn back from the other (the same angle, to within the
    gap between the limits, where it stops; ``angle`` is less than a turn past)."""
    if full_turns and upper - lower >= FULL_TURN_RAD:
        if angle > upper:
            angle -= _TWO_PI
        elif angle < lower:
            angle += _TWO_PI
    return min(max(angle, lower), upper)


@_jit
def _solve_point(  # noqa: PLR0915 - one compiled loop per row: kinematics, Jacobian, a 2x2 or 3x3 solve, the step
    q: np.ndarray,
    targets: np.ndarray,
    offsets: np.ndarray,
    angles: np.ndarray,
    chain: tuple[Any, ...],
    solving: tuple[Any, ...],
    error: np.ndarray,
    steps: np.ndarray,
) -> None:
    """Damped least squares, in place on ``q (B, n)``: the point ``offsets[b]`` of the end-effector frame
    to ``targets[b]``, and (``angles[b]`` not NaN) the frame's angle within ``angle_tolerance`` of it;
    a row stops once its error is at most ``tolerance``; a step past a limit is :func:`_within_limits`.
    ``error[b]``: what is left (m; the angle's excess counts ``angle_scale`` m per rad); ``steps[b]``: the
    steps taken. ``chain`` and ``solving``: a :class:`~.packed.Chain` and :class:`~.packed.Solving` as plain tuples.
    """
    base, lengths, lower, upper = Chain(*chain)
    angle_tolerance, angle_scale, iterations, damping, max_step, tolerance, full_turns = Solving(*solving)
    n = lengths.shape[0]
    px = np.empty(n)
    py = np.empty(n)
    jx = np.empty(n)
    jy = np.empty(n)
    for b in range(q.shape[0]):
        use_angle = angles[b] == angles[b]
        for it in range(iterations + 1):
            x, y, phi = base[0], base[1], 0.0
            for i in range(n):
                px[i], py[i] = x, y
                phi += q[b, i]
                x += lengths[i] * math.cos(phi)
                y += lengths[i] * math.sin(phi)
            c, s = math.cos(phi), math.sin(phi)
            x += c * offsets[b, 0] - s * offsets[b, 1]
            y += s * offsets[b, 0] + c * offsets[b, 1]
            ex, ey, et = x - targets[b, 0], y - targets[b, 1], 0.0
            if use_angle:
                turn = phi - angles[b]
                turn -= _TWO_PI * math.floor((turn + math.pi) / _TWO_PI)
                if turn > angle_tolerance:
                    et = angle_scale * (turn - angle_tolerance)
                elif turn < -angle_tolerance:
                    et = angle_scale * (turn + angle_tolerance)
            error[b] = math.sqrt(ex * ex + ey * ey + et * et)
            steps[b] = it
            if it == iterations or error[b] <= tolerance:
                break
            a11 = a12 = a22 = a13 = a23 = 0.0
            for i in range(n):
                jx[i], jy[i] = py[i] - y, x - px[i]
                a11 += jx[i] * jx[i]
                a12 += jx[i] * jy[i]
                a22 += jy[i] * jy[i]
                a13 += jx[i] * angle_scale
                a23 += jy[i] * angle_scale
            a11 += damping
            a22 += damping
            if use_angle:
                a33 = n * angle_scale * angle_scale + damping
                c11, c12, c13 = a22 * a33 - a23 * a23, a13 * a23 - a12 * a33, a12 * a23 - a13 * a22
                c22, c23, c33 = a11 * a33 - a13 * a13, a12 * a13 - a11 * a23, a11 * a22 - a12 * a12
                det = a11 * c11 + a12 * c12 + a13 * c13
                w1 = (c11 * ex + c12 * ey + c13 * et) / det
                w2 = (c12 * ex + c22 * ey + c23 * et) / det
                w3 = (c13 * ex + c23 * ey + c33 * et) / det
            else:
                det = a11 * a22 - a12 * a12
                w1 = (a22 * ex - a12 * ey) / det
                w2 = (a11 * ey - a12 * ex) / det
                w3 = 0.0
            largest = 0.0
            for i in range(n):
                jx[i] = -(jx[i] * w1 + jy[i] * w2 + angle_scale * w3)  # the step, in place
                largest = max(largest, abs(jx[i]))
            scale = min(1.0, max_step / largest) if largest > 0.0 else 0.0
            for i in range(n):
                q[b, i] = _within_limits(q[b, i] + scale * jx[i], lower[i], upper[i], full_turns)


def chain(base: np.ndarray, lengths: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Compiled forward kinematics: joint positions ``(B, n + 1, 2)`` and tip frames ``(B, 3)``."""
    q = _arg(q)
    points = np.empty((len(q), len(lengths) + 1, 2))
    tips = np.empty((len(q), 3))
    _chain(q, base, lengths, points, tips)
    return points, tips


def solve_point(
    chain: Chain, seeds: np.ndarray, targets: np.ndarray, offsets: np.ndarray, angles: np.ndarray, solving: Solving
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Compiled damped least squares from ``seeds (B, n)`` (see :func:`clew_ros.planar.inverse.solve_point`):
    the configurations, the error left and the steps taken ``(B,)``."""
    q = np.array(seeds, dtype=np.float64, order="C")
    error = np.empty(len(q))
    steps = np.zeros(len(q), dtype=np.int64)
    chain = Chain(*(_arg(array) for array in chain))
    solving = Solving(
        float(solving.angle_tolerance),
        float(solving.angle_scale),
        int(solving.iterations),
        float(solving.damping),
        float(solving.max_step),
        float(solving.tolerance),
        bool(solving.full_turns),
    )
    _solve_point(q, _arg(targets), _arg(offsets), _arg(angles), plain(chain), plain(solving), error, steps)
    return q, error, steps
