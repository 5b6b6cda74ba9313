"""The reach bounds are necessary conditions: they refuse only what no arm pose can do."""

from pathlib import Path

import numpy as np

from clew_ros.core.kinematics import compose, relative, tip_poses
from clew_ros.core.reach import goal_within_reach, within_reach
from clew_ros.core.world import load_world

CONFIG = Path(__file__).resolve().parents[1] / "config"


def test_within_reach_is_the_annulus_the_links_sweep():
    world = load_world(CONFIG / "figure1.yaml")
    lengths = world.robot.link_lengths
    base = world.robot.base
    outer = float(lengths.sum())
    inner = max(0.0, 2.0 * float(lengths.max()) - outer)
    direction = np.array([np.cos(0.3), np.sin(0.3)])
    assert within_reach(world, base + 0.999 * outer * direction)
    assert not within_reach(world, base + 1.001 * outer * direction)
    assert within_reach(world, base + 1.001 * outer * direction, slack=0.01 * outer)
    if inner > 0:
        assert not within_reach(world, base + 0.5 * inner * direction)


def test_every_tip_the_arm_reaches_is_within_reach():
    world = load_world(CONFIG / "arm3_regrasp.yaml")
    rng = np.random.default_rng(0)
    q = rng.uniform(-np.pi, np.pi, size=(500, world.robot.dof))
    tips = tip_poses(world.robot, q)[:, :2]
    assert all(within_reach(world, tip, slack=1e-9) for tip in tips)


def test_goal_within_reach_accepts_poses_the_arm_can_hold_and_refuses_far_ones():
    world = load_world(CONFIG / "figure1.yaml")
    rng = np.random.default_rng(1)
    grasp_rel = relative(np.zeros(3), np.array([0.02, 0.0, 0.0]))  # object just beyond the tip
    q = rng.uniform(-np.pi, np.pi, size=(200, world.robot.dof))
    held = compose(tip_poses(world.robot, q), grasp_rel)
    assert all(goal_within_reach(world, grasp_rel, pose) for pose in held)
    far = world.robot.base + 3.0 * float(world.robot.link_lengths.sum())
    assert not goal_within_reach(world, grasp_rel, np.array([far[0], far[1], 0.0]))
