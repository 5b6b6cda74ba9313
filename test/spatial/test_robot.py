"""clew_ros.spatial.robot: the URDF chain folded into frames, collision geometry, exemptions, refusals."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from helpers.urdf_fk import urdf_fk
from urdf_parser_py.urdf import URDF

from clew_ros.core.errors import WorldError
from clew_ros.spatial.robot import RobotModel, load_robot, robot_from_parameters
from clew_ros.spatial.transforms import pose_matrix

from .conftest import CONFIG, PANDA, UR5

TWO_LINKS = """<robot name="two">
  <link name="base"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="arm"><collision><origin xyz="0 0 0.2"/><geometry><cylinder length="0.4" radius="0.02"/></geometry>
  </collision></link>
  <link name="tool"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/><origin xyz="0 0 0.05"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="fix" type="fixed"><parent link="arm"/><child link="tool"/>
    <origin xyz="0 0 0.4" rpy="0 1.5707963 0"/></joint>
</robot>"""


def test_panda_chain_limits_and_links(panda: RobotModel) -> None:
    assert panda.joint_names == tuple(f"panda_joint{k}" for k in range(1, 8))
    assert (panda.lower[3], panda.upper[3]) == (-3.0718, -0.0698)
    names = [link.name for link in panda.links]
    assert names[:8] == [f"panda_link{k}" for k in range(8)]
    assert {"panda_hand", "panda_leftfinger", "panda_rightfinger"} <= set(names)
    assert [g.kind for g in panda.links[names.index("panda_leftfinger")].geometries] == ["box"] * 4
    assert all(g.kind == "mesh" and len(g.faces) > 0 for g in panda.links[0].geometries)
    # fingers ride on frame 7 (their prismatic joints are not planned: held at 0)
    assert panda.links[names.index("panda_leftfinger")].frame == 7
    assert panda.fixed_positions == {"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0}


def test_ur5_matches_a_forward_kinematics_written_from_the_urdf_spec(ur5: RobotModel) -> None:
    parsed = URDF.from_xml_file(str(CONFIG / "robots/ur5/ur5.urdf"))
    rng = np.random.default_rng(4)
    for _ in range(5):
        q = rng.uniform(ur5.lower, ur5.upper)
        reference = urdf_fk(parsed, dict(zip(ur5.joint_names, q, strict=True)))
        ours = ur5.link_poses(q)
        for name, pose in ours.items():
            np.testing.assert_allclose(pose, reference[name], atol=1e-9)
        np.testing.assert_allclose(ur5.tcp_pose(q), reference["tool0"], atol=1e-9)


def test_panda_matches_pinocchio(panda: RobotModel) -> None:
    pinocchio = pytest.importorskip("pinocchio")
    model = pinocchio.buildModelFromUrdf(str(CONFIG / "robots/panda/panda.urdf"))
    data = model.createData()
    rng = np.random.default_rng(5)
    for _ in range(5):
        q = rng.uniform(panda.lower, panda.upper)
        full = pinocchio.neutral(model)
        for name, value in zip(panda.joint_names, q, strict=True):
            full[model.joints[model.getJointId(name)].idx_q] = value
        pinocchio.framesForwardKinematics(model, data, full)
        for name, pose in panda.link_poses(q).items():
            np.testing.assert_allclose(pose, data.oMf[model.getFrameId(name)].homogeneous, atol=1e-9)


def test_base_pose_and_tcp_compose(tmp_path: Path) -> None:
    base_pose = [0.5, -0.2, 0.8, 0.0, 0.0, math.pi / 2]
    tcp = [0.0, 0.0, 0.1, 0.0, 0.0, 0.0]
    robot = load_robot(TWO_LINKS, folder=tmp_path, base_link="base", tip_link="tool", base_pose=base_pose, tcp=tcp)
    assert robot.joint_names == ("j1",)
    q = [0.3]
    expected = pose_matrix(base_pose) @ pose_matrix([0, 0, 0.05, 0, 0, 0.3]) @ pose_matrix([0, 0, 0.4, 0, 1.5707963, 0])
    np.testing.assert_allclose(robot.tcp_pose(q), expected @ pose_matrix(tcp), atol=1e-12)
    # the fixed joint folds into the tcp: tool has no geometry, so only base and arm are links
    assert [link.name for link in robot.links] == ["base", "arm"]
    assert robot.exempt == {(0, 1)}  # a link and its parent


def test_srdf_pairs_and_adjacent_links_are_exempt(panda: RobotModel, ur5: RobotModel) -> None:
    index = {link.name: i for i, link in enumerate(panda.links)}

    def exempt(a: str, b: str) -> bool:
        return (min(index[a], index[b]), max(index[a], index[b])) in panda.exempt

    assert exempt("panda_link0", "panda_link1")  # parent
    assert exempt("panda_link3", "panda_link7")  # SRDF "Never"
    assert exempt("panda_hand", "panda_link7")  # parent over the geometry-less panda_link8
    assert not exempt("panda_link0", "panda_link5")
    assert not exempt("panda_leftfinger", "panda_link5")  # the SRDF keeps it
    ur5_index = {link.name: i for i, link in enumerate(ur5.links)}
    assert (ur5_index["base_link"], ur5_index["forearm_link"]) not in ur5.exempt


def test_joint_limits_may_only_be_narrowed() -> None:
    narrowed = robot_from_parameters({**UR5, "joint_lower": [-1.0] * 6, "joint_upper": [1.0] * 6}, CONFIG)
    assert list(narrowed.lower) == [-1.0] * 6
    with pytest.raises(WorldError, match=r"world\.robot\.joint_upper: may only narrow") as error:
        robot_from_parameters({**UR5, "joint_upper": [7.0] * 6}, CONFIG)
    assert error.value.parameter == "world.robot.joint_upper"


def write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("change", "parameter", "message"),
    [
        ({"tip_link": "nowhere"}, "world.robot.tip_link", "link 'nowhere' is not in the URDF"),
        ({"base_link": "panda_link5", "tip_link": "panda_link2"}, "world.robot.tip_link", "is not below base_link"),
        ({"tip_link": "panda_link0"}, "world.robot.tip_link", "no movable joint"),
        ({"urdf": "robots/panda/missing.urdf"}, "world.robot.urdf", "cannot read"),
        ({"description": "<robot/>"}, "world.robot.urdf", "exactly one of"),
        ({"tcp": [0.0, 0.0]}, "world.robot.tcp", "6 finite numbers"),
        ({"base_pose": "up"}, "world.robot.base_pose", "expected a pose"),
        (
            {"fixed_joint_names": ["panda_joint1"], "fixed_joint_positions": [0.0]},
            "world.robot.fixed_joint_names",
            "not a movable joint outside",
        ),
        ({"fixed_joint_names": ["panda_finger_joint1"], "fixed_joint_positions": [0.5]}, "", "outside its limits"),
        ({"gripper_links": ["claw"]}, "world.robot.gripper_links", "'claw' is not in the URDF"),
        ({"fixed_joint_positions": ["open"]}, "world.robot.fixed_joint_positions", "a list of numbers"),
        ({"joint_lower": "low"}, "world.robot.joint_lower", "expected 7 finite numbers"),
        ({"srdf": "robots/panda/none.srdf"}, "world.robot.srdf", "cannot read"),
    ],
)
def test_bad_robot_parameters_are_refused_by_name(change: dict[str, object], parameter: str, message: str) -> None:
    with pytest.raises(WorldError, match=re.escape(message)) as error:
        robot_from_parameters({**PANDA, **change}, CONFIG)
    assert error.value.parameter.startswith(parameter or "world.robot.")


@pytest.mark.parametrize(
    ("urdf", "message"),
    [
        ("<robot name='x'><link name='a'>", "does not parse"),
        (
            TWO_LINKS.replace('<limit lower="-1" upper="1" effort="1" velocity="1"/>', ""),
            "expected <limit lower upper>",
        ),
        (TWO_LINKS.replace('<child link="arm"/>', '<child link="elbow"/>'), "names link 'elbow', which the URDF lacks"),
        (TWO_LINKS.replace('type="revolute"', 'type="planar"'), "type 'planar' is not supported"),
        (TWO_LINKS.replace('<axis xyz="0 0 1"/>', '<axis xyz="0 0 0"/>'), "<axis xyz>: expected a non-zero 3-vector"),
        (TWO_LINKS.replace('radius="0.02"', 'radius="-0.02"'), "expected positive finite sizes"),
        (TWO_LINKS.replace('<box size="0.1 0.1 0.1"/>', '<mesh filename="gone.stl"/>'), "mesh file"),
        (TWO_LINKS.replace('<box size="0.1 0.1 0.1"/>', '<mesh filename="bad.stl"/>'), "bad.stl' holds no triangles"),
        (TWO_LINKS.replace('<box size="0.1 0.1 0.1"/>', '<mesh filename="bad.dae"/>'), "cannot read mesh"),
    ],
)
def test_malformed_urdf_is_refused_naming_the_element(tmp_path: Path, urdf: str, message: str) -> None:
    write(tmp_path, "bad.stl", "solid nothing\nthis is not an STL file at all\n")
    write(tmp_path, "bad.dae", "<COLLADA><library_geometries><geometry>")
    write(tmp_path, "robot.urdf", urdf)
    with pytest.raises(WorldError, match=re.escape(message)) as error:
        robot_from_parameters({"urdf": "robot.urdf", "base_link": "base", "tip_link": "tool"}, tmp_path)
    assert error.value.parameter == "world.robot.urdf"


def test_srdf_naming_an_unknown_link_is_refused(tmp_path: Path) -> None:
    write(tmp_path, "r.srdf", '<robot name="r"><disable_collisions link1="base" link2="ghost"/></robot>')
    write(tmp_path, "robot.urdf", TWO_LINKS)
    tree = {"urdf": "robot.urdf", "srdf": "r.srdf", "base_link": "base", "tip_link": "tool"}
    with pytest.raises(WorldError, match="link 'ghost', which the URDF lacks") as error:
        robot_from_parameters(tree, tmp_path)
    assert error.value.parameter == "world.robot.srdf"


def test_meshes_of_every_format_load(tmp_path: Path) -> None:
    trimesh = pytest.importorskip("trimesh")
    box = trimesh.creation.box(extents=[0.1, 0.2, 0.3])
    for suffix in ("stl", "obj", "dae"):
        box.export(str(tmp_path / f"part.{suffix}"))
        urdf = TWO_LINKS.replace('<box size="0.1 0.1 0.1"/>', f'<mesh filename="part.{suffix}" scale="2 2 2"/>')
        robot = load_robot(urdf, folder=tmp_path, base_link="base", tip_link="tool")
        mesh = robot.links[0].geometries[0]
        assert mesh.kind == "mesh"
        np.testing.assert_allclose(mesh.vertices.max(axis=0) - mesh.vertices.min(axis=0), [0.2, 0.4, 0.6], atol=1e-9)
