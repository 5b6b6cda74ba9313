"""The spatial checker never calls valid a configuration the exact reference (pinocchio + coal on the URDF's
own geometry) finds colliding; skipped without the spatial-ref extra."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.spatial_checker import CONFIG, ROBOTS, Reference, scene
from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.robot import RobotModel
from clew_ros.spatial.spheres import SphereModel

pytest.importorskip("pinocchio")
pytest.importorskip("coal")


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_no_configuration_called_valid_collides_under_the_exact_reference(
    name: str, request: pytest.FixtureRequest
) -> None:
    robot: RobotModel = request.getfixturevalue(name)
    spheres: SphereModel = request.getfixturevalue(f"{name}_spheres")
    obstacles = scene(robot, spheres, seed=7)
    checker = SpatialChecker(robot, spheres, obstacles)
    reference = Reference(robot, CONFIG / ROBOTS[name]["urdf"], obstacles, checker.pairs)
    qs = np.random.default_rng(8).uniform(robot.lower, robot.upper, size=(3000, robot.dof))
    valid = checker.valid(qs)
    free = np.array([not reference.collides(q) for q in qs])
    assert not np.any(valid & ~free)
    # and the checker is of use: it finds most of what the reference calls free (it is conservative)
    assert valid.sum() > 0.5 * free.sum() > 100
