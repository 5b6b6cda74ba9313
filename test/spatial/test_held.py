"""The held object in the checker (transfer): it rides on the tcp, touches its supports only from above, and
its spheres limit the free intervals."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from clew_ros.spatial.checker import Held, SpatialChecker
from clew_ros.spatial.inverse import InverseKinematics
from clew_ros.spatial.placements import MovableObject, placement_pose, supports_from_parameters
from clew_ros.spatial.robot import RobotModel
from clew_ros.spatial.scene import make_obstacle
from clew_ros.spatial.spheres import SphereModel
from clew_ros.spatial.transforms import pose_matrix

TABLE = make_obstacle("table", "box", [0.6, 1.0, 0.04], pose_matrix([0.6, 0.0, 0.1, 0.0, 0.0, 0.0]), "table")
SUPPORT = supports_from_parameters({"supports": ["table"]}, [TABLE])
BOX = MovableObject("box", (0.04, 0.04, 0.08))
CAN = MovableObject("cylinder", (0.08, 0.02))
#: a top-down grasp 2 cm above the object's centre (2 cm under its top): the tcp's z axis points down
GRASP = pose_matrix([0.0, 0.0, 0.02, math.pi, 0.0, 0.0])
GRIPPER = ("panda_hand", "panda_leftfinger", "panda_rightfinger")


@pytest.fixture(scope="module")
def arm(panda: RobotModel) -> RobotModel:
    return replace(panda, gripper_links=GRIPPER)


def holding(arm: RobotModel, spheres: SphereModel, object_pose: np.ndarray, held: Held, extra=()) -> tuple:
    """A checker with ``held``, and the valid configurations that hold the object at ``object_pose``."""
    checker = SpatialChecker(arm, spheres, [TABLE, *extra], held=held)
    solutions = InverseKinematics(arm).solve(object_pose @ GRASP, np.random.default_rng(1))
    return checker, solutions


@pytest.mark.parametrize("thing", [BOX, CAN], ids=["box", "cylinder"])
def test_the_held_object_may_rest_on_its_support(
    arm: RobotModel, panda_spheres: SphereModel, thing: MovableObject
) -> None:
    resting = placement_pose(thing, SUPPORT[0], "-z", x=0.5, y=0.2, yaw=0.0)
    checker, solutions = holding(arm, panda_spheres, resting, Held(thing, GRASP, SUPPORT))
    assert len(solutions) > 0
    valid = checker.valid(solutions)
    assert valid.any()
    # without leave to touch its support, the object's spheres (which reach below its face) collide
    strict, _ = holding(arm, panda_spheres, resting, Held(thing, GRASP, ()))
    assert not strict.valid(solutions[valid]).any()
    # sunk 2 cm into the table: neither above its top nor clear of it
    sunk = resting @ pose_matrix([0.0, 0.0, -0.02, 0.0, 0.0, 0.0])
    checker, deeper = holding(arm, panda_spheres, sunk, Held(thing, GRASP, SUPPORT))
    assert len(deeper) > 0
    assert not checker.valid(deeper).any()


def test_every_non_gripper_link_is_checked_against_the_object(arm: RobotModel, panda_spheres: SphereModel) -> None:
    checker = SpatialChecker(arm, panda_spheres, [TABLE], held=Held(BOX, GRASP, SUPPORT))
    held_index = len(arm.links)
    against = {arm.links[i].name for i, j in checker.pairs.tolist() if j == held_index}
    assert against == {link.name for link in arm.links} - set(GRIPPER)


def test_intervals_count_the_held_object(arm: RobotModel, panda_spheres: SphereModel) -> None:
    lifted = placement_pose(BOX, SUPPORT[0], "-z", x=0.5, y=0.2, yaw=0.0) @ pose_matrix([0, 0, 0.1, 0, 0, 0])
    # a post beside the object, where only the object (not the arm) passes when joint 1 turns
    angle = math.atan2(0.2, 0.5) + 0.25
    post = make_obstacle(
        "post",
        "cylinder",
        [0.1, 0.015],
        pose_matrix([0.54 * math.cos(angle), 0.54 * math.sin(angle), 0.2, 0, 0, 0]),
        "p",
    )
    checker, solutions = holding(arm, panda_spheres, lifted, Held(BOX, GRASP, SUPPORT), [post])
    qs = solutions[checker.valid(solutions)]
    assert len(qs) > 0
    free = SpatialChecker(arm, panda_spheres, [TABLE, post])  # the arm alone
    for joint in range(arm.dof):
        lo, hi, ok = checker.free_intervals(qs, joint)
        assert ok.all()
        for b in range(len(qs)):
            values = np.append(np.arange(lo[b], hi[b], 0.002), hi[b])
            moved = np.repeat(qs[b][None], len(values), axis=0)
            moved[:, joint] = values
            assert checker.valid(moved).all(), (joint, b)
    _, hi, _ = checker.free_intervals(qs, 0)
    _, alone_hi, _ = free.free_intervals(qs, 0)
    # turning joint 1 one way swings the object into the post: the object's interval ends sooner
    assert np.all(hi <= alone_hi + 1e-12)
    assert np.any(hi < alone_hi - 0.05)
