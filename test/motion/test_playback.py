"""The timed plan behind ~/trajectory and the playback (no ROS graph needed)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from helpers.rec_plan import quick_plan, quick_world

from clew_ros.core.plan import Plan, PlanSegment
from clew_ros.core.settings import PlannerSettings
from clew_ros.motion.playback import MIN_STEP_NS, Track, track_from_plan
from clew_ros.motion.timing import quintic_spline
from clew_ros.planar.kinematics import compose, relative, tip_poses
from clew_ros.planar.space import plan
from clew_ros.planar.world import World, load_world, read_parameter_file

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


def test_times_follow_the_limits_and_dwell(world) -> None:
    plan = hand_plan([0.0, 0.0], [0.5, -0.2], [0.5, 0.4], [0.1, 0.4])
    track = track_from_plan(world, plan, max_velocity_rad_s=2.0, max_acceleration_rad_s2=4.0, grasp_dwell_s=0.25)
    assert track.joint_names == ["joint_1", "joint_2", "gripper"]
    assert track.gripper.tolist() == [0.0, 0.0, 1.0, 1.0, 0.0, 0.0]
    steps = np.diff(track.times_s)

    def rest_to_rest(d: float) -> float:  # the quintic's peaks: 15/8 d / T <= v, 10/sqrt(3) d / T^2 <= a
        return max(15 / 8 * d / 2.0, math.sqrt(10 / math.sqrt(3) * d / 4.0))

    # move 0.5 rad, grasp dwell, move 0.6 rad, ungrasp dwell, move 0.4 rad
    expected = [rest_to_rest(0.5), 0.25, rest_to_rest(0.6), 0.25, rest_to_rest(0.4)]
    assert np.allclose(steps, expected, atol=2e-9)
    assert track.times_ns[0] == 0
    assert np.all(np.diff(track.times_ns) >= MIN_STEP_NS)
    assert track.max_velocity.tolist() == [2.0, 2.0]
    assert track.max_acceleration.tolist() == [4.0, 4.0]


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
    assert np.allclose(joints, 0.5 * (q1 + q2))  # halfway in time is halfway along: the profile is symmetric
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
    some = hand_plan([0, 0], [0, 0], [0, 0], [0, 0])
    with pytest.raises(ValueError, match="must be > 0"):
        track_from_plan(world, some, max_velocity_rad_s=0.0)
    with pytest.raises(ValueError, match="must be > 0"):
        track_from_plan(world, some, max_acceleration_rad_s2=[1.0, math.nan])
    with pytest.raises(ValueError, match="must be > 0"):
        track_from_plan(world, some, grasp_dwell_s=0.0)
    with pytest.raises(ValueError, match="one per joint"):
        track_from_plan(world, some, max_velocity_rad_s=[1.0, 1.0, 1.0])


# --------------------------------------------------------------------------- the trajectory respects the limits

CONFIG = Path(__file__).parents[2] / "config"
#: (max velocity, max acceleration) per joint or for all: the node's defaults, a slow and a fast setting, per joint.
LIMITS = [(1.0, 2.0), (3.0, 0.5), (20.0, 400.0), ([0.4, 1.5, 2.0, 1.0, 0.7], [3.0, 0.8, 1.0, 2.0, 5.0])]
#: Finite differences of the playback: every FD_STEP_S, at most FD_SAMPLES samples per track.
FD_STEP_S, FD_SAMPLES = 2e-3, 2500


def _config_plan(name: str) -> tuple[World, Plan]:
    path = CONFIG / f"{name}.yaml"
    world = load_world(path)
    result = plan(world, PlannerSettings.from_parameters(read_parameter_file(path), seed=0))
    assert result.success, result.message
    return world, Plan.from_result(world, result)


@pytest.fixture(scope="module")
def real_plans() -> dict[str, tuple[World, Plan]]:
    plans = {"rec_quick": (quick_world(), Plan.from_dict(quick_plan()))}
    for name in ("figure1", "single_transfer", "arm3_regrasp"):
        plans[name] = _config_plan(name)
    return plans


def _per_joint(limit, n: int) -> np.ndarray:
    return np.broadcast_to(np.asarray(limit, dtype=float), (5,))[:n] if np.ndim(limit) else np.full(n, limit)


def distance_to_segment(q: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance (rad, Euclidean in joint space) of each row of ``q`` (N, n) to the segment ``a``-``b``."""
    d = b - a
    length2 = float(d @ d)
    u = np.zeros(len(q)) if length2 == 0 else np.clip((q - a) @ d / length2, 0.0, 1.0)
    return np.linalg.norm(q - (a + u[:, None] * d), axis=1)


def assert_track_respects_the_limits(track: Track, grasp_dwell_s: float) -> None:
    v, a = track.max_velocity, track.max_acceleration
    times_ns, p = track.times_ns, track.positions
    assert times_ns[0] == 0
    assert np.all(np.diff(times_ns) >= MIN_STEP_NS)  # strictly increasing
    # the points' velocities and accelerations are the profile's at their times: every point is at rest
    # (times in float seconds land within ~1e-5 ns of a point: the acceleration there is 0 within 1e-6 of the limit)
    q, dq, ddq = track.joints_at(track.times_s)
    assert np.allclose(q, p, rtol=0, atol=1e-12)
    assert np.all(np.abs(dq - track.velocities) <= 1e-9 * v)
    assert np.all(np.abs(ddq - track.accelerations) <= 1e-6 * a)
    assert not np.any(track.velocities)
    assert not np.any(track.accelerations)
    # a controller that runs the points as quintic splines moves exactly as the playback does
    t = np.linspace(0.0, track.duration_s, 5001)
    assert np.allclose(
        quintic_spline(track.times_s, p, track.velocities, track.accelerations, t), track.joints_at(t)[0], atol=1e-9
    )
    u = np.linspace(0.0, 1.0, 201)
    for k in range(len(times_ns) - 1):
        span_s = float(times_ns[k + 1] - times_ns[k]) * 1e-9
        q, dq, ddq = track.joints_at(track.times_s[k] + u * span_s)
        # within the limits, at rest at both ends of the piece, on the straight segment between its points
        assert np.all(np.abs(dq) <= v * (1 + 1e-9)), k
        assert np.all(np.abs(ddq) <= a * (1 + 1e-9)), k
        assert np.all(np.abs(dq[[0, -1]]) <= 1e-9 * v), k
        assert np.all(np.abs(ddq[[0, -1]]) <= 1e-6 * a), k
        assert np.max(distance_to_segment(q, p[k], p[k + 1])) <= 1e-12, k
        if track.gripper[k + 1] != track.gripper[k]:  # a grasp or an ungrasp: the arm rests for the dwell
            assert times_ns[k + 1] - times_ns[k] == round(grasp_dwell_s * 1e9)
            assert np.array_equal(p[k], p[k + 1])
            assert np.allclose(q, p[k], rtol=0, atol=1e-12)
            assert np.allclose(dq, 0.0, rtol=0, atol=1e-12)
        else:  # as short as the limits allow: one joint reaches its velocity or its acceleration limit
            reached = max(np.max(np.abs(dq) / v), np.max(np.abs(ddq) / a))
            if times_ns[k + 1] - times_ns[k] > MIN_STEP_NS:
                assert reached == pytest.approx(1.0, rel=2e-3), k  # the grid misses the exact peak by < 1e-3
    # finite differences of the playback's own samples (what ~/joint_states publishes): a first difference
    # is a mean velocity, a second difference a weighted mean acceleration, so neither may exceed its limit
    h = max(FD_STEP_S, track.duration_s / FD_SAMPLES)
    t = np.arange(0.0, track.duration_s + h, h)
    states = [track.state(float(s)) for s in t]
    samples = np.array([state.joints for state in states])
    assert np.array_equal(samples, [track.sample(float(s))[0] for s in t])
    # the velocities ~/joint_states carries: the same timing's, each joint within its own limit, at rest at the end
    velocities = np.array([state.velocities for state in states])
    inside = t < track.duration_s
    assert np.allclose(velocities[inside], track.joints_at(t[inside])[1], rtol=0, atol=1e-12)
    assert np.all(np.abs(velocities) <= v * (1 + 1e-9))
    assert not np.any(track.state(track.duration_s).velocities)
    first = np.diff(samples, axis=0) / h
    second = np.diff(samples, 2, axis=0) / h**2
    assert np.all(np.abs(first) <= v * (1 + 1e-9) + 1e-9)
    assert np.all(np.abs(second) <= a * (1 + 1e-6) + 1e-6)
    # the playback samples lie on the plan's path: on the segment of the piece they fall in
    piece = np.clip(np.searchsorted(times_ns, t * 1e9, side="right") - 1, 0, len(times_ns) - 2)
    for k in np.unique(piece):
        rows = samples[piece == k]
        assert np.max(distance_to_segment(rows, p[k], p[k + 1])) <= 1e-12


@pytest.mark.parametrize("limits", LIMITS, ids=["default", "slow", "fast", "per_joint"])
@pytest.mark.parametrize("name", ["rec_quick", "figure1", "single_transfer", "arm3_regrasp"])
def test_real_plans_respect_the_limits(real_plans, name: str, limits) -> None:
    world, planned = real_plans[name]
    n = world.robot.dof
    v, a = _per_joint(limits[0], n), _per_joint(limits[1], n)
    track = track_from_plan(world, planned, max_velocity_rad_s=v, max_acceleration_rad_s2=a, grasp_dwell_s=0.3)
    assert np.array_equal(track.max_velocity, v)
    assert np.array_equal(track.max_acceleration, a)
    assert_track_respects_the_limits(track, 0.3)
    # the points are the plan's waypoints, in order (interface.md §3)
    assert np.array_equal(track.positions, np.concatenate([s.waypoints for s in planned.segments]))
    assert [e.grasp for e in track.events() if e.kind == "grasp"] == [
        s.grasp for s in planned.segments if s.kind == "transfer"
    ]


def test_hand_made_plans_respect_the_limits(world) -> None:
    plans = [
        hand_plan([0.0, 0.0], [0.5, -0.2], [0.5, 0.4], [0.1, 0.4]),
        # all joints at once, long and short pieces, a zero-length piece, a piece shorter than MIN_STEP_NS
        plan_of(
            PlanSegment(
                "transit", None, np.array([[0.0, 0.0], [2.5, -1.5], [2.5, -1.5], [2.49, -1.5], [2.49, -1.5 + 1e-7]])
            ),
            PlanSegment("transfer", 1, np.array([[2.49, -1.5 + 1e-7], [-2.0, 1.0], [-2.0, 1.001]])),
        ),
        # a start that already holds a grasp
        plan_of(
            PlanSegment("transit", None, np.array([[0.0, 0.0]])),
            PlanSegment("transfer", 0, np.array([[0.0, 0.0], [0.3, -3.0]])),
            PlanSegment("transit", None, np.array([[0.3, -3.0], [0.0, 0.0]])),
        ),
    ]
    for planned in plans:
        for v, a in [(1.0, 2.0), (0.2, 10.0), ([0.5, 2.0], [4.0, 0.3])]:
            track = track_from_plan(world, planned, max_velocity_rad_s=v, max_acceleration_rad_s2=a, grasp_dwell_s=0.2)
            assert_track_respects_the_limits(track, 0.2)


def test_a_one_point_plan(world) -> None:
    track = track_from_plan(world, plan_of(PlanSegment("transit", None, np.array([[0.2, 0.1]]))))
    assert track.duration_s == 0.0
    q, dq, ddq = track.joints_at(np.array([0.0, 1.0]))
    assert np.allclose(q, [[0.2, 0.1], [0.2, 0.1]])
    assert not np.any(dq)
    assert not np.any(ddq)
    assert np.allclose(track.sample(3.0)[0], [0.2, 0.1])
