"""The timed plan behind ~/trajectory and the playback (no ROS graph needed)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from clew_ros.core.kinematics import compose, relative, tip_poses
from clew_ros.core.plan import Plan, PlanSegment
from clew_ros.core.world import load_world
from clew_ros.node.playback import MIN_STEP_NS, track_from_plan

QUICK = Path(__file__).parents[1] / "worlds" / "node_quick.yaml"


@pytest.fixture(scope="module")
def world():
    return load_world(QUICK)


def plan_of(*segments: PlanSegment) -> Plan:
    return Plan(
        world="node_quick",
        joint_names=("joint_1", "joint_2"),
        success=bool(segments),
        message="by hand",
        segments=segments,
    )


def hand_plan(q0, q1, q2, q3, grasp=2) -> Plan:
    """transit q0 -> q1, transfer (grasp) q1 -> q2, transit q2 -> q3."""
    return plan_of(
        PlanSegment("transit", None, np.array([q0, q1], float)),
        PlanSegment("transfer", grasp, np.array([q1, q2], float)),
        PlanSegment("transit", None, np.array([q2, q3], float)),
    )


def test_times_follow_joint_speed_and_dwell(world) -> None:
    plan = hand_plan([0.0, 0.0], [0.5, -0.2], [0.5, 0.4], [0.1, 0.4])
    track = track_from_plan(world, plan, joint_speed_rad_s=2.0, grasp_dwell_s=0.25)
    assert track.joint_names == ["joint_1", "joint_2", "gripper"]
    assert track.gripper.tolist() == [0.0, 0.0, 1.0, 1.0, 0.0, 0.0]
    steps = np.diff(track.times_s)
    # move 0.5 rad at 2 rad/s, grasp dwell, move 0.6 rad, ungrasp dwell, move 0.4 rad
    assert np.allclose(steps, [0.25, 0.25, 0.3, 0.25, 0.2])
    assert track.times_ns[0] == 0
    assert np.all(np.diff(track.times_ns) >= MIN_STEP_NS)


def test_nearly_equal_points_still_get_increasing_times(world) -> None:
    plan = plan_of(PlanSegment("transit", None, np.array([[0.0, 0.0], [1e-12, 0.0], [0.0, 0.0]])))
    track = track_from_plan(world, plan)
    assert np.all(np.diff(track.times_ns) == MIN_STEP_NS)


def test_grasp_events_follow_the_transfer_segments(world) -> None:
    plan = hand_plan([0.0, 0.0], [0.5, -0.2], [0.5, 0.4], [0.1, 0.4], grasp=3)
    track = track_from_plan(world, plan)
    events = track.events()
    assert [(e.kind, e.grasp) for e in events] == [("grasp", 3), ("ungrasp", 3)]
    assert [e.time_s for e in events] == [track.times_s[2], track.times_s[4]]
    # the gripper value changes exactly at the event times
    for event in events:
        before = track.sample(event.time_s - 1e-6)[1]
        after = track.sample(event.time_s)[1]
        assert (before, after) == ((0.0, 1.0) if event.kind == "grasp" else (1.0, 0.0))


def test_a_start_that_already_holds_a_grasp(world) -> None:
    plan = plan_of(
        PlanSegment("transit", None, np.array([[0.0, 0.0]])),
        PlanSegment("transfer", 0, np.array([[0.0, 0.0], [0.3, 0.0]])),
    )
    track = track_from_plan(world, plan, grasp_dwell_s=0.2)
    assert [(e.kind, e.grasp, e.time_s) for e in track.events()] == [("grasp", 0, pytest.approx(0.2))]


def test_samples_move_the_object_with_the_end_effector(world) -> None:
    q1, q2 = np.array([0.5, -0.2]), np.array([0.9, 0.4])
    track = track_from_plan(world, hand_plan([0.0, 0.0], q1, q2, [0.1, 0.4]))
    rest = world.object.initial
    rel = relative(tip_poses(world.robot, q1[None])[0], rest)
    t_grasp, t_place = track.times_s[2], track.times_s[3]
    # before and at the grasp, the object rests
    for t in (0.0, 0.5 * track.times_s[1], t_grasp):
        assert np.allclose(track.sample(t)[2], rest)
    # halfway through the transfer it follows the tip
    joints, gripper, pose = track.sample(0.5 * (t_grasp + t_place))
    assert gripper == 1.0
    assert np.allclose(joints, 0.5 * (q1 + q2))
    assert np.allclose(pose, compose(tip_poses(world.robot, joints[None])[0], rel))
    # after the ungrasp it rests where the transfer left it, to the end
    placed = compose(tip_poses(world.robot, q2[None])[0], rel)
    for t in (track.times_s[4], track.duration_s, track.duration_s + 5.0):
        assert np.allclose(track.sample(t)[2], placed)
    assert np.allclose(track.sample(track.duration_s)[0], [0.1, 0.4])
    assert np.allclose(track.sample(-1.0)[0], [0.0, 0.0])


def test_a_plan_without_segments_has_no_track(world) -> None:
    with pytest.raises(ValueError, match="without segments"):
        track_from_plan(world, plan_of())
    with pytest.raises(ValueError, match="must be > 0"):
        track_from_plan(world, hand_plan([0, 0], [0, 0], [0, 0], [0, 0]), joint_speed_rad_s=0.0)
