"""The witness: a random manipulation simulated in a world without obstacles, valid as a plan."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clew_ros.core.plan import Plan
from clew_ros.planar.kinematics import compose, tip_poses, transform_points, wrap_angle
from clew_ros.planar.plan import replay, validate_plan
from clew_ros.planar.world import World, world_from_parameters
from clew_ros.worlds.arms import make_arm
from clew_ros.worlds.shapes import ObjectShape, make_shape
from clew_ros.worlds.witness import MAX_APPROACH_RAD, grasp_configurations, grasp_relation, simulate


def free_world(joints: int, kind: str, seed: int) -> tuple[World, ObjectShape]:
    rng = np.random.default_rng(seed)
    arm = make_arm(rng, joints)
    shape = make_shape(kind, rng, 0.4)
    half = arm.reach + 0.4
    tree = {
        "name": "free",
        "bounds": [-half, -half, half, half],
        "robot": {
            "base": [0.0, 0.0],
            "link_lengths": arm.link_lengths.tolist(),
            "link_width": arm.link_width,
            "joint_lower": arm.joint_lower.tolist(),
            "joint_upper": arm.joint_upper.tolist(),
            "initial": [0.0] * joints,
        },
        "object": {
            "polygon": shape.vertices.ravel().tolist(),
            "initial": [0.0, 0.0, 0.0],
            "goal": [0.0, 0.0, 0.0],
            "grasps": shape.grasps.ravel().tolist(),
        },
    }
    return world_from_parameters({"world": tree}), shape


def test_grasp_relation_puts_the_grasp_at_the_tip_and_the_link_outside() -> None:
    shape = make_shape("box", np.random.default_rng(0), 0.4)
    tip = np.array([0.3, -0.2, 0.7])
    for grasp in range(len(shape.grasps)):
        for approach in (-0.8, 0.0, 0.5):
            pose = compose(tip, grasp_relation(shape, grasp, approach))
            point = transform_points(pose, shape.grasps[grasp][None])[0]
            assert np.allclose(point, tip[:2], atol=1e-12)
            normal = pose[2] + math.atan2(shape.normals[grasp][1], shape.normals[grasp][0])
            assert float(wrap_angle(normal - tip[2] - math.pi)) == pytest.approx(approach)


@pytest.mark.parametrize(("joints", "kind", "transfers"), [(2, "bar", 1), (3, "L", 2), (5, "triangle", 3)])
def test_simulate_gives_a_valid_plan_with_the_transfers_asked(joints: int, kind: str, transfers: int) -> None:
    for seed in range(10):
        world, shape = free_world(joints, kind, seed)
        try:
            witness = simulate(world, shape, np.random.default_rng(seed), transfers=transfers)
        except Exception:  # noqa: BLE001 - a stream may find no candidate; the generator tries the next one
            continue
        break
    else:
        pytest.fail("no stream of 10 gave a witness")
    kinds = [segment.kind for segment in witness.segments]
    assert kinds == ["transit", "transfer"] * transfers
    assert np.array_equal(witness.segments[0].waypoints[0], witness.initial)
    parameters = dict(world.parameters)
    parameters["robot"] = {**parameters["robot"], "initial": witness.initial.tolist()}
    parameters["object"] = {**parameters["object"], "initial": witness.object_initial.tolist()}
    started = world_from_parameters({"world": parameters})
    plan = Plan("free", tuple(started.robot.joint_names), True, "", None, witness.segments, None)
    end = list(replay(started, plan))[-1].object_poses[-1]
    parameters["object"]["goal"] = end.tolist()
    done = world_from_parameters({"world": parameters})
    plan = Plan("free", tuple(done.robot.joint_names), True, "", None, witness.segments, end)
    assert validate_plan(done, plan) == []


def test_grasp_configurations_hold_a_grasp_from_outside() -> None:
    world, shape = free_world(4, "convex", 1)
    pose = np.array([0.9, 0.4, 0.3])
    q, grasps = grasp_configurations(world, shape, pose, np.random.default_rng(0), 512)
    assert len(q) > 10
    tips = tip_poses(world.robot, q)
    held = transform_points(pose, shape.grasps)[grasps]
    assert np.allclose(tips[:, :2], held, atol=1e-9)
    assert np.all((q >= world.robot.joint_lower) & (q <= world.robot.joint_upper))
    normal = pose[2] + np.arctan2(shape.normals[grasps, 1], shape.normals[grasps, 0])
    assert np.all(np.abs(wrap_angle(normal - tips[:, 2] - math.pi)) <= MAX_APPROACH_RAD + 1e-9)
