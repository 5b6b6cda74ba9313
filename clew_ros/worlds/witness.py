"""The witness: a random manipulation simulated from the start, whose end placement becomes the goal.

It is simulated in the world without obstacles (only bounds, joint limits, self-collision and the
object at rest or held count, exactly section 1's validity test), then the layout is built around it:

1. a grasping configuration is drawn first, and the object's start placement is where that
   configuration holds one of its grasps (approached within :data:`MAX_APPROACH_RAD` of the edge's
   outward normal);
2. the arm's start configuration is drawn so that a straight transit reaches the grasp;
3. each transfer is a few random straight joint-space moves, picked among valid candidates for how
   far they carry the object;
4. the object is released where the transfer ends; a regrasp takes it again by another grasp, or by
   the same one from another direction, at a configuration found by sampling the first n - 2 joints
   and solving the last two in closed form, reached by a straight transit or one through a waypoint.

Every straight piece is checked at :data:`~clew_ros.planar.plan.CHECK_STEP_RAD` with
:func:`~clew_ros.planar.collision.is_valid`, many candidates in one call. :func:`simulate` returns the
segments as a :class:`~clew_ros.core.plan.Plan` would hold them, or raises :class:`WitnessError`
when a step found no valid candidate (the generator then starts over with the next random stream).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from clew_ros.core.plan import PlanSegment
from clew_ros.planar.collision import is_valid
from clew_ros.planar.kinematics import compose, relative, tip_poses, transform_points, wrap_angle
from clew_ros.planar.plan import CHECK_STEP_RAD
from clew_ros.planar.world import World
from clew_ros.worlds.shapes import ObjectShape

__all__ = [
    "MAX_APPROACH_RAD",
    "Witness",
    "WitnessError",
    "grasp_configurations",
    "grasp_relation",
    "random_configurations",
    "simulate",
    "transfer_valid",
    "transit_valid",
]

#: Largest angle (rad) between the last link, pointing back from the tip, and the grasped edge's normal.
MAX_APPROACH_RAD = 1.1
#: Smallest change of approach angle (rad) that makes taking the same grasp again a regrasp.
MIN_REGRASP_TURN_RAD = 0.5
#: Times a transfer is drawn again when no regrasp follows from where it left the object.
REGRASP_ATTEMPTS = 6
#: Candidates drawn per step (one batch of validity tests each).
CANDIDATES = 48


class WitnessError(Exception):
    """A step of the simulation found no valid candidate."""


@dataclass(frozen=True, eq=False)
class Witness:
    """The simulated manipulation: the arm's start ``initial`` (n,) rad, the object's start
    ``object_initial`` (3,), and the plan's ``segments`` from there."""

    initial: np.ndarray
    object_initial: np.ndarray
    segments: tuple[PlanSegment, ...]


def grasp_relation(shape: ObjectShape, grasp: int, approach: float) -> np.ndarray:
    """The object's pose (3,) in the end-effector frame when the tip holds ``grasp`` exactly and the last
    link comes in at ``approach`` rad from the edge's outward normal."""
    normal, point = shape.normals[grasp], shape.grasps[grasp]
    theta = math.pi + approach - math.atan2(normal[1], normal[0])
    c, s = math.cos(theta), math.sin(theta)
    return np.array([-(c * point[0] - s * point[1]), -(s * point[0] + c * point[1]), theta])


def _approach(shape: ObjectShape, object_poses: np.ndarray, grasps: np.ndarray, last_link: np.ndarray) -> np.ndarray:
    """Angle (rad) between the last link (pointing back from the tip) and the normal of each grasp's edge."""
    normal = shape.normals[grasps]
    normal_angle = object_poses[..., 2] + np.arctan2(normal[..., 1], normal[..., 0])
    approach: np.ndarray = wrap_angle(normal_angle - last_link - math.pi)
    return approach


#: Steps (rad per joint) of the successive checks of a batch of straight pieces: coarse ones first
#: drop most invalid candidates cheaply, the last one is the validator's.
CHECK_STEPS_RAD = (0.1, 0.02, CHECK_STEP_RAD)


def _pieces(starts: np.ndarray, ends: np.ndarray, step: float) -> tuple[np.ndarray, np.ndarray]:
    """Configurations along the straight pieces ``starts[k] -> ends[k]`` ``(K, n)``, at most ``step``
    rad apart per joint, both ends included, and the piece of each one."""
    counts = np.maximum(1, np.ceil(np.abs(ends - starts).max(axis=1) / step).astype(int))
    piece = np.repeat(np.arange(len(starts)), counts + 1)
    offsets = np.cumsum(counts + 1) - (counts + 1)
    t = (np.arange(len(piece)) - offsets[piece]) / counts[piece]
    configurations = starts[piece] + t[:, None] * (ends[piece] - starts[piece])
    return configurations, piece


def _pieces_valid(
    world: World,
    starts: np.ndarray,
    ends: np.ndarray,
    object_poses: Callable[[np.ndarray], np.ndarray],
    steps: tuple[float, ...] = CHECK_STEPS_RAD,
) -> np.ndarray:
    """Whether each straight piece ``starts[k] -> ends[k]`` is valid at every configuration
    ``steps[-1]`` rad apart, the object at ``object_poses(configurations)``."""
    starts = np.atleast_2d(starts)
    ends = np.broadcast_to(ends, starts.shape)
    ok = np.ones(len(starts), dtype=bool)
    for step in steps:
        alive = np.flatnonzero(ok)
        if not len(alive):
            break
        configurations, piece = _pieces(starts[alive], ends[alive], step)
        valid = is_valid(world, configurations, object_poses(configurations))
        ok[alive[np.unique(piece[~valid])]] = False
    return ok


def _first_valid(
    world: World,
    starts: np.ndarray,
    ends: np.ndarray,
    object_poses: Callable[[np.ndarray], np.ndarray],
    order: np.ndarray | None = None,
) -> int | None:
    """The first piece, in ``order`` (default: as given), that is valid at :data:`CHECK_STEP_RAD`, or
    ``None``: the coarse checks on all of them, the fine one a few at a time."""
    starts = np.atleast_2d(starts)
    ends = np.broadcast_to(ends, starts.shape)
    order = np.arange(len(starts)) if order is None else order
    coarse = _pieces_valid(world, starts, ends, object_poses, CHECK_STEPS_RAD[:-1])
    alive = order[coarse[order]]
    for batch in range(0, len(alive), 4):
        chosen = alive[batch : batch + 4]
        fine = _pieces_valid(world, starts[chosen], ends[chosen], object_poses, CHECK_STEPS_RAD[-1:])
        if fine.any():
            return int(chosen[int(np.argmax(fine))])
    return None


def _resting(object_pose: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    return lambda configurations: object_pose


def _held(world: World, grasp_rel: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    return lambda configurations: compose(tip_poses(world.robot, configurations), grasp_rel)


def transit_valid(world: World, starts: np.ndarray, ends: np.ndarray, object_pose: np.ndarray) -> np.ndarray:
    """Whether each straight transit ``starts[k] -> ends[k]`` is valid with the object at rest at ``object_pose``."""
    return _pieces_valid(world, starts, ends, _resting(object_pose))


def transfer_valid(world: World, starts: np.ndarray, ends: np.ndarray, grasp_rel: np.ndarray) -> np.ndarray:
    """Whether each straight transfer ``starts[k] -> ends[k]`` is valid, the object held as ``grasp_rel``."""
    return _pieces_valid(world, starts, ends, _held(world, grasp_rel))


def random_configurations(world: World, rng: np.random.Generator, count: int) -> np.ndarray:
    """``count`` configurations within the joint limits: joint 1 uniform, the others half uniform and half
    near 0 (an arm stretched out more often than a uniform draw gives)."""
    lower, upper = world.robot.joint_lower, world.robot.joint_upper
    uniform = rng.uniform(lower, upper, (count, len(lower)))
    stretched = rng.normal(0.0, 0.8, (count, len(lower)))
    q = np.where(rng.random((count, 1)) < 0.5, uniform, stretched)
    q[:, 0] = uniform[:, 0]
    clipped: np.ndarray = np.clip(q, lower, upper)
    return clipped


def grasp_configurations(
    world: World, shape: ObjectShape, object_pose: np.ndarray, rng: np.random.Generator, count: int = 2048
) -> tuple[np.ndarray, np.ndarray]:
    """Valid configurations whose tip holds a grasp of the object resting at ``object_pose``, and the grasps.

    The first n - 2 joints are drawn (:func:`random_configurations`), the last two solved in closed
    form for the tip at the grasp (either elbow); kept when within the joint limits, approaching within
    :data:`MAX_APPROACH_RAD` of the edge's normal and valid. Returns ``(q (M, n), grasps (M,))``, M <= ``count``.
    """
    robot = world.robot
    n = robot.dof
    lengths = robot.link_lengths
    grasps = rng.integers(0, len(shape.grasps), count)
    targets = transform_points(np.asarray(object_pose, float), shape.grasps)[grasps]
    free = random_configurations(world, rng, count)[:, : n - 2]
    angles = np.cumsum(free, axis=1)
    wrist = robot.base + np.stack(
        [(lengths[: n - 2] * np.cos(angles)).sum(axis=1), (lengths[: n - 2] * np.sin(angles)).sum(axis=1)], axis=1
    )
    heading = angles[:, -1] if n > 2 else np.zeros(count)
    l1, l2 = float(lengths[n - 2]), float(lengths[n - 1])
    to_target = targets - wrist
    cosine = (np.einsum("ij,ij->i", to_target, to_target) - l1 * l1 - l2 * l2) / (2 * l1 * l2)
    reachable = np.abs(cosine) <= 1.0
    elbow = np.where(rng.random(count) < 0.5, -1.0, 1.0) * np.arccos(np.clip(cosine, -1.0, 1.0))
    shoulder = wrap_angle(
        np.arctan2(to_target[:, 1], to_target[:, 0]) - np.arctan2(l2 * np.sin(elbow), l1 + l2 * np.cos(elbow)) - heading
    )
    q = np.concatenate([free, shoulder[:, None], elbow[:, None]], axis=1)
    keep = reachable & np.all((q >= robot.joint_lower) & (q <= robot.joint_upper), axis=1)
    q, grasps = q[keep], grasps[keep]
    poses = np.broadcast_to(np.asarray(object_pose, float), (len(q), 3))
    approach = _approach(shape, poses, grasps, tip_poses(robot, q)[:, 2]) if len(q) else np.zeros(0)
    keep = np.abs(approach) <= MAX_APPROACH_RAD
    q, grasps = q[keep], grasps[keep]
    if len(q):
        keep = is_valid(world, q, poses[: len(q)])
        q, grasps = q[keep], grasps[keep]
    return q, grasps


class _Simulation:
    """One witness being simulated: the arm's configuration, where the object is, the segments so far."""

    def __init__(self, world: World, shape: ObjectShape, rng: np.random.Generator) -> None:
        self.world = world
        self.shape = shape
        self.rng = rng
        self.segments: list[PlanSegment] = []

    def first_grasp(self) -> tuple[np.ndarray, int, np.ndarray]:
        """A grasping configuration, its grasp, and the object's start placement it holds."""
        world, shape, rng = self.world, self.shape, self.rng
        q = random_configurations(world, rng, CANDIDATES * 4)
        grasps = rng.integers(0, len(shape.grasps), len(q))
        approach = rng.uniform(-MAX_APPROACH_RAD, MAX_APPROACH_RAD, len(q)) * 0.8
        relations = np.array([grasp_relation(shape, int(g), float(a)) for g, a in zip(grasps, approach, strict=True)])
        poses = compose(tip_poses(world.robot, q), relations)
        valid = np.flatnonzero(is_valid(world, q, poses))
        if not len(valid):
            raise WitnessError("no configuration holds a grasp of a valid start placement")
        pick = int(valid[0])
        return q[pick], int(grasps[pick]), poses[pick]

    def start(self, grasping: np.ndarray, object_pose: np.ndarray) -> np.ndarray:
        """The arm's start: a valid configuration away from the object from which a straight transit
        reaches ``grasping``."""
        world, rng = self.world, self.rng
        candidates = np.concatenate(
            [
                np.clip(grasping + rng.normal(0.0, 0.9, (CANDIDATES, len(grasping))), *_limits(world)),
                random_configurations(world, rng, CANDIDATES),
            ]
        )
        candidates = np.round(candidates, 6)  # the parameter file's robot.initial, exactly
        tips = tip_poses(world.robot, candidates)[:, :2]
        away = np.hypot(*(tips - object_pose[:2]).T) > 0.25 + self.shape.radius
        usable = np.flatnonzero(away & is_valid(world, candidates, object_pose))
        found = _first_valid(world, candidates[usable], grasping, _resting(object_pose), rng.permutation(len(usable)))
        if found is None:
            raise WitnessError("no start configuration reaches the first grasp in a straight transit")
        start: np.ndarray = candidates[usable[found]]
        return start

    def transfer(self, q: np.ndarray, grasp: int, object_pose: np.ndarray, moves: int) -> tuple[np.ndarray, np.ndarray]:
        """Carry the object from ``q`` by ``moves`` random straight moves; the end configuration and placement."""
        world, rng = self.world, self.rng
        n = len(q)
        rel = relative(tip_poses(world.robot, q[None])[0], object_pose)
        scale = 1.5 * math.sqrt(min(1.0, 3.0 / n))
        waypoints = [q]
        origin = object_pose[:2]
        for _ in range(moves):
            mask = rng.random((CANDIDATES, n)) < 0.7
            mask[np.arange(CANDIDATES), rng.integers(0, n, CANDIDATES)] = True
            targets = np.clip(q + mask * rng.uniform(-scale, scale, (CANDIDATES, n)), *_limits(world))
            ends = compose(tip_poses(world.robot, targets), rel)[:, :2]
            score = np.hypot(*(ends - origin).T) + rng.uniform(0.0, 0.3, len(ends))
            found = _first_valid(
                world, np.broadcast_to(q, targets.shape), targets, _held(world, rel), np.argsort(-score)
            )
            if found is None:
                break
            q = targets[found]
            waypoints.append(q)
        if len(waypoints) == 1:
            raise WitnessError("no valid transfer move")
        self.segments.append(PlanSegment("transfer", grasp, np.array(waypoints)))
        return q, compose(tip_poses(world.robot, q[None])[0], rel)

    def regrasp(self, q: np.ndarray, grasp: int, object_pose: np.ndarray) -> tuple[np.ndarray, int]:
        """Leave the object at ``object_pose`` and take it again (another grasp, or the same one turned by
        at least :data:`MIN_REGRASP_TURN_RAD`): appends the transit; the new configuration and grasp."""
        world, shape = self.world, self.shape
        held = _approach(shape, object_pose[None], np.array([grasp]), tip_poses(world.robot, q[None])[:, 2])[0]
        targets, grasps = grasp_configurations(world, shape, object_pose, self.rng)
        if len(targets):
            approach = _approach(
                shape, np.broadcast_to(object_pose, (len(targets), 3)), grasps, tip_poses(world.robot, targets)[:, 2]
            )
            other = (grasps != grasp) | (np.abs(wrap_angle(approach - held)) >= MIN_REGRASP_TURN_RAD)
            targets, grasps = targets[other][:CANDIDATES], grasps[other][:CANDIDATES]
        if not len(targets):
            raise WitnessError("no configuration takes the object again")
        pick = _first_valid(world, np.broadcast_to(q, targets.shape), targets, _resting(object_pose))
        if pick is not None:
            self.transit(q, targets[pick])
            return targets[pick], int(grasps[pick])
        for target, new_grasp in zip(targets[:8], grasps[:8], strict=False):
            via = self.waypoint(q, target, object_pose)
            if via is not None:
                self.transit(q, via, target)
                return target, int(new_grasp)
        raise WitnessError("no transit reaches a regrasp")

    def waypoint(self, q: np.ndarray, target: np.ndarray, object_pose: np.ndarray) -> np.ndarray | None:
        """A configuration joined to ``q`` and to ``target`` by valid straight transits, or ``None``."""
        world, rng = self.world, self.rng
        middle = (q + target) / 2
        vias = np.clip(middle + rng.normal(0.0, 0.9, (CANDIDATES, len(q))), *_limits(world))
        ok = _pieces_valid(world, np.broadcast_to(q, vias.shape), vias, _resting(object_pose), CHECK_STEPS_RAD[:-1])
        ok[ok] = _pieces_valid(world, vias[ok], target, _resting(object_pose), CHECK_STEPS_RAD[:-1])
        candidates = np.flatnonzero(ok)
        for index in candidates[:8]:
            via: np.ndarray = vias[int(index)]
            if transit_valid(world, np.stack([q, via]), np.stack([via, target]), object_pose).all():
                return via
        return None

    def transit(self, *waypoints: np.ndarray) -> None:
        self.segments.append(PlanSegment("transit", None, np.array(waypoints)))


def _limits(world: World) -> tuple[np.ndarray, np.ndarray]:
    return world.robot.joint_lower, world.robot.joint_upper


def simulate(
    world: World, shape: ObjectShape, rng: np.random.Generator, *, transfers: int, moves: tuple[int, int] = (1, 3)
) -> Witness:
    """Simulate a manipulation of ``transfers`` transfers in ``world`` (its obstacles, if any, count too;
    the generator passes a world without them) with the object ``shape``; ``moves``: the range of
    straight moves per transfer. Raises :class:`WitnessError` when a step finds no valid candidate."""
    simulation = _Simulation(world, shape, rng)
    grasping, grasp, object_initial = simulation.first_grasp()
    initial = simulation.start(grasping, object_initial)
    simulation.transit(initial, grasping)
    q, object_pose = grasping, object_initial
    for index in range(transfers):
        for attempt in range(REGRASP_ATTEMPTS):
            kept = len(simulation.segments)
            try:
                q_end, pose_end = simulation.transfer(q, grasp, object_pose, int(rng.integers(moves[0], moves[1] + 1)))
                if index + 1 < transfers:
                    q_end, next_grasp = simulation.regrasp(q_end, grasp, pose_end)
            except WitnessError:
                del simulation.segments[kept:]
                if attempt + 1 == REGRASP_ATTEMPTS:
                    raise
                continue
            break
        q, object_pose = q_end, pose_end
        if index + 1 < transfers:
            grasp = next_grasp
    return Witness(initial, object_initial, tuple(simulation.segments))
