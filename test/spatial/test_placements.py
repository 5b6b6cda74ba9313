"""clew_ros.spatial.placements: supports, faces, stable placements, sampling and projection."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from clew_ros.core.errors import WorldError
from clew_ros.spatial.placements import (
    FACE_RPY,
    MovableObject,
    check_placement,
    object_from_parameters,
    placement_pose,
    project,
    resting_on,
    sample_placements,
    supports_from_parameters,
)
from clew_ros.spatial.scene import make_obstacle
from clew_ros.spatial.tier import object_touches
from clew_ros.spatial.transforms import matrix_pose, pose_matrix, rpy_matrix

BOX = MovableObject("box", (0.06, 0.04, 0.1))
CAN = MovableObject("cylinder", (0.12, 0.03))
TABLE = make_obstacle("table", "box", [0.8, 0.6, 0.04], pose_matrix([0.5, 0.0, 0.3, 0.0, 0.0, 0.4]), "table")
STOOL = make_obstacle("stool", "cylinder", [0.4, 0.15], pose_matrix([-0.5, 0.2, 0.2, 0.0, 0.0, 0.0]), "stool")
ON_ITS_SIDE = make_obstacle("crate", "box", [0.3, 0.5, 0.2], pose_matrix([0.0, -0.8, 0.25, math.pi / 2, 0, 0]), "crate")
SUPPORTS = supports_from_parameters({"supports": ["table", "stool", "crate"]}, [TABLE, STOOL, ON_ITS_SIDE])


def test_each_face_turns_down() -> None:
    for face, rpy in FACE_RPY.items():
        axis = "xyz".index(face[1])
        normal = np.zeros(3)
        normal[axis] = 1.0 if face[0] == "+" else -1.0
        np.testing.assert_allclose(rpy_matrix(*rpy) @ normal, [0.0, 0.0, -1.0], atol=1e-12)


def test_supports_top_faces() -> None:
    table, stool, crate = SUPPORTS
    assert (table.round, table.top, table.half) == (False, pytest.approx(0.32), (0.4, 0.3))
    assert (stool.round, stool.top, stool.half[0]) == (True, pytest.approx(0.4), 0.15)
    # the crate lies on its side: its local y axis is vertical, 0.5 m tall
    assert crate.top == pytest.approx(0.5)
    assert sorted(crate.half) == [0.1, 0.15]


@pytest.mark.parametrize("thing", [BOX, CAN], ids=["box", "cylinder"])
def test_sampled_placements_rest_inside_the_top_face_and_touch_nothing(thing: MovableObject) -> None:
    wall = make_obstacle("wall", "box", [0.02, 0.6, 0.3], pose_matrix([0.55, 0.0, 0.47, 0.0, 0.0, 0.4]), "wall")
    rng = np.random.default_rng(0)
    for support in SUPPORTS:
        for face in thing.faces:
            poses = sample_placements(thing, support, face, [TABLE, STOOL, ON_ITS_SIDE, wall], count=20, rng=rng)
            assert len(poses) >= 10, (support.name, face)
            for pose in poses:
                assert resting_on(thing, pose, SUPPORTS) == (support, face)
                corners = thing.face_points(face) @ pose[:3, :3].T + pose[:3, 3]
                inset = thing.size[1] if thing.shape == "cylinder" else 0.0
                points = pose[None, :2, 3] if thing.shape == "cylinder" else corners[:, :2]
                assert support.contains(points, inset=inset - 1e-9).all()
                assert object_touches(thing, pose, [wall]) == []  # its exact box or cylinder


def test_what_is_not_a_stable_placement() -> None:
    table = SUPPORTS[0]
    resting = placement_pose(BOX, table, "+x", x=0.5, y=0.0, yaw=0.3)
    assert resting_on(BOX, resting, SUPPORTS) == (table, "+x")
    raised = resting.copy()
    raised[2, 3] += 0.002
    assert resting_on(BOX, raised, SUPPORTS) is None
    assert resting_on(BOX, raised, SUPPORTS, tolerance=0.003) == (table, "+x")
    tilted = resting @ pose_matrix([0, 0, 0, 0, 0.05, 0])  # about local y: the +x face no longer flat
    assert resting_on(BOX, tilted, SUPPORTS) is None
    off = placement_pose(BOX, table, "+x", x=2.0, y=0.0, yaw=0.3)
    assert resting_on(BOX, off, SUPPORTS) is None
    can = placement_pose(CAN, table, "+z", x=0.5, y=0.1, yaw=1.0)
    assert resting_on(CAN, can, SUPPORTS) == (table, "+z")
    assert resting_on(CAN, can @ pose_matrix([0, 0, 0, 0.01, 0, 0]), SUPPORTS) == (table, "+z")  # rim within 0.3 mm
    assert resting_on(CAN, can @ pose_matrix([0, 0, 0, 0.1, 0, 0]), SUPPORTS) is None  # rim 3 mm off


def test_projection_onto_the_placement_manifold() -> None:
    table = SUPPORTS[0]
    rng = np.random.default_rng(1)
    for face in BOX.faces:
        resting = placement_pose(BOX, table, face, x=0.45, y=0.05, yaw=rng.uniform(-3, 3))
        nudged = resting @ pose_matrix([*rng.uniform(-0.01, 0.01, 3), *rng.uniform(-0.1, 0.1, 3)])
        projected = project(BOX, nudged, SUPPORTS)
        assert projected is not None
        assert resting_on(BOX, projected, SUPPORTS) == (table, face)
        np.testing.assert_allclose(projected[:3, 3], [nudged[0, 3], nudged[1, 3], resting[2, 3]], atol=1e-12)
    assert project(BOX, pose_matrix([3.0, 3.0, 1.0, 0, 0, 0]), SUPPORTS) is None


def test_given_placements_are_checked_by_name() -> None:
    pose = matrix_pose(placement_pose(CAN, SUPPORTS[1], "-z", x=-0.5, y=0.25, yaw=0.0))
    assert check_placement(CAN, pose, SUPPORTS, 0.001, "world.object.initial") == (SUPPORTS[1], "-z")
    floating = [pose[0], pose[1], pose[2] + 0.05, *pose[3:]]
    with pytest.raises(WorldError, match=re.escape("is not a stable placement")) as error:
        check_placement(CAN, floating, SUPPORTS, 0.001, "world.object.goal")
    assert error.value.parameter == "world.object.goal"


def test_matrix_pose_inverts_pose_matrix() -> None:
    rng = np.random.default_rng(2)
    for _ in range(20):
        pose = [*rng.uniform(-1, 1, 3), rng.uniform(-3, 3), rng.uniform(-1.5, 1.5), rng.uniform(-3, 3)]
        np.testing.assert_allclose(pose_matrix(matrix_pose(pose_matrix(pose))), pose_matrix(pose), atol=1e-12)


@pytest.mark.parametrize(
    ("world", "parameter", "message"),
    [
        ({"object": {"shape": "sphere", "size": [0.1]}}, "world.object.shape", "box or cylinder"),
        ({"object": {"shape": "box", "size": [0.1, 0.1]}}, "world.object.size", "3 positive numbers"),
        ({"object": {"shape": "cylinder", "size": [0.1, -1]}}, "world.object.size", "[height, radius]"),
    ],
)
def test_bad_objects_are_refused(world: dict[str, object], parameter: str, message: str) -> None:
    with pytest.raises(WorldError, match=re.escape(message)) as error:
        object_from_parameters(world)
    assert error.value.parameter == parameter


def test_bad_supports_are_refused() -> None:
    tilted = make_obstacle("ramp", "box", [0.5, 0.5, 0.05], pose_matrix([0, 0, 0, 0.3, 0, 0]), "ramp")
    with pytest.raises(WorldError, match="'ramp' has no horizontal top face"):
        supports_from_parameters({"supports": ["ramp"]}, [tilted])
    with pytest.raises(WorldError, match="'shelf' is not an obstacle"):
        supports_from_parameters({"supports": ["shelf"]}, [tilted])
