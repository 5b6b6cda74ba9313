"""Inverse kinematics of the tool centre point: the configurations that put the tcp at a pose in ``world``.

Grasping and placing need them: a grasp is a tcp pose (interface.md section 1b), and the ACA looks for
the arm configurations that hold it. :class:`InverseKinematics` runs damped least squares with
Levenberg-Marquardt damping (:mod:`~clew_ros.spatial.kernels.ik`) from many seeds at once (drawn
uniformly within the joint limits from a given :class:`numpy.random.Generator`, after any seeds the
caller gives), keeps the runs that reach the target within the tolerances, and returns the *distinct*
ones: two solutions are the same when no joint differs by more than
:attr:`IKSettings.distinct_rad` (the joint distance ``max_j |q_j - q'_j|``). A redundant arm (7 joints)
has a continuum of solutions for one pose, so each seed tends to give its own. Every solution lies
within the joint limits; given a :class:`~clew_ros.spatial.checker.SpatialChecker`, only those it calls
valid (collision-free) are kept. Same generator state, same answers.

Grasping and placing: :func:`grasp_targets` turns an object pose and its grasps (tcp poses in the
object's frame, ``world.object.grasps``) into the tcp targets in ``world``; :meth:`InverseKinematics.solve_grasps`
solves them all at once.

Arms of fewer than 6 joints reach a full tcp pose only on a thin set: :meth:`InverseKinematics.solve_rows`
meets only some rows of the pose error (a level face at a height, a position), the others left where the
seed's neighbourhood puts them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.kernels import ik
from clew_ros.spatial.kernels.packed import chain_of
from clew_ros.spatial.robot import RobotModel
from clew_ros.spatial.transforms import pose_matrix

__all__ = ["LEVEL_ROWS", "POSE_ROWS", "IKSettings", "InverseKinematics", "distinct", "grasp_targets", "pose_rows"]

#: The rows of a pose error, in order: position x, y, z (m in ``world``), then the rotation vector's x, y, z
#: (rad in ``world``; its x and y are 0 exactly when the two frames differ by a turn about world z alone).
POSE_ROWS = ("x", "y", "z", "rx", "ry", "rz")


@dataclass(frozen=True)
class IKSettings:
    """How :class:`InverseKinematics` searches."""

    #: Random seeds per target (on top of the caller's): more finds more of a redundant arm's solutions and
    #: reaches awkward poses more often, at a cost proportional.
    seeds: int = 32
    #: Accepted steps per seed at most: Levenberg-Marquardt converges in 5-30 from most seeds; a seed that
    #: needs more is usually crawling along a joint limit.
    max_iterations: int = 100
    #: Initial damping added to the diagonal of ``J J^T`` (m^2 on position rows, rad^2 on rotation rows):
    #: small, so the first steps are nearly Gauss-Newton.
    damping: float = 1e-3
    #: The damping never shrinks below this after good steps: keeps the 6x6 system well conditioned near
    #: singular configurations.
    damping_min: float = 1e-9
    #: A seed whose damping must grow past this to lower the error is at a local minimum: given up.
    damping_max: float = 1e6
    #: A solution puts the tcp within this distance (m) of the target's position...
    position_tolerance_m: float = 1e-6
    #: ... and within this angle (rad) of its orientation (both far below the grasp tolerances).
    angle_tolerance_rad: float = 1e-6
    #: No joint moves more than this per step (rad, m for a prismatic joint): a linearisation holds only
    #: near the current configuration.
    max_step_rad: float = 0.5
    #: A step that lowers the squared error by less than this fraction is a stall...
    stall_ratio: float = 1e-2
    #: ... and a seed that stalls this many steps in a row is given up (it is creeping towards a local
    #: minimum, the nearest the arm gets to an unreachable target from there).
    stall_steps: int = 5
    #: Solutions closer than this joint distance (rad, m; max over joints) are one solution: well above the
    #: scatter of converged runs, below any gap worth a different plan.
    distinct_rad: float = 1e-2
    #: Whether a joint at a limit that the step would push past it is left out of the step (an active set):
    #: a target reachable only with joints at their limits is then solved (clamping the step instead leaves
    #: the error's share of those joints unmet, and the seed stalls); False: the step is only clamped.
    active_set: bool = True

    def __post_init__(self) -> None:
        for item in fields(self):
            value = getattr(self, item.name)
            if item.name == "active_set":
                if not isinstance(value, bool):
                    raise ValueError(f"IKSettings.active_set: expected true or false, got {value!r}")
            elif item.name in ("seeds", "max_iterations", "stall_steps"):
                if not isinstance(value, int) or value < 0:
                    raise ValueError(f"IKSettings.{item.name}: expected an integer >= 0, got {value!r}")
            elif not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise ValueError(f"IKSettings.{item.name}: expected a positive finite number, got {value!r}")
        if not self.damping_min <= self.damping <= self.damping_max:
            raise ValueError(
                "IKSettings.damping: expected damping_min <= damping <= damping_max, got "
                f"{self.damping_min} <= {self.damping} <= {self.damping_max}"
            )


def pose_rows(names: Sequence[str]) -> NDArray[np.bool_]:
    """The mask (6,) of the pose error's rows named (:data:`POSE_ROWS`)."""
    unknown = [name for name in names if name not in POSE_ROWS]
    if unknown or not names:
        raise ValueError(f"rows: expected names among {', '.join(POSE_ROWS)}, got {list(names)!r}")
    return np.array([row in names for row in POSE_ROWS], dtype=bool)


#: a level face at a height: the pose error's z and its rotation's x and y (its x, y and yaw free)
LEVEL_ROWS = pose_rows(("z", "rx", "ry"))


def distinct(solutions: NDArray[np.float64], distance: float) -> NDArray[np.float64]:
    """The rows of ``solutions`` (k, n) in order, dropping each one within joint distance ``distance``
    (max over joints of the absolute difference) of a row already kept."""
    kept: list[NDArray[np.float64]] = []
    for row in solutions:
        if all(float(np.max(np.abs(row - other))) > distance for other in kept):
            kept.append(row)
    return np.array(kept).reshape(-1, solutions.shape[1])


def grasp_targets(object_pose: Any, grasps: Any) -> NDArray[np.float64]:
    """The tcp poses (g, 4, 4) in ``world`` that hold each of ``grasps`` (tcp poses in the object's frame:
    a flat list of 6 numbers each, or (g, 6), as ``world.object.grasps``) when the object is at
    ``object_pose`` (a 4x4 pose or 6 numbers in ``world``)."""
    pose = _target_matrix(object_pose, "object_pose")
    try:
        flat = np.asarray(grasps, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise ValueError("grasps: expected tcp poses of 6 numbers each [x, y, z, roll, pitch, yaw]") from None
    if len(flat) == 0 or len(flat) % 6 or not np.all(np.isfinite(flat)):
        raise ValueError(
            f"grasps: expected tcp poses of 6 finite numbers each [x, y, z, roll, pitch, yaw], got {len(flat)} numbers"
        )
    return np.array([pose @ pose_matrix(row.tolist()) for row in flat.reshape(-1, 6)])


class InverseKinematics:
    """The tcp's inverse kinematics of one robot (its kinematics packed once into arrays)."""

    def __init__(self, robot: RobotModel, settings: IKSettings | None = None) -> None:
        self.robot = robot
        self.settings = settings or IKSettings()
        #: The kinematics and the solver's settings packed for the kernels (:mod:`clew_ros.spatial.kernels.ik`).
        self.chain = chain_of(robot)
        s = self.settings
        self._solver = ik.Solver(
            s.max_iterations, s.damping, s.damping_min, s.damping_max, s.position_tolerance_m, s.angle_tolerance_rad,
            s.max_step_rad, s.stall_ratio, s.stall_steps, s.active_set,
        )  # fmt: skip

    def tcp_poses(self, qs: Any) -> NDArray[np.float64]:
        """The tcp's 4x4 pose in ``world`` for every row of ``qs`` (N, n) (compiled forward kinematics)."""
        batch = np.ascontiguousarray(qs, dtype=np.float64)
        if batch.ndim != 2 or batch.shape[1] != self.robot.dof:
            raise ValueError(f"qs: expected an (N, {self.robot.dof}) array of joint values, got shape {batch.shape}")
        out_r = np.empty((len(batch), 3, 3))
        out_t = np.empty((len(batch), 3))
        ik.tcp_batch(batch, self.chain, out_r, out_t)
        out = np.zeros((len(batch), 4, 4))
        out[:, :3, :3] = out_r
        out[:, :3, 3] = out_t
        out[:, 3, 3] = 1.0
        return out

    def solve(
        self,
        target: Any,
        rng: np.random.Generator,
        *,
        seeds: Any = None,
        checker: SpatialChecker | None = None,
    ) -> NDArray[np.float64]:
        """The distinct configurations (k, n) found whose tcp is at ``target`` (a 4x4 pose in ``world`` or
        ``[x, y, z, roll, pitch, yaw]``), within the joint limits; with ``checker``, only the valid ones.
        ``seeds`` (m, n), optional, are tried first, then :attr:`IKSettings.seeds` random ones from
        ``rng``. Empty (0, n) when none is found."""
        return self.solve_many([target], rng, seeds=None if seeds is None else [seeds], checker=checker)[0]

    def solve_many(
        self,
        targets: Sequence[Any],
        rng: np.random.Generator,
        *,
        seeds: Sequence[Any] | None = None,
        checker: SpatialChecker | None = None,
    ) -> list[NDArray[np.float64]]:
        """:meth:`solve` for each target in one compiled call (``seeds``, if given, one (m, n) array per
        target, all with the same m). Random seeds are drawn for all targets at once, target by target."""
        matrices = np.array([_target_matrix(target, f"targets[{i}]") for i, target in enumerate(targets)])
        matrices = matrices.reshape(-1, 4, 4)
        n = self.robot.dof
        given = self._given_seeds(seeds, len(matrices))
        random = rng.uniform(self.robot.lower, self.robot.upper, size=(len(matrices), self.settings.seeds, n))
        all_seeds = np.ascontiguousarray(np.concatenate([given, random], axis=1))
        out_q = np.empty_like(all_seeds)
        out_ok = np.zeros(all_seeds.shape[:2], dtype=np.bool_)
        s = self.settings
        if all_seeds.shape[1] > 0 and len(matrices) > 0:
            targets = (
                np.ascontiguousarray(matrices[:, :3, :3]),
                np.ascontiguousarray(matrices[:, :3, 3]),
                np.ones(6, dtype=np.bool_),
            )
            ik.solve_batch(targets, all_seeds, self.chain, self._solver, (out_q, out_ok))
        out = []
        for t in range(len(matrices)):
            found = out_q[t][out_ok[t]]
            if checker is not None and len(found):
                found = found[checker.valid(found)]
            out.append(distinct(found, s.distinct_rad))
        return out

    def solve_rows(
        self,
        targets: Any,
        seeds: Any,
        rows: NDArray[np.bool_],
        *,
        frame: Any = None,
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """From each seed (B, n), a configuration whose ``frame`` (a 4x4 pose in the tcp's frame, default the
        tcp) meets its target (B, 4, 4) on the pose error's ``rows`` (a mask (6,), :func:`pose_rows`) within
        the tolerances, the other rows free: the damped least squares of :meth:`solve` (the same compiled
        solver, its Jacobian's free rows left out) from that one seed, within the joint limits, so the free
        rows stay near the seed's. Returns the configurations reached and whether each met its rows (an arm of
        4-5 joints holds a level face at a height, or a position, where the whole pose is out of reach).
        Deterministic: no random seeds."""
        goal = np.asarray(targets, dtype=np.float64).reshape(-1, 4, 4)
        start = np.array(seeds, dtype=np.float64).reshape(len(goal), 1, self.robot.dof)
        mask = np.ascontiguousarray(rows, dtype=np.bool_).reshape(6)
        chain = self.chain
        if frame is not None:  # the frame met instead of the tcp: the chain's tcp moved onto it
            tool = self.robot.tcp @ np.asarray(frame, dtype=np.float64).reshape(4, 4)
            chain = chain._replace(tcp_r=np.ascontiguousarray(tool[:3, :3]), tcp_t=np.ascontiguousarray(tool[:3, 3]))
        out_q = np.empty_like(start)
        out_ok = np.zeros(start.shape[:2], dtype=np.bool_)
        if len(goal):
            targets = (np.ascontiguousarray(goal[:, :3, :3]), np.ascontiguousarray(goal[:, :3, 3]), mask)
            ik.solve_batch(targets, start, chain, self._solver, (out_q, out_ok))
        return out_q[:, 0], out_ok[:, 0]

    def solve_grasps(
        self, object_pose: Any, grasps: Any, rng: np.random.Generator, *, checker: SpatialChecker | None = None
    ) -> list[NDArray[np.float64]]:
        """For each grasp (see :func:`grasp_targets`) of the object at ``object_pose``: the distinct
        configurations that hold it (as :meth:`solve`)."""
        return self.solve_many(list(grasp_targets(object_pose, grasps)), rng, checker=checker)

    def _given_seeds(self, seeds: Sequence[Any] | None, count: int) -> NDArray[np.float64]:
        n = self.robot.dof
        if seeds is None:
            return np.zeros((count, 0, n))
        try:
            given = np.array([np.asarray(row, dtype=np.float64).reshape(-1, n) for row in seeds])
        except ValueError:
            raise ValueError(
                f"seeds: expected one (m, {n}) array of joint values per target, all with the same m"
            ) from None
        if given.ndim != 3 or given.shape[0] != count or not np.all(np.isfinite(given)):
            raise ValueError(
                f"seeds: expected {count} arrays of shape (m, {n}) of finite joint values, got shape {given.shape}"
            )
        return given


def _target_matrix(target: Any, parameter: str) -> NDArray[np.float64]:
    try:
        array = np.asarray(target, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{parameter}: expected a 4x4 pose or [x, y, z, roll, pitch, yaw], got {target!r}") from None
    if array.shape == (6,) and np.all(np.isfinite(array)):
        return pose_matrix(array.tolist())
    if array.shape != (4, 4) or not np.all(np.isfinite(array)):
        raise ValueError(
            f"{parameter}: expected a 4x4 pose or [x, y, z, roll, pitch, yaw] of finite numbers, "
            f"got shape {array.shape}"
        )
    rotation = array[:3, :3]
    if not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-6) or np.linalg.det(rotation) <= 0:
        raise ValueError(f"{parameter}: expected a rigid transform (its 3x3 block a rotation)")
    return array
