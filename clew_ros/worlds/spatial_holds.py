"""The pieces a spatial world's witness is built from (:mod:`clew_ros.worlds.spatial` assembles them).

- :class:`SpatialGeneration`: the numbers the generator builds with;
- :class:`Arm` (:func:`load_arm`): the shipped Panda or UR5, or a random serial arm, with its sphere model and
  a bound on its reach;
- :func:`draw_object` and :func:`grasps_of`: a box or a cylinder and its grasps (from above, into each side);
- :class:`Solver` and :func:`find_hold`: a configuration holding the object level on a face near a point
  (damped least squares on the tcp's forward kinematics), with its approach and its lift (:class:`Hold`);
- :class:`Sweep`: the witness's configurations and placements, and whether a new obstacle clears them.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.plan import Plan
from clew_ros.spatial.checker import Held, SpatialChecker
from clew_ros.spatial.inverse import IKSettings, InverseKinematics
from clew_ros.spatial.kernels.collide import clearance_of_sphere
from clew_ros.spatial.placements import FACE_NORMALS, FACE_RPY, MovableObject, face_yaw
from clew_ros.spatial.plan import replay
from clew_ros.spatial.random_robot import BASE_LINK, TIP_LINK, RandomRobotSettings, random_robot_urdf
from clew_ros.spatial.robot import RobotModel, load_robot, robot_from_parameters
from clew_ros.spatial.scene import Obstacle, obstacle_arrays
from clew_ros.spatial.spheres import SphereModel, SphereSettings, cover, sphere_model
from clew_ros.spatial.transforms import matrix_pose, pose_matrix, rpy_matrix
from clew_ros.spatial.world import SpatialWorld

__all__ = [
    "APPROACH_STEPS",
    "Arm",
    "Hold",
    "Solver",
    "SpatialGeneration",
    "Sweep",
    "config_folder",
    "draw_object",
    "find_hold",
    "footprint",
    "grasps_of",
    "hold_from",
    "inflated",
    "load_arm",
]

Matrix = NDArray[np.float64]


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


def config_folder() -> Path:
    """The package's ``config`` folder (the source tree's, else the installed share)."""
    source = Path(__file__).resolve().parents[2] / "config"
    if (source / "robots").is_dir():
        return source
    from ament_index_python.packages import get_package_share_directory  # an installed package only

    return Path(get_package_share_directory("clew_ros")) / "config"


# --------------------------------------------------------------------------------------------- the arms


@dataclass(frozen=True, eq=False)
class Arm:
    tree: dict[str, Any]  # world.robot without initial
    robot: RobotModel
    spheres: SphereModel
    home: NDArray[np.float64] | None
    reach: float  # the tcp is never farther than this from the first joint (m)
    shoulder: NDArray[np.float64]  # the first joint's origin in world


def reach_bound(robot: RobotModel) -> tuple[float, NDArray[np.float64]]:
    """A bound on the tcp's distance from the first joint (sum of the offsets after it, prismatic travel
    added), and that joint's origin."""
    offsets = [float(np.linalg.norm(robot.origins[j][:3, 3])) for j in range(1, robot.dof)]
    travel = [max(abs(robot.lower[j]), abs(robot.upper[j])) for j in range(robot.dof) if robot.prismatic[j]]
    tcp = float(np.linalg.norm(robot.tcp[:3, 3]))
    shoulder = (robot.base @ robot.origins[0])[:3, 3]
    return sum(offsets) + sum(travel) + tcp, shoulder


@functools.cache
def shipped_arm(name: str) -> Arm:
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
    reach, shoulder = reach_bound(robot)
    return Arm(tree, robot, sphere_model(robot), home, reach, shoulder)


def load_arm(name: str, rng: np.random.Generator, *, wrist: bool = False) -> Arm:
    """The shipped arm ``name``, or a random arm drawn from ``rng`` (``wrist``: of 6-7 joints, its last three a
    wrist: :attr:`~clew_ros.spatial.random_robot.RandomRobotSettings.wrist`)."""
    if name != "random":
        return shipped_arm(name)
    text = random_robot_urdf(rng, RandomRobotSettings(joints=(6, 7), wrist=True) if wrist else None)
    robot = load_robot(text, folder=Path.cwd(), base_link=BASE_LINK, tip_link=TIP_LINK, source="random_robot")
    last = f"link_{robot.dof}"
    tree = {"description": text, "base_link": BASE_LINK, "tip_link": TIP_LINK, "gripper_links": [last]}
    robot = replace(robot, gripper_links=(last,))
    reach, shoulder = reach_bound(robot)
    return Arm(tree, robot, sphere_model(robot), None, reach, shoulder)


# ----------------------------------------------------------------------------------- object and grasps


def draw_object(rng: np.random.Generator) -> MovableObject:
    if rng.random() < 0.6:
        return MovableObject(
            "box",
            (round(rng.uniform(0.03, 0.06), 3), round(rng.uniform(0.03, 0.06), 3), round(rng.uniform(0.06, 0.14), 3)),
        )
    return MovableObject("cylinder", (round(rng.uniform(0.06, 0.14), 3), round(rng.uniform(0.015, 0.03), 3)))


def grasp_pose(normal: NDArray[np.float64], up: NDArray[np.float64], reach: float, raised: float = 0.0) -> list[float]:
    """The tcp pose (6 numbers, object frame) entering along ``-normal`` from the face ``reach`` out (and
    ``raised`` along ``up``), its x axis along ``up``."""
    z = -normal
    y = np.cross(z, up)
    matrix = np.eye(4)
    matrix[:3, :3] = np.column_stack([up, y, z])
    matrix[:3, 3] = normal * reach + up * raised
    return [round(v, 9) for v in matrix_pose(matrix)]


def grasps_of(thing: MovableObject, depth: float) -> list[tuple[str, list[float]]]:
    """Named grasps: ``top`` (down into the +z face; a box also turned a quarter) and ``side`` ones."""
    out = []
    ez, ex, ey = np.array([0.0, 0, 1]), np.array([1.0, 0, 0]), np.array([0.0, 1, 0])
    half_z = thing.size[2] / 2 if thing.shape == "box" else thing.size[0] / 2
    out.append(("top", grasp_pose(ez, ex, half_z - min(depth, 0.4 * half_z))))
    out.append(("top", grasp_pose(ez, ey, half_z - min(depth, 0.4 * half_z))))
    if thing.shape == "box":
        sides = [(ex, thing.size[0] / 2), (-ex, thing.size[0] / 2), (ey, thing.size[1] / 2), (-ey, thing.size[1] / 2)]
    else:
        radius = thing.size[1]
        sides = [(np.array([math.cos(a), math.sin(a), 0.0]), radius) for a in (0.0, math.pi / 2, math.pi, -math.pi / 2)]
    # the side grasps hold the upper part (a quarter of the height above the centre): the hand clear of the support
    out += [("side", grasp_pose(n, ez, half - min(depth, 0.4 * half), half_z / 2)) for n, half in sides]
    return out


# ---------------------------------------------------------------------------------- holds by least squares


class Solver:
    """Damped least squares on residuals of the tcp's pose (numerical Jacobian, one compiled forward
    kinematics call per step), within the joint limits."""

    def __init__(self, arm: Arm, settings: SpatialGeneration) -> None:
        self.robot = arm.robot
        # the step only clamped at the joint limits: the worlds stay the ones generated before the active set
        self.kinematics = InverseKinematics(arm.robot, IKSettings(active_set=False))
        self.settings = settings
        #: the arm alone (limits, self-collision)
        self.alone = SpatialChecker(arm.robot, arm.spheres, exact=False)

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


def level_residual(
    grasp: Matrix, face: str, target: Sequence[float | None], weight: float
) -> Callable[[Matrix], Matrix]:
    """Residuals of holding the object (by ``grasp``) with ``face`` straight down, its centre near ``target``
    (``None``: that coordinate free), position errors weighted ``weight``."""
    inverse = np.linalg.inv(grasp)
    axis, sign = FACE_NORMALS[face]
    chosen = [i for i, t in enumerate(target) if t is not None]
    goal = np.array([target[i] for i in chosen], dtype=np.float64)

    def residual(tcp: Matrix) -> Matrix:
        placed = tcp @ inverse
        normal = placed[:, :3, axis] * sign
        normal[:, 2] += 1.0  # straight down: (0, 0, -1)
        return np.hstack([normal, weight * (placed[:, chosen, 3] - goal)])

    return residual


def position_residual(target: Matrix) -> Callable[[Matrix], Matrix]:
    def residual(tcp: Matrix) -> Matrix:
        return np.asarray(tcp[:, :3, 3] - target[:3, 3])

    return residual


#: The approach is followed through these fractions of :attr:`SpatialGeneration.approach_m`.
APPROACH_STEPS = (0.1, 0.25, 0.5, 0.75, 1.0)


@dataclass
class Hold:
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


def follow(
    solver: Solver, arm: Arm, q: NDArray[np.float64], targets: Sequence[Matrix], rng: np.random.Generator
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
            last, miss = solver.solve(last, position_residual(target))
            if miss > 0.3 * float(np.linalg.norm(target[:3, 3] - start[:3, 3])):
                return None
        path.append(last)
    return path


def find_hold(
    solver: Solver,
    arm: Arm,
    grasp: Matrix,
    face: str,
    point: NDArray[np.float64],
    *,
    height: float | None,
    rng: np.random.Generator,
    near: NDArray[np.float64] | None = None,
    lift_m: float | None = None,
) -> Hold | None:
    """A configuration holding the object level on ``face`` near ``point`` (its centre at ``height`` when
    given), and the approach above it (the object lifted ``lift_m``, default the settings'); ``None`` when
    the solve does not get there."""
    seeds = [s for s in (near, arm.home) if s is not None]
    seeds += list(rng.uniform(arm.robot.lower, arm.robot.upper, size=(solver.settings.hold_seeds, arm.robot.dof)))
    for seed in seeds:  # the first seed that gets there, the arm clear of itself
        q, _ = solver.solve(seed, level_residual(grasp, face, list(point), 1.0))
        q, error = solver.solve(q, level_residual(grasp, face, [None, None, height], 10.0))
        if error <= solver.settings.level_tolerance and solver.alone.valid(q[None])[0]:
            break
    else:
        return None
    tcp = solver.kinematics.tcp_poses(q[None])[0]
    pose = tcp @ np.linalg.inv(grasp)
    axis, sign = FACE_NORMALS[face]
    if pose[2, axis] * sign > -0.5:
        return None
    pose[:3, :3] = rpy_matrix(0.0, 0.0, face_yaw(pose[:3, :3], face)) @ rpy_matrix(*FACE_RPY[face])
    return hold_from(solver, arm, q, pose, face, rng=rng, lift_m=lift_m)


def hold_from(
    solver: Solver,
    arm: Arm,
    q: NDArray[np.float64],
    pose: Matrix,
    face: str,
    *,
    rng: np.random.Generator,
    lift_m: float | None = None,
) -> Hold | None:
    """The hold of the object at ``pose`` by configuration ``q``: the tcp's way back along its approach and the
    object's lift (straight up, then back along the approach); ``None`` when one leaves the arm's reach."""
    tcp = solver.kinematics.tcp_poses(q[None])[0]
    distance = solver.settings.approach_m  # in short steps: nearly straight for the tcp
    back = [tcp @ pose_matrix([0.0, 0.0, -f * distance, 0.0, 0.0, 0.0]) for f in APPROACH_STEPS]
    rise = solver.settings.lift_m if lift_m is None else lift_m
    raised = [pose_matrix([0.0, 0.0, f * rise, 0.0, 0.0, 0.0]) @ tcp for f in (0.5, 1.0)]
    up = [*raised, *(raised[-1] @ pose_matrix([0.0, 0.0, -f * distance, 0.0, 0.0, 0.0]) for f in APPROACH_STEPS)]
    path, lift = follow(solver, arm, q, back, rng), follow(solver, arm, q, up, rng)
    if path is None or lift is None:
        return None
    return Hold(q, path, lift, pose, face)


# -------------------------------------------------------------------------------------- the witness sweep


class Sweep:
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
        grown = inflated(obstacle, self.margin) if inflate else obstacle
        robot, spheres = self.world.robot, self.world.spheres
        if not SpatialChecker(robot, spheres, [grown], self_collision=False, exact=False).valid(self.all).all():
            return False
        held = Held(self.shape, self.grasp_rel, ())
        if (
            not SpatialChecker(robot, spheres, [grown], self_collision=False, held=held, exact=False)
            .valid(self.held)
            .all()
        ):
            return False
        return all(object_clear(self.cover, pose, grown) for pose in self.rests)


def object_clear(cover_: tuple[Matrix, Matrix], pose: Matrix, obstacle: Obstacle) -> bool:
    centers, radii = cover_
    packed = obstacle_arrays([obstacle])
    placed = centers @ pose[:3, :3].T + pose[:3, 3]
    return all(
        clearance_of_sphere(p, r, packed["obs_kind"][0], packed["obs_r"][0], packed["obs_t"][0], packed["obs_dims"][0])
        > 0.0
        for p, r in zip(placed, radii, strict=True)
    )


def inflated(obstacle: Obstacle, margin: float) -> Obstacle:
    if obstacle.shape == "box":
        size = tuple(v + 2 * margin for v in obstacle.size)
    elif obstacle.shape == "cylinder":
        size = (obstacle.size[0] + 2 * margin, obstacle.size[1] + margin)
    else:
        size = (obstacle.size[0] + margin,)
    return Obstacle(obstacle.name, obstacle.shape, size, obstacle.pose)


def footprint(thing: MovableObject, hold: Hold) -> NDArray[np.float64]:
    """The object's extent about its centre in world x, y (corners of its bounding box, (8, 2))."""
    if thing.shape == "box":
        half = np.asarray(thing.size) / 2
    else:
        half = np.array([thing.size[1], thing.size[1], thing.size[0] / 2])
    local = np.array(np.meshgrid(*[[-h, h] for h in half], indexing="ij")).reshape(3, -1).T
    return np.asarray((local @ hold.pose[:3, :3].T)[:, :2])
