"""An arm the package does not ship, as a newcomer brings it: a random serial arm written as a ROS description
package in a temporary folder, its links as STL meshes named by ``package://`` URIs, its first and last
joints ``continuous``, beside a MoveIt config package with its SRDF; and a motion-only world for it."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
import yaml

from clew_ros.spatial.random_robot import BASE_LINK, TIP_LINK, RandomRobotSettings, random_robot_urdf
from clew_ros.spatial.transforms import pose_matrix

PACKAGE = "my_arm_description"
MOVEIT_PACKAGE = "my_arm_moveit_config"


def _numbers(text: str | None) -> list[float]:
    return [float(v) for v in (text or "0 0 0").split()]


def _solid(geometry: ET.Element) -> trimesh.Trimesh:
    shape = geometry[0]
    if shape.tag == "box":
        return trimesh.creation.box(extents=_numbers(shape.get("size")))
    if shape.tag == "cylinder":
        return trimesh.creation.cylinder(radius=float(shape.get("radius", 0)), height=float(shape.get("length", 0)))
    return trimesh.creation.icosphere(subdivisions=2, radius=float(shape.get("radius", 0)))


def write_description_package(root: Path, seed: int, joints: int = 6) -> Path:
    """``root/<PACKAGE>/`` (``package.xml``, ``urdf/arm.urdf``, ``meshes/<link>.stl``) for the random arm of
    ``seed`` with ``joints`` joints, the first and the last ``continuous``; the URDF's path."""
    text = random_robot_urdf(np.random.default_rng(seed), RandomRobotSettings(joints=(joints, joints)), name="my_arm")
    robot = ET.fromstring(text)
    package = root / PACKAGE
    (package / "meshes").mkdir(parents=True)
    (package / "urdf").mkdir()
    (package / "package.xml").write_text(
        f'<?xml version="1.0"?>\n<package format="3"><name>{PACKAGE}</name><version>0.0.1</version>'
        "<description>test arm</description><maintainer email='a@b.c'>a</maintainer><license>MIT</license>"
        "</package>\n"
    )
    for link in robot.iter("link"):
        collisions = link.findall("collision")
        if not collisions:
            continue
        parts = []
        for collision in collisions:
            origin = collision.find("origin")
            xyz = _numbers(origin.get("xyz")) if origin is not None else [0.0] * 3
            rpy = _numbers(origin.get("rpy")) if origin is not None else [0.0] * 3
            solid = _solid(collision.find("geometry"))  # type: ignore[arg-type]
            solid.apply_transform(pose_matrix([*xyz, *rpy]))
            parts.append(solid)
            link.remove(collision)
        name = link.get("name")
        trimesh.util.concatenate(parts).export(package / "meshes" / f"{name}.stl")
        uri = f"package://{PACKAGE}/meshes/{name}.stl"
        for tag in ("visual", "collision"):
            element = ET.SubElement(link, tag)
            ET.SubElement(ET.SubElement(element, "geometry"), "mesh", filename=uri)
    movable = [joint for joint in robot.iter("joint") if joint.get("type") == "revolute"]
    for joint in (movable[0], movable[-1]):
        joint.set("type", "continuous")
        limit = joint.find("limit")
        if limit is not None:
            limit.attrib.pop("lower", None)
            limit.attrib.pop("upper", None)
    urdf = package / "urdf" / "arm.urdf"
    urdf.write_text(ET.tostring(robot, encoding="unicode"))
    _write_moveit_config(root, robot)
    return urdf


def _write_moveit_config(root: Path, robot: ET.Element) -> None:
    """``root/<MOVEIT_PACKAGE>/config/my_arm.srdf``: the planning group base_link -> tool and each joint's two
    links as a disable_collisions pair (as MoveIt Setup Assistant writes adjacent links)."""
    config = root / MOVEIT_PACKAGE / "config"
    config.mkdir(parents=True)
    (root / MOVEIT_PACKAGE / "package.xml").write_text(
        f'<?xml version="1.0"?>\n<package format="3"><name>{MOVEIT_PACKAGE}</name><version>0.0.1</version>'
        "<description>test arm</description><maintainer email='a@b.c'>a</maintainer><license>MIT</license>"
        "</package>\n"
    )
    pairs = [
        (joint.find("parent").get("link"), joint.find("child").get("link"))  # type: ignore[union-attr]
        for joint in robot.iter("joint")
    ]
    disabled = "".join(f'  <disable_collisions link1="{a}" link2="{b}" reason="Adjacent"/>\n' for a, b in pairs)
    (config / "my_arm.srdf").write_text(
        f'<?xml version="1.0"?>\n<robot name="my_arm">\n  <group name="arm"><chain base_link="{BASE_LINK}" '
        f'tip_link="{TIP_LINK}"/></group>\n{disabled}</robot>\n'
    )


def motion_world(folder: Path, urdf: Path, **robot: Any) -> dict[str, Any]:
    """A motion-only world's parameter tree for the arm at ``urdf`` (given as ``package://``), its packages
    under ``world.robot.package_paths`` relative to ``folder``; ``robot`` adds or replaces ``world.robot``
    keys (``initial`` and ``goal`` or ``goal_pose`` among them)."""
    packages = urdf.parent.parent.parent
    tree = {
        "kind": "spatial",
        "name": "own_arm",
        "robot": {
            "urdf": f"package://{PACKAGE}/urdf/arm.urdf",
            "srdf": f"package://{MOVEIT_PACKAGE}/config/my_arm.srdf",
            "package_paths": [str(packages.relative_to(folder))],
            "base_link": BASE_LINK,
            "tip_link": TIP_LINK,
            **robot,
        },
        "obstacle_names": ["floor"],
        "obstacles": {"floor": {"shape": "box", "size": [3.0, 3.0, 0.02], "pose": [0.0, 0.0, -0.05, 0.0, 0.0, 0.0]}},
    }
    return {"/**": {"ros__parameters": {"world": tree, "planner": {"seed": 0, "time_limit": 30.0}}}}


def write_world(path: Path, document: dict[str, Any]) -> Path:
    path.write_text(yaml.safe_dump(document, sort_keys=False))
    return path


def angle_gap(a: float, b: float) -> float:
    """|a - b| modulo 2 pi, in [0, pi]."""
    return abs(math.remainder(a - b, 2.0 * math.pi))


def roomy(world: Any, qs: np.ndarray) -> np.ndarray:
    """Which of ``qs`` are free with room to spare (the sphere model alone calls them free, centimetres from
    any contact), as a user's start and goal usually are: the search's ends, not its tight spots, are tested
    here (test/spatial/test_tier.py tests the tight ones)."""
    from clew_ros.spatial.checker import SpatialChecker

    alone = SpatialChecker(world.robot, world.spheres, world.obstacles, world.bounds, exact=False)
    return alone.valid(qs)


def pose_goal_world(root: Path, seed: int) -> Path:
    """``root/world.yaml``: a motion-only world for the arm of ``seed`` (written under ``root/src``) from a
    valid configuration to ``world.robot.goal_pose``, the tcp's pose at another valid one (reachable by
    construction); its path."""
    from clew_ros.spatial.transforms import matrix_pose
    from clew_ros.spatial.world import spatial_world_from_parameters

    urdf = write_description_package(root / "src", seed)
    document = motion_world(root, urdf, initial=[0.0] * 6, goal=[0.0] * 6)
    parameters = document["/**"]["ros__parameters"]
    world = spatial_world_from_parameters(parameters, root)
    robot = world.robot
    qs = np.random.default_rng(seed).uniform(robot.lower, robot.upper, (400, robot.dof))
    start, goal = qs[roomy(world, qs)][:2]
    tree = parameters["world"]["robot"]
    del tree["goal"]
    tree["initial"] = [round(float(v), 6) for v in start]
    tree["goal_pose"] = [round(float(v), 6) for v in matrix_pose(robot.tcp_pose(goal))]
    return write_world(root / "world.yaml", document)
