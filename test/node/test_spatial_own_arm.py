"""An arm the package does not ship, served by ``clew_planner`` (issue 58): its ``package://`` meshes found
through ``world.robot.package_paths``; a motion-only query to a tcp pose planned through ``~/goal_pose`` and
``PlannerClient`` (the world's own pose and another one), a query to joint values through ``call_plan``
(``~/plan``); a package found nowhere stops the node with one error naming it, exit 2."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

rclpy = pytest.importorskip("rclpy")
pytest.importorskip("trimesh")

from helpers.node_harness import NodeProcess, Session  # noqa: E402
from helpers.own_arm import pose_goal_world, roomy  # noqa: E402

from clew_ros.planar.world import read_parameter_file  # noqa: E402
from clew_ros.ros.spatial import resolved_parameters, with_goal  # noqa: E402
from clew_ros.spatial.inverse import InverseKinematics  # noqa: E402
from clew_ros.spatial.plan import rotation_angle, validate_plan  # noqa: E402
from clew_ros.spatial.transforms import matrix_pose, pose_matrix  # noqa: E402
from clew_ros.spatial.world import SpatialWorld, spatial_world_from_parameters  # noqa: E402

pytestmark = pytest.mark.ros

SEED = 3
#: The node reads the meshes, builds the sphere model and compiles its kernels before it serves.
STARTUP_S = 180.0
FAST = {"playback.rate": 50.0, "trajectory.max_velocity": 20.0, "trajectory.max_acceleration": 200.0}


def _node_file(world_file: Path, target: Path, **robot: Any) -> Path:
    """The world as a launch file hands it to the node (package_paths absolute), ``world.robot`` changed."""
    parameters = resolved_parameters(world_file)
    parameters["world"]["robot"].update(robot)
    target.write_text(yaml.safe_dump({"/**": {"ros__parameters": parameters}}))
    return target


@pytest.fixture(scope="module")
def served(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Session, SpatialWorld]]:
    tmp = tmp_path_factory.mktemp("own_arm")
    world_file = pose_goal_world(tmp, SEED)
    world = spatial_world_from_parameters(read_parameter_file(world_file), tmp)
    node = NodeProcess(tmp / "node.log", _node_file(world_file, tmp / "node.yaml"), {"record.enabled": False, **FAST})
    session = Session(node)
    session.status.wait_for(timeout_s=STARTUP_S)  # the node serves once its URDF, meshes and kernels are ready
    yield session, world
    assert session.close() == 0, node.output()


def _tcp_reaches(world: SpatialWorld, plan: Any, pose: list[float]) -> None:
    end = np.asarray(plan.segments[-1].waypoints[-1], dtype=float)
    tcp = InverseKinematics(world.robot).tcp_poses(end[None])[0]
    goal = pose_matrix(pose)
    assert np.linalg.norm(tcp[:3, 3] - goal[:3, 3]) <= 0.001
    assert rotation_angle(tcp, goal) <= 0.01


def test_planner_client_plans_the_worlds_pose_goal_and_another(served: tuple[Session, SpatialWorld]) -> None:
    from clew_ros.client import PlannerClient

    session, world = served
    context = rclpy.Context()
    rclpy.init(context=context)
    node = rclpy.create_node("clew_own_arm_client", context=context)
    try:
        client = PlannerClient(node, session.node.name)
        client.wait_for_planner(timeout_s=30.0)
        assert world.goal_pose is not None
        assert client.default_goal() == pytest.approx(world.goal_pose)
        own = client.send_goal().wait(timeout_s=120.0)
        assert own.succeeded, own.message + session.node.output()
        assert own.plan is not None
        assert validate_plan(world, own.plan) == []
        _tcp_reaches(world, own.plan, list(world.goal_pose))
        qs = np.random.default_rng(11).uniform(world.robot.lower, world.robot.upper, (400, world.robot.dof))
        other = [round(float(v), 6) for v in matrix_pose(world.robot.tcp_pose(qs[world.checker.valid(qs)][0]))]
        moved = client.send_goal(other).wait(timeout_s=120.0)
        assert moved.succeeded, moved.message
        assert moved.plan is not None
        assert validate_plan(with_goal(world, other), moved.plan) == []
        _tcp_reaches(world, moved.plan, other)
        client.destroy()
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=context)


def test_call_plan_plans_a_motion_only_query_to_joint_values(tmp_path: Path) -> None:
    world_file = pose_goal_world(tmp_path, SEED)
    robot = read_parameter_file(world_file)["world"]["robot"]
    world = spatial_world_from_parameters(read_parameter_file(world_file), tmp_path)
    qs = np.random.default_rng(12).uniform(world.robot.lower, world.robot.upper, (400, world.robot.dof))
    goal = [round(float(v), 6) for v in qs[roomy(world, qs)][0]]
    document = _node_file(world_file, tmp_path / "joints.yaml", goal=goal)
    tree = yaml.safe_load(document.read_text())
    del tree["/**"]["ros__parameters"]["world"]["robot"]["goal_pose"]
    document.write_text(yaml.safe_dump(tree))
    assert robot["initial"]
    node = NodeProcess(tmp_path / "node.log", document, {"record.enabled": False, **FAST})
    try:
        done = subprocess.run(
            [sys.executable, "-m", "clew_ros.client.call_plan", "--node", node.name, "--timeout", "120"],
            capture_output=True,
            text=True,
            timeout=200,
            check=False,
        )
        assert done.returncode == 0, done.stdout + done.stderr + node.output()
        assert "success: True" in done.stdout
        assert "outcome: SUCCEEDED" in done.stdout
    finally:
        assert node.stop() == 0, node.output()


def test_a_package_found_nowhere_stops_the_node_with_one_error(tmp_path: Path) -> None:
    world_file = pose_goal_world(tmp_path, SEED)
    document = _node_file(world_file, tmp_path / "lost.yaml", package_paths=[str(tmp_path / "elsewhere")])
    env = {k: v for k, v in os.environ.items() if k not in ("AMENT_PREFIX_PATH", "ROS_PACKAGE_PATH")}
    node = NodeProcess(tmp_path / "node.log", document, {"record.enabled": False}, env=env)
    code = node.proc.wait(timeout=60)
    output = node.output()
    assert code == 2, output
    assert "package 'my_arm_description'" in output
    assert "world.robot.package_paths" in output
    assert "Traceback" not in output
