"""The grid reference planner (benchmarks/reference.py): its plans pass the validator, it finds the
analytic shortest plan of an open world within its grid error, and the planner never beats it by more
than that error (it is a near-lower bound)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers.open_reach import open_reach

from benchmarks.reference import ReferenceSettings, load_worlds, main, planner_runs, reference_plan
from clew_ros.planar.collision import check_start_and_goal
from clew_ros.planar.plan import validate_plan
from clew_ros.planar.world import World, world_from_parameters

STEP_RAD = 0.04
#: The reference's error bound for a plan of one transfer (module docstring of benchmarks.reference):
#: 2 h per end that is off the lattice, 4 ends.
GRID_ERROR_RAD = 8 * STEP_RAD

OPEN_WORLD = {**open_reach(goal_tolerance=0.001), "planner": {"time_limit": 30.0}}


@pytest.fixture(scope="module")
def open_world() -> World:
    return check_start_and_goal(world_from_parameters(OPEN_WORLD))


@pytest.fixture(scope="module")
def one_transfer(open_world: World):
    return reference_plan(open_world, ReferenceSettings(step_rad=STEP_RAD, max_transfers=1))


def _elbows(base: np.ndarray, l1: float, l2: float, point: np.ndarray) -> list[np.ndarray]:
    """Both configurations of a two-link arm ``l1``, ``l2`` whose end is at ``point`` (no limits)."""
    x, y = point - base
    cosine = (x * x + y * y - l1 * l1 - l2 * l2) / (2 * l1 * l2)
    answers = []
    for sign in (1.0, -1.0):
        q2 = sign * math.acos(max(-1.0, min(1.0, cosine)))
        q1 = math.atan2(y, x) - math.atan2(l2 * math.sin(q2), l1 + l2 * math.cos(q2))
        answers.append(np.array([q1, q2]))
    return answers


def _analytic_shortest(world: World) -> float:
    """The least joint travel of a one-transfer plan in a world where nothing is in the way: from the start
    to a configuration holding the (only) grasp, then to one putting the object's origin on the goal."""
    robot, start = world.robot, world.robot.initial
    l1, l2 = (float(v) for v in robot.link_lengths)
    pose = world.object.initial
    c, s = math.cos(pose[2]), math.sin(pose[2])
    grasp = world.object.grasps[0]
    held = pose[:2] + np.array([c * grasp[0] - s * grasp[1], s * grasp[0] + c * grasp[1]])
    best = math.inf
    for hold in _elbows(robot.base, l1, l2, held):
        if np.any(hold < robot.joint_lower) or np.any(hold > robot.joint_upper):
            continue
        phi = hold.sum()  # the object in the end effector's frame, then the virtual last link to its origin
        offset = np.array(
            [
                math.cos(phi) * (pose[0] - held[0]) + math.sin(phi) * (pose[1] - held[1]),
                -math.sin(phi) * (pose[0] - held[0]) + math.cos(phi) * (pose[1] - held[1]),
            ]
        )
        virtual = np.array([l2 + offset[0], offset[1]])
        for elbow in _elbows(robot.base, l1, float(np.hypot(*virtual)), world.object.goal[:2]):
            end = elbow - np.array([0.0, math.atan2(virtual[1], virtual[0])])
            if np.all(end >= robot.joint_lower) and np.all(end <= robot.joint_upper):
                best = min(best, float(np.abs(hold - start).sum() + np.abs(end - hold).sum()))
    return best


def test_the_reference_plan_is_valid(open_world: World, one_transfer) -> None:
    assert one_transfer.plan is not None
    assert one_transfer.problems == []
    assert validate_plan(open_world, one_transfer.plan) == []
    assert one_transfer.transfers == 1
    kinds = [segment.kind for segment in one_transfer.plan.segments]
    assert kinds == ["transit", "transfer"]


def test_in_an_open_world_the_reference_travels_the_analytic_shortest(open_world: World, one_transfer) -> None:
    shortest = _analytic_shortest(open_world)
    assert math.isfinite(shortest)
    # never shorter than the analytic optimum (up to the goal tolerance's sliver), never longer than the grid error
    assert shortest - 0.01 <= one_transfer.travel <= shortest + GRID_ERROR_RAD


def test_the_planner_never_beats_the_reference_by_more_than_the_grid_error(open_world: World) -> None:
    reference = reference_plan(open_world, ReferenceSettings(step_rad=STEP_RAD))
    assert reference.plan is not None
    assert reference.problems == []
    runs = planner_runs(open_world, OPEN_WORLD, 2)
    assert len(runs.travel) == 2
    for travel, transfers in zip(runs.travel, runs.transfers, strict=True):
        assert transfers <= reference.settings.max_transfers
        assert travel >= reference.travel - GRID_ERROR_RAD - 0.01


def test_the_reference_refuses_arms_that_do_not_have_two_joints() -> None:
    parameters = {"world": dict(OPEN_WORLD["world"])}
    parameters["world"]["robot"] = dict(
        OPEN_WORLD["world"]["robot"],
        link_lengths=[0.6, 0.6, 0.6],
        joint_lower=[-2.0, -2.5, -2.5],
        joint_upper=[2.0, 2.5, 2.5],
        initial=[0.2, 0.4, 0.0],
    )
    with pytest.raises(ValueError, match="2-joint arms only"):
        reference_plan(world_from_parameters(parameters), ReferenceSettings(step_rad=STEP_RAD))


def test_the_command_line_names_a_bad_world(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--worlds", "no_such_world", "--seeds", "0"]) == 2
    assert "no_such_world" in capsys.readouterr().err
    assert main(["--step", "-1", "--seeds", "0"]) == 2


def test_worlds_by_name_include_any_count_of_joints_or_obstacles() -> None:
    (listed, _), (more, _), (joints, _) = load_worlds(["obstacles_8", "obstacles_12", "joints_4"])
    assert len(listed.obstacles) == 8
    assert len(more.obstacles) == 12
    assert more.robot.dof == 3
    assert joints.robot.dof == 4
    for name in ("obstacles_1", "elbows_3", "obstacles_x"):
        with pytest.raises(ValueError, match="--worlds"):
            load_worlds([name])


def test_worlds_by_name_include_a_generated_familys_world_as_clew_world_writes_it(tmp_path) -> None:
    from clew_ros.planar.world import load_world
    from clew_ros.worlds import generate, write_world

    ((named, parameters),) = load_worlds(["shapes2_60"])
    write_world(generate("shapes2", 60), tmp_path / "shapes2_60.yaml")
    written = load_world(tmp_path / "shapes2_60.yaml")
    assert named.name == written.name == "shapes2_60"
    np.testing.assert_array_equal(named.robot.initial, written.robot.initial)
    np.testing.assert_array_equal(named.object.goal, written.object.goal)
    assert len(named.obstacles) == len(written.obstacles)
    assert "world" in parameters
    with pytest.raises(ValueError, match="--worlds"):
        load_worlds(["shapes3_60"])
