"""clew_ros.spatial.ik: tcp poses solved from many seeds, every solution distinct and within the limits."""

from __future__ import annotations

import numpy as np
import pytest

from clew_ros.spatial.ik import IkSettings, solve_tcp_pose
from clew_ros.spatial.robot import RobotModel
from clew_ros.spatial.transforms import pose_matrix

SETTINGS = IkSettings()


def rotation_angle(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.arccos(np.clip((np.trace(a[:3, :3] @ b[:3, :3].T) - 1) / 2, -1.0, 1.0)))


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_reachable_poses_are_solved(name: str, request: pytest.FixtureRequest) -> None:
    robot: RobotModel = request.getfixturevalue(name)
    rng = np.random.default_rng(3)
    found = 0
    for q in rng.uniform(robot.lower, robot.upper, size=(6, robot.dof)):
        target = robot.tcp_pose(q)
        solutions = solve_tcp_pose(robot, target, np.random.default_rng(4), SETTINGS)
        found += len(solutions) > 0
        for solution in solutions:
            assert np.all((robot.lower <= solution) & (solution <= robot.upper))
            reached = robot.tcp_pose(solution)
            assert np.linalg.norm(reached[:3, 3] - target[:3, 3]) <= SETTINGS.position_tolerance_m + 1e-12
            assert rotation_angle(reached, target) <= SETTINGS.angle_tolerance_rad + 1e-9
        for i in range(len(solutions)):
            for j in range(i):
                assert np.max(np.abs(solutions[i] - solutions[j])) > SETTINGS.distinct_rad
    assert found >= 5  # from 32 random seeds, nearly every reachable pose


def test_a_redundant_arm_gets_several_solutions(panda: RobotModel) -> None:
    target = panda.tcp_pose([0.0, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8])
    assert len(solve_tcp_pose(panda, target, np.random.default_rng(5), SETTINGS)) >= 3


def test_out_of_reach_and_deterministic(panda: RobotModel) -> None:
    far = pose_matrix([2.0, 0.0, 0.5, 0.0, 0.0, 0.0])
    assert solve_tcp_pose(panda, far, np.random.default_rng(6), SETTINGS).shape == (0, 7)
    target = panda.tcp_pose([0.3, -0.2, 0.1, -2.2, 0.1, 2.0, 0.3])
    first = solve_tcp_pose(panda, target, np.random.default_rng(7), SETTINGS)
    again = solve_tcp_pose(panda, target, np.random.default_rng(7), SETTINGS)
    np.testing.assert_array_equal(first, again)
