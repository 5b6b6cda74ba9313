"""Grasp sanity: what each grasp of a spatial world does to the object, in words, and what looks wrong.

A grasp is a tcp pose in the object's frame (interface.md section 1b). The planner holds the object there
whatever the gripper is; this check says how a real gripper would take it: the tcp's +z is the approach
(the direction the hand moves in along, the ROS and MoveIt convention), and the fingers close along the
axis of the prismatic finger joints among ``world.robot.gripper_links`` (expressed in the tcp's frame at
``world.robot.initial``; without such a joint, the tcp's y as on the Panda). :func:`check_grasps` names, for
each grasp, the face approached and the pair of faces the fingers close on, with their distance, and warns
when the fingers close on no pair of faces (a box's axis or a cylinder's axis or side within
:attr:`GraspCheckSettings.angle_deg`), when the faces lie farther apart than the fingers open, when the
hand comes through the face the object rests on, or when the fingers close on that face.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.transforms import pose_matrix
from clew_ros.spatial.world import SpatialWorld

__all__ = ["FingerAxis", "GraspCheckSettings", "GraspReport", "check_grasps", "finger_axis"]

Vector = NDArray[np.float64]
_AXES = "xyz"


@dataclass(frozen=True)
class GraspCheckSettings:
    """How strict :func:`check_grasps` is."""

    #: Largest angle (deg) between the fingers' closing axis (or the approach) and the object's axis (or
    #: its side) for the fingers to close on that pair of faces.
    angle_deg: float = 15.0


@dataclass(frozen=True)
class FingerAxis:
    """The fingers' closing axis (unit, in the tcp's frame), where it comes from, and how wide the fingers
    open (m; ``inf`` when unknown)."""

    axis: Vector
    source: str
    opening_m: float = math.inf


@dataclass(frozen=True)
class GraspReport:
    """One grasp as a gripper takes it: ``summary`` in words, and ``warnings`` (empty: it looks right)."""

    index: int
    summary: str
    warnings: list[str] = field(default_factory=list)


def _finger_joints(
    urdf: str, gripper_links: Sequence[str], planned: Sequence[str]
) -> list[tuple[str, str, Vector, float]]:
    """The prismatic joints that move a link of ``gripper_links`` and are not planned: name, child link, unit
    axis (in the child's frame) and travel (m)."""
    out = []
    for joint in ET.fromstring(urdf).iter("joint"):
        child = joint.find("child")
        name, link = joint.get("name", ""), "" if child is None else child.get("link", "")
        if joint.get("type") != "prismatic" or link not in gripper_links or name in planned:
            continue
        axis_element, limit = joint.find("axis"), joint.find("limit")
        axis = np.array(
            [float(v) for v in (axis_element.get("xyz", "1 0 0") if axis_element is not None else "1 0 0").split()]
        )
        travel = float(limit.get("upper", "0")) - float(limit.get("lower", "0")) if limit is not None else math.inf
        if axis.shape == (3,) and np.linalg.norm(axis) > 1e-9:
            out.append((name, link, axis / np.linalg.norm(axis), travel))
    return out


def finger_axis(world: SpatialWorld) -> FingerAxis:
    """The fingers' closing axis in the tcp's frame (the module docstring)."""
    robot = world.robot
    links = {link.name for link in robot.links}
    fingers = [f for f in _finger_joints(robot.urdf, robot.gripper_links, robot.joint_names) if f[1] in links]
    if not fingers:
        return FingerAxis(np.array([0.0, 1.0, 0.0]), "the tcp's y (no prismatic finger joint in gripper_links)")
    q = world.initial.tolist()
    _, child, axis, _ = fingers[0]
    link = robot.links[robot.link_index(child)]
    rotation = robot.frames(q)[link.frame][:3, :3] @ link.offset[:3, :3]
    along = robot.tcp_pose(q)[:3, :3].T @ rotation @ axis
    opening = sum(f[3] for f in fingers)
    names = ", ".join(f[0] for f in fingers)
    return FingerAxis(along / np.linalg.norm(along), f"finger joint {names}", opening)


def _direction(v: Vector) -> str:
    return "(" + ", ".join(f"{float(c):.2f}" for c in v) + ")"


def _box_face(direction: Vector) -> tuple[str, float]:
    """The box face whose outward normal is nearest ``direction`` (unit, object frame), and the angle (deg)."""
    i = int(np.argmax(np.abs(direction)))
    return f"{'+' if direction[i] > 0 else '-'}{_AXES[i]}", math.degrees(math.acos(min(1.0, abs(direction[i]))))


def _cylinder_face(direction: Vector, limit: float) -> tuple[str, float]:
    """A cylinder's cap (``+z`` / ``-z``) or ``side`` nearest ``direction``, and the angle (deg) off it."""
    cap = math.degrees(math.acos(min(1.0, abs(float(direction[2])))))
    del limit
    if cap <= 45.0:
        return ("+z" if direction[2] > 0 else "-z"), cap
    return "side", 90.0 - cap


def _pair(world: SpatialWorld, fingers: Vector, limit: float) -> tuple[str, float, float]:
    """The pair of faces fingers closing along ``fingers`` (object frame) meet, the angle (deg) off it and
    the faces' distance (m)."""
    assert world.object is not None
    shape = world.object.shape
    if shape.shape == "box":
        i = int(np.argmax(np.abs(fingers)))
        off = math.degrees(math.acos(min(1.0, abs(float(fingers[i])))))
        return f"+-{_AXES[i]}", off, float(shape.size[i])
    face, off = _cylinder_face(fingers, limit)
    if face == "side":
        return "the curved side", off, 2.0 * float(shape.size[1])
    return "the caps +-z", off, float(shape.size[0])


def check_grasps(world: SpatialWorld, settings: GraspCheckSettings | None = None) -> list[GraspReport]:
    """Every grasp of ``world.object.grasps`` as a gripper takes it (the module docstring)."""
    settings = settings or GraspCheckSettings()
    if world.object is None:
        return []
    thing = world.object
    limit = settings.angle_deg
    fingers = finger_axis(world)
    rests = {thing.goal_on[1]: "world.object.goal", thing.initial_on[1]: "world.object.initial"}
    reports = []
    for k, grasp in enumerate(np.asarray(thing.grasps, dtype=float)):
        rotation = pose_matrix(grasp.tolist())[:3, :3]
        into = -rotation[:, 2]  # the approached face's outward normal: against the tcp's +z
        if thing.shape.shape == "box":
            face, face_off = _box_face(into)
        else:
            face, face_off = _cylinder_face(into, limit)
        closing = rotation @ fingers.axis
        pair, pair_off, span = _pair(world, closing, limit)
        where = "the curved side" if face == "side" else f"face {face}"
        summary = (
            f"grasp {k}: approaches {where} of the {thing.shape.shape} (the tcp's z along "
            f"{_direction(-into)} in its frame), the fingers close along {_direction(closing)} on {pair}, "
            f"{span:.3f} m apart ({fingers.source})"
        )
        warnings = []
        if face_off > limit:
            warnings.append(f"grasp {k}: the approach is {face_off:.0f} deg off {where}: it meets no face square on")
        if pair_off > limit:
            warnings.append(
                f"grasp {k}: the fingers would close on no pair of faces: their axis {_direction(closing)} is "
                f"{pair_off:.0f} deg off {pair} (a tcp whose approach is not its z, or a grasp turned the wrong way?)"
            )
        elif span > fingers.opening_m + 1e-9:
            warnings.append(
                f"grasp {k}: the faces {pair} lie {span:.3f} m apart, wider than the fingers open "
                f"({fingers.opening_m:.3f} m)"
            )
        if face in rests and face_off <= limit:
            warnings.append(f"grasp {k}: approaches through face {face}, which rests on its support at {rests[face]}")
        if pair_off <= limit and thing.shape.shape == "box":
            axis = pair[-1]
            for rest, name in rests.items():
                if rest[-1] == axis:
                    warnings.append(
                        f"grasp {k}: the fingers close on face {rest}, which rests on its support at {name}"
                    )
        reports.append(GraspReport(k, summary, warnings))
    return reports
