"""clew_ros.spatial.inverse and kernels/ik: tcp inverse kinematics on the shipped Panda and UR5, and on random
arms (joint limits, 5 joints)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.inverse import IKSettings, InverseKinematics, distinct, grasp_targets, pose_rows
from clew_ros.spatial.kernels.ik import pose_error
from clew_ros.spatial.random_robot import RandomRobotSettings, random_robot
from clew_ros.spatial.robot import RobotModel
from clew_ros.spatial.scene import make_obstacle
from clew_ros.spatial.spheres import SphereModel
from clew_ros.spatial.transforms import axis_motion, pose_matrix

SETTINGS = IKSettings()


def angle_between(a: np.ndarray, b: np.ndarray) -> float:
    """The rotation angle (rad) between two 3x3 rotations."""
    return math.acos(min(1.0, max(-1.0, (np.trace(a @ b.T) - 1.0) / 2.0)))


def reachable_targets(robot: RobotModel, seed: int, count: int) -> tuple[np.ndarray, list[np.ndarray]]:
    qs = np.random.default_rng(seed).uniform(robot.lower, robot.upper, (count, robot.dof))
    return qs, [robot.tcp_pose(q) for q in qs]


def assert_solutions(robot: RobotModel, target: np.ndarray, solutions: np.ndarray) -> None:
    """Every solution within the limits, its (numpy reference) tcp at the target, all pairwise distinct."""
    assert solutions.shape[1] == robot.dof
    assert np.all(solutions >= robot.lower)
    assert np.all(solutions <= robot.upper)
    for q in solutions:
        pose = robot.tcp_pose(q)
        assert np.linalg.norm(pose[:3, 3] - target[:3, 3]) <= SETTINGS.position_tolerance_m * 1.001
        assert angle_between(pose[:3, :3], target[:3, :3]) <= SETTINGS.angle_tolerance_rad * 1.001
    for i in range(len(solutions)):
        for j in range(i):
            assert np.abs(solutions[i] - solutions[j]).max() > SETTINGS.distinct_rad


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_reachable_targets_are_solved(name: str, request: pytest.FixtureRequest) -> None:
    robot: RobotModel = request.getfixturevalue(name)
    solver = InverseKinematics(robot, SETTINGS)
    _, targets = reachable_targets(robot, 0, 25)
    found = solver.solve_many(targets, np.random.default_rng(1))
    assert len(found) == len(targets)
    assert sum(len(s) > 0 for s in found) >= 24  # 99-100 % over 200 targets (benchmarks/spatial_ik.py)
    for target, solutions in zip(targets, found, strict=True):
        assert_solutions(robot, target, solutions)
    assert np.mean([len(s) for s in found]) > 2  # redundant (Panda) or wrapping joints (UR5): several each


def test_a_redundant_arm_gives_many_distinct_solutions(panda: RobotModel) -> None:
    _, targets = reachable_targets(panda, 3, 1)
    solutions = InverseKinematics(panda, SETTINGS).solve(targets[0], np.random.default_rng(4))
    assert len(solutions) >= 4
    assert_solutions(panda, targets[0], solutions)


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_unreachable_targets_have_no_solution(name: str, request: pytest.FixtureRequest) -> None:
    robot: RobotModel = request.getfixturevalue(name)
    solver = InverseKinematics(robot, SETTINGS)
    far = [pose_matrix([3.0, 0.0, 0.5, 0.0, 0.0, 0.0]), pose_matrix([0.0, -2.5, 2.0, 1.0, 0.2, 0.3])]
    assert [len(s) for s in solver.solve_many(far, np.random.default_rng(0))] == [0, 0]


def test_same_seed_same_answers(ur5: RobotModel) -> None:
    _, targets = reachable_targets(ur5, 5, 4)
    first = InverseKinematics(ur5, SETTINGS).solve_many(targets, np.random.default_rng(11))
    again = InverseKinematics(ur5, SETTINGS).solve_many(targets, np.random.default_rng(11))
    for a, b in zip(first, again, strict=True):
        assert a.tobytes() == b.tobytes()
    other = InverseKinematics(ur5, SETTINGS).solve_many(targets, np.random.default_rng(12))
    assert any(a.shape != b.shape or not np.array_equal(a, b) for a, b in zip(first, other, strict=True))


def test_given_seeds_are_tried_first_and_a_six_number_pose_is_a_target(panda: RobotModel) -> None:
    q = np.array([0.3, -0.4, 0.2, -2.0, 0.1, 1.9, 0.5])
    pose = panda.tcp_pose(q)
    roll = math.atan2(pose[2, 1], pose[2, 2])
    pitch = -math.asin(pose[2, 0])
    yaw = math.atan2(pose[1, 0], pose[0, 0])
    target = [*pose[:3, 3], roll, pitch, yaw]
    only_given = InverseKinematics(panda, IKSettings(seeds=0))
    solutions = only_given.solve(target, np.random.default_rng(0), seeds=[q + 0.05])
    assert len(solutions) == 1
    assert np.abs(solutions[0] - q).max() < 0.1  # converged near the seed (on the self-motion of q), not elsewhere
    assert_solutions(panda, pose, solutions)


def test_only_collision_free_solutions_with_a_checker(panda: RobotModel, panda_spheres: SphereModel) -> None:
    _, targets = reachable_targets(panda, 7, 1)
    solver = InverseKinematics(panda, SETTINGS)
    free = solver.solve(targets[0], np.random.default_rng(8))
    assert len(free) >= 3
    elbow = panda.link_poses(free[0])["panda_link4"][:3, 3]  # a box at the first solution's elbow
    blocked = make_obstacle("box", "box", [0.06] * 3, pose_matrix([*elbow, 0, 0, 0]), "box")
    checker = SpatialChecker(panda, panda_spheres, [blocked])
    assert not checker.valid(free[:1])[0]
    kept = solver.solve(targets[0], np.random.default_rng(8), checker=checker)
    assert len(kept) < len(free)
    assert checker.valid(kept).all()
    for q in kept:  # the same runs, filtered
        assert np.abs(free - q).max(axis=1).min() == 0.0


def test_compiled_tcp_matches_the_model(panda: RobotModel, ur5: RobotModel) -> None:
    for robot in (panda, ur5):
        qs, targets = reachable_targets(robot, 9, 6)
        np.testing.assert_allclose(InverseKinematics(robot).tcp_poses(qs), np.array(targets), atol=1e-12)


@pytest.mark.parametrize("angle", [0.0, 1e-9, 1e-4, 0.7, 2.5, math.pi - 1e-7, math.pi])
def test_pose_error_is_the_rotation_vector(angle: float) -> None:
    rng = np.random.default_rng(int(angle * 1000))
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    current = pose_matrix([0.1, 0.2, 0.3, *rng.uniform(-3, 3, 3)])
    target = current.copy()
    target[:3, :3] = axis_motion(axis, angle, prismatic=False)[:3, :3] @ current[:3, :3]
    target[:3, 3] += [0.01, -0.02, 0.03]
    out = np.empty(6)
    total = pose_error((target[:3, :3], target[:3, 3]), (current[:3, :3], current[:3, 3]), np.empty((3, 3)), out)
    np.testing.assert_allclose(out[:3], [0.01, -0.02, 0.03], atol=1e-12)
    if angle > math.pi - 1e-6:  # a half turn either way is the same rotation
        assert min(np.linalg.norm(out[3:] - axis * angle), np.linalg.norm(out[3:] + axis * angle)) < 1e-6
    else:
        np.testing.assert_allclose(out[3:], axis * angle, atol=1e-9)
    assert total == pytest.approx(float(out @ out))


def test_distinct_keeps_the_first_of_close_rows() -> None:
    rows = np.array([[0.0, 0.0], [0.005, -0.004], [0.02, 0.0], [0.0, 0.011]])
    np.testing.assert_array_equal(distinct(rows, 0.01), rows[[0, 2, 3]])
    assert distinct(np.zeros((0, 3)), 0.01).shape == (0, 3)


def test_bad_input_is_refused_naming_it(panda: RobotModel) -> None:
    solver = InverseKinematics(panda, IKSettings(seeds=2))
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match=r"targets\[0\]: expected a 4x4 pose"):
        solver.solve([1.0, 2.0, 3.0], rng)
    with pytest.raises(ValueError, match=r"targets\[1\]: expected a 4x4 pose"):
        solver.solve_many([np.eye(4), np.full((4, 4), np.nan)], rng)
    with pytest.raises(ValueError, match=r"targets\[0\]: expected a rigid transform"):
        solver.solve(np.diag([2.0, 1.0, 1.0, 1.0]), rng)
    with pytest.raises(ValueError, match=r"seeds: expected"):
        solver.solve(np.eye(4), rng, seeds=np.zeros((2, 3)))
    with pytest.raises(ValueError, match=r"qs: expected an \(N, 7\) array"):
        solver.tcp_poses(np.zeros(7))
    with pytest.raises(ValueError, match=r"IKSettings.position_tolerance_m: expected a positive"):
        IKSettings(position_tolerance_m=0.0)
    with pytest.raises(ValueError, match=r"IKSettings.seeds: expected an integer"):
        IKSettings(seeds=-1)
    with pytest.raises(ValueError, match=r"IKSettings.damping: expected damping_min <= damping"):
        IKSettings(damping=1e9)


def test_grasps_of_an_object_are_solved(panda: RobotModel) -> None:
    box_on_table = [0.5, 0.1, 0.3, 0.0, 0.0, 0.4]
    grasps = [0.0, 0.0, 0.06, math.pi, 0.0, 0.0, 0.0, 0.0, 0.06, math.pi, 0.0, math.pi / 2]  # from above, 2 yaws
    targets = grasp_targets(box_on_table, grasps)
    assert targets.shape == (2, 4, 4)
    np.testing.assert_allclose(targets[0][:3, 3], [0.5, 0.1, 0.36], atol=1e-12)
    np.testing.assert_allclose(targets[0][:3, 2], [0.0, 0.0, -1.0], atol=1e-12)  # the tcp's z points down
    found = InverseKinematics(panda, SETTINGS).solve_grasps(box_on_table, grasps, np.random.default_rng(5))
    assert [len(s) > 0 for s in found] == [True, True]
    for target, solutions in zip(targets, found, strict=True):
        assert_solutions(panda, target, solutions)
    with pytest.raises(ValueError, match=r"grasps: expected tcp poses of 6 finite numbers each"):
        grasp_targets(box_on_table, [0.0] * 7)
    with pytest.raises(ValueError, match=r"object_pose: expected a 4x4 pose"):
        grasp_targets([0.0] * 5, grasps)


def test_targets_reached_with_joints_at_their_limits_are_solved_more_often_with_the_active_set() -> None:
    """Tcp poses put there with the last three joints at their lower limits (as a generated world's hold
    may be), on five random arms: the active set (the default) solves more of them, from the same seeds,
    than the clamped step, and nearly all."""
    solved = {True: 0, False: 0}
    count = 0
    for k in range(5):
        robot = random_robot(np.random.default_rng(k))
        qs = np.random.default_rng(0).uniform(robot.lower, robot.upper, (20, robot.dof))
        qs[:, -3:] = robot.lower[-3:]
        targets = [robot.tcp_pose(q) for q in qs]
        count += len(targets)
        for active in (True, False):
            solver = InverseKinematics(robot, IKSettings(seeds=16, active_set=active))
            found = solver.solve_many(targets, np.random.default_rng(1))
            for target, solutions in zip(targets, found, strict=True):
                if len(solutions):
                    assert_solutions(robot, target, solutions)
                    solved[active] += 1
    assert solved[True] > solved[False]
    assert solved[True] >= 0.9 * count


def test_rows_meet_only_the_rows_asked() -> None:
    """An arm of 5 joints sets its tcp level at a height from tilted starts: z and the tilt met within the
    tolerances, x, y and yaw left near the start's, every configuration within the limits."""
    robot = random_robot(np.random.default_rng(7), RandomRobotSettings(joints=(5, 5)))
    solver = InverseKinematics(robot)
    starts = np.random.default_rng(2).uniform(robot.lower, robot.upper, (24, robot.dof))
    here = solver.tcp_poses(starts)
    targets = here.copy()
    targets[:, 2, 3] -= 0.02
    targets[:, :3, :3] = np.eye(3)  # level, yaw 0: only its tilt is asked for
    reached, ok = solver.solve_rows(targets, starts, pose_rows(("z", "rx", "ry")))
    assert ok.sum() >= 12  # most starts get there (some are too tilted for 5 joints within their limits)
    assert np.all(reached >= robot.lower)
    assert np.all(reached <= robot.upper)
    poses = solver.tcp_poses(reached[ok])
    assert np.abs(poses[:, 2, 3] - targets[ok, 2, 3]).max() <= SETTINGS.position_tolerance_m
    assert np.abs(poses[:, 2, 2] - 1.0).max() <= SETTINGS.angle_tolerance_rad  # the tcp's z points up
    moved = np.linalg.norm(poses[:, :2, 3] - here[ok, :2, 3], axis=1)
    assert np.all(moved > 1e-6)  # x and y are free: nothing holds them
    exact = solver.solve_many(list(targets[ok]), np.random.default_rng(0), seeds=[s[None] for s in starts[ok]])
    assert sum(len(found) for found in exact) < ok.sum()  # the whole pose is out of reach from most of them


def test_rows_are_named() -> None:
    assert pose_rows(("x", "rz")).tolist() == [True, False, False, False, False, True]
    with pytest.raises(ValueError, match="rows: expected names among x, y, z, rx, ry, rz"):
        pose_rows(("x", "yaw"))
    with pytest.raises(ValueError, match=r"IKSettings\.active_set: expected true or false"):
        IKSettings(active_set=1)  # type: ignore[arg-type]
