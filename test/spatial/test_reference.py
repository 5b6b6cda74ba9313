"""The spatial checker never calls valid a configuration the exact reference (pinocchio + coal on the URDF's
own geometry) finds colliding; skipped without the spatial-ref extra."""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks.spatial_checker import CONFIG, ROBOTS, Reference, scene
from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.robot import RobotModel
from clew_ros.spatial.scene import Obstacle, make_obstacle
from clew_ros.spatial.spheres import SphereModel, sphere_model
from clew_ros.spatial.transforms import pose_matrix

pytest.importorskip("pinocchio")
pytest.importorskip("coal")

URDFS = {**{name: tree["urdf"] for name, tree in ROBOTS.items()}, "panda_capsules": "robots/panda/panda_capsules.urdf"}


def mixed(checker: SpatialChecker, seed: int) -> list[Obstacle]:
    """Boxes, cylinders and spheres around the arm, none touching its base."""
    rng = np.random.default_rng(seed)
    out: list[Obstacle] = []
    while len(out) < 24:
        radius, angle = rng.uniform(0.25, 0.8), rng.uniform(-math.pi, math.pi)
        pose = pose_matrix(
            [radius * math.cos(angle), radius * math.sin(angle), rng.uniform(-0.1, 1.0), *rng.uniform(-3, 3, 3)]
        )
        shape = ("box", "cylinder", "sphere")[len(out) % 3]
        size = {"box": rng.uniform(0.03, 0.2, 3), "cylinder": [rng.uniform(0.05, 0.4), rng.uniform(0.01, 0.08)]}.get(
            shape, [rng.uniform(0.02, 0.1)]
        )
        candidate = make_obstacle(f"o{len(out)}", shape, size, pose, "o")
        if not SpatialChecker(checker.robot, checker.spheres, [candidate]).static_collision:
            out.append(candidate)
    return out


@pytest.mark.parametrize(
    ("name", "kind"), [("panda", "boxes"), ("ur5", "boxes"), ("panda", "mixed"), ("panda_capsules", "mixed")]
)
def test_no_configuration_called_valid_collides_under_the_exact_reference(
    name: str, kind: str, request: pytest.FixtureRequest
) -> None:
    robot: RobotModel = request.getfixturevalue(name)
    spheres: SphereModel = (
        request.getfixturevalue(f"{name}_spheres") if name != "panda_capsules" else sphere_model(robot)
    )
    obstacles = scene(robot, spheres, seed=7) if kind == "boxes" else mixed(SpatialChecker(robot, spheres), seed=9)
    checker = SpatialChecker(robot, spheres, obstacles)
    reference = Reference(robot, CONFIG / URDFS[name], obstacles, checker.pairs)
    qs = np.random.default_rng(8).uniform(robot.lower, robot.upper, size=(2000, robot.dof))
    valid = checker.valid(qs)
    free = np.array([not reference.collides(q) for q in qs])
    assert not np.any(valid & ~free)
    # and the checker is of use: it finds most of what the reference calls free (it is conservative)
    assert valid.sum() > 0.5 * free.sum() > 100
