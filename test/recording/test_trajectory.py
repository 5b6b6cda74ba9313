"""trajectory_to_plan: a recorded ~/trajectory gives back the plan it played (no ROS graph)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from helpers.rec_plan import quick_plan, quick_world

from clew_ros.planar.plan import validate_plan
from clew_ros.recording import trajectory_to_plan


def as_trajectory(plan: dict, *, names: list[str] | None = None) -> SimpleNamespace:
    """A JointTrajectory-like value: the plan's waypoints, gripper 1.0 on transfer points."""
    points = []
    for segment in plan["segments"]:
        gripper = 1.0 if segment["kind"] == "transfer" else 0.0
        points += [SimpleNamespace(positions=[*list(w), gripper]) for w in segment["waypoints"]]
    return SimpleNamespace(joint_names=names or plan["joint_names"] + ["gripper"], points=points)


def test_round_trip_of_a_real_plan() -> None:
    world, plan = quick_world(), quick_plan()
    rebuilt = trajectory_to_plan(world, as_trajectory(plan)).to_dict()
    assert rebuilt["success"]
    assert rebuilt["format"] == "clew-plan/1"
    assert rebuilt["world"] == world.name
    assert [(s["kind"], s["grasp"]) for s in rebuilt["segments"]] == [(s["kind"], s["grasp"]) for s in plan["segments"]]
    for mine, theirs in zip(rebuilt["segments"], plan["segments"], strict=False):
        np.testing.assert_allclose(mine["waypoints"], theirs["waypoints"])
    np.testing.assert_allclose(rebuilt["final_object_pose"], plan["final_object_pose"], atol=1e-6)
    assert validate_plan(world, rebuilt) == []


def test_grasps_from_events_win_and_joint_order_follows_names() -> None:
    world, plan = quick_world(), quick_plan()
    transfers = sum(s["kind"] == "transfer" for s in plan["segments"])
    given = [(s["grasp"] + 1) % 4 for s in plan["segments"] if s["kind"] == "transfer"]
    rebuilt = trajectory_to_plan(world, as_trajectory(plan), grasps=given).to_dict()
    assert [s["grasp"] for s in rebuilt["segments"] if s["kind"] == "transfer"] == given
    # a wrong number of grasp events falls back to the nearest grasp point
    fallback = trajectory_to_plan(world, as_trajectory(plan), grasps=given + [0] * (transfers + 1)).to_dict()
    assert [s["grasp"] for s in fallback["segments"]] == [s["grasp"] for s in plan["segments"]]
    # joints found by name, whatever their order
    swapped = as_trajectory(plan)
    swapped.joint_names = ["gripper", "joint_2", "joint_1"]
    for point in swapped.points:
        q1, q2, g = point.positions
        point.positions = [g, q2, q1]
    again = trajectory_to_plan(world, swapped).to_dict()
    np.testing.assert_allclose(again["segments"][0]["waypoints"], plan["segments"][0]["waypoints"])


def test_start_holding_and_empty_trajectory() -> None:
    world = quick_world()
    held = SimpleNamespace(
        joint_names=["joint_1", "joint_2", "gripper"],
        points=[SimpleNamespace(positions=[0.1, 0.2, 1.0]), SimpleNamespace(positions=[0.3, 0.2, 1.0])],
    )
    plan = trajectory_to_plan(world, held).to_dict()
    assert [(s["kind"], len(s["waypoints"])) for s in plan["segments"]] == [("transit", 1), ("transfer", 2)]
    empty = trajectory_to_plan(
        world, SimpleNamespace(joint_names=["joint_1", "joint_2", "gripper"], points=[])
    ).to_dict()
    assert not empty["success"]
    assert empty["segments"] == []
    assert empty["final_object_pose"] is None


def test_segments_join_even_without_a_repeated_point() -> None:
    world = quick_world()
    points = [[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [0.5, 0.0, 1.0], [0.5, 0.4, 1.0], [0.7, 0.4, 0.0]]
    trajectory = SimpleNamespace(
        joint_names=["joint_1", "joint_2", "gripper"], points=[SimpleNamespace(positions=p) for p in points]
    )
    plan = trajectory_to_plan(world, trajectory).to_dict()
    assert [s["kind"] for s in plan["segments"]] == ["transit", "transfer", "transit"]
    for a, b in zip(plan["segments"][:-1], plan["segments"][1:], strict=False):
        assert a["waypoints"][-1] == b["waypoints"][0]
    assert plan["segments"][2]["waypoints"] == [[0.5, 0.4], [0.7, 0.4]]


def test_strict_holds_the_trajectory_to_the_contract() -> None:
    world, plan = quick_world(), quick_plan()
    trajectory = as_trajectory(plan)
    assert (
        trajectory_to_plan(world, trajectory, strict=True).to_dict() == trajectory_to_plan(world, trajectory).to_dict()
    )
    for names in (["a", "b"], ["joint_1", "joint_2"], ["gripper", "joint_2", "joint_1"]):
        with pytest.raises(ValueError, match="joint_names"):
            trajectory_to_plan(world, as_trajectory(plan, names=names), strict=True).to_dict()
    empty = SimpleNamespace(joint_names=["joint_1", "joint_2", "gripper"], points=[])
    with pytest.raises(ValueError, match="no points"):
        trajectory_to_plan(world, empty, strict=True).to_dict()
