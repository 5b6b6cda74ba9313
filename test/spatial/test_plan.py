"""clew_ros.spatial.plan: the spatial plan file, its replay and validator (transit and transfer).

A Panda takes a box from one table to another (a witness built here by inverse kinematics); the validator
accepts it, through the file too, and refuses each way of breaking it with a reason naming what is wrong."""

from __future__ import annotations

import copy
import json
import math
import re
from dataclasses import replace
from typing import Any

import numpy as np
import pytest

from clew_ros.core.errors import PlanFileError
from clew_ros.core.plan import Plan, PlanSegment
from clew_ros.spatial.inverse import InverseKinematics
from clew_ros.spatial.plan import make_plan, replay, validate_plan
from clew_ros.spatial.scene import make_obstacle
from clew_ros.spatial.transforms import pose_matrix
from clew_ros.spatial.world import SpatialWorld, spatial_world_from_parameters

from .conftest import CONFIG

HOME = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]
TREE: dict[str, Any] = {
    "world": {
        "kind": "spatial",
        "name": "two_tables",
        "bounds": [-1.0, -1.0, -0.2, 1.0, 1.0, 1.5],
        "robot": {
            "urdf": "robots/panda/panda.urdf",
            "srdf": "robots/panda/panda.srdf",
            "base_link": "panda_link0",
            "tip_link": "panda_hand_tcp",
            "gripper_links": ["panda_hand", "panda_leftfinger", "panda_rightfinger"],
            "initial": HOME,
        },
        "obstacle_names": ["table_a", "table_b"],
        "obstacles": {
            "table_a": {"shape": "box", "size": [0.3, 0.3, 0.04], "pose": [0.5, 0.3, 0.1, 0, 0, 0]},
            "table_b": {"shape": "box", "size": [0.3, 0.3, 0.04], "pose": [0.5, -0.3, 0.1, 0, 0, 0]},
        },
        "supports": ["table_a", "table_b"],
        "object": {
            "shape": "box",
            "size": [0.04, 0.04, 0.1],
            "initial": [0.5, 0.3, 0.17, 0, 0, 0],
            "goal": [0.5, -0.3, 0.17, 0, 0, 0.5],
            "grasps": [0, 0, 0.03, math.pi, 0, 0],
        },
    }
}


@pytest.fixture(scope="module")
def world() -> SpatialWorld:
    return spatial_world_from_parameters(TREE, CONFIG)


@pytest.fixture(scope="module")
def holds(world: SpatialWorld) -> dict[str, np.ndarray]:
    """The witness's configurations: above and at the box on each table (top-down grasp, 10 cm approach)."""
    assert world.object is not None
    ik = InverseKinematics(world.robot)
    rng = np.random.default_rng(0)
    grasp = pose_matrix(world.object.grasps[0].tolist())
    back = pose_matrix([0, 0, -0.1, 0, 0, 0])

    def nearest(target: np.ndarray, seed: np.ndarray) -> np.ndarray:
        found = ik.solve(target, rng, seeds=seed[None], checker=world.checker)
        assert len(found)
        return np.asarray(found[np.argmin(np.abs(found - seed).max(axis=1))])

    start, goal = pose_matrix(world.object.initial), pose_matrix(world.object.goal)
    out = {"home": np.array(HOME)}
    out["a_up"] = nearest(start @ grasp @ back, out["home"])
    out["a"] = nearest(start @ grasp, out["a_up"])
    out["b_up"] = nearest(goal @ grasp @ back, out["a_up"])
    out["b"] = nearest(goal @ grasp, out["b_up"])
    return out


def witness(world: SpatialWorld, q: dict[str, np.ndarray]) -> Plan:
    return make_plan(
        world,
        [
            ("transit", None, [q["home"], q["a_up"], q["a"]]),
            ("transfer", 0, [q["a"], q["a_up"], q["b_up"], q["b"]]),
            ("transit", None, [q["b"], q["b_up"]]),
        ],
    )


def with_segments(plan: Plan, *segments: tuple[str, int | None, Any]) -> Plan:
    return replace(plan, segments=tuple(PlanSegment(k, g, np.asarray(w, dtype=float)) for k, g, w in segments))


def test_the_witness_is_accepted_and_its_file_reads_back(world: SpatialWorld, holds: dict[str, np.ndarray]) -> None:
    plan = witness(world, holds)
    assert validate_plan(world, plan) == []
    document = json.loads(plan.to_json())
    assert document["world_kind"] == "spatial"
    assert len(document["final_object_pose"]) == 6
    assert list(document)[:3] == ["format", "world", "world_kind"]
    again = Plan.from_json(plan.to_json())
    assert again.world_kind == "spatial"
    assert again.to_json() == plan.to_json()
    assert validate_plan(world, document) == []
    # the object ends at the goal: same face, same place, same yaw (the grasp turned it there)
    assert np.allclose(again.final_object_pose, world.object.goal, atol=1e-6)


def test_replay_carries_the_object(world: SpatialWorld, holds: dict[str, np.ndarray]) -> None:
    motions = list(replay(world, witness(world, holds)))
    assert [m.kind for m in motions] == ["transit", "transfer", "transit"]
    for motion in motions:
        assert np.all(np.abs(np.diff(motion.configurations, axis=0)) <= 0.002 + 1e-12)
    transit, transfer, last = motions
    assert np.allclose(transit.object_poses, world.object.initial)
    assert transfer.grasp_rel is not None
    assert np.allclose(transfer.object_poses[0], world.object.initial, atol=1e-9)
    assert np.allclose(transfer.object_poses[-1], world.object.goal, atol=1e-6)
    lifted = transfer.object_matrices[:, 2, 3].max()
    assert lifted > world.object.initial[2] + 0.09  # carried over, 10 cm up
    assert np.allclose(last.object_poses, transfer.object_poses[-1])
    waypoints = list(replay(world, witness(world, holds), waypoints_only=True))
    assert [len(m.configurations) for m in waypoints] == [3, 4, 2]


def test_a_jump_between_segments_is_refused(world: SpatialWorld, holds: dict[str, np.ndarray]) -> None:
    q = holds
    jumped = q["a"] + np.r_[0.003, np.zeros(6)]
    plan = with_segments(
        witness(world, q),
        ("transit", None, [q["home"], q["a_up"], q["a"]]),
        ("transfer", 0, [jumped, q["a_up"], q["b_up"], q["b"]]),
    )
    problems = validate_plan(world, plan)
    assert any(p.startswith("segment 1: starts 0.003 from the end of the previous segment") for p in problems), problems
    moved_start = with_segments(plan, ("transit", None, [q["home"] + 0.003, q["a_up"]]))
    assert any("from world.robot.initial" in p for p in validate_plan(world, moved_start))


def test_a_collision_is_refused_naming_the_obstacle(world: SpatialWorld, holds: dict[str, np.ndarray]) -> None:
    plan = witness(world, holds)
    carried = list(replay(world, plan))[1]
    middle = carried.object_matrices[len(carried.object_matrices) // 2]
    post = make_obstacle("post", "sphere", [0.03], middle, "post")
    blocked = replace(world, obstacles=(*world.obstacles, post))
    problems = validate_plan(blocked, plan)
    assert len(problems) == 1
    assert problems[0].startswith("segment 1 (transfer): piece 1 (waypoints 1 -> 2)")
    assert "'post'" in problems[0]
    # only the held object meets a post below the hand: the problem says so
    below = make_obstacle("post", "sphere", [0.02], middle @ pose_matrix([0, 0, -0.045, 0, 0, 0]), "post")
    problems = validate_plan(replace(world, obstacles=(*world.obstacles, below)), plan)
    assert problems
    assert "the held object touches obstacle 'post'" in problems[0]


def test_letting_go_off_a_stable_placement_is_refused(world: SpatialWorld, holds: dict[str, np.ndarray]) -> None:
    q = holds
    plan = with_segments(
        witness(world, q),
        ("transit", None, [q["home"], q["a_up"], q["a"]]),
        ("transfer", 0, [q["a"], q["a_up"], q["b_up"]]),
        ("transit", None, [q["b_up"], q["home"]]),
    )
    problems = validate_plan(world, plan)
    assert any(p.startswith("segment 1 (transfer): lets go of the object at") for p in problems), problems
    assert any("not a stable placement" in p for p in problems)


def test_a_grasp_away_from_the_grasp_pose_is_refused(world: SpatialWorld, holds: dict[str, np.ndarray]) -> None:
    q = holds
    plan = with_segments(
        witness(world, q),
        ("transit", None, [q["home"], q["a_up"]]),
        ("transfer", 0, [q["a_up"], q["b_up"], q["b"]]),
    )
    problems = validate_plan(world, plan)
    assert problems[0].startswith("segment 1 (transfer): its first waypoint does not hold grasp 0: the tcp is 0.1000")
    assert "world.grasp_tolerance" in problems[0]


def test_a_missed_goal_is_refused(world: SpatialWorld, holds: dict[str, np.ndarray]) -> None:
    q = holds
    back_home = make_plan(
        world,
        [("transit", None, [q["home"], q["a_up"], q["a"]]), ("transfer", 0, [q["a"], q["a_up"], q["a"]])],
    )
    problems = validate_plan(world, back_home)
    assert problems == ["the object ends 0.6000 m from the goal (world.goal_tolerance 0.02)"]
    lying = replace(world.object, goal=(0.5, -0.3, 0.14, math.pi / 2, 0.0, 0.5), goal_on=("table_b", "+y"))
    problems = validate_plan(replace(world, object=lying), witness(world, q))
    assert any("the goal rests it on face +y" in p for p in problems)
    turned = replace(world.object, goal=(0.5, -0.3, 0.17, 0.0, 0.0, 0.8))
    strict = replace(world, object=turned, tolerances={**world.tolerances, "goal_angle_tolerance": 0.2})
    assert validate_plan(strict, witness(world, q)) == [
        "the object ends 0.3000 rad (yaw about z) from the goal's orientation (world.goal_angle_tolerance 0.2)"
    ]
    loose = replace(strict, tolerances={**world.tolerances, "goal_angle_tolerance": 0.35})
    assert validate_plan(loose, witness(world, q)) == []
    wrong_final = replace(witness(world, q), final_object_pose=np.array([0.5, -0.3, 0.2, 0.0, 0.0, 0.5]))
    assert any(p.startswith("final_object_pose [0.5, -0.3, 0.2") for p in validate_plan(world, wrong_final))


def test_malformed_files_are_refused_naming_the_field(world: SpatialWorld, holds: dict[str, np.ndarray]) -> None:
    document = json.loads(witness(world, holds).to_json())
    cases = {
        "final_object_pose: expected an array of shape 6": ("final_object_pose", [0.5, -0.3, 0.17]),
        "world_kind: expected one of ['planar', 'spatial']": ("world_kind", "cubic"),
        "segments[1].waypoints: expected rows of 7 joint values": ("segments", None),
        "expected a JSON object with format 'clew-plan/1'": ("format", "clew-plan/2"),
    }
    for expected, (key, value) in cases.items():
        broken = copy.deepcopy(document)
        if key == "segments":
            broken["segments"][1]["waypoints"] = [row[:6] for row in broken["segments"][1]["waypoints"]]
        else:
            broken[key] = value
        problems = validate_plan(world, broken)
        assert len(problems) == 1
        assert problems[0].startswith("malformed plan: ")
        assert expected in problems[0], problems
    with pytest.raises(PlanFileError, match=re.escape("landmarks[0].object_pose: expected an array of shape 6")):
        Plan.from_dict({**document, "landmarks": [{"id": 0, "parent": None, "joints": HOME, "object_pose": [0, 0, 0]}]})
    planar = {k: v for k, v in document.items() if k != "world_kind"}
    planar["final_object_pose"] = [0.5, -0.3, 0.0]
    assert validate_plan(world, planar) == ["world_kind: expected 'spatial' (the world is spatial), got 'planar'"]


def test_a_planar_validator_refuses_a_spatial_plan(world: SpatialWorld, holds: dict[str, np.ndarray]) -> None:
    from clew_ros.planar.plan import validate_plan as planar_validate
    from clew_ros.planar.world import load_world

    figure1 = load_world(CONFIG / "figure1.yaml")
    assert planar_validate(figure1, witness(world, holds)) == [
        "world_kind: expected planar (the world's kind), got 'spatial'"
    ]


def test_a_motion_only_plan(world: SpatialWorld, holds: dict[str, np.ndarray]) -> None:
    q = holds
    query = replace(world, object=None, goal=q["b_up"])
    plan = make_plan(query, [("transit", None, [q["home"], q["a_up"], q["b_up"]])])
    assert plan.final_object_pose is None
    assert validate_plan(query, plan) == []
    assert next(iter(replay(query, plan))).object_poses is None
    short = make_plan(query, [("transit", None, [q["home"], q["a_up"]])])
    assert any(p.startswith("the plan ends") and "world.robot.goal" in p for p in validate_plan(query, short))
    two = with_segments(plan, ("transit", None, [q["home"], q["a_up"]]), ("transfer", 0, [q["a_up"], q["b_up"]]))
    problems = validate_plan(query, two)
    assert "segment 1: transfer with grasp 0: the world has no object" in problems
    assert "a motion-only query's plan is one transit segment, got 2 segments" in problems
