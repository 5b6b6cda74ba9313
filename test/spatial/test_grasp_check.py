"""Grasp sanity (``clew_world check WORLD``): each grasp named against the object, and warnings for fingers
that close on no pair of faces, on faces wider than they open, or on the face the object rests on."""

from __future__ import annotations

import copy
import math
import subprocess
import sys
from pathlib import Path

import yaml

from clew_ros.planar.world import read_parameter_file
from clew_ros.spatial.grasp_check import check_grasps
from clew_ros.spatial.world import spatial_world_from_parameters

ROOT = Path(__file__).resolve().parents[2]
TABLE = ROOT / "config" / "spatial" / "panda_table_to_table.yaml"


def _world(change: dict[str, object] | None = None, **robot: object):  # type: ignore[no-untyped-def]
    parameters = copy.deepcopy(read_parameter_file(TABLE))
    parameters["world"]["robot"].update(robot)
    parameters["world"]["object"].update(change or {})
    return spatial_world_from_parameters(parameters, TABLE.parent)


def test_the_shipped_grasps_are_named_and_raise_no_warning() -> None:
    reports = check_grasps(_world())
    assert [r.warnings for r in reports] == [[], []]
    assert "approaches face +z of the box" in reports[0].summary
    assert "on +-y, 0.040 m apart" in reports[0].summary
    assert "on +-x, 0.040 m apart" in reports[1].summary
    assert "finger joint panda_finger_joint1" in reports[0].summary


def test_fingers_on_no_pair_of_faces_are_warned() -> None:
    turned = [0.0, 0.0, 0.02, math.pi, 0.0, math.pi / 4]  # from above, turned 45 deg: the fingers on the edges
    (report,) = check_grasps(_world({"grasps": turned}))
    assert len(report.warnings) == 1
    assert "the fingers would close on no pair of faces" in report.warnings[0]
    assert "45 deg off" in report.warnings[0]


def test_a_tcp_whose_approach_is_not_z_closes_the_fingers_on_the_face_it_rests_on() -> None:
    # the tcp turned a quarter about the hand's x: its z is no longer the approach; a grasp "from above"
    # then closes the fingers up and down, on the top and on the face resting on the table
    world = _world({"grasps": [0.0, 0.0, 0.0, math.pi, 0.0, 0.0]}, tcp=[0.0, 0.0, 0.1034, math.pi / 2, 0.0, 0.0])
    (report,) = check_grasps(world)
    assert "on +-z" in report.summary
    assert any("close on face -z, which rests on its support" in w for w in report.warnings)


def test_faces_wider_than_the_fingers_open_are_warned() -> None:
    wide = {"size": [0.1, 0.1, 0.14], "initial": [0.5, 0.4, 0.19, 0.0, 0.0, 0.0], "goal": [0.5, -0.4, 0.19, 0, 0, 0]}
    reports = check_grasps(_world(wide))
    assert all(any("wider than the fingers open (0.080 m)" in w for w in r.warnings) for r in reports)


def test_clew_world_check_exits_0_clean_1_with_warnings_2_invalid(tmp_path: Path) -> None:
    def check(path: Path) -> subprocess.CompletedProcess[str]:
        command = [sys.executable, "-m", "clew_ros.cli.world", "check", str(path)]
        return subprocess.run(command, capture_output=True, text=True, timeout=300, check=False)

    clean = check(TABLE)
    assert clean.returncode == 0, clean.stderr
    assert clean.stdout.count("grasp ") == 2
    document = yaml.safe_load(TABLE.read_text())
    world = document["clew_planner"]["ros__parameters"]["world"]
    for key in ("urdf", "srdf"):
        world["robot"][key] = str((TABLE.parent / world["robot"][key]).resolve())
    world["object"]["grasps"] = [0.0, 0.0, 0.02, math.pi, 0.0, math.pi / 4]
    (tmp_path / "turned.yaml").write_text(yaml.safe_dump(document))
    warned = check(tmp_path / "turned.yaml")
    assert warned.returncode == 1, warned.stderr
    assert "clew_world: warning: grasp 0: the fingers would close on no pair of faces" in warned.stderr
    world["object"]["grasps"] = [0.0, 0.0, 0.5, 0.0, 0.0, 0.0]  # off the box
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(document))
    invalid = check(tmp_path / "bad.yaml")
    assert invalid.returncode == 2
    assert "world.object.grasps" in invalid.stderr
