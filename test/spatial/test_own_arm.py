"""An arm the package does not ship, as docs/own_arm.md brings it: a description package with ``package://``
meshes and continuous joints, found through world.robot.package_paths, planned to a pose goal by clew_plan."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from helpers.own_arm import pose_goal_world

from clew_ros.core.errors import WorldError
from clew_ros.planar.world import read_parameter_file
from clew_ros.spatial.inverse import InverseKinematics
from clew_ros.spatial.plan import rotation_angle, validate_plan
from clew_ros.spatial.space import plan
from clew_ros.spatial.transforms import pose_matrix
from clew_ros.spatial.world import spatial_world_from_parameters

SEED = 3


def _plan_cli(world: Path, *args: object) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k not in ("AMENT_PREFIX_PATH", "ROS_PACKAGE_PATH")}
    command = [sys.executable, "-m", "clew_ros.cli.plan", str(world), *map(str, args)]
    return subprocess.run(command, capture_output=True, text=True, timeout=600, cwd=world.parent, env=env)


def test_clew_plan_reaches_a_pose_goal_for_an_arm_not_shipped(tmp_path: Path) -> None:
    world_file = pose_goal_world(tmp_path, SEED)
    done = _plan_cli(world_file, "-o", "plan.json", "--seed", 0, "-q")
    assert done.returncode == 0, done.stderr
    document = json.loads((tmp_path / "plan.json").read_text())
    assert document["code"] == "SUCCEEDED"
    assert document["final_object_pose"] is None
    world = spatial_world_from_parameters(read_parameter_file(world_file), tmp_path)
    assert world.robot.continuous.tolist() == [True, False, False, False, False, True]
    assert all(g.kind == "mesh" for link in world.robot.links for g in link.geometries)
    assert validate_plan(world, document) == []
    end = np.array(document["segments"][-1]["waypoints"][-1])
    tcp = InverseKinematics(world.robot).tcp_poses(end[None])[0]
    goal = pose_matrix(list(world.goal_pose or ()))
    assert np.linalg.norm(tcp[:3, 3] - goal[:3, 3]) <= 0.001
    assert rotation_angle(tcp, goal) <= 0.01
    again = _plan_cli(world_file, "-o", "again.json", "--seed", 0, "-q")
    assert again.returncode == 0, again.stderr
    first, second = (json.loads((tmp_path / name).read_text()) for name in ("plan.json", "again.json"))
    assert first["segments"] == second["segments"]  # same seed, same plan


def test_every_ik_solution_is_a_goal_the_search_may_reach(tmp_path: Path) -> None:
    world_file = pose_goal_world(tmp_path, SEED)
    world = spatial_world_from_parameters(read_parameter_file(world_file), tmp_path)
    result = plan(world)
    assert result.success, result.message
    roots = [lm for lm in result.tree if lm.parent is None]
    assert len(roots) == 1  # the start tree has one root ...
    assert result.stats["goal_landmarks"] > 1  # ... the goal tree one per IK solution (and turn) at least


def test_a_pose_goal_is_refused_beside_a_joint_goal_or_an_object(tmp_path: Path) -> None:
    world_file = pose_goal_world(tmp_path, SEED)
    parameters = read_parameter_file(world_file)
    robot = parameters["world"]["robot"]
    with pytest.raises(WorldError, match=r"world.robot.goal_pose: expected either world.robot.goal or"):
        spatial_world_from_parameters(
            {"world": {**parameters["world"], "robot": {**robot, "goal": robot["initial"]}}}, tmp_path
        )
    with pytest.raises(WorldError, match=r"world.robot.goal_pose: expected a pose"):
        spatial_world_from_parameters(
            {"world": {**parameters["world"], "robot": {**robot, "goal_pose": [1.0]}}}, tmp_path
        )


def test_an_unreachable_pose_goal_is_an_outcome_not_a_crash(tmp_path: Path) -> None:
    world_file = pose_goal_world(tmp_path, SEED)
    document = yaml.safe_load(world_file.read_text())
    document["/**"]["ros__parameters"]["world"]["robot"]["goal_pose"] = [5.0, 0.0, 0.5, 0.0, 0.0, 0.0]
    world_file.write_text(yaml.safe_dump(document))
    done = _plan_cli(world_file, "-o", "plan.json", "-q")
    assert done.returncode == 1, done.stderr
    assert json.loads((tmp_path / "plan.json").read_text())["code"] == "GOAL_OUT_OF_REACH"


def test_the_guides_parameter_file_plans_as_written(tmp_path: Path) -> None:
    """docs/own_arm.md's parameter file, its start and goal pose set for the random arm (the guide's numbers
    are for its reader's arm), next to the packages it names under ``src``."""
    guide = (Path(__file__).resolve().parents[2] / "docs" / "own_arm.md").read_text()
    block = guide.split("```yaml\n", 1)[1].split("```", 1)[0]
    document = yaml.safe_load(block)
    reference = read_parameter_file(pose_goal_world(tmp_path, SEED))["world"]["robot"]
    robot = document["/**"]["ros__parameters"]["world"]["robot"]
    assert robot["package_paths"] == ["src"]
    assert robot["srdf"].startswith("package://my_arm_moveit_config/")
    robot["initial"], robot["goal_pose"] = reference["initial"], reference["goal_pose"]
    world_file = tmp_path / "my_cell.yaml"
    world_file.write_text(yaml.safe_dump(document))
    done = _plan_cli(world_file, "-o", "plan.json", "-q")
    assert done.returncode == 0, done.stderr
    world = spatial_world_from_parameters(read_parameter_file(world_file), tmp_path)
    assert validate_plan(world, json.loads((tmp_path / "plan.json").read_text())) == []
