"""Inverse kinematics (clew_ros/planar/inverse.py): answers put the point on its target, stay within the
joint limits and near their seeds; a mirrored configuration keeps a point that lies on the mirror line."""

from __future__ import annotations

import numpy as np
import pytest

from clew_ros.planar.inverse import InverseSettings, mirrored, solve_point
from clew_ros.planar.kinematics import compose, tip_poses, wrap_angle
from clew_ros.planar.world import Robot


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


def test_full_turns_reach_targets_behind_the_base_from_either_elbow() -> None:
    """shapes2 seed 50: the bar's grasp points lie behind the base (near pi), joint 1 turns all the way round
    (+-3.14159). From the start and from its mirror image the solver stopped at joint 1's limit on every grasp
    point; with ``full_turns`` each seed reaches its point, its own elbow kept, joint 1 inside its limits."""
    robot = Robot(
        np.zeros(2),
        np.array([1.088, 0.715]),
        np.array([-3.14159, -2.17]),
        np.array([3.14159, 2.17]),
        np.array([1.638439, -1.009121]),
    )
    angles = np.linspace(2.93, 2.97, 4)
    targets = np.tile(
        np.column_stack([np.cos(angles), np.sin(angles)]) * np.array([1.2, 1.3, 1.4, 1.25])[:, None], (2, 1)
    )
    start = np.repeat(robot.initial[None], 4, axis=0)
    seeds = np.concatenate([start, mirrored(robot, start, angles)])
    stopped = solve_point(robot, seeds, targets)
    assert np.all(stopped.error > 1e-2)
    wrapped = solve_point(robot, seeds, targets, full_turns=True)
    assert np.all(wrapped.error <= 1e-9)
    assert np.all((wrapped.q >= robot.joint_lower) & (wrapped.q <= robot.joint_upper))
    np.testing.assert_allclose(tip_poses(robot, wrapped.q)[:, :2], targets, atol=1e-9)
    assert np.all(np.sign(wrapped.q[:, 1]) == np.sign(seeds[:, 1]))  # each seed's elbow


def test_full_turns_leave_a_joint_with_narrower_limits_stopped_at_them() -> None:
    """Joint 1 within +-3.1 (not a whole turn): from the seed below the solver meets the limit and stops there,
    ``full_turns`` or not; with +-3.14159 and ``full_turns`` the same seed goes on and reaches the target."""
    target = 1.2 * np.array([[np.cos(-3.0), np.sin(-3.0)]])
    seeds = np.array([[2.6, -0.9]])
    narrow = _robot(2)
    a = solve_point(narrow, seeds, target, full_turns=True)
    b = solve_point(narrow, seeds, target)
    np.testing.assert_array_equal(a.q, b.q)
    assert a.q[0, 0] == pytest.approx(3.1)
    assert a.error[0] > 0.1
    whole = Robot(
        narrow.base, narrow.link_lengths, np.array([-3.14159, -2.8]), np.array([3.14159, 2.8]), narrow.initial
    )
    c = solve_point(whole, seeds, target, full_turns=True)
    assert c.error[0] <= 1e-9
    assert whole.joint_lower[0] <= c.q[0, 0] < 0.0


def test_settings_bound_the_steps_and_a_call_overrides_them() -> None:
    """A copy of :class:`InverseSettings` with fewer iterations stops sooner; a call's ``iterations`` wins."""
    robot = _robot(3)
    rng = np.random.default_rng(4)
    truth = rng.uniform(robot.joint_lower, robot.joint_upper, (50, 3))
    targets = tip_poses(robot, truth)[:, :2]
    seeds = np.clip(truth + rng.normal(0.0, 0.5, truth.shape), robot.joint_lower, robot.joint_upper)
    full = solve_point(robot, seeds, targets)
    one = solve_point(robot, seeds, targets, settings=InverseSettings(iterations=1))
    assert one.steps <= len(seeds) < full.steps
    assert one.error.mean() > full.error.mean()
    again = solve_point(robot, seeds, targets, iterations=40, settings=InverseSettings(iterations=1))
    assert np.array_equal(again.q, full.q)
