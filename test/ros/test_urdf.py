"""The URDF of ``~/robot_description`` read by a URDF library (urdf_parser_py): its forward kinematics at
random joint states equals the planner's (``clew_ros.planar.kinematics``) and the TF frames of
``clew_ros.ros.frames``; its joints, limits, link sizes and gripper are the world's.
"""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
import pytest

urdf_lib = pytest.importorskip("urdf_parser_py.urdf")

from helpers.urdf_fk import matrix, urdf_fk  # noqa: E402

from clew_ros.planar.kinematics import joint_positions, tip_poses  # noqa: E402
from clew_ros.planar.world import World, load_world, world_from_parameters, world_to_parameters  # noqa: E402
from clew_ros.ros import frames, urdf  # noqa: E402

CONFIG = Path(__file__).parents[2] / "config"
TOLERANCE = 1e-9


def _wide(world: World, *, joints: int, width: float, base: tuple[float, float]) -> World:
    """``world`` with an arm of ``joints`` links of random lengths, ``link_width`` ``width``, at ``base``."""
    rng = np.random.default_rng(joints)
    parameters = copy.deepcopy(world_to_parameters(world))
    robot = parameters["world"]["robot"]
    robot["base"] = list(base)
    robot["link_lengths"] = rng.uniform(0.1, 0.6, joints).tolist()
    robot["link_width"] = width
    robot["joint_lower"] = rng.uniform(-3.0, -0.5, joints).tolist()
    robot["joint_upper"] = rng.uniform(0.5, 3.0, joints).tolist()
    robot["initial"] = [0.0] * joints
    return world_from_parameters(parameters)


def worlds() -> list[World]:
    figure1 = load_world(CONFIG / "figure1.yaml")
    return [
        figure1,  # 2 joints, segments
        load_world(CONFIG / "arm3_regrasp.yaml"),
        load_world(CONFIG / "arm5_regrasp.yaml"),
        _wide(figure1, joints=7, width=0.05, base=(0.3, -0.7)),
        _wide(figure1, joints=2, width=0.1, base=(-1.0, 0.25)),
    ]


@pytest.fixture(params=range(5), ids=["figure1", "arm3", "arm5", "arm7_wide", "arm2_wide"], scope="module")
def world(request: pytest.FixtureRequest) -> World:
    return worlds()[request.param]


# ----------------------------------------------------------------- forward kinematics of a parsed URDF


def tf_fk(transforms: list[frames.FrameTransform]) -> dict[str, np.ndarray]:
    """Every frame's 4x4 pose in ``world``, composing TF edges (parents first or not)."""
    poses = {"world": np.eye(4)}
    pending = list(transforms)
    while pending:
        edge = next(t for t in pending if t.parent in poses)
        pending.remove(edge)
        x, y, z, w = edge.rotation
        rotation = np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
            ]
        )
        poses[edge.child] = poses[edge.parent] @ matrix(rotation, np.array(edge.translation))
    return poses


def _planar(pose: np.ndarray) -> np.ndarray:
    """``(x, y, theta)`` of a 4x4 pose that lies in the plane (z = 0, rotation about z only)."""
    assert abs(pose[2, 3]) < TOLERANCE
    assert np.allclose(pose[2, :3], [0, 0, 1], atol=TOLERANCE)
    return np.array([pose[0, 3], pose[1, 3], math.atan2(pose[1, 0], pose[0, 0])])


def _same_angle(a: float, b: float) -> bool:
    return abs(math.remainder(a - b, 2 * math.pi)) < TOLERANCE


def random_states(world: World, count: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    robot = world.robot
    return rng.uniform(robot.joint_lower, robot.joint_upper, size=(count, robot.dof))


# ----------------------------------------------------------------- tests


def test_urdf_forward_kinematics_is_the_planners(world: World) -> None:
    parsed = urdf_lib.URDF.from_xml_string(urdf.robot_urdf(world))
    robot = world.robot
    states = random_states(world, 40)
    points = joint_positions(robot, states)  # (N, n + 1, 2)
    tips = tip_poses(robot, states)
    for k, q in enumerate(states):
        gripper = float(k % 3) / 2.0  # 0, 0.5, 1
        state = {f"joint_{i + 1}": float(v) for i, v in enumerate(q)} | {"gripper": gripper}
        by_urdf = urdf_fk(parsed, state)
        by_tf = tf_fk(frames.static_transforms(robot) + frames.arm_transforms(robot, q, gripper))
        assert set(by_tf) == set(by_urdf), "TF names every link of the URDF"
        phi = np.cumsum(q)
        for i in range(1, robot.dof + 1):
            for poses in (by_urdf, by_tf):
                x, y, theta = _planar(poses[urdf.link_name(i)])
                assert np.allclose([x, y], points[k, i - 1], rtol=0, atol=TOLERANCE)  # link i starts at p_(i-1)
                assert _same_angle(theta, phi[i - 1])
        for poses in (by_urdf, by_tf):
            x, y, theta = _planar(poses[urdf.TOOL_FRAME])
            assert np.allclose([x, y], tips[k, :2], rtol=0, atol=TOLERANCE)
            assert np.allclose([x, y], points[k, -1], rtol=0, atol=TOLERANCE)
            assert _same_angle(theta, tips[k, 2])
            for jaw in urdf.JAW_LINKS:
                assert np.allclose(poses[jaw], by_urdf[jaw], rtol=0, atol=TOLERANCE)


def test_urdf_joints_limits_and_sizes(world: World) -> None:
    parsed = urdf_lib.URDF.from_xml_string(urdf.robot_urdf(world))
    robot = world.robot
    assert parsed.get_root() == "world"
    joints = {j.name: j for j in parsed.joints}
    arm = [f"joint_{i + 1}" for i in range(robot.dof)]
    assert [j.name for j in parsed.joints if j.type == "revolute" and j.mimic is None] == [*arm, "gripper"]
    assert robot.joint_names == arm  # the names of ~/trajectory and ~/joint_states
    assert joints["base_joint"].type == "fixed"
    assert list(joints["base_joint"].origin.xyz) == [*robot.base.tolist(), 0.0]
    for i, name in enumerate(arm):
        joint = joints[name]
        assert list(joint.axis) == [0.0, 0.0, 1.0]
        assert joint.limit.lower == robot.joint_lower[i]
        assert joint.limit.upper == robot.joint_upper[i]
        link = parsed.link_map[urdf.link_name(i + 1)]
        cylinder = next(v.geometry for v in link.visuals if isinstance(v.geometry, urdf_lib.Cylinder))
        assert cylinder.length == robot.link_lengths[i]
        assert cylinder.radius == pytest.approx(0.5 * urdf.visual_width_m(robot))
        if robot.link_width > 0:  # the capsule of interface.md §1: a cylinder and two spheres
            shapes = sorted(type(c.geometry).__name__ for c in link.collisions)
            assert shapes == ["Cylinder", "Sphere", "Sphere"]
            assert all(c.geometry.radius == 0.5 * robot.link_width for c in link.collisions)
        else:
            assert link.collisions == []
    gripper = joints["gripper"]
    assert (gripper.limit.lower, gripper.limit.upper) == (0.0, 1.0)  # ~/joint_states: 1.0 while grasping
    assert joints["gripper_right"].mimic.joint == "gripper"
    assert joints["tool_joint"].type == "fixed"
    assert joints["tool_joint"].parent == urdf.link_name(robot.dof)


def test_gripper_closes_at_one(world: World) -> None:
    parsed = urdf_lib.URDF.from_xml_string(urdf.robot_urdf(world))
    q = {f"joint_{i + 1}": 0.0 for i in range(world.robot.dof)}
    closed = urdf_fk(parsed, q | {"gripper": 1.0})
    opened = urdf_fk(parsed, q | {"gripper": 0.0})
    tool = np.linalg.inv(closed[urdf.TOOL_FRAME])
    for jaw, sign in zip(urdf.JAW_LINKS, (1, -1), strict=True):
        assert _same_angle(_planar(tool @ closed[jaw])[2], 0.0)  # closed: the jaws lie along the tool's x axis
        assert _same_angle(_planar(tool @ opened[jaw])[2], sign * urdf.JAW_OPEN_RAD)


def test_object_frame() -> None:
    edge = frames.object_transform([0.5, -0.25, 2.0])
    pose = tf_fk([edge])[frames.OBJECT_FRAME]
    assert np.allclose(_planar(pose), [0.5, -0.25, 2.0], atol=TOLERANCE)


def test_frames_refuse_a_wrong_joint_count() -> None:
    world = worlds()[0]
    with pytest.raises(ValueError, match="expected 2 joint angles"):
        frames.arm_transforms(world.robot, [0.0, 0.0, 0.0], 0.0)
