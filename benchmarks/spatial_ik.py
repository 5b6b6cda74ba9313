"""``python -m benchmarks.spatial_ik [--robots panda ur5] [--targets 200] [--seeds 32] [--random-robots 0]``:
the tcp inverse kinematics' success rate and speed (issue 43).

For each shipped robot (config/robots), and for ``--random-robots`` generated chains
(:mod:`clew_ros.spatial.random_robot`, seeds 100, 101, ...): ``--targets`` reachable targets (the tcp poses of random
configurations within the limits) solved in one batch with ``--seeds`` random seeds each. Printed: the
share of targets with at least one solution, the mean number of distinct solutions, the worst tcp error
of any solution (m, rad; the numpy reference forward kinematics), and CPU milliseconds per target (the
compiled kernel warmed up first). Then the same number of unreachable targets (3 m beyond the robot's
reach): the share wrongly solved (must be 0) and their CPU time per target. For the shipped robots, also
the share of targets with a collision-free solution in the 30-box scene of
:mod:`benchmarks.spatial_checker` (targets from valid configurations there) and the CPU time per target
including the checker's filtering. For the generated chains, also :meth:`InverseKinematics.solve_rows` (one seed
per target, the target's configuration moved by up to 0.3 rad a joint): a level face (rows z, rx, ry of a frame
5 cm under the tcp; the target turned about world z by up to 3 rad and moved up to 0.3 m sideways) and a position
(rows x, y, z; a random orientation): the share met and CPU milliseconds per target.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from benchmarks.spatial_checker import CONFIG, ROBOTS, scene
from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.inverse import IKSettings, InverseKinematics, pose_rows
from clew_ros.spatial.random_robot import random_robot
from clew_ros.spatial.robot import RobotModel, robot_from_parameters
from clew_ros.spatial.spheres import sphere_model
from clew_ros.spatial.transforms import pose_matrix


def errors(robot: RobotModel, target: np.ndarray, q: np.ndarray) -> tuple[float, float]:
    pose = robot.tcp_pose(q.tolist())
    cos = (np.trace(pose[:3, :3] @ target[:3, :3].T) - 1.0) / 2.0
    return float(np.linalg.norm(pose[:3, 3] - target[:3, 3])), math.acos(min(1.0, max(-1.0, cos)))


def measure(label: str, robot: RobotModel, targets: int, settings: IKSettings, seed: int) -> None:
    solver = InverseKinematics(robot, settings)
    rng = np.random.default_rng(seed)
    qs = rng.uniform(robot.lower, robot.upper, (targets, robot.dof))
    poses = [robot.tcp_pose(q) for q in qs]
    solver.solve(poses[0], np.random.default_rng(0))  # compiles (or loads) the kernel
    start = time.process_time()
    found = solver.solve_many(poses, rng)
    cpu = time.process_time() - start
    worst_m = worst_rad = 0.0
    for pose, solutions in zip(poses, found, strict=True):
        for q in solutions:
            m, rad = errors(robot, pose, q)
            worst_m, worst_rad = max(worst_m, m), max(worst_rad, rad)
    reach = float(np.max(np.linalg.norm([p[:3, 3] - robot.base[:3, 3] for p in poses], axis=1)))
    far = [pose_matrix([reach + 3.0, 0.0, 0.0, 0.0, 0.0, 0.0]) @ p for p in poses]
    start = time.process_time()
    wrong = solver.solve_many(far, rng)
    far_cpu = time.process_time() - start
    print(
        f"{label:<14} dof {robot.dof}  solved {np.mean([len(s) > 0 for s in found]):6.1%}  "
        f"solutions/target {np.mean([len(s) for s in found]):5.1f}  worst error {worst_m:.1e} m {worst_rad:.1e} rad  "
        f"{cpu / targets * 1e3:6.2f} ms/target  |  unreachable solved {np.mean([len(s) > 0 for s in wrong]):.0%} "
        f"{far_cpu / targets * 1e3:6.2f} ms/target"
    )


def measure_in_scene(label: str, robot: RobotModel, targets: int, settings: IKSettings, seed: int) -> None:
    spheres = sphere_model(robot)
    checker = SpatialChecker(robot, spheres, scene(robot, spheres))
    solver = InverseKinematics(robot, settings)
    rng = np.random.default_rng(seed)
    qs = rng.uniform(robot.lower, robot.upper, (20 * targets, robot.dof))
    qs = qs[checker.valid(qs)][:targets]
    poses = [robot.tcp_pose(q) for q in qs]
    start = time.process_time()
    found = solver.solve_many(poses, rng, checker=checker)
    cpu = time.process_time() - start
    print(
        f"{label:<14} in a 30-box scene: collision-free solved {np.mean([len(s) > 0 for s in found]):6.1%}  "
        f"solutions/target {np.mean([len(s) for s in found]):5.1f}  {cpu / len(poses) * 1e3:6.2f} ms/target"
    )


def measure_rows(label: str, robot: RobotModel, targets: int, seed: int) -> None:
    """:meth:`InverseKinematics.solve_rows` on a level face and on a position (see the module docstring)."""
    solver = InverseKinematics(robot)
    rng = np.random.default_rng(seed)
    qs = rng.uniform(robot.lower, robot.upper, (targets, robot.dof))
    seeds = np.clip(qs + rng.uniform(-0.3, 0.3, qs.shape), robot.lower, robot.upper)
    face = pose_matrix([0.0, 0.0, -0.05, 0.3, 0.0, 0.0])
    level = np.array([pose_matrix([*rng.uniform(-0.3, 0.3, 2), 0.0, 0.0, 0.0, rng.uniform(-3, 3)]) for _ in qs])
    level = level @ solver.tcp_poses(qs) @ face
    position = solver.tcp_poses(qs)
    position[:, :3, :3] = np.array([pose_matrix([0, 0, 0, *rng.uniform(-3, 3, 3)])[:3, :3] for _ in qs])
    parts = []
    for name, goal, rows, frame in (
        ("level face", level, pose_rows(("z", "rx", "ry")), face),
        ("position", position, pose_rows(("x", "y", "z")), None),
    ):
        solver.solve_rows(goal[:2], seeds[:2], rows, frame=frame)  # compiles (or loads) the kernel
        start = time.process_time()
        _, ok = solver.solve_rows(goal, seeds, rows, frame=frame)
        parts.append(f"{name} met {ok.mean():6.1%} {(time.process_time() - start) / targets * 1e3:6.3f} ms/target")
    print(f"{label:<14} dof {robot.dof}  solve_rows: " + "  ".join(parts))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--robots", nargs="*", default=list(ROBOTS), choices=list(ROBOTS))
    parser.add_argument("--targets", type=int, default=200)
    parser.add_argument("--seeds", type=int, default=IKSettings().seeds)
    parser.add_argument("--random-robots", type=int, default=0, help="also this many generated chains")
    args = parser.parse_args(argv)
    settings = IKSettings(seeds=args.seeds)
    print(f"{args.targets} random reachable targets per robot, {args.seeds} seeds each; CPU time, one core")
    for name in args.robots:
        robot = robot_from_parameters(ROBOTS[name], CONFIG)
        measure(name, robot, args.targets, settings, seed=1)
        measure_in_scene(name, robot, args.targets, settings, seed=2)
    if args.random_robots:
        for k in range(args.random_robots):
            robot = random_robot(np.random.default_rng(100 + k))
            measure(f"random {100 + k}", robot, args.targets, settings, seed=1)
            measure_rows(f"random {100 + k}", robot, args.targets, seed=7)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
