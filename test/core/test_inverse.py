"""Inverse kinematics (clew_ros/core/inverse.py): answers put the point on its target, stay within the
joint limits and near their seeds; a mirrored configuration keeps a point that lies on the mirror line."""

from __future__ import annotations

import numpy as np
import pytest

from clew_ros.core.inverse import mirrored, solve_point
from clew_ros.core.kinematics import compose, tip_poses, wrap_angle
from clew_ros.core.world import Robot


def _robot(joints: int) -> Robot:
    lengths = np.linspace(1.0, 0.6, joints) * 1.7 / np.linspace(1.0, 0.6, joints).sum()
    return Robot(
        np.zeros(2),
        lengths,
        np.r_[-3.1, np.full(joints - 1, -2.8)],
        np.r_[3.1, np.full(joints - 1, 2.8)],
        np.zeros(joints),
    )


@pytest.mark.parametrize("joints", [2, 3, 5, 7])
def test_answers_reach_their_targets_within_the_limits(joints: int) -> None:
    robot = _robot(joints)
    rng = np.random.default_rng(joints)
    truth = rng.uniform(robot.joint_lower, robot.joint_upper, (200, joints))
    offsets = rng.uniform(-0.2, 0.2, (200, 2))
    targets = compose(tip_poses(robot, truth), np.c_[offsets, np.zeros(200)])[:, :2]
    seeds = np.clip(truth + rng.normal(0.0, 0.3, truth.shape), robot.joint_lower, robot.joint_upper)
    q, error, steps = solve_point(robot, seeds, targets, offsets=offsets)
    assert np.all(q >= robot.joint_lower)
    assert np.all(q <= robot.joint_upper)
    reached = error <= 1e-9
    assert reached.mean() >= 0.9
    found = compose(tip_poses(robot, q[reached]), np.c_[offsets[reached], np.zeros(reached.sum())])[:, :2]
    assert np.max(np.linalg.norm(found - targets[reached], axis=1)) <= 1e-9
    # least-norm steps: an answer lies about as near its seed as the configuration the target came from
    assert np.median(np.abs(q - seeds).sum(axis=1)) <= 1.5 * np.median(np.abs(truth - seeds).sum(axis=1))
    assert 0 < steps <= 200 * 40


def test_the_angle_is_brought_within_its_tolerance() -> None:
    robot = _robot(3)
    rng = np.random.default_rng(1)
    truth = rng.uniform(-1.5, 1.5, (100, 3))
    targets = tip_poses(robot, truth)
    seeds = truth + rng.normal(0.0, 0.2, truth.shape)
    q, error, _ = solve_point(robot, seeds, targets[:, :2], angles=targets[:, 2], angle_tolerance=0.05)
    reached = error <= 1e-9
    assert reached.mean() >= 0.8
    assert np.all(np.abs(wrap_angle(q[reached].sum(axis=1) - targets[reached, 2])) <= 0.05 + 1e-9)


def test_a_configuration_stops_once_it_is_close_enough() -> None:
    robot = _robot(2)
    q = np.array([[0.3, 0.9]])
    target = tip_poses(robot, q)[:, :2]
    _, error, steps = solve_point(robot, q, target)
    assert error[0] <= 1e-12
    assert steps == 0  # already there: no step taken


def test_mirroring_keeps_the_tip_on_the_mirror_line_and_flips_the_elbow() -> None:
    robot = _robot(2)
    rng = np.random.default_rng(2)
    q = rng.uniform(-1.2, 1.2, (50, 2))
    tips = tip_poses(robot, q)[:, :2]
    other = mirrored(robot, q, np.arctan2(tips[:, 1], tips[:, 0]))
    assert np.max(np.linalg.norm(tip_poses(robot, other)[:, :2] - tips, axis=1)) <= 1e-12
    assert np.array_equal(other[:, 1], -q[:, 1])
