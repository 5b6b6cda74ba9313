"""Spatial worlds in ROS terms, without a ROS graph (issue 45): ``clew_ros.ros.spatial`` and
``clew_ros.motion.spatial`` on the shipped Panda.

The URDF's every joint and link (:class:`UrdfTree`) against the checker's packed chain; mesh URIs a viewer
opens (``package://`` inside an installed share directory, else ``file://``); ``~/goal_pose`` read as a
stable placement or refused with the face, the tilt and the distance off the support; the trajectory's
velocity limits; the spatial launch file's parameters.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("urdf_parser_py")

from geometry_msgs.msg import PoseStamped
from helpers.launch_api import install, started_nodes
from visualization_msgs.msg import Marker

from clew_ros.motion.spatial import UrdfTree, velocity_limits
from clew_ros.planar.world import read_parameter_file
from clew_ros.render.spatial.meshes import simplify
from clew_ros.ros.messages import GoalPoseError
from clew_ros.ros.spatial import (
    LinkMarkerSettings,
    goal_from_pose_stamped,
    link_markers,
    load_spatial,
    pose_stamped,
    resolved_parameters,
    robot_description,
    state_transforms,
    static_transforms,
)
from clew_ros.spatial.transforms import quaternion_matrix

ROOT = Path(__file__).resolve().parents[2]
WORLD_FILE = ROOT / "config" / "spatial" / "panda_table_to_table.yaml"
PANDA = ROOT / "config" / "robots" / "panda" / "panda.urdf"


@pytest.fixture(scope="module")
def loaded():  # type: ignore[no-untyped-def]
    return load_spatial(read_parameter_file(WORLD_FILE), WORLD_FILE.parent)


def _goal(pose: list[float]) -> PoseStamped:
    return pose_stamped(pose, 0)


def test_urdf_tree_puts_every_link_where_the_checker_does(loaded) -> None:  # type: ignore[no-untyped-def]
    world, setup = loaded
    robot = world.robot
    assert setup.joints.movable_joint_names == [*robot.joint_names, "panda_finger_joint1", "panda_finger_joint2"]
    rng = np.random.default_rng(0)
    for q in rng.uniform(robot.lower, robot.upper, size=(20, robot.dof)):
        frames = {"world": np.eye(4)}
        pending = static_transforms(setup, world) + state_transforms(setup, world, q, world.object.initial)
        while pending:
            edge = next(e for e in pending if e.parent in frames)
            pending.remove(edge)
            frames[edge.child] = frames[edge.parent] @ quaternion_matrix(edge.translation, edge.rotation)
        for link, pose in robot.link_poses(q).items():
            assert np.allclose(frames[link], pose, atol=1e-9), link
        assert np.allclose(frames["object"][:3, 3], world.object.initial[:3], atol=1e-12)


def test_a_mimic_joint_follows_and_velocity_limits_take_the_lower(loaded) -> None:  # type: ignore[no-untyped-def]
    world, setup = loaded
    values = setup.joints.joint_values(world.robot.joint_names, world.initial, {"panda_finger_joint1": 0.03})
    assert values["panda_finger_joint2"] == pytest.approx(0.03)  # <mimic joint="panda_finger_joint1"/>
    limits = velocity_limits(setup.joints, world.robot.joint_names, 2.4)
    assert limits.tolist() == [2.175, 2.175, 2.175, 2.175, 2.4, 2.4, 2.4]  # panda.urdf: 2.175 and 2.61 rad/s
    assert velocity_limits(setup.joints, world.robot.joint_names, [1.0] * 7).tolist() == [1.0] * 7


def test_the_links_are_markers_in_their_frames(loaded) -> None:  # type: ignore[no-untyped-def]
    world, _setup = loaded
    markers = link_markers(world, 0, LinkMarkerSettings(max_link_faces=100), simplify)
    assert [m.id for m in markers] == list(range(len(markers)))
    assert {m.header.frame_id for m in markers} == {link.name for link in world.robot.links}
    meshes = [m for m in markers if m.type == Marker.TRIANGLE_LIST]
    assert len(meshes) >= 8  # the Panda's links are meshes (and a few primitives)
    assert all(m.frame_locked for m in markers)
    assert {m.type for m in markers} <= {Marker.TRIANGLE_LIST, Marker.CUBE, Marker.CYLINDER, Marker.SPHERE}
    for marker in meshes:
        assert 0 < len(marker.points) <= 300
        assert len(marker.points) % 3 == 0
    hand = next(link for link in world.robot.links if link.name == "panda_hand")
    (geometry,) = hand.geometries
    corners = np.array([[p.x, p.y, p.z] for m in meshes if m.header.frame_id == "panda_hand" for p in m.points])
    low, high = geometry.vertices.min(axis=0), geometry.vertices.max(axis=0)
    assert np.all(corners >= low - 1e-9)
    assert np.all(corners <= high + 1e-9)  # the simplified mesh stays within the link's (origin is identity)


def test_mesh_uris_are_package_uris_when_installed_else_file_uris(tmp_path: Path) -> None:
    text = PANDA.read_text()
    plain = robot_description(text, PANDA.parent, share=tmp_path)  # not inside that share directory
    uris = re.findall(r'filename="([^"]+)"', plain)
    assert uris
    assert all(uri.startswith("file:///") and Path(uri[len("file://") :]).is_file() for uri in uris)
    installed = robot_description(text, PANDA.parent, share=ROOT)  # as if the source tree were the share
    uris = re.findall(r'filename="([^"]+)"', installed)
    assert uris
    assert all(uri.startswith("package://clew_ros/config/robots/panda/meshes/") for uri in uris)
    assert UrdfTree(installed).movable_joint_names == UrdfTree(text).movable_joint_names


def test_goal_pose_is_a_stable_placement_or_refused_with_the_reason(loaded) -> None:  # type: ignore[no-untyped-def]
    world, _setup = loaded
    goal = [0.45, -0.25, 0.17, 0.0, 0.0, 1.0]
    assert np.allclose(goal_from_pose_stamped(_goal(goal), world), goal, atol=1e-12)
    lying = [0.5, -0.3, 0.14, math.pi / 2, 0.0, 0.2]  # on its side: another face down
    assert np.allclose(goal_from_pose_stamped(_goal(lying), world), lying, atol=1e-12)
    cases = {
        "tilted": ([0.5, -0.3, 0.17, 0.0, 0.25, 0.0], ["face -z", "tilted 0.2500 rad"]),
        "above": ([0.5, -0.3, 0.2, 0.0, 0.0, 0.0], ["face -z", "0.0300 m off support table_b's top face"]),
        "sunk": ([0.5, 0.3, 0.16, 0.0, 0.0, 0.0], ["0.0100 m off support table_a's top face"]),
        "nowhere": ([0.0, 0.0, 0.5, 0.0, 0.0, 0.0], ["lies over no support (supports: table_a, table_b)"]),
    }
    for name, (pose, words) in cases.items():
        with pytest.raises(GoalPoseError) as refused:
            goal_from_pose_stamped(_goal(pose), world)
        assert "not a stable placement" in str(refused.value), name
        for word in words:
            assert word in str(refused.value), (name, str(refused.value))
    squashed = _goal(goal)
    squashed.pose.orientation.w = 2.0
    with pytest.raises(GoalPoseError, match="unit quaternion"):
        goal_from_pose_stamped(squashed, world)
    elsewhere = _goal(goal)
    elsewhere.header.frame_id = "panda_link0"
    with pytest.raises(GoalPoseError, match="frame_id"):
        goal_from_pose_stamped(elsewhere, world)


def test_the_worlds_own_goal_sent_as_a_pose_is_that_goal_to_the_last_bit(loaded) -> None:  # type: ignore[no-untyped-def]
    """A client that sends ``world.object.goal`` as a PoseStamped gets clew_plan's plan: the quaternion's
    round-off does not move the goal (a goal 1e-6 away is a goal of its own)."""
    world, _setup = loaded
    own = np.asarray(world.object.goal, dtype=float)
    assert np.array_equal(goal_from_pose_stamped(_goal(own.tolist()), world), own)
    nearby = own + np.array([1e-6, 0.0, 0.0, 0.0, 0.0, 0.0])
    moved = goal_from_pose_stamped(_goal(nearby.tolist()), world)
    assert not np.array_equal(moved, own)
    assert np.allclose(moved, nearby, atol=1e-12)


def test_the_spatial_launch_file_hands_the_node_absolute_paths(monkeypatch: pytest.MonkeyPatch) -> None:
    install(monkeypatch, ROOT)
    launch = ROOT / "launch" / "clew_spatial_planner.launch.py"
    ((node, (parameters,)),) = started_nodes(launch, {})
    assert (node.kwargs["package"], node.kwargs["executable"], node.kwargs["name"]) == (
        "clew_ros",
        "clew_planner",
        "clew_planner",
    )
    robot = parameters["world"]["robot"]
    assert Path(robot["urdf"]) == PANDA
    assert Path(robot["srdf"]).is_file()
    assert parameters["world"]["kind"] == "spatial"
    assert "record" not in parameters
    motion = ROOT / "config" / "spatial" / "panda_scene_motion.yaml"
    ((_node, (parameters,)),) = started_nodes(launch, {"world": str(motion), "record_directory": "/runs"})
    assert Path(parameters["world"]["scene_file"]).is_file()
    assert parameters["record"] == {"directory": "/runs"}
    assert (
        resolved_parameters(motion)["world"]["robot"]["goal"] == read_parameter_file(motion)["world"]["robot"]["goal"]
    )


def test_world_yaml_names_the_files_absolutely(loaded) -> None:  # type: ignore[no-untyped-def]
    import yaml

    from clew_ros.core.settings import PlannerSettings
    from clew_ros.ros.spatial import with_goal, world_yaml_message

    world, setup = loaded
    assert setup.tree["world"]["robot"]["urdf"] == "../robots/panda/panda.urdf"  # as given
    goal = [0.45, -0.25, 0.17, 0.0, 0.0, 1.0]
    text = world_yaml_message(setup, with_goal(world, goal), PlannerSettings(seed=4), "clew_planner").data
    parameters = yaml.safe_load(text)["clew_planner"]["ros__parameters"]
    assert Path(parameters["world"]["robot"]["urdf"]) == PANDA
    assert Path(parameters["world"]["robot"]["srdf"]).is_file()
    assert parameters["world"]["object"]["goal"] == goal
    assert parameters["planner"]["seed"] == 4
    assert setup.tree["world"]["robot"]["urdf"] == "../robots/panda/panda.urdf"  # the setup's tree unchanged


def test_markers_link_faces_zero_draws_the_exact_collision_meshes(loaded) -> None:  # type: ignore[no-untyped-def]
    """markers.link_faces 0: every triangle of every link mesh, at the link's own vertices (no simplification)."""
    world, _setup = loaded
    markers = link_markers(world, 0, LinkMarkerSettings(max_link_faces=0), simplify)
    meshes = {m.header.frame_id: m for m in markers if m.type == Marker.TRIANGLE_LIST}
    for link in world.robot.links:
        for geometry in link.geometries:
            if geometry.kind != "mesh":
                continue
            drawn = np.array([[p.x, p.y, p.z] for p in meshes[link.name].points])
            expected = (geometry.vertices @ geometry.origin[:3, :3].T + geometry.origin[:3, 3])[
                geometry.faces.reshape(-1)
            ]
            assert len(drawn) == 3 * len(geometry.faces)
            assert np.allclose(drawn, expected)
