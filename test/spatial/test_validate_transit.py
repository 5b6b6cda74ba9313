"""clew_ros.spatial.validate: transit paths checked at 0.002 rad per joint under the spatial checker."""

from __future__ import annotations

import numpy as np
import pytest

from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.robot import RobotModel
from clew_ros.spatial.scene import make_obstacle
from clew_ros.spatial.spheres import SphereModel
from clew_ros.spatial.transforms import pose_matrix
from clew_ros.spatial.validate import ValidationSettings, validate_transit, validation_samples

START = np.array([0.0, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8])


def path() -> np.ndarray:
    """Turn the wrist, then swing the whole arm about joint 1 by 1 rad."""
    turned = START + np.array([0, 0, 0, 0, 0, 0, 0.3])
    return np.array([START, turned, turned + np.array([1.0, 0, 0, 0, 0, 0, 0])])


def test_samples_move_no_joint_more_than_its_step() -> None:
    a, b = np.array([0.0, 1.0, -0.2]), np.array([0.5, 0.99, 0.1])
    steps = np.array([0.002, 0.002, 0.001])
    samples = validation_samples(a, b, steps)
    assert np.array_equal(samples[0], a)
    assert np.array_equal(samples[-1], b)
    assert np.all(np.abs(np.diff(samples, axis=0)) <= steps * (1 + 1e-9))
    assert len(samples) - 1 in {300, 301}  # the third joint's 0.3 m at 1 mm sets the count (0.3 / 0.001 may round up)
    assert len(validation_samples(a, a, steps)) == 2


def test_a_free_path_passes(panda: RobotModel, panda_spheres: SphereModel) -> None:
    checker = SpatialChecker(panda, panda_spheres)
    assert validate_transit(checker, path()) == []
    assert validate_transit(checker, path()[:1]) == []


def test_a_path_through_an_obstacle_is_refused_naming_the_piece(panda: RobotModel, panda_spheres: SphereModel) -> None:
    waypoints = path()
    middle = panda.tcp_pose(waypoints[1] + [0.5, 0, 0, 0, 0, 0, 0])[:3, 3]
    wall = make_obstacle("wall", "box", [0.04, 0.04, 0.04], pose_matrix([*middle, 0, 0, 0]), "world.obstacles.wall")
    checker = SpatialChecker(panda, panda_spheres, [wall])
    assert checker.valid(waypoints).all()  # the waypoints themselves are free: only the piece between is not
    problems = validate_transit(checker, waypoints)
    assert len(problems) == 1
    assert problems[0].startswith("piece 1 (waypoints 1 -> 2): configuration [")
    assert "touches obstacle 'wall'" in problems[0]
    assert validate_transit(checker, waypoints[:2]) == []
    reversed_problems = validate_transit(checker, waypoints[::-1])
    assert len(reversed_problems) == 1
    assert reversed_problems[0].startswith("piece 0 (waypoints 0 -> 1)")


def test_limits_and_self_collisions_are_named(panda: RobotModel, panda_spheres: SphereModel) -> None:
    checker = SpatialChecker(panda, panda_spheres)
    beyond = START.copy()
    beyond[3] = 0.1  # joint 4's upper limit is -0.0698
    (problem,) = validate_transit(checker, [START, beyond])
    assert problem.startswith("piece 0 (waypoints 0 -> 1)")
    assert "joint panda_joint4 = " in problem
    assert "outside its limits" in problem
    qs = np.random.default_rng(0).uniform(panda.lower, panda.upper, (400, panda.dof))
    folded = qs[~checker.valid(qs)][0]
    assert validate_transit(checker, [folded]) == [
        "waypoint 0 is invalid: a self-collision (two links not exempted touch)"
    ]


def test_leaving_the_bounds_is_named(panda: RobotModel, panda_spheres: SphereModel) -> None:
    tcp_z = panda.tcp_pose(START)[2, 3]
    low_ceiling = np.array([-1.5, -1.5, -0.5, 1.5, 1.5, tcp_z + 0.02])
    checker = SpatialChecker(panda, panda_spheres, bounds=low_ceiling)
    assert validate_transit(checker, [START]) == ["waypoint 0 is invalid: leaves the bounds"]


def test_bad_input_is_refused_naming_it(panda: RobotModel, panda_spheres: SphereModel) -> None:
    checker = SpatialChecker(panda, panda_spheres)
    with pytest.raises(ValueError, match=r"waypoints: expected a \(k, 7\) array"):
        validate_transit(checker, np.zeros((2, 6)))
    with pytest.raises(ValueError, match=r"waypoints: expected a \(k, 7\) array"):
        validate_transit(checker, np.zeros((0, 7)))
    with pytest.raises(ValueError, match=r"waypoints: expected a \(k, 7\) array"):
        validate_transit(checker, [[0.0] * 6 + [float("nan")]])
    with pytest.raises(ValueError, match=r"ValidationSettings.step_rad: expected a positive finite number"):
        ValidationSettings(step_rad=0.0)
