"""The plan file and its validator: a real plan passes, broken plans are caught."""

import copy
import itertools
import json
from pathlib import Path

import numpy as np
import pytest

from clew_ros.core.plan import FORMAT, Plan
from clew_ros.core.settings import Outcome, PlannerSettings
from clew_ros.planar.plan import validate_plan
from clew_ros.planar.space import plan
from clew_ros.planar.world import load_world

ROOT = Path(__file__).resolve().parents[2]
QUICK = ROOT / "test" / "worlds" / "node_quick.yaml"


@pytest.fixture(scope="module")
def quick():
    world = load_world(QUICK)
    result = plan(world, PlannerSettings(seed=0, time_limit=30))
    assert result.success, result.message
    return world, Plan.from_result(world, result).to_dict()


def test_a_real_plan_passes_and_has_the_contract_shape(quick):
    world, document = quick
    assert validate_plan(world, document) == []
    assert document["format"] == FORMAT
    assert document["world"] == world.name
    assert document["joint_names"] == ["joint_1", "joint_2"]
    kinds = [s["kind"] for s in document["segments"]]
    assert kinds[0] == "transit"
    assert all(a != b for a, b in itertools.pairwise(kinds))
    assert document["landmarks"][0] == {
        "id": 0,
        "parent": None,
        "joints": world.robot.initial.tolist(),
        "object_pose": world.object.initial.tolist(),
        "grasp": None,
    }
    assert set(document["stats"]) >= {"time_s", "landmarks", "collision_checks", "seed"}
    assert json.loads(Plan.from_dict(document).to_json()) == document


def _transfer_index(document):
    return next(i for i, s in enumerate(document["segments"]) if s["kind"] == "transfer")


@pytest.mark.parametrize(
    ("breakage", "expected"),
    [
        ("start", "not at robot.initial"),
        ("gap", "not at the end of the previous segment"),
        ("grasp_far", "from grasp"),
        ("final", "differs from the replayed"),
        ("kinds", "kinds must alternate"),
        ("collision", "is invalid"),
        ("limits", "joint limits"),
    ],
)
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
        from clew_ros.planar.collision import is_valid

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
    document = Plan.from_result(world, result).to_dict()
    assert not document["success"]
    assert document["segments"] == []
    assert document["final_object_pose"] is None
    assert document["code"] in {"TIME_LIMIT", "NO_PATH_AT_RESOLUTION"}
    assert validate_plan(world, document) == []


def test_the_plan_file_round_trips_byte_for_byte(quick, tmp_path):
    world, document = quick
    planned = Plan.from_dict(document)
    assert planned.success
    assert planned.outcome is Outcome.SUCCEEDED
    assert planned.world == world.name
    path = planned.write(tmp_path / "sub" / "plan.json")
    again = Plan.read(path)
    assert again.to_json() == planned.to_json() == path.read_text()
    assert again.grasp_count == sum(s["kind"] == "transfer" for s in document["segments"]) >= 1
    assert not again.segments[0].waypoints.flags.writeable  # a value: nobody edits a plan in place


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (lambda d: d.update(format="clew-plan/0"), "format"),
        (lambda d: d.update(success="yes"), "success"),
        (lambda d: d.update(code="DONE"), "code"),
        (lambda d: d["segments"][1].update(kind="carry"), "segments[1].kind"),
        (lambda d: d["segments"][0].update(grasp=1.5), "segments[0].grasp"),
        (lambda d: d["segments"][0].update(waypoints=[[0.0, 1.0], [0.0]]), "segments[0].waypoints"),
        (lambda d: d.update(final_object_pose=[0.0, 1.0]), "final_object_pose"),
        (lambda d: d["landmarks"][0].update(object_pose="here"), "landmarks[0].object_pose"),
    ],
)
def test_a_malformed_plan_file_names_the_field_at_fault(quick, tmp_path, change, field):
    from clew_ros.core.errors import PlanFileError

    _world, good = quick
    document = copy.deepcopy(good)
    change(document)
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(document))
    with pytest.raises(PlanFileError, match=field.replace("[", r"\[").replace("]", r"\]")):
        Plan.read(path)
    assert validate_plan(quick[0], document)[0].startswith("malformed plan:")


def test_replay_carries_the_object_with_the_tip_during_transfers(quick):
    from clew_ros.planar.kinematics import relative, tip_poses
    from clew_ros.planar.plan import replay

    world, document = quick
    planned = Plan.from_dict(document)
    rest = world.object.initial
    for coarse, fine in zip(replay(world, planned, step_rad=None), replay(world, planned), strict=True):
        assert np.array_equal(coarse.configurations, planned.segments[coarse.index].waypoints)
        assert np.allclose(fine.configurations[[0, -1]], coarse.configurations[[0, -1]])
        assert np.max(np.abs(np.diff(fine.configurations, axis=0))) <= 0.002 + 1e-12
        if coarse.kind == "transit":
            assert coarse.grasp_rel is None
            assert np.allclose(fine.object_poses, rest)
        else:
            held = relative(tip_poses(world.robot, fine.configurations), fine.object_poses)
            assert np.allclose(held, coarse.grasp_rel, atol=1e-9)  # rigid in the end-effector frame
            rest = coarse.object_poses[-1]
    assert np.allclose(rest, planned.final_object_pose, atol=1e-9)


def test_checked_plan_never_hands_out_an_invalid_plan(quick):
    """A planner result whose plan fails validation becomes INTERNAL_ERROR, with no segments."""
    import dataclasses

    from clew_ros.planar.plan import checked_plan

    world = quick[0]
    result = plan(world, PlannerSettings(seed=0, time_limit=30))
    assert checked_plan(world, result).to_dict()["segments"] == quick[1]["segments"]
    broken = dataclasses.replace(result, final_object_pose=result.final_object_pose + np.array([0.05, 0.0, 0.0]))
    planned = checked_plan(world, broken)
    assert not planned.success
    assert planned.outcome is Outcome.INTERNAL_ERROR
    assert "differs from the replayed" in planned.message
    assert planned.segments == ()
    assert planned.final_object_pose is None
    assert len(planned.landmarks) == len(result.tree)
    assert validate_plan(world, planned) == []


def test_a_non_finite_final_pose_is_refused(quick):
    world, good = quick
    document = copy.deepcopy(good)
    document["final_object_pose"] = [float("nan")] * 3
    assert any("final_object_pose" in p for p in validate_plan(world, document))
