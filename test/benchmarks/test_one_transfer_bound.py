"""The one-transfer bound (benchmarks/one_transfer_bound.py): its plan passes the validator, carries the object
to the goal in one transfer, and travels at least the straight joint distance between its ends."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.one_transfer_bound import main, one_transfer_bound
from benchmarks.reference import load_worlds
from clew_ros.planar.plan import replay
from clew_ros.planar.search import goal_reached


def test_the_bound_is_a_valid_one_transfer_plan_to_the_goal() -> None:
    world, _ = load_worlds(["joints_3"])[0]
    bound = one_transfer_bound(world, step=0.29, approaches=48, goal_angles=72, margin=0.0005)
    assert bound.plan is not None
    assert bound.problems == []
    assert [s.kind for s in bound.plan.segments] == ["transit", "transfer"]
    transit, transfer = (np.asarray(s.waypoints) for s in bound.plan.segments)
    assert np.array_equal(transit[0], world.robot.initial)
    assert np.array_equal(transit[-1], transfer[0])
    final = list(replay(world, bound.plan, None))[-1].object_poses[-1]
    assert goal_reached(world, final, world.object.goal)
    ends = np.abs(transit[-1] - transit[0]).sum() + np.abs(transfer[-1] - transfer[0]).sum()
    assert bound.travel >= ends - 1e-9
    travel = sum(np.abs(np.diff(np.asarray(s.waypoints), axis=0)).sum() for s in bound.plan.segments)
    assert bound.travel == pytest.approx(travel)


def test_the_command_line_refuses_bad_options_and_other_arms(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--step", "0"]) == 2
    assert "--step" in capsys.readouterr().err
    assert main(["--worlds", "figure1", "--seeds", "1"]) == 0
    assert "not a 3-joint world" in capsys.readouterr().out
