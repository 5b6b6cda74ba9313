"""Generated spatial worlds (``clew_world spatial_* --robot panda|ur5|random``), solvable by construction.

A world is built around its witness, in this order, from one random stream (a function of the family, the
robot, the seed and the attempt):

1. the arm (the shipped Panda or UR5, or a random serial arm of 4-8 joints from
   :func:`~clew_ros.spatial.random_robot.random_robot_urdf`), the object (a box or a cylinder) and its grasps
   (top-down, and into each side; the tcp :attr:`SpatialGeneration.grasp_depth_m` inside the object);
2. the witness's holds: a configuration that holds the object level (the family's face down) near a point
   drawn in the arm's workspace, found by damped least squares on the tcp's forward kinematics (any arm of
   3 joints or more: only the face's tilt and, where a family shares one table, the height are
   constrained), for the start and for the goal; and the approach above each (the tcp backed off along its
   approach axis);
3. the supports under the two placements (tables, shelf boards), then the family's obstacles (shelf walls
   and boards, clutter, a closed box), each kept only when it is :attr:`SpatialGeneration.margin_m` clear of
   the arm, the held object and the resting object along the whole witness (screened inflated by that
   margin);
4. the witness plan -- transit to the grasp, transfer to the goal (through a via configuration when the
   straight move collides), transit back to the approach -- checked as a user's plan is, by
   :func:`clew_ros.spatial.plan.validate_plan` at 0.002 rad.

An attempt that fails at any step (no level hold near the drawn point, a support or wall that cannot be made
clear, a witness the validator refuses) starts over with the next stream. The unsolvable family puts the
goal inside a closed box (walls, a lid and the support as its floor, the object starting outside it), or
on a table out of every grasp's reach (the arm's reach bounded by its link offsets); the witness is then a
failed plan that says why.
"""

from __future__ import annotations

import functools
import math
import os
import zlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray

from clew_ros.core.plan import Plan
from clew_ros.spatial.checker import Held, SpatialChecker
from clew_ros.spatial.inverse import InverseKinematics
from clew_ros.spatial.kernels.collide import clearance_of_sphere
from clew_ros.spatial.placements import FACE_RPY, MovableObject
from clew_ros.spatial.plan import WORLD_KIND, make_plan, object_obstacle, replay, resting_problems, validate_plan
from clew_ros.spatial.random_robot import BASE_LINK, TIP_LINK, random_robot_urdf
from clew_ros.spatial.robot import RobotModel, load_robot, robot_from_parameters
from clew_ros.spatial.scene import Obstacle, make_obstacle, obstacle_arrays
from clew_ros.spatial.spheres import SphereModel, SphereSettings, cover, sphere_model
from clew_ros.spatial.transforms import matrix_pose, pose_matrix, rpy_matrix
from clew_ros.spatial.validate import validate_transit
from clew_ros.spatial.world import SpatialWorld, spatial_world_from_parameters
from clew_ros.worlds.errors import GenerationError, UnknownFamilyError

__all__ = [
    "SPATIAL_FAMILIES",
    "SPATIAL_ROBOTS",
    "SpatialFamily",
    "SpatialGenerated",
    "SpatialGeneration",
    "config_folder",
    "generate_spatial",
    "spatial_world_text",
    "write_spatial_world",
]

Matrix = NDArray[np.float64]

#: The arms a spatial family is generated on: the shipped Panda and UR5, or a random serial arm.
SPATIAL_ROBOTS = ("panda", "ur5", "random")


@dataclass(frozen=True)
class SpatialGeneration:
    """The numbers the spatial generator builds with."""

    #: The tcp backs off this far (m) along its approach axis above a grasp (approach and lift): room for the
    #: hand to leave the object without dragging it.
    approach_m: float = 0.1
    #: With the object, the tcp first rises this far (m) straight up, then backs off along its approach axis
    #: (up for a grasp from above, out for one from the side): the object leaves its support without sliding.
    lift_m: float = 0.015
    #: Every obstacle but the supports is screened inflated by this much (m) against the whole witness: the
    #: witness keeps that clearance, so the check at 0.002 rad never hangs on rounding.
    margin_m: float = 0.02
    #: The witness carries the object at least this far (m, centre to centre).
    min_carry_m: float = 0.25
    #: The tcp sits this deep (m) inside the object at a grasp (at most 40% of the half extent it enters by).
    grasp_depth_m: float = 0.015
    #: Streams tried per world before :class:`~clew_ros.worlds.errors.GenerationError`...
    attempts: int = 40
    #: ... on a random arm (each stream draws another arm: many cannot hold the object level where asked).
    random_attempts: int = 200
    #: Damped least-squares steps per hold at most (each one forward kinematics of n + 1 configurations).
    solve_iterations: int = 120
    #: A hold is level when its face's normal is this close (its horizontal part) to straight down.
    level_tolerance: float = 1e-10
    #: Random seeds a hold is solved from, after the arm's home and the start's hold.
    hold_seeds: int = 4
    #: Random via configurations tried when the straight transfer between the two approaches collides.
    via_tries: int = 40
    #: Table tops and shelf boards (m thick).
    table_thickness_m: float = 0.03
    board_thickness_m: float = 0.02
    #: Steps of the bisection that puts a shelf's lid and walls as near the witness as it allows.
    bisection_steps: int = 7


@dataclass(frozen=True)
class SpatialFamily:
    """A family of spatial worlds: ``layout`` builds the supports and obstacles around the witness's holds;
    ``grasps`` which grasps a witness may use (``top``, ``side``, ``any``); ``reorient``: the goal rests on
    another face than the start; ``one_table``: start and goal on one table (same height)."""

    name: str
    summary: str
    layout: str
    grasps: str = "any"
    reorient: bool = False
    one_table: bool = False
    solvable: bool = True
    angle_tolerances: tuple[float, ...] = (math.pi, 0.3)
    #: the arm starts at the approach of the start's grasp (not at its home, which may reach over a shelf)
    start_at_approach: bool = False


SPATIAL_FAMILIES: dict[str, SpatialFamily] = {
    family.name: family
    for family in (
        SpatialFamily("spatial_table", "spatial: pick and place from one table to another", "tables"),
        SpatialFamily("spatial_shelf", "spatial: from a table into a shelf (boards, walls, a lid)", "shelf"),
        SpatialFamily(
            "spatial_clutter",
            "spatial: one table, 5-12 boxes and cylinders around the start and the goal",
            "clutter",
            one_table=True,
        ),
        SpatialFamily(
            "spatial_reorient",
            "spatial: the goal rests the object on another face (taken from the side, turned over)",
            "tables",
            grasps="side",
            reorient=True,
            angle_tolerances=(math.pi, 0.3),
        ),
        SpatialFamily(
            "spatial_narrow",
            "spatial: shelf to shelf, lids and walls as close as the witness lets them",
            "narrow",
            grasps="side",
            start_at_approach=True,
        ),
        SpatialFamily(
            "spatial_unsolvable",
            "spatial: the goal inside a closed box, or on a table out of every grasp's reach",
            "unsolvable",
            solvable=False,
        ),
    )
}


@dataclass(frozen=True, eq=False)
class SpatialGenerated:
    """One generated spatial world: its ``parameters`` (``{"world": ...}``; robot files as absolute paths,
    :func:`write_spatial_world` writes them relative to the file), its ``witness`` (a valid plan, or a failed
    plan saying why none exists) and how it was made."""

    family: str
    robot: str
    seed: int
    parameters: dict[str, Any]
    witness: Plan
    solvable: bool
    notes: tuple[str, ...]
    attempts: int
    stats: dict[str, Any] = field(default_factory=dict)

    @property
    def name(self) -> str:
        return str(self.parameters["world"]["name"])

    def world(self) -> SpatialWorld:
        """The world as a user's file gives it (parsed, its robot and sphere model loaded)."""
        return spatial_world_from_parameters(self.parameters, config_folder())


class _RejectedError(Exception):
    """This stream gave no acceptable world."""


def config_folder() -> Path:
    """The package's ``config`` folder (the source tree's, else the installed share)."""
    source = Path(__file__).resolve().parents[2] / "config"
    if (source / "robots").is_dir():
        return source
    from ament_index_python.packages import get_package_share_directory  # an installed package only

    return Path(get_package_share_directory("clew_ros")) / "config"


# --------------------------------------------------------------------------------------------- the arms


@dataclass(frozen=True, eq=False)
class _Arm:
    tree: dict[str, Any]  # world.robot without initial
    robot: RobotModel
    spheres: SphereModel
    home: NDArray[np.float64] | None
    reach: float  # the tcp is never farther than this from the first joint (m)
    shoulder: NDArray[np.float64]  # the first joint's origin in world


def _reach(robot: RobotModel) -> tuple[float, NDArray[np.float64]]:
    """A bound on the tcp's distance from the first joint (sum of the offsets after it, prismatic travel
    added), and that joint's origin."""
    offsets = [float(np.linalg.norm(robot.origins[j][:3, 3])) for j in range(1, robot.dof)]
    travel = [max(abs(robot.lower[j]), abs(robot.upper[j])) for j in range(robot.dof) if robot.prismatic[j]]
    tcp = float(np.linalg.norm(robot.tcp[:3, 3]))
    shoulder = (robot.base @ robot.origins[0])[:3, 3]
    return sum(offsets) + sum(travel) + tcp, shoulder


@functools.cache
def _shipped(name: str) -> _Arm:
    robots = config_folder() / "robots"
    if name == "panda":
        tree: dict[str, Any] = {
            "urdf": str(robots / "panda/panda.urdf"),
            "srdf": str(robots / "panda/panda.srdf"),
            "base_link": "panda_link0",
            "tip_link": "panda_hand_tcp",
            "gripper_links": ["panda_hand", "panda_leftfinger", "panda_rightfinger"],
        }
        home = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
    else:
        tree = {
            "urdf": str(robots / "ur5/ur5.urdf"),
            "srdf": str(robots / "ur5/ur5.srdf"),
            "base_link": "base_link",
            "tip_link": "tool0",
            "tcp": [0.0, 0.0, 0.05, 0.0, 0.0, 0.0],
            "gripper_links": ["wrist_3_link", "ee_link"],
        }
        home = np.array([0.0, -1.9, 1.9, -1.571, -1.571, 0.0])
    robot = robot_from_parameters(tree, robots)
    reach, shoulder = _reach(robot)
    return _Arm(tree, robot, sphere_model(robot), home, reach, shoulder)


def _arm(name: str, rng: np.random.Generator) -> _Arm:
    if name != "random":
        return _shipped(name)
    text = random_robot_urdf(rng)
    robot = load_robot(text, folder=Path.cwd(), base_link=BASE_LINK, tip_link=TIP_LINK, source="random_robot")
    last = f"link_{robot.dof}"
    tree = {"description": text, "base_link": BASE_LINK, "tip_link": TIP_LINK, "gripper_links": [last]}
    robot = replace(robot, gripper_links=(last,))
    reach, shoulder = _reach(robot)
    return _Arm(tree, robot, sphere_model(robot), None, reach, shoulder)


# ----------------------------------------------------------------------------------- object and grasps


def _object(rng: np.random.Generator) -> MovableObject:
    if rng.random() < 0.6:
        return MovableObject(
            "box",
            (round(rng.uniform(0.03, 0.06), 3), round(rng.uniform(0.03, 0.06), 3), round(rng.uniform(0.06, 0.14), 3)),
        )
    return MovableObject("cylinder", (round(rng.uniform(0.06, 0.14), 3), round(rng.uniform(0.015, 0.03), 3)))


def _grasp(normal: NDArray[np.float64], up: NDArray[np.float64], reach: float, raised: float = 0.0) -> list[float]:
    """The tcp pose (6 numbers, object frame) entering along ``-normal`` from the face ``reach`` out (and
    ``raised`` along ``up``), its x axis along ``up``."""
    z = -normal
    y = np.cross(z, up)
    matrix = np.eye(4)
    matrix[:3, :3] = np.column_stack([up, y, z])
    matrix[:3, 3] = normal * reach + up * raised
    return [round(v, 9) for v in matrix_pose(matrix)]


def _grasps(thing: MovableObject, depth: float) -> list[tuple[str, list[float]]]:
    """Named grasps: ``top`` (down into the +z face; a box also turned a quarter) and ``side`` ones."""
    out = []
    ez, ex, ey = np.array([0.0, 0, 1]), np.array([1.0, 0, 0]), np.array([0.0, 1, 0])
    half_z = thing.size[2] / 2 if thing.shape == "box" else thing.size[0] / 2
    out.append(("top", _grasp(ez, ex, half_z - min(depth, 0.4 * half_z))))
    out.append(("top", _grasp(ez, ey, half_z - min(depth, 0.4 * half_z))))
    if thing.shape == "box":
        sides = [(ex, thing.size[0] / 2), (-ex, thing.size[0] / 2), (ey, thing.size[1] / 2), (-ey, thing.size[1] / 2)]
    else:
        radius = thing.size[1]
        sides = [(np.array([math.cos(a), math.sin(a), 0.0]), radius) for a in (0.0, math.pi / 2, math.pi, -math.pi / 2)]
    # the side grasps hold the upper part (a quarter of the height above the centre): the hand clear of the support
    out += [("side", _grasp(n, ez, half - min(depth, 0.4 * half), half_z / 2)) for n, half in sides]
    return out


_NORMAL = {"-z": (2, -1.0), "+z": (2, 1.0), "+x": (0, 1.0), "-x": (0, -1.0), "+y": (1, 1.0), "-y": (1, -1.0)}


# ---------------------------------------------------------------------------------- holds by least squares


class _Solver:
    """Damped least squares on residuals of the tcp's pose (numerical Jacobian, one compiled forward
    kinematics call per step), within the joint limits."""

    def __init__(self, arm: _Arm, settings: SpatialGeneration) -> None:
        self.robot = arm.robot
        self.kinematics = InverseKinematics(arm.robot)
        self.settings = settings
        #: the arm alone (limits, self-collision)
        self.alone = SpatialChecker(arm.robot, arm.spheres)

    def solve(self, q0: NDArray[np.float64], residual: Callable[[Matrix], Matrix]) -> tuple[NDArray[np.float64], float]:
        robot, h = self.robot, 1e-7
        low, high = robot.lower + 1e-6, robot.upper - 1e-6
        q = np.clip(q0, low, high)
        r = residual(self.kinematics.tcp_poses(q[None]))[0]
        damping = 1e-3
        for _ in range(self.settings.solve_iterations):
            if float(r @ r) < 1e-22:
                break
            probes = q[None] + np.vstack([np.zeros(robot.dof), h * np.eye(robot.dof)])
            values = residual(self.kinematics.tcp_poses(probes))
            jacobian = ((values[1:] - values[0]) / h).T  # (m, n)
            step = -jacobian.T @ np.linalg.solve(jacobian @ jacobian.T + damping * np.eye(len(r)), r)
            step *= min(1.0, 0.4 / max(float(np.max(np.abs(step))), 1e-12))
            trial = np.clip(q + step, low, high)
            new = residual(self.kinematics.tcp_poses(trial[None]))[0]
            if float(new @ new) < float(r @ r):
                q, r, damping = trial, new, max(damping / 3, 1e-12)
            else:
                damping *= 5
                if damping > 1e6:
                    break
        return q, float(np.sqrt(r @ r))


def _level(grasp: Matrix, face: str, target: Sequence[float | None], weight: float) -> Callable[[Matrix], Matrix]:
    """Residuals of holding the object (by ``grasp``) with ``face`` straight down, its centre near ``target``
    (``None``: that coordinate free), position errors weighted ``weight``."""
    inverse = np.linalg.inv(grasp)
    axis, sign = _NORMAL[face]
    chosen = [i for i, t in enumerate(target) if t is not None]
    goal = np.array([target[i] for i in chosen], dtype=np.float64)

    def residual(tcp: Matrix) -> Matrix:
        placed = tcp @ inverse
        normal = placed[:, :3, axis] * sign
        normal[:, 2] += 1.0  # straight down: (0, 0, -1)
        return np.hstack([normal, weight * (placed[:, chosen, 3] - goal)])

    return residual


def _position_error(target: Matrix) -> Callable[[Matrix], Matrix]:
    def residual(tcp: Matrix) -> Matrix:
        return np.asarray(tcp[:, :3, 3] - target[:3, 3])

    return residual


#: The approach is followed through these fractions of :attr:`SpatialGeneration.approach_m`.
APPROACH_STEPS = (0.1, 0.25, 0.5, 0.75, 1.0)


@dataclass
class _Hold:
    q: NDArray[np.float64]  # holds the object at pose
    path: list[NDArray[np.float64]]  # backing off from it along the tcp's approach axis, to the approach
    lift: list[NDArray[np.float64]]  # raising the object off its support, then backing off (the object held)
    pose: Matrix  # the object's placement (4x4)
    face: str

    @property
    def up(self) -> NDArray[np.float64]:
        return self.path[-1]

    @property
    def leaving(self) -> list[NDArray[np.float64]]:
        """From the hold to the approach (the hand leaving the object)."""
        return [self.q, *self.path]

    @property
    def coming(self) -> list[NDArray[np.float64]]:
        """From the approach to the hold."""
        return self.leaving[::-1]

    @property
    def raising(self) -> list[NDArray[np.float64]]:
        """From the hold, the object lifted off its support."""
        return [self.q, *self.lift]

    @property
    def lowering(self) -> list[NDArray[np.float64]]:
        """Down onto the support, to the hold."""
        return self.raising[::-1]


def _follow(
    solver: _Solver, arm: _Arm, q: NDArray[np.float64], targets: Sequence[Matrix], rng: np.random.Generator
) -> list[NDArray[np.float64]] | None:
    """Configurations putting the tcp at each of ``targets`` in turn, each the solution nearest the one
    before (the exact inverse kinematics on 6 joints or more; else the tcp's position only, as near as the
    arm gets); ``None`` when one is out of reach."""
    path, last = [], q
    start = solver.kinematics.tcp_poses(q[None])[0]
    for target in targets:
        found = solver.kinematics.solve(target, rng, seeds=last[None]) if arm.robot.dof >= 6 else np.zeros((0, 1))
        if len(found):
            last = found[np.argmin(np.abs(found - last).max(axis=1))]
        else:
            last, miss = solver.solve(last, _position_error(target))
            if miss > 0.3 * float(np.linalg.norm(target[:3, 3] - start[:3, 3])):
                return None
        path.append(last)
    return path


def _hold(
    solver: _Solver,
    arm: _Arm,
    grasp: Matrix,
    face: str,
    point: NDArray[np.float64],
    *,
    height: float | None,
    rng: np.random.Generator,
    near: NDArray[np.float64] | None = None,
) -> _Hold | None:
    """A configuration holding the object level on ``face`` near ``point`` (its centre at ``height`` when
    given), and the approach above it; ``None`` when the solve does not get there."""
    seeds = [s for s in (near, arm.home) if s is not None]
    seeds += list(rng.uniform(arm.robot.lower, arm.robot.upper, size=(solver.settings.hold_seeds, arm.robot.dof)))
    for seed in seeds:  # the first seed that gets there, the arm clear of itself
        q, _ = solver.solve(seed, _level(grasp, face, list(point), 1.0))
        q, error = solver.solve(q, _level(grasp, face, [None, None, height], 10.0))
        if error <= solver.settings.level_tolerance and solver.alone.valid(q[None])[0]:
            break
    else:
        return None
    tcp = solver.kinematics.tcp_poses(q[None])[0]
    pose = tcp @ np.linalg.inv(grasp)
    axis, sign = _NORMAL[face]
    if pose[2, axis] * sign > -0.5:
        return None
    pose[:3, :3] = rpy_matrix(0.0, 0.0, math.atan2(*_yaw_vector(pose, face))) @ rpy_matrix(*FACE_RPY[face])
    distance = solver.settings.approach_m  # in short steps: nearly straight for the tcp
    back = [tcp @ pose_matrix([0.0, 0.0, -f * distance, 0.0, 0.0, 0.0]) for f in APPROACH_STEPS]
    raised = [pose_matrix([0.0, 0.0, f * solver.settings.lift_m, 0.0, 0.0, 0.0]) @ tcp for f in (0.5, 1.0)]
    up = [*raised, *(raised[-1] @ pose_matrix([0.0, 0.0, -f * distance, 0.0, 0.0, 0.0]) for f in APPROACH_STEPS)]
    path, lift = _follow(solver, arm, q, back, rng), _follow(solver, arm, q, up, rng)
    if path is None or lift is None:
        return None
    return _Hold(q, path, lift, pose, face)


def _yaw_vector(pose: Matrix, face: str) -> tuple[float, float]:
    turned = pose[:3, :3] @ rpy_matrix(*FACE_RPY[face]).T
    return float(turned[1, 0]), float(turned[0, 0])


# -------------------------------------------------------------------------------------- the witness sweep


class _Sweep:
    """The witness's configurations (0.002 rad apart), the held object's relation and the resting placements:
    what a new obstacle must clear."""

    def __init__(self, world: SpatialWorld, plan: Plan, margin: float) -> None:
        self.world, self.margin = world, margin
        motions = list(replay(world, plan))
        self.all = np.concatenate([m.configurations for m in motions])
        transfers = [m for m in motions if m.kind == "transfer"]
        self.held = np.concatenate([m.configurations for m in transfers])
        assert transfers[0].grasp_rel is not None
        self.grasp_rel = transfers[0].grasp_rel
        assert world.object is not None
        self.shape = world.object.shape
        self.rests = [m.object_matrices[0] for m in motions if m.kind == "transit" and m.object_matrices is not None]
        self.cover = cover(self.shape.geometry(), SphereSettings())

    def clear(self, obstacle: Obstacle, *, inflate: bool = True) -> bool:
        grown = _inflated(obstacle, self.margin) if inflate else obstacle
        robot, spheres = self.world.robot, self.world.spheres
        if not SpatialChecker(robot, spheres, [grown], self_collision=False).valid(self.all).all():
            return False
        held = Held(self.shape, self.grasp_rel, ())
        if not SpatialChecker(robot, spheres, [grown], self_collision=False, held=held).valid(self.held).all():
            return False
        return all(_object_clear(self.cover, pose, grown) for pose in self.rests)


def _object_clear(cover_: tuple[Matrix, Matrix], pose: Matrix, obstacle: Obstacle) -> bool:
    centers, radii = cover_
    packed = obstacle_arrays([obstacle])
    placed = centers @ pose[:3, :3].T + pose[:3, 3]
    return all(
        clearance_of_sphere(p, r, packed["obs_kind"][0], packed["obs_r"][0], packed["obs_t"][0], packed["obs_dims"][0])
        > 0.0
        for p, r in zip(placed, radii, strict=True)
    )


def _inflated(obstacle: Obstacle, margin: float) -> Obstacle:
    if obstacle.shape == "box":
        size = tuple(v + 2 * margin for v in obstacle.size)
    elif obstacle.shape == "cylinder":
        size = (obstacle.size[0] + 2 * margin, obstacle.size[1] + margin)
    else:
        size = (obstacle.size[0] + margin,)
    return Obstacle(obstacle.name, obstacle.shape, size, obstacle.pose)


# ------------------------------------------------------------------------------------------- building


def _box(name: str, size: Sequence[float], pose: Sequence[float]) -> dict[str, Any]:
    return {"shape": "box", "size": [round(float(v), 6) for v in size], "pose": [round(float(v), 6) for v in pose]}


def _obstacle(name: str, entry: dict[str, Any]) -> Obstacle:
    return make_obstacle(name, entry["shape"], entry["size"], pose_matrix(entry["pose"]), name)


class _Builder:
    """One attempt: the arm, the object, the holds, the tree and the witness."""

    def __init__(
        self, family: SpatialFamily, robot: str, seed: int, rng: np.random.Generator, settings: SpatialGeneration
    ) -> None:
        self.family, self.seed, self.rng, self.settings = family, seed, rng, settings
        self.robot_name = robot
        self.arm = _arm(robot, rng)
        self.solver = _Solver(self.arm, settings)
        self.thing = _object(rng)
        self.grasps = _grasps(self.thing, settings.grasp_depth_m)
        self.obstacles: dict[str, dict[str, Any]] = {}
        self.supports: list[str] = []
        self.notes: list[str] = []

    # -- holds

    def _point(self, angle: float) -> NDArray[np.float64]:
        reach, shoulder = self.arm.reach, self.arm.shoulder
        radius = self.rng.uniform(0.35, 0.7) * reach
        return np.array(
            [
                shoulder[0] + radius * math.cos(angle),
                shoulder[1] + radius * math.sin(angle),
                shoulder[2] + self.rng.uniform(-0.45, 0.1) * reach,
            ]
        )

    def holds(self) -> tuple[int, _Hold, _Hold]:
        kinds = {"any": ("top", "side"), "top": ("top",), "side": ("side",)}[self.family.grasps]
        usable = [i for i, (kind, _) in enumerate(self.grasps) if kind in kinds]
        index = int(self.rng.choice(usable))
        grasp = pose_matrix(self.grasps[index][1])
        face_a = "-z"
        face_b = self._goal_face(grasp) if self.family.reorient else face_a
        angle = self.rng.uniform(-math.pi, math.pi)
        start = _hold(self.solver, self.arm, grasp, face_a, self._point(angle), height=None, rng=self.rng)
        if start is None:
            raise _RejectedError("no level hold near the start point")
        turn = self.rng.uniform(0.5, 1.2 if self.family.one_table else 2.2) * self.rng.choice([-1.0, 1.0])
        height = None
        if self.family.one_table:
            height = start.pose[2, 3] - self.thing.height(face_a) + self.thing.height(face_b)
        goal = _hold(
            self.solver, self.arm, grasp, face_b, self._point(angle + turn), height=height, rng=self.rng, near=start.q
        )
        if goal is None:
            raise _RejectedError("no level hold near the goal point")
        if np.linalg.norm(goal.pose[:3, 3] - start.pose[:3, 3]) < self.settings.min_carry_m:
            raise _RejectedError("start and goal too close")
        return index, start, goal

    def _goal_face(self, grasp: Matrix) -> str:
        """A face other than -z on which the grasp's approach points down or sideways."""
        approach = grasp[:3, 2]
        faces = [
            face
            for face in self.thing.faces
            if face != "-z" and float((rpy_matrix(*FACE_RPY[face]) @ approach)[2]) <= 0.1
        ]
        if not faces:
            raise _RejectedError("no other face to turn the object onto with this grasp")
        return str(self.rng.choice(faces))

    # -- supports

    def table(self, name: str, hold: _Hold, *, extra: Sequence[_Hold] = ()) -> None:
        """A table under ``hold``'s placement (and ``extra``'s: one table for both), facing the arm."""
        poses = [hold.pose, *[h.pose for h in extra]]
        centres = np.array([p[:3, 3] for p in poses])
        top = float(hold.pose[2, 3] - self.thing.height(hold.face))
        thickness = self.settings.table_thickness_m
        if len(poses) > 1:
            chord = centres[1, :2] - centres[0, :2]
            yaw = math.atan2(chord[1], chord[0])
            length = float(np.linalg.norm(chord)) + self.rng.uniform(0.2, 0.35)
            width = self.rng.uniform(0.25, 0.4)
            middle = centres[:, :2].mean(axis=0)
        else:
            offset = centres[0, :2] - self.arm.shoulder[:2]
            yaw = math.atan2(offset[1], offset[0])
            length, width = self.rng.uniform(0.2, 0.4), self.rng.uniform(0.25, 0.45)
            # the object near the edge that faces the arm (a few cm in), the top reaching away from it
            inset = float(np.max(np.abs(_footprint(self.thing, hold)))) + self.rng.uniform(0.02, 0.06)
            middle = centres[0, :2] + (length / 2 - inset) * np.array([math.cos(yaw), math.sin(yaw)])
            middle += self.rng.uniform(-0.03, 0.03) * np.array([-math.sin(yaw), math.cos(yaw)])
        for _ in range(2):  # as drawn, else as small as the object's footprint allows
            entry = _box(name, [length, width, thickness], [*middle, top - thickness / 2, 0, 0, yaw])
            table = SpatialChecker(self.arm.robot, self.arm.spheres, [_obstacle(name, entry)], self_collision=False)
            configurations = np.array([q for h in (hold, *extra) for q in (*h.leaving, *h.lift)])
            if table.valid(configurations).all():
                break
            middle = centres[:, :2].mean(axis=0)
            reach = float(np.max(np.linalg.norm(centres[:, :2] - middle, axis=1)))
            length = width = 2 * (reach + float(np.max(np.abs(_footprint(self.thing, hold)))) + 0.01)
        else:
            raise _RejectedError(f"the arm holding the object reaches through {name}")
        self.obstacles[name] = entry
        self.supports.append(name)

    # -- the world and its witness

    def tree(self, start: _Hold, goal: _Hold, initial: NDArray[np.float64]) -> dict[str, Any]:
        reach, shoulder = self.arm.reach, self.arm.shoulder
        span = reach + 0.5
        bounds = [
            shoulder[0] - span,
            shoulder[1] - span,
            shoulder[2] - span,
            shoulder[0] + span,
            shoulder[1] + span,
            shoulder[2] + span,
        ]
        return {
            "kind": "spatial",
            "name": f"{self.family.name}_{self.robot_name}_{self.seed}",
            "bounds": [round(float(v), 3) for v in bounds],
            "robot": {**self.arm.tree, "initial": [round(float(v), 9) for v in initial]},
            "obstacle_names": list(self.obstacles),
            "obstacles": dict(self.obstacles),
            "supports": list(self.supports),
            "object": {
                "shape": self.thing.shape,
                "size": list(self.thing.size),
                "initial": [round(v, 9) for v in matrix_pose(start.pose)],
                "goal": [round(v, 9) for v in matrix_pose(goal.pose)],
                "grasps": [v for _, grasp in self.grasps for v in grasp],
            },
            "goal_angle_tolerance": float(self.rng.choice(self.family.angle_tolerances)),
        }

    def world(self, tree: dict[str, Any]) -> SpatialWorld:
        return spatial_world_from_parameters(
            {"world": tree}, config_folder(), prepared=(self.arm.robot, self.arm.spheres)
        )

    def initial(self, world: SpatialWorld, start: _Hold) -> NDArray[np.float64]:
        """The arm's start: its home (or a random configuration) from which the straight move to the approach
        is free, else the approach itself."""
        resting = SpatialChecker(
            world.robot, world.spheres, world.obstacles, world.bounds, resting_object=object_obstacle(world, start.pose)
        )
        if self.family.start_at_approach:
            return start.up
        candidates = [] if self.arm.home is None else [self.arm.home]
        candidates += list(
            self.rng.uniform(world.robot.lower, world.robot.upper, size=(self.settings.via_tries, world.robot.dof))
        )
        for q in candidates:
            if resting.valid(q[None])[0] and not validate_transit(resting, [q, start.up]):
                return np.asarray(q)
        return start.up

    def carry(self, world: SpatialWorld, grasp_rel: Matrix, start: _Hold, goal: _Hold) -> list[NDArray[np.float64]]:
        """The transfer's waypoints: straight from approach to approach, else through a via configuration."""
        held = Held(self.thing, grasp_rel, world.supports, world.tolerances["placement_tolerance"])
        checker = SpatialChecker(world.robot, world.spheres, world.obstacles, world.bounds, held=held)
        direct = [*start.raising, *goal.lowering]
        if not validate_transit(checker, direct):
            return direct
        vias = self.rng.uniform(world.robot.lower, world.robot.upper, size=(self.settings.via_tries, world.robot.dof))
        vias = vias[checker.valid(vias)]
        for via in vias:
            path = [*start.raising, via, *goal.lowering]
            if not validate_transit(checker, path):
                return path
        raise _RejectedError(
            f"no straight or single-via transfer between the approaches: {validate_transit(checker, direct)[0]}"
        )

    def witness(self, tree: dict[str, Any], index: int, start: _Hold, goal: _Hold) -> tuple[SpatialWorld, Plan]:
        world = self.world(tree)
        initial = self.initial(world, start)
        tree["robot"]["initial"] = [round(float(v), 9) for v in initial]
        world = self.world(tree)
        assert world.object is not None
        tcp = self.solver.kinematics.tcp_poses(start.q[None])[0]
        grasp_rel = np.linalg.inv(pose_matrix(world.object.initial)) @ tcp
        carried = self.carry(world, grasp_rel, start, goal)
        first = [world.initial, *start.coming] if np.any(world.initial != start.up) else start.coming
        plan = make_plan(
            world,
            [("transit", None, first), ("transfer", index, carried), ("transit", None, goal.leaving)],
            message="witness: the manipulation the world was built around",
        )
        problems = validate_plan(world, plan)
        if problems:
            raise _RejectedError(f"the witness does not validate: {problems[0]}")
        return world, plan


# ------------------------------------------------------------------------------------------- layouts


def _bisect(fits: Callable[[float], bool], low: float, high: float, steps: int) -> float | None:
    """The smallest value in [low, high] (to ``steps`` halvings) for which ``fits`` holds, assuming it holds
    from some value on; ``None`` when it does not hold at ``high``."""
    if not fits(high):
        return None
    if fits(low):
        return low
    for _ in range(steps):
        middle = (low + high) / 2
        low, high = (low, middle) if fits(middle) else (middle, high)
    return high


def _shelf(builder: _Builder, sweep: _Sweep, name: str, hold: _Hold, *, narrow: bool) -> None:
    """A shelf around a placement: its board (the support, already in), a lid and two side walls, as near
    as the witness allows (``narrow``) or a few cm farther."""
    rng, settings = builder.rng, builder.settings
    board = builder.obstacles[name]
    length, width, thickness = board["size"]
    x, y, z, _, _, yaw = board["pose"]
    top = z + thickness / 2
    frame = rpy_matrix(0.0, 0.0, yaw)
    slack = 0.0 if narrow else float(rng.uniform(0.04, 0.12))
    height = builder.thing.size[2] if builder.thing.shape == "box" else builder.thing.size[0]

    def lid(gap: float) -> dict[str, Any]:
        return _box(
            f"{name}_lid",
            [length, width, settings.board_thickness_m],
            [x, y, top + gap + settings.board_thickness_m / 2, 0, 0, yaw],
        )

    gap = _bisect(lambda g: sweep.clear(_obstacle("lid", lid(g))), 1.2 * height, 1.2, settings.bisection_steps)
    if gap is None or (narrow and gap > height + 0.3):
        raise _RejectedError("no lid clear of the witness near the shelf")
    gap += slack + settings.margin_m
    builder.obstacles[f"{name}_lid"] = lid(gap)
    wall_height = gap + thickness + settings.board_thickness_m

    def wall(side: float, offset: float) -> dict[str, Any]:
        centre = np.array([x, y, 0.0]) + frame @ np.array([0.0, side * (offset + settings.board_thickness_m / 2), 0.0])
        return _box(
            f"{name}_wall",
            [length, settings.board_thickness_m, wall_height],
            [centre[0], centre[1], z - thickness / 2 + wall_height / 2, 0, 0, yaw],
        )

    for side, label in ((1.0, "left"), (-1.0, "right")):
        offset = _bisect(
            functools.partial(_wall_clear, sweep, wall, side),
            width / 2,
            width / 2 + 0.5,
            settings.bisection_steps,
        )
        if offset is None:
            raise _RejectedError(f"no {label} wall clear of the witness")
        builder.obstacles[f"{name}_{label}"] = wall(side, offset + slack + settings.margin_m)
    builder.notes.append(f"{name}: lid {gap:.3f} m above the board ({'narrow' if narrow else 'with room'})")


def _wall_clear(sweep: _Sweep, wall: Callable[[float, float], dict[str, Any]], side: float, offset: float) -> bool:
    return sweep.clear(_obstacle("wall", wall(side, offset)))


def _clutter(builder: _Builder, sweep: _Sweep, table: str) -> None:
    rng = builder.rng
    entry = builder.obstacles[table]
    length, width, thickness = entry["size"]
    x, y, z, _, _, yaw = entry["pose"]
    top = z + thickness / 2
    frame = rpy_matrix(0.0, 0.0, yaw)
    wanted, placed, tries = int(rng.integers(5, 13)), 0, 0
    while placed < wanted and tries < 6 * wanted:
        tries += 1
        local = np.array([rng.uniform(-0.5, 0.5) * length, rng.uniform(-0.5, 0.5) * width, 0.0])
        centre = np.array([x, y, 0.0]) + frame @ local
        height = rng.uniform(0.04, 0.16)
        name = f"clutter_{placed}"
        if rng.random() < 0.6:
            side = rng.uniform(0.03, 0.07, size=2)
            entry_ = _box(
                name, [*side, height], [centre[0], centre[1], top + height / 2, 0, 0, rng.uniform(-math.pi, math.pi)]
            )
        else:
            radius = rng.uniform(0.015, 0.04)
            entry_ = {
                "shape": "cylinder",
                "size": [round(height, 6), round(radius, 6)],
                "pose": [round(float(v), 6) for v in (centre[0], centre[1], top + height / 2, 0, 0, 0)],
            }
        obstacle = _obstacle(name, entry_)
        if sweep.clear(obstacle) and all(
            _apart(obstacle, _obstacle(other, builder.obstacles[other]))
            for other in builder.obstacles
            if other.startswith("clutter")
        ):
            builder.obstacles[name] = entry_
            placed += 1
    if placed < 3:
        raise _RejectedError(f"only {placed} clutter items found room")
    builder.notes.append(f"{placed} clutter items on {table}")


def _apart(a: Obstacle, b: Obstacle) -> bool:
    """Bounding spheres apart (clutter items do not overlap)."""

    def radius(o: Obstacle) -> float:
        if o.shape == "box":
            return float(np.linalg.norm(o.size)) / 2
        return math.hypot(o.size[0] / 2, o.size[1])

    return float(np.linalg.norm(a.pose[:3, 3] - b.pose[:3, 3])) > radius(a) + radius(b)


# ------------------------------------------------------------------------------------------- families


def _solvable(builder: _Builder) -> SpatialGenerated:
    family = builder.family
    index, start, goal = builder.holds()
    if family.one_table:
        builder.table("table", start, extra=[goal])
    else:
        builder.table("table_a", start)
        builder.table("shelf" if family.layout in ("shelf", "narrow") else "table_b", goal)
        if family.layout == "narrow":
            builder.obstacles["shelf_a"] = builder.obstacles.pop("table_a")
            builder.supports[0] = "shelf_a"
    tree = builder.tree(start, goal, start.up)
    world, plan = builder.witness(tree, index, start, goal)
    sweep = _Sweep(world, plan, builder.settings.margin_m)
    if family.layout == "shelf":
        _shelf(builder, sweep, "shelf", goal, narrow=False)
    elif family.layout == "narrow":
        _shelf(builder, sweep, "shelf_a", start, narrow=True)
        _shelf(builder, sweep, "shelf", goal, narrow=True)
    elif family.layout == "clutter":
        _clutter(builder, sweep, "table")
    final = {**tree, "obstacle_names": list(builder.obstacles), "obstacles": dict(builder.obstacles)}
    world = builder.world(final)
    problems = validate_plan(world, plan)
    if problems:
        raise _RejectedError(f"the witness does not validate among the obstacles: {problems[0]}")
    travel = float(sum(np.abs(np.diff(s.waypoints, axis=0)).sum() for s in plan.segments))
    stats = {
        "expected": "solvable",
        "family": family.name,
        "robot": builder.robot_name,
        "seed": builder.seed,
        "transfers": plan.grasp_count,
        "joint_travel_rad": round(travel, 6),
    }
    plan = replace(plan, stats=stats)
    what = (
        f"{builder.robot_name} ({world.robot.dof} joints), a {builder.thing.shape} {list(builder.thing.size)} m, "
        f"from face {start.face} to face {goal.face}, grasp {index} ({builder.grasps[index][0]})"
    )
    notes = (
        what,
        *builder.notes,
        f"Witness: {plan.grasp_count} transfer, joint travel {travel:.2f} rad, validated at 0.002 rad.",
    )
    return SpatialGenerated(
        family.name, builder.robot_name, builder.seed, {"world": final}, plan, True, notes, 0, stats
    )


def _unsolvable(builder: _Builder) -> SpatialGenerated:
    """The goal inside a closed box (its support the floor, four walls and a lid), or on a table out of
    reach."""
    family, rng, settings = builder.family, builder.rng, builder.settings
    index, start, goal = builder.holds()
    builder.table("table_a", start)
    boxed = rng.random() < 0.5
    thing = builder.thing
    assert builder.grasps
    if not boxed:  # move the goal out of reach, along the same direction
        grasp_reach = max(float(np.linalg.norm(g[:3])) for _, g in builder.grasps)
        bound = builder.arm.reach + grasp_reach + 0.005 + 0.02  # + grasp_tolerance + goal_tolerance
        direction = goal.pose[:2, 3] - builder.arm.shoulder[:2]
        direction /= np.linalg.norm(direction)
        far = builder.arm.shoulder[:2] + direction * (bound + rng.uniform(0.1, 0.3))
        goal.pose[:2, 3] = far
        goal.pose[2, 3] = builder.arm.shoulder[2] + (goal.pose[2, 3] - builder.arm.shoulder[2]) * 0.5
    builder.table("table_b", goal)
    tree = builder.tree(start, goal, start.up)
    world = builder.world(tree)
    initial = builder.initial(world, start)
    tree["robot"]["initial"] = [round(float(v), 9) for v in initial]
    if boxed:
        _closed_box(builder, goal)
        why = (
            "the goal lies inside a closed box (table_b its floor, four walls and a lid) and the object starts "
            "outside it: it cannot get in"
        )
    else:
        distance = float(np.linalg.norm(goal.pose[:3, 3] - builder.arm.shoulder))
        why = (
            f"the goal's centre is {distance:.3f} m from the first joint; the tcp never gets farther than "
            f"{builder.arm.reach:.3f} m from it, nor a grasp's tcp nearer the object's centre than its offset "
            "allows: no grasp holds the object within the goal tolerance"
        )
    final = {**tree, "obstacle_names": list(builder.obstacles), "obstacles": dict(builder.obstacles)}
    world = builder.world(final)
    checker = SpatialChecker(
        world.robot, world.spheres, world.obstacles, world.bounds, resting_object=object_obstacle(world, start.pose)
    )
    if not checker.valid(world.initial[None])[0] or resting_problems(world, start.pose, "start"):
        raise _RejectedError("the start is not free")
    if boxed and resting_problems(world, goal.pose, "goal"):
        raise _RejectedError("the object does not fit in the closed box")
    stats = {"expected": "unsolvable", "family": family.name, "robot": builder.robot_name, "seed": builder.seed}
    failed = Plan(
        world.name,
        tuple(world.robot.joint_names),
        False,
        f"no plan exists (unsolvable by construction): {why}",
        stats=stats,
        world_kind=WORLD_KIND,
    )
    notes = (
        f"{builder.robot_name} ({world.robot.dof} joints), a {thing.shape} {list(thing.size)} m",
        f"No plan exists: {why}.",
    )
    del index, settings
    return SpatialGenerated(
        family.name, builder.robot_name, builder.seed, {"world": final}, failed, False, notes, 0, stats
    )


def _closed_box(builder: _Builder, goal: _Hold) -> None:
    """Walls and a lid around the goal placement, on ``table_b`` (which then reaches under the walls)."""
    rng, settings = builder.rng, builder.settings
    thing = builder.thing
    corners = _footprint(thing, goal)
    gap = float(rng.uniform(0.02, 0.04))
    half = np.abs(corners).max(axis=0) + gap
    centre = goal.pose[:3, 3]
    top = float(goal.pose[2, 3] - thing.height(goal.face))
    height = 2 * thing.height(goal.face) + gap
    t = settings.board_thickness_m
    floor = builder.obstacles["table_b"]
    floor["size"] = [
        round(float(max(floor["size"][0], 2 * (half[0] + t) + 0.02)), 6),
        round(float(max(floor["size"][1], 2 * (half[1] + t) + 0.02)), 6),
        floor["size"][2],
    ]
    floor["pose"][3:] = [0, 0, 0]
    floor["pose"][:2] = [round(float(centre[0]), 6), round(float(centre[1]), 6)]
    for name, size, offset in (
        ("box_north", [2 * (half[0] + t), t, height], [0, half[1] + t / 2]),
        ("box_south", [2 * (half[0] + t), t, height], [0, -half[1] - t / 2]),
        ("box_east", [t, 2 * half[1], height], [half[0] + t / 2, 0]),
        ("box_west", [t, 2 * half[1], height], [-half[0] - t / 2, 0]),
    ):
        builder.obstacles[name] = _box(
            name, size, [centre[0] + offset[0], centre[1] + offset[1], top + height / 2, 0, 0, 0]
        )
    builder.obstacles["box_lid"] = _box(
        "box_lid", [2 * (half[0] + t), 2 * (half[1] + t), t], [centre[0], centre[1], top + height + t / 2, 0, 0, 0]
    )


def _footprint(thing: MovableObject, hold: _Hold) -> NDArray[np.float64]:
    """The object's extent about its centre in world x, y (corners of its bounding box, (8, 2))."""
    if thing.shape == "box":
        half = np.asarray(thing.size) / 2
    else:
        half = np.array([thing.size[1], thing.size[1], thing.size[0] / 2])
    local = np.array(np.meshgrid(*[[-h, h] for h in half], indexing="ij")).reshape(3, -1).T
    return np.asarray((local @ hold.pose[:3, :3].T)[:, :2])


# ------------------------------------------------------------------------------------------- entry points


def _stream(family: str, robot: str, seed: int, attempt: int) -> np.random.Generator:
    return np.random.default_rng([zlib.crc32(family.encode()), zlib.crc32(robot.encode()), seed, attempt])


def generate_spatial(
    family: str, seed: int, robot: str = "panda", settings: SpatialGeneration | None = None
) -> SpatialGenerated:
    """The world of spatial ``family`` on ``robot`` (``panda``, ``ur5`` or ``random``) for ``seed``; the same
    arguments give the same world and witness. :class:`UnknownFamilyError` for an unknown family,
    ``ValueError`` for a bad robot or seed, :class:`GenerationError` when no attempt gave a world."""
    if family not in SPATIAL_FAMILIES:
        raise UnknownFamilyError(family, list(SPATIAL_FAMILIES))
    if robot not in SPATIAL_ROBOTS:
        raise ValueError(f"robot: expected one of {', '.join(SPATIAL_ROBOTS)}, got {robot!r}")
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ValueError(f"seed: expected an integer >= 0, got {seed!r}")
    settings = settings or SpatialGeneration()
    chosen = SPATIAL_FAMILIES[family]
    reasons: list[str] = []
    attempts = settings.random_attempts if robot == "random" else settings.attempts
    for attempt in range(attempts):
        builder = _Builder(chosen, robot, int(seed), _stream(family, robot, int(seed), attempt), settings)
        try:
            made = _solvable(builder) if chosen.solvable else _unsolvable(builder)
        except _RejectedError as rejected:
            reasons.append(str(rejected))
            continue
        return replace(made, attempts=attempt + 1, stats={**made.stats, "attempts": attempt + 1})
    raise GenerationError(
        f"family {family} on {robot}, seed {seed}: no world in {attempts} attempts (last: {reasons[-1]})"
    )


def _relative(parameters: dict[str, Any], folder: Path) -> dict[str, Any]:
    """The parameters with the robot's files written relative to ``folder`` (where the file goes)."""
    world = dict(parameters["world"])
    robot = dict(world["robot"])
    for key in ("urdf", "srdf"):
        if key in robot:
            robot[key] = os.path.relpath(robot[key], folder.resolve())
    world["robot"] = robot
    return {"world": world}


def spatial_world_text(generated: SpatialGenerated, folder: Path) -> str:
    """The parameter file's text for a file in ``folder``: a comment header, then the tree."""
    header = [
        f"# Generated by `clew_world {generated.family} --robot {generated.robot} --seed {generated.seed}`.",
        f"# expected: {'solvable' if generated.solvable else 'unsolvable'}",
        *(f"# {line}" for line in generated.notes),
    ]
    if generated.solvable:
        header.append(
            "# Solvable by construction: its witness plan (clew-plan/1) is written next to it as *.witness.json."
        )
    body = yaml.safe_dump(
        {"clew_planner": {"ros__parameters": _relative(generated.parameters, folder)}},
        sort_keys=False,
        default_flow_style=None,
        width=1 << 16,
    )
    return "\n".join(header) + "\n" + body


def write_spatial_world(generated: SpatialGenerated, path: str | Path, *, witness: bool = True) -> list[Path]:
    """Write the parameter file at ``path`` (robot files relative to it) and, unless ``witness`` is false,
    the witness next to it (``WORLD.witness.json``); returns the paths written."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(spatial_world_text(generated, path.parent), encoding="utf-8")
    written = [path]
    if witness:
        written.append(generated.witness.write(path.with_name(path.stem + ".witness.json")))
    return written
