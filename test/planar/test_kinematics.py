"""Forward kinematics against hand-computed poses; pose algebra."""

import numpy as np
import pytest

from clew_ros.planar.kinematics import compose, joint_positions, relative, tip_poses, transform_points, wrap_angle
from clew_ros.planar.world import Robot


def robot(lengths, base=(0.0, 0.0)):
    n = len(lengths)
    return Robot(np.array(base, float), np.array(lengths, float), -np.full(n, 3.0), np.full(n, 3.0), np.zeros(n))


def test_two_link_poses_by_hand():
    r = robot([1.0, 0.5], base=(1.0, 2.0))
    q = np.array([[0.0, 0.0], [np.pi / 2, 0.0], [np.pi / 2, -np.pi / 2], [np.pi, np.pi / 2]])
    points = joint_positions(r, q)
    expected_tips = [(2.5, 2.0), (1.0, 3.5), (1.5, 3.0), (0.0, 1.5)]
    np.testing.assert_allclose(points[:, -1], expected_tips, atol=1e-12)
    np.testing.assert_allclose(points[2, 1], (1.0, 3.0), atol=1e-12)
    np.testing.assert_allclose(tip_poses(r, q)[:, 2], [0.0, np.pi / 2, 0.0, 1.5 * np.pi])


def test_three_link_redundant_pose():
    r = robot([1.0, 1.0, 1.0])
    tip = tip_poses(r, np.array([[np.pi / 2, -np.pi / 2, -np.pi / 2]]))[0]
    np.testing.assert_allclose(tip, (1.0, 0.0, -np.pi / 2), atol=1e-12)


def test_compose_and_relative_are_inverse():
    rng = np.random.default_rng(0)
    a = rng.uniform(-3, 3, (50, 3))
    b = rng.uniform(-3, 3, (50, 3))
    np.testing.assert_allclose(compose(a, relative(a, b)), b, atol=1e-12)


def test_transform_points():
    pose = np.array([1.0, 0.0, np.pi / 2])
    np.testing.assert_allclose(transform_points(pose, np.array([[1.0, 0.0]])), [[1.0, 1.0]], atol=1e-12)


@pytest.mark.parametrize(("angle", "wrapped"), [(0.0, 0.0), (np.pi + 0.1, -np.pi + 0.1), (-7.0, -7.0 + 2 * np.pi)])
def test_wrap_angle(angle, wrapped):
    assert wrap_angle(angle) == pytest.approx(wrapped)
