"""Continuous joints (interface.md section 1b): equal modulo 2 pi, a move takes the short way round, in the
validator, the planner and the trajectory a controller gets."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from clew_ros.core.plan import Plan
from clew_ros.motion.spatial import UrdfTree, spatial_track
from clew_ros.spatial.plan import make_plan, validate_plan
from clew_ros.spatial.space import plan
from clew_ros.spatial.turns import (
    goal_turns,
    joint_features,
    joint_gaps,
    nearest_turns,
    short_way,
    split_turns,
    unwrapped,
    wrapped,
)
from clew_ros.spatial.world import SpatialWorld, spatial_world_from_parameters

#: A turntable (joint_1, continuous about z) carrying an arm 0.5 m long along its x, and an elbow
#: (joint_2, revolute about y) at its end; then a fixed tool.
TURNTABLE = """<?xml version="1.0"?>
<robot name="turntable">
  <link name="base_link"><collision><geometry><cylinder radius="0.05" length="0.1"/></geometry></collision></link>
  <link name="arm"><collision><origin xyz="0.3 0 0" rpy="0 0 0"/><geometry><box size="0.4 0.04 0.04"/></geometry>
  </collision></link>
  <link name="forearm"><collision><origin xyz="0.1 0 0" rpy="0 0 0"/><geometry><box size="0.16 0.03 0.03"/>
  </geometry></collision></link>
  <link name="tool"/>
  <joint name="joint_1" type="continuous"><parent link="base_link"/><child link="arm"/>
    <origin xyz="0 0 0.1" rpy="0 0 0"/><axis xyz="0 0 1"/><limit effort="1" velocity="1"/></joint>
  <joint name="joint_2" type="revolute"><parent link="arm"/><child link="forearm"/>
    <origin xyz="0.52 0 0" rpy="0 0 0"/><axis xyz="0 1 0"/><limit lower="-1.5" upper="1.5" effort="1" velocity="1"/>
  </joint>
  <joint name="tool_joint" type="fixed"><parent link="forearm"/><child link="tool"/><origin xyz="0.2 0 0"/></joint>
</robot>
"""


@dataclass(frozen=True)
class Timing:
    """The ``trajectory.*`` settings a plan is timed with (:class:`clew_ros.motion.playback.TrackTiming`)."""

    velocity_limit_rad_s: float = 1.0
    max_acceleration_rad_s2: float = 2.0
    grasp_dwell_s: float = 0.5


def turntable_world(tmp_path: Path, **robot: object) -> SpatialWorld:
    """The turntable among one post on +x (the arm at joint_1 = 0 goes through it)."""
    tree = {
        "kind": "spatial",
        "name": "turntable",
        "robot": {"description": TURNTABLE, "base_link": "base_link", "tip_link": "tool", **robot},
        "obstacle_names": ["post"],
        "obstacles": {"post": {"shape": "box", "size": [0.1, 0.1, 0.6], "pose": [0.45, 0.0, 0.1, 0.0, 0.0, 0.0]}},
    }
    return spatial_world_from_parameters({"world": tree}, tmp_path)


def test_the_helpers_turn_the_short_way() -> None:
    mask = np.array([True, False])
    assert short_way(np.array([3.0, 3.0]), np.array([-3.0, -3.0]), mask) == pytest.approx([2 * math.pi - 3.0, -3.0])
    assert joint_gaps(np.array([3.0, 3.0]), np.array([-3.0, -3.0]), mask) == pytest.approx([2 * math.pi - 6.0, 6.0])
    path = np.array([[3.0, 0.0], [-3.0, 0.0], [3.0, 0.0], [-2.9, 0.1]])
    flat = unwrapped(path, mask)
    assert flat[0] == pytest.approx(path[0])
    assert np.all(np.abs(np.diff(flat[:, 0])) < math.pi)
    assert np.allclose(np.remainder(flat[:, 0] - path[:, 0], 2 * math.pi) % (2 * math.pi - 1e-9), 0.0, atol=1e-9)
    assert wrapped(np.array([7.0, 7.0]), mask) == pytest.approx([7.0 - 2 * math.pi, 7.0])
    cut = split_turns(np.array([[-6.0, 0.0], [6.0, 1.0]]), mask)
    assert len(cut) == 5  # 12 rad in parts of at most 3 rad: the same straight line
    assert np.all(np.abs(np.diff(cut[:, 0])) <= 3.0 + 1e-12)
    assert np.allclose(cut[:, 1], np.linspace(0.0, 1.0, 5))
    lower, upper = np.array([-2 * math.pi, -1.0]), np.array([2 * math.pi, 1.0])
    assert goal_turns(np.array([1.0, 0.5]), lower, upper, mask).tolist() == [[1.0, 0.5], [1.0 - 2 * math.pi, 0.5]]
    near = nearest_turns(np.array([6.0, 0.0]), np.array([[-0.5, 0.2], [0.5, 0.2]]), lower, upper, mask)
    assert near[:, 0] == pytest.approx([2 * math.pi - 0.5, 0.5])  # 2 pi + 0.5 would leave the limits
    a, b, c = joint_features(np.array([[3.0, 0.5], [3.0 - 2 * math.pi, 0.5], [-3.0, 0.5]]), mask)
    assert np.linalg.norm(a - b) < 1e-12  # a turn apart: the same point
    assert np.linalg.norm(a - c) == pytest.approx(2 * math.sin((2 * math.pi - 6.0) / 2))  # the short way's chord
    plain = np.array([[0.1, 0.2]])
    assert np.array_equal(joint_features(plain, np.array([False, False])), plain)  # no continuous joint: as is


def test_a_robot_knows_its_continuous_joints(tmp_path: Path) -> None:
    world = turntable_world(tmp_path, initial=[3.0, 0.0], goal=[-3.0, 0.0])
    assert world.robot.continuous.tolist() == [True, False]
    narrowed = turntable_world(
        tmp_path, initial=[0.5, 0.0], goal=[0.5, 0.0], joint_lower=[-1.0, -1.5], joint_upper=[1.0, 1.5]
    )
    assert narrowed.robot.continuous.tolist() == [False, False]  # narrowed below a turn: it has limits


def _plan(world: SpatialWorld, *waypoints: list[float]) -> Plan:
    return make_plan(world, [("transit", None, np.array(waypoints))])


def test_the_validator_takes_the_short_way_and_goals_modulo_two_pi(tmp_path: Path) -> None:
    world = turntable_world(tmp_path, initial=[3.0, 0.0], goal=[-3.0, 0.0])
    assert validate_plan(world, _plan(world, [3.0, 0.0], [-3.0, 0.0])) == []  # the short way, round the back
    long_way = _plan(world, [3.0, 0.0], [0.0, 0.0], [-3.0, 0.0])
    assert any("touches obstacle 'post'" in p for p in validate_plan(world, long_way))
    unwrapped_end = _plan(world, [3.0, 0.0], [2 * math.pi - 3.0, 0.0])  # beyond pi: equal to the goal
    assert validate_plan(world, unwrapped_end) == []
    beyond = _plan(world, [3.0, 0.0], [2 * math.pi - 3.0 + 2 * math.pi, 0.0])
    assert validate_plan(world, beyond) == []  # a continuous joint has no limits
    short = _plan(world, [3.0, 0.0], [-3.1, 0.0])
    assert any("from world.robot.goal" in p for p in validate_plan(world, short))


def test_the_planner_goes_the_short_way_and_the_trajectory_is_unwrapped(tmp_path: Path) -> None:
    world = turntable_world(tmp_path, initial=[3.0, 0.0], goal=[-3.0, 0.0])
    result = plan(world)
    assert result.success, result.message
    waypoints = np.array(result.segments[0].waypoints)
    assert float(np.abs(np.diff(waypoints[:, 0])).sum()) < 1.0  # 0.28 rad round the back, not 6 rad through the post
    plan_file = make_plan(world, [(s.kind, s.grasp, s.waypoints) for s in result.segments])
    assert validate_plan(world, plan_file) == []
    # a plan written with the goal's own value (a jump of 6 rad the short way) is timed unwrapped
    jump = _plan(world, [3.0, 0.0], [-3.0, 0.0])
    track = spatial_track(world, jump, UrdfTree(TURNTABLE), Timing())
    assert track.positions[0] == pytest.approx([3.0, 0.0])
    assert np.all(np.abs(np.diff(track.positions[:, 0])) < math.pi)
    assert track.positions[-1, 0] == pytest.approx(2 * math.pi - 3.0)


def test_a_long_turn_is_cut_so_that_the_short_way_is_the_planned_one(tmp_path: Path) -> None:
    """A plan whose straight piece turns the continuous joint by more than pi is written in parts: the
    validator's short way is then the motion the planner checked."""
    world = turntable_world(tmp_path, initial=[-2.0, 1.2], goal=[2.0, 1.2])  # forearm raised: over the post
    result = plan(world)
    assert result.success, result.message
    waypoints = np.array(result.segments[0].waypoints)
    assert np.all(np.abs(np.diff(waypoints[:, 0])) <= 3.0 + 1e-12)
    assert validate_plan(world, make_plan(world, [(s.kind, s.grasp, s.waypoints) for s in result.segments])) == []
