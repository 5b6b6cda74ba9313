"""A run's snapshot (``clew_ros.spatial.snapshot``, interface.md section 3c) on the shipped Panda: the state
written into the parameter tree reads back as that world (start, fixed joints, object, added obstacles and
cubes, the parameters' own kept); a perceived object pose near a stable placement is snapped onto it, a
farther one refused naming the face, its tilt and the support; a start in collision names what it touches."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("urdf_parser_py")

from clew_ros.ros.spatial import load_spatial, resolved_parameters
from clew_ros.spatial.placements import resting_on
from clew_ros.spatial.snapshot import (
    AddedObstacle,
    SnapError,
    WorldState,
    snap_object_pose,
    snapshot_tree,
    start_contacts,
)
from clew_ros.spatial.transforms import pose_matrix
from clew_ros.spatial.world import spatial_world_from_parameters

WORLD = Path(__file__).resolve().parents[2] / "config" / "spatial" / "panda_table_to_table.yaml"


@pytest.fixture(scope="module")
def loaded():  # type: ignore[no-untyped-def]
    parameters = resolved_parameters(WORLD)
    return load_spatial({"world": parameters["world"]}, WORLD.parent)


def test_the_state_written_into_the_tree_reads_back_as_that_world(loaded) -> None:  # type: ignore[no-untyped-def]
    world, setup = loaded
    q = tuple(world.initial + 0.01)
    state = WorldState(
        initial=q,
        object_pose=(0.45, 0.25, 0.17, 0.0, 0.0, 0.3),
        obstacles=(AddedObstacle("rviz/3", "cylinder", (0.2, 0.05), (-0.4, 0.1, 0.3, 0.0, 0.0, 0.0)),),
        cubes=np.array([[-0.41, -0.41, 0.51], [-0.39, -0.41, 0.51]]),
        cube_m=0.02,
    )
    tree = snapshot_tree(setup.tree, state)
    assert setup.tree["world"]["robot"]["initial"] != list(q), "the parameters' tree is left as it was"
    assert "rviz/3" not in setup.tree["world"].get("obstacle_names", [])
    snapshot = spatial_world_from_parameters(tree, setup.folder, prepared=(world.robot, world.spheres))
    assert tuple(snapshot.initial) == q
    assert snapshot.object.initial == state.object_pose
    names = [o.name for o in snapshot.obstacles]
    assert names == ["table_a", "table_b", "rviz/3", "points/0", "points/1"]
    cube = snapshot.obstacles[3]
    assert cube.shape == "box"
    assert cube.size == (0.02, 0.02, 0.02)
    assert np.allclose(cube.pose[:3, 3], [-0.41, -0.41, 0.51])
    assert [s.name for s in snapshot.supports] == ["table_a", "table_b"]


def test_fixed_joints_are_written_into_the_tree(loaded) -> None:  # type: ignore[no-untyped-def]
    _world, setup = loaded
    tree = snapshot_tree(setup.tree, WorldState(fixed={"panda_finger_joint1": 0.02}))
    robot = tree["world"]["robot"]
    assert robot["fixed_joint_positions"][robot["fixed_joint_names"].index("panda_finger_joint1")] == 0.02


def test_a_pose_near_a_stable_placement_is_snapped_onto_it(loaded) -> None:  # type: ignore[no-untyped-def]
    world, _ = loaded
    thing = world.object.shape
    near = pose_matrix([0.51, 0.31, 0.176, 0.03, -0.02, 0.4])
    snapped = snap_object_pose(thing, near, world.supports, snap_m=0.01, snap_rad=0.05)
    assert snapped[:2] == pytest.approx((0.51, 0.31), abs=1e-12)
    assert snapped[2] == pytest.approx(0.17, abs=1e-12)
    assert snapped[3:5] == pytest.approx((0.0, 0.0), abs=1e-12)
    assert snapped[5] == pytest.approx(0.4, abs=0.01)
    assert resting_on(thing, pose_matrix(list(snapped)), world.supports, 1e-9) is not None


@pytest.mark.parametrize(
    ("pose", "words"),
    [
        ([0.5, 0.3, 0.17, 0.2, 0.0, 0.0], ["face -z", "tilted 0.2000 rad", "table_a"]),
        ([0.5, 0.3, 0.2, 0.0, 0.0, 0.0], ["face -z", "0.0300 m from support table_a"]),
        ([0.5, 0.3, 0.17, math.pi / 2 + 0.01, 0.0, 0.0], ["face -y", "tilted 0.0100 rad", "0.0300 m"]),
        ([0.0, 0.9, 0.17, 0.0, 0.0, 0.0], ["over no support"]),
    ],
)
def test_a_pose_far_from_any_is_refused_saying_why(loaded, pose: list[float], words: list[str]) -> None:  # type: ignore[no-untyped-def]
    world, _ = loaded
    with pytest.raises(SnapError) as caught:
        snap_object_pose(world.object.shape, pose_matrix(pose), world.supports, snap_m=0.01, snap_rad=0.05)
    for word in words:
        assert word in str(caught.value), str(caught.value)


def test_a_start_in_collision_names_the_obstacle_it_touches(loaded) -> None:  # type: ignore[no-untyped-def]
    world, setup = loaded
    hand = world.checker.sphere_positions(world.initial.tolist())[-1]
    block = AddedObstacle("camera/2", "box", (0.05, 0.05, 0.05), (*hand.tolist(), 0.0, 0.0, 0.0))
    far = np.stack(np.meshgrid(np.arange(20) * 0.02 - 0.9, np.arange(20) * 0.02 - 0.9, [0.05]), axis=-1)
    state = WorldState(obstacles=(block,), cubes=far.reshape(-1, 3), cube_m=0.02)  # 400 cubes on the floor, far
    tree = snapshot_tree(setup.tree, state)
    snapshot = spatial_world_from_parameters(tree, setup.folder, prepared=(world.robot, world.spheres))
    said = start_contacts(snapshot)
    assert "'camera/2'" in said
    assert "points/" not in said


def test_a_start_in_a_sensed_cube_names_the_cube(loaded) -> None:  # type: ignore[no-untyped-def]
    world, setup = loaded
    hand = world.checker.sphere_positions(world.initial.tolist())[-1]
    cubes = np.array([[-0.9, -0.9, 0.05], hand])  # points/0 far, points/1 at the hand
    tree = snapshot_tree(setup.tree, WorldState(cubes=cubes, cube_m=0.02))
    snapshot = spatial_world_from_parameters(tree, setup.folder, prepared=(world.robot, world.spheres))
    said = start_contacts(snapshot)
    assert "'points/1'" in said
    assert "'points/0'" not in said
