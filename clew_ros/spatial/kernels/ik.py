"""Inverse kinematics of the tool centre point, batched over targets and seeds (numba).

Damped least squares with Levenberg-Marquardt damping, projected onto the joint limits: from each seed,
``dq = J^T (J J^T + lambda I)^-1 e`` where ``e`` (6) is the pose error in ``world`` (position, then the
rotation vector of ``R_target R^T``) and ``J`` (6, n) the geometric Jacobian of the tcp; a step that
lowers ``|e|^2`` is taken (clamped to the limits) and ``lambda`` shrinks, one that does not is refused
and ``lambda`` grows (with ``active_set``, joints at a limit that the step would push past it are left out
of ``J``); past ``damping_max`` the seed is given up (a local minimum: the target is out of
reach from there), as it is after ``stall_steps`` steps in a row that each lower ``|e|^2`` by less than
the fraction ``stall_ratio`` (creeping towards such a minimum). Some rows of ``e`` may be left free (a
level face at any yaw, a position at any orientation): then only the others count, and the Jacobian's rotation
rows are the rotation vector's own derivative (:func:`_partial_rows`). Frames as in
:mod:`~clew_ros.spatial.kernels.collide` (:func:`forward`); the tcp is ``tcp_r``, ``tcp_t`` in frame
``tcp_frame`` of the :class:`~clew_ros.spatial.kernels.packed.Chain`; the settings come packed as a
:class:`Solver`.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.kernels.collide import _leaf, forward  # helpers that allocate nothing: no reference counting
from clew_ros.spatial.kernels.packed import Chain

__all__ = ["Solver", "pose_error", "solve_batch", "tcp_batch"]

Array = NDArray[Any]

_jit = numba.njit(cache=True, nogil=True, error_model="numpy")


class Solver(NamedTuple):
    """The solver's settings (:class:`clew_ros.spatial.inverse.IKSettings`), packed for :func:`solve_batch`."""

    max_iterations: int
    damping: float
    damping_min: float
    damping_max: float
    position_tolerance: float
    angle_tolerance: float
    max_step: float
    stall_ratio: float
    stall_steps: int
    active_set: bool


@_leaf
def _tcp(chain: Chain, frame_r: Array, frame_t: Array, out_r: Array, out_t: Array) -> None:
    tcp_r, tcp_t = chain.tcp_r, chain.tcp_t
    fr = frame_r[chain.tcp_frame]
    ft = frame_t[chain.tcp_frame]
    for a in range(3):
        out_t[a] = fr[a, 0] * tcp_t[0] + fr[a, 1] * tcp_t[1] + fr[a, 2] * tcp_t[2] + ft[a]
        for c in range(3):
            out_r[a, c] = fr[a, 0] * tcp_r[0, c] + fr[a, 1] * tcp_r[1, c] + fr[a, 2] * tcp_r[2, c]


@_leaf
def pose_error(target: Any, pose: Any, m: Array, out: Array) -> float:
    """``out`` (6): for ``target`` and ``pose`` (``(rotation, translation)`` each), the position error
    ``target_t - t`` (m) and the rotation vector (rad) of ``target_r r^T`` (the rotation that takes ``r`` onto
    ``target_r``, in ``world``); returns ``|out|^2``. ``m`` (3, 3) is scratch."""
    target_r, target_t = target
    r, t = pose
    for a in range(3):
        out[a] = target_t[a] - t[a]
    # m = target_r @ r^T
    for a in range(3):
        for c in range(3):
            m[a, c] = target_r[a, 0] * r[c, 0] + target_r[a, 1] * r[c, 1] + target_r[a, 2] * r[c, 2]
    sx = 0.5 * (m[2, 1] - m[1, 2])
    sy = 0.5 * (m[0, 2] - m[2, 0])
    sz = 0.5 * (m[1, 0] - m[0, 1])
    sin = math.sqrt(sx * sx + sy * sy + sz * sz)
    cos = 0.5 * (m[0, 0] + m[1, 1] + m[2, 2] - 1.0)
    angle = math.atan2(sin, cos)
    if sin > 1e-6:
        scale = angle / sin
        out[3], out[4], out[5] = sx * scale, sy * scale, sz * scale
    elif cos > 0.0:  # nearly no rotation: the rotation vector is s to first order
        out[3], out[4], out[5] = sx, sy, sz
    else:  # nearly a half turn: the axis from the symmetric part, (m + m^T) / 2 - cos I = (1 - cos) a a^T
        k = 0
        for a in range(1, 3):
            if m[a, a] > m[k, k]:
                k = a
        bkk = m[k, k] - cos
        norm = math.sqrt(max(bkk * (1.0 - cos), 1e-300))
        ax = (0.5 * (m[0, k] + m[k, 0]) - (cos if k == 0 else 0.0)) / norm
        ay = (0.5 * (m[1, k] + m[k, 1]) - (cos if k == 1 else 0.0)) / norm
        az = (0.5 * (m[2, k] + m[k, 2]) - (cos if k == 2 else 0.0)) / norm
        if ax * sx + ay * sy + az * sz < 0.0:
            ax, ay, az = -ax, -ay, -az
        out[3], out[4], out[5] = ax * angle, ay * angle, az * angle
    total = 0.0
    for a in range(6):
        total += out[a] * out[a]
    return total


@_leaf
def _jacobian(chain: Chain, frame_r: Array, frame_t: Array, p: Array, out: Array) -> None:
    """The geometric Jacobian (6, n) of the tcp at ``p``: joint j turns about (or slides along) its axis
    through frame j + 1's origin; joints past ``tcp_frame`` do not move it."""
    axes, prismatic, tcp_frame = chain.axes, chain.prismatic, chain.tcp_frame
    n = axes.shape[0]
    for j in range(n):
        if j >= tcp_frame:
            for a in range(6):
                out[a, j] = 0.0
            continue
        r = frame_r[j + 1]
        zx = r[0, 0] * axes[j, 0] + r[0, 1] * axes[j, 1] + r[0, 2] * axes[j, 2]
        zy = r[1, 0] * axes[j, 0] + r[1, 1] * axes[j, 1] + r[1, 2] * axes[j, 2]
        zz = r[2, 0] * axes[j, 0] + r[2, 1] * axes[j, 1] + r[2, 2] * axes[j, 2]
        if prismatic[j]:
            out[0, j], out[1, j], out[2, j] = zx, zy, zz
            out[3, j] = out[4, j] = out[5, j] = 0.0
            continue
        dx = p[0] - frame_t[j + 1, 0]
        dy = p[1] - frame_t[j + 1, 1]
        dz = p[2] - frame_t[j + 1, 2]
        out[0, j] = zy * dz - zz * dy
        out[1, j] = zz * dx - zx * dz
        out[2, j] = zx * dy - zy * dx
        out[3, j], out[4, j], out[5, j] = zx, zy, zz


@_leaf
def _cholesky(a: Array) -> bool:
    """Factor the symmetric 6x6 ``a`` (its lower triangle) in place into ``L`` with ``L L^T = a``; False
    when it is not positive definite (the damping too small for the rounding)."""
    for r in range(6):
        for c in range(r + 1):
            s = a[r, c]
            for k in range(c):
                s -= a[r, k] * a[c, k]
            if r == c:
                if s <= 0.0:
                    return False
                a[r, r] = math.sqrt(s)
            else:
                a[r, c] = s / a[c, c]
    return True


@_leaf
def _solve_factored(a: Array, e: Array, y: Array) -> None:
    """``y = (L L^T)^-1 e`` for the factor ``L`` in the lower triangle of ``a``."""
    for r in range(6):
        s = e[r]
        for k in range(r):
            s -= a[r, k] * y[k]
        y[r] = s / a[r, r]
    for r in range(5, -1, -1):
        s = y[r]
        for k in range(r + 1, 6):
            s -= a[k, r] * y[k]
        y[r] = s / a[r, r]


@_leaf
def _damped_step(jac: Array, e: Array, damping: float, scratch: Array, out: Array) -> bool:
    """``out = J^T (J J^T + damping I)^-1 e``; ``scratch`` (7, 6): the system and its solution. False when
    the system is not positive definite."""
    n = jac.shape[1]
    a = scratch[:6]
    y = scratch[6]
    for r in range(6):
        for c in range(r + 1):
            s = 0.0
            for j in range(n):
                s += jac[r, j] * jac[c, j]
            a[r, c] = s
        a[r, r] += damping
    if not _cholesky(a):
        return False
    _solve_factored(a, e, y)
    for j in range(n):
        s = 0.0
        for r in range(6):
            s += jac[r, j] * y[r]
        out[j] = s
    return True


@_leaf
def _within(e: Array, rows: Array, position2: float, angle2: float) -> bool:
    """Whether the pose error ``e`` on ``rows`` is within the squared tolerances (position, then angle)."""
    if rows.all():
        return bool(
            e[0] * e[0] + e[1] * e[1] + e[2] * e[2] <= position2 and e[3] * e[3] + e[4] * e[4] + e[5] * e[5] <= angle2
        )
    position = angle = 0.0
    for a in range(3):
        if rows[a]:
            position += e[a] * e[a]
        if rows[a + 3]:
            angle += e[a + 3] * e[a + 3]
    return position <= position2 and angle <= angle2


@_leaf
def _clamped_step(q: Array, dq: Array, max_step: float, chain: Chain, out: Array) -> None:
    """``out = q + dq``, ``dq`` scaled down so no joint moves more than ``max_step``, clamped to the limits."""
    lower, upper = chain.lower, chain.upper
    biggest = 0.0
    for j in range(q.shape[0]):
        biggest = max(biggest, abs(dq[j]))
    scale = max_step / biggest if biggest > max_step else 1.0
    for j in range(q.shape[0]):
        out[j] = min(max(q[j] + scale * dq[j], lower[j]), upper[j])


@_leaf
def _free_limits(solver: Solver, chain: Chain, damping: float, state: Any) -> None:
    """Zero the Jacobian's columns of the joints at a limit that the damped step would push past it: the
    step is then taken by the other joints (an active set), where clamping it would leave the error's share
    of those joints unmet and stall (a target reachable only with joints at their limits, as a generated
    world's hold may be); nothing without ``active_set``. ``state``: ``(jac, e, q, scratch, dq)``, ``dq``
    scratch."""
    jac, e, q, scratch, dq = state
    lower, upper = chain.lower, chain.upper
    if not solver.active_set or not _damped_step(jac, e, damping, scratch, dq):
        return
    for j in range(q.shape[0]):
        if (q[j] <= lower[j] and dq[j] < 0.0) or (q[j] >= upper[j] and dq[j] > 0.0):
            for a in range(6):
                jac[a, j] = 0.0


@_leaf
def _partial_rows(rows: Array, e: Array, jac: Array) -> None:
    """The Jacobian ``jac`` (6, n) made the derivative of the rows ``rows`` of the pose error, the others 0 (then
    ``J J^T + damping I`` keeps only the damping there and the step ignores them). Its rotation rows turn from
    the tcp's angular velocity into the derivative of the rotation vector ``phi = e[3:]``:
    ``J_r^-1(phi) w``, ``J_r^-1(phi) = I + [phi]/2 + (1/t^2 - (1 + cos t) / (2 t sin t)) [phi]^2``, ``t = |phi|``.
    A whole pose keeps the angular velocity (the two agree where the error vanishes): a few rows left free
    leave the rotation error large where the rows met converge, as a level face at any yaw."""
    px, py, pz = e[3], e[4], e[5]
    t2 = px * px + py * py + pz * pz
    t = math.sqrt(t2)
    c = 0.0
    if t > 1e-6:
        c = 1.0 / t2 - (1.0 + math.cos(t)) / (2.0 * t * math.sin(t)) if math.sin(t) > 1e-9 else 1.0 / t2
    for j in range(jac.shape[1]):
        wx, wy, wz = jac[3, j], jac[4, j], jac[5, j]
        cx, cy, cz = py * wz - pz * wy, pz * wx - px * wz, px * wy - py * wx  # phi x w
        dx, dy, dz = py * cz - pz * cy, pz * cx - px * cz, px * cy - py * cx  # phi x (phi x w)
        jac[3, j] = wx + 0.5 * cx + c * dx
        jac[4, j] = wy + 0.5 * cy + c * dy
        jac[5, j] = wz + 0.5 * cz + c * dz
    for a in range(6):
        if not rows[a]:
            for j in range(jac.shape[1]):
                jac[a, j] = 0.0


@_leaf
def _masked_cost(e: Array, rows: Array, total: float) -> float:
    """``total`` (``|e|^2``) or, when some rows are free, the squares of ``e`` on ``rows`` alone."""
    if rows.all():
        return total
    total = 0.0
    for a in range(6):
        if rows[a]:
            total += e[a] * e[a]
    return total


@_jit
def solve_batch(  # noqa: C901, PLR0912, PLR0915  # one loop: split into calls it ran 40 % slower
    targets: Any, seeds: Array, chain: Chain, solver: Solver, out: Any
) -> None:
    """For target ``t`` (``targets``: ``(rotations (T, 3, 3), translations (T, 3) m, rows (6,))``) and seed ``s``
    (``seeds[t, s]``, n), into ``out`` (``(q, ok)``): ``q[t, s]`` the configuration reached (within the limits)
    and ``ok[t, s]`` whether its tcp is within ``position_tolerance`` (m) and ``angle_tolerance`` (rad) of
    the target on the pose error's ``rows`` (the mask of :data:`clew_ros.spatial.inverse.POSE_ROWS` met; the
    others free)."""
    targets_r, targets_t, rows = targets
    out_q, out_ok = out
    lower, upper = chain.lower, chain.upper
    n = seeds.shape[2]
    frame_r = np.empty((n + 1, 3, 3))
    frame_t = np.empty((n + 1, 3))
    pr = np.empty((3, 3))
    pt = np.empty(3)
    m = np.empty((3, 3))
    jac = np.empty((6, n))
    scratch = np.empty((7, 6))
    e = np.empty(6)
    e_trial = np.empty(6)
    q = np.empty(n)
    trial = np.empty(n)
    dq = np.empty(n)
    tol_p2 = solver.position_tolerance * solver.position_tolerance
    tol_r2 = solver.angle_tolerance * solver.angle_tolerance
    every_row = rows.all()
    for t in range(seeds.shape[0]):
        target = (targets_r[t], targets_t[t])
        for s in range(seeds.shape[1]):
            for j in range(n):
                q[j] = min(max(seeds[t, s, j], lower[j]), upper[j])
            forward(q, chain, frame_r, frame_t)
            _tcp(chain, frame_r, frame_t, pr, pt)
            cost = _masked_cost(e, rows, pose_error(target, (pr, pt), m, e))
            lam = solver.damping
            stalls = 0
            for _ in range(solver.max_iterations):
                if _within(e, rows, tol_p2, tol_r2):
                    break
                _jacobian(chain, frame_r, frame_t, pt, jac)
                if not every_row:
                    _partial_rows(rows, e, jac)
                _free_limits(solver, chain, lam, (jac, e, q, scratch, dq))
                improved = False
                while lam <= solver.damping_max:
                    if not _damped_step(jac, e, lam, scratch, dq):
                        lam *= 10.0
                        continue
                    _clamped_step(q, dq, solver.max_step, chain, trial)
                    forward(trial, chain, frame_r, frame_t)
                    _tcp(chain, frame_r, frame_t, pr, pt)
                    trial_cost = _masked_cost(e_trial, rows, pose_error(target, (pr, pt), m, e_trial))
                    if trial_cost < cost:
                        improved = True
                        stalls = stalls + 1 if trial_cost > cost * (1.0 - solver.stall_ratio) else 0
                        cost = trial_cost
                        for j in range(n):
                            q[j] = trial[j]
                        for k in range(6):
                            e[k] = e_trial[k]
                        lam = max(lam * 0.1, solver.damping_min)
                        break
                    lam *= 10.0
                if not improved or stalls >= solver.stall_steps:
                    break
            for j in range(n):
                out_q[t, s, j] = q[j]
            out_ok[t, s] = _within(e, rows, tol_p2, tol_r2)


@_jit
def tcp_batch(qs: Array, chain: Chain, out_r: Array, out_t: Array) -> None:
    """The tcp pose (``out_r[b]`` 3x3, ``out_t[b]`` m, in ``world``) of every row of ``qs`` (N, n)."""
    n = qs.shape[1]
    frame_r = np.empty((n + 1, 3, 3))
    frame_t = np.empty((n + 1, 3))
    for b in range(qs.shape[0]):
        forward(qs[b], chain, frame_r, frame_t)
        _tcp(chain, frame_r, frame_t, out_r[b], out_t[b])
