"""The plan file and its validator: a real plan passes, broken plans are caught."""

import copy
import json
from pathlib import Path

import numpy as np
import pytest

from clew_ros.core.clew import plan
from clew_ros.core.plan import FORMAT, dumps_plan, plan_to_dict, validate_plan
from clew_ros.core.settings import Outcome, PlannerSettings, Termination
from clew_ros.core.world import load_world

ROOT = Path(__file__).resolve().parents[1]
QUICK = ROOT / "test" / "worlds" / "node_quick.yaml"


@pytest.fixture(scope="module")
def quick():
    world = load_world(QUICK)
    result = plan(world, PlannerSettings(seed=0, time_limit=30))
    assert result.success, result.message
    return world, plan_to_dict(world, result)


def test_a_real_plan_passes_and_has_the_contract_shape(quick):
    world, document = quick
    assert validate_plan(world, document) == []
    assert document["format"] == FORMAT and document["world"] == world.name
    assert document["joint_names"] == ["joint_1", "joint_2"]
    kinds = [s["kind"] for s in document["segments"]]
    assert kinds[0] == "transit" and all(a != b for a, b in zip(kinds, kinds[1:]))
    assert document["landmarks"][0] == {"id": 0, "parent": None, "joints": world.robot.initial.tolist(),
                                        "object_pose": world.object.initial.tolist(), "grasp": None}
    assert set(document["stats"]) >= {"time_s", "landmarks", "collision_checks", "seed"}
    json.loads(dumps_plan(document))


def _transfer_index(document):
    return next(i for i, s in enumerate(document["segments"]) if s["kind"] == "transfer")


@pytest.mark.parametrize("breakage,expected", [
    ("start", "not at robot.initial"),
    ("gap", "not at the end of the previous segment"),
    ("grasp_far", "from grasp"),
    ("final", "differs from the replayed"),
    ("kinds", "kinds must alternate"),
    ("collision", "is invalid"),
    ("limits", "joint limits"),
])
def test_validator_catches_broken_plans(quick, breakage, expected):
    world, good = quick
    document = copy.deepcopy(good)
    segments = document["segments"]
    t = _transfer_index(document)
    if breakage == "start":
        segments[0]["waypoints"][0][0] += 0.01
    elif breakage == "gap":
        segments[t]["waypoints"][0][1] += 0.01
        segments[t - 1]["waypoints"][-1][1] += 0.0  # previous end unchanged
    elif breakage == "grasp_far":
        segments[t]["grasp"] = (segments[t]["grasp"] + 1) % len(world.object.grasps)
    elif breakage == "final":
        document["final_object_pose"][0] += 0.01
    elif breakage == "kinds":
        segments.insert(t, copy.deepcopy(segments[t]))
    elif breakage == "collision":
        # a detour through a configuration where the arm goes into the resting object
        from clew_ros.core.collision import is_valid

        rng = np.random.default_rng(0)
        candidates = rng.uniform(world.robot.joint_lower, world.robot.joint_upper, (2000, 2))
        bad = candidates[~is_valid(world, candidates, world.object.initial)][0].tolist()
        last = segments[0]["waypoints"][-1]
        segments[0]["waypoints"][-1:] = [last, [bad[0], last[1]], bad, [bad[0], last[1]], last]
    elif breakage == "limits":
        segments[0]["waypoints"].insert(1, [world.robot.joint_upper[0] + 0.5, segments[0]["waypoints"][0][1]])
    problems = validate_plan(world, document)
    assert any(expected in p for p in problems), problems


def test_failed_plan_shape():
    world = load_world(ROOT / "config" / "unreachable.yaml")
    result = plan(world, PlannerSettings(seed=0, time_limit=0.5))
    document = plan_to_dict(world, result)
    assert not document["success"] and document["segments"] == [] and document["final_object_pose"] is None
    assert document["code"] in {"TIME_LIMIT", "NO_PATH_AT_RESOLUTION"}
    assert validate_plan(world, document) == []


def test_goal_out_of_reach_is_refused_at_once():
    world = load_world(QUICK)
    result = plan(world, PlannerSettings(time_limit=30), goal=np.array([1.85, 1.0, 0.0]))
    assert result.outcome is Outcome.GOAL_OUT_OF_REACH
    assert result.stats["time_s"] < 0.5


def test_cancel_is_honoured_quickly():
    import threading
    import time

    world = load_world(ROOT / "config" / "unreachable.yaml")
    cancel = threading.Event()
    timer = threading.Timer(0.3, cancel.set)
    timer.start()
    started = time.monotonic()
    result = plan(world, PlannerSettings(seed=1, time_limit=30), termination=Termination(30, cancel))
    assert result.outcome is Outcome.CANCELED
    assert time.monotonic() - started < 0.3 + 0.5
