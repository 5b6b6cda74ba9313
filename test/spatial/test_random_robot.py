"""clew_ros.spatial.random_robot: random arms load, their sphere models cover them, the checker and IK work."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.inverse import IKSettings, InverseKinematics
from clew_ros.spatial.random_robot import RandomRobotSettings, random_robot, random_robot_urdf
from clew_ros.spatial.robot import RobotModel, robot_from_parameters
from clew_ros.spatial.spheres import sphere_model, surface_points

SEEDS = range(8)


@pytest.fixture(scope="module")
def robots() -> list[RobotModel]:
    return [random_robot(np.random.default_rng(seed)) for seed in SEEDS]


def test_same_seed_same_bytes_and_different_seeds_differ() -> None:
    first = random_robot_urdf(np.random.default_rng(3))
    assert random_robot_urdf(np.random.default_rng(3)).encode() == first.encode()
    assert random_robot_urdf(np.random.default_rng(4)) != first


def test_every_generated_robot_loads(robots: list[RobotModel]) -> None:
    kinds = set()
    for robot in robots:
        assert 4 <= robot.dof <= 8
        assert robot.joint_names == tuple(f"joint_{k}" for k in range(1, robot.dof + 1))
        assert np.all(robot.lower < robot.upper)
        assert not robot.prismatic.any()
        assert [link.name for link in robot.links] == ["base_link"] + [f"link_{k}" for k in range(1, robot.dof + 1)]
        assert robot.tcp_frame == robot.dof
        kinds |= {g.kind for link in robot.links for g in link.geometries}
        axes_spread = np.abs(robot.axes @ robot.axes.T)[np.triu_indices(robot.dof, 1)]
        assert axes_spread.min() < 0.99  # axes are not all parallel
    assert kinds == {"box", "cylinder", "sphere"}  # boxes, cylinders and capsules (a cylinder and two spheres)


def test_the_text_loads_as_a_robot_description(tmp_path: Path) -> None:
    text = random_robot_urdf(np.random.default_rng(5))
    parameters = {"description": text, "base_link": "base_link", "tip_link": "tool"}
    robot = robot_from_parameters(parameters, tmp_path)
    expected = random_robot(np.random.default_rng(5))
    assert robot.joint_names == expected.joint_names
    q = np.random.default_rng(6).uniform(robot.lower, robot.upper, robot.dof)
    np.testing.assert_allclose(robot.tcp_pose(q), expected.tcp_pose(q), atol=1e-12)


def test_the_joint_count_follows_the_settings() -> None:
    for count in (4, 8):
        settings = RandomRobotSettings(joints=(count, count))
        assert random_robot(np.random.default_rng(count), settings).dof == count


def test_the_sphere_model_covers_every_geometry(robots: list[RobotModel]) -> None:
    rng = np.random.default_rng(0)
    for robot in robots:
        spheres = sphere_model(robot)
        for i, link in enumerate(robot.links):
            centers = spheres.centers[spheres.starts[i] : spheres.starts[i + 1]]
            radii = spheres.radii[spheres.starts[i] : spheres.starts[i + 1]]
            for geometry in link.geometries:
                pose = link.offset @ geometry.origin
                points = surface_points(geometry, 1500, rng) @ pose[:3, :3].T + pose[:3, 3]
                outside = (np.linalg.norm(points[:, None] - centers[None], axis=2) - radii).min(axis=1)
                assert outside.max() <= 1e-12, (robot.name, link.name, geometry.kind)


def test_the_checker_runs_and_sees_self_collisions(robots: list[RobotModel]) -> None:
    for robot in robots:
        checker = SpatialChecker(robot, sphere_model(robot))
        qs = np.random.default_rng(1).uniform(robot.lower, robot.upper, (300, robot.dof))
        valid = checker.valid(qs)
        assert valid.any()
        assert not valid.all()  # no obstacles: the invalid ones fold a link into another
        lo, hi, ok = checker.free_intervals(qs[:50], robot.dof - 1)
        np.testing.assert_array_equal(ok, valid[:50])
        assert np.all(lo[ok] <= qs[:50][ok, -1])
        assert np.all(qs[:50][ok, -1] <= hi[ok])


def test_ik_solves_targets_from_forward_kinematics(robots: list[RobotModel]) -> None:
    settings = IKSettings()
    for robot in robots:
        qs = np.random.default_rng(2).uniform(robot.lower, robot.upper, (8, robot.dof))
        targets = [robot.tcp_pose(q) for q in qs]
        found = InverseKinematics(robot, settings).solve_many(targets, np.random.default_rng(3))
        assert sum(len(s) > 0 for s in found) >= 7, robot.name
        for target, solutions in zip(targets, found, strict=True):
            assert np.all(solutions >= robot.lower)
            assert np.all(solutions <= robot.upper)
            for q in solutions:
                pose = robot.tcp_pose(q)
                assert np.linalg.norm(pose[:3, 3] - target[:3, 3]) <= 1.001 * settings.position_tolerance_m
                cos = (np.trace(pose[:3, :3] @ target[:3, :3].T) - 1) / 2
                assert math.acos(min(1.0, cos)) <= 1.001 * settings.angle_tolerance_rad


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"joints": (5, 4)}, r"RandomRobotSettings.joints: expected \(low, high\)"),
        ({"joints": (0, 3)}, r"RandomRobotSettings.joints: expected whole numbers >= 1"),
        ({"radius_m": (-0.01, 0.02)}, r"RandomRobotSettings.radius_m: expected positive"),
        ({"length_m": (0.05, 0.3)}, r"RandomRobotSettings.length_m: expected the shortest link longer"),
    ],
)
def test_bad_settings_are_refused_naming_them(change: dict[str, tuple[float, float]], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        RandomRobotSettings(**change)  # type: ignore[arg-type]


def test_a_wrist_ends_the_arm_in_three_axes_in_line() -> None:
    settings = RandomRobotSettings(joints=(6, 7), wrist=True)
    for seed in range(5):
        robot = random_robot(np.random.default_rng(seed), settings)
        assert robot.dof in (6, 7)
        wrist = robot.axes[-3:]  # each in its own frame: z, y, z
        assert np.allclose(wrist, [[0, 0, 1], [0, 1, 0], [0, 0, 1]])
        assert np.allclose(robot.origins[-2:, :3, :3], np.eye(3))  # in line: no turn between them
        assert np.allclose(robot.origins[-2:, :2, 3], 0.0)  # each the next one's offset along its own z
        assert np.all(robot.upper[-3:] - robot.lower[-3:] >= 2 * math.pi - 1e-6)  # a full turn (9 digits in the URDF)
    with pytest.raises(ValueError, match="wrist needs 6 joints"):
        RandomRobotSettings(joints=(4, 8), wrist=True)
