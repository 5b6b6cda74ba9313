"""``package://`` URIs (interface.md section 1b): world.robot.package_paths, then the ament index, then
ROS_PACKAGE_PATH; a package found nowhere is one line naming it and the three ways, exit 2."""

from __future__ import annotations

import errno
import os
import subprocess
import sys
from pathlib import Path

import pytest
from helpers.own_arm import PACKAGE, motion_world, write_description_package, write_world

from clew_ros.cli.render import _os_reason
from clew_ros.core.errors import WorldError
from clew_ros.ros.spatial import absolute_paths
from clew_ros.spatial.packages import package_paths_from_parameters, resolve_package_uri
from clew_ros.spatial.robot import robot_from_parameters

URI = f"package://{PACKAGE}/urdf/arm.urdf"


@pytest.fixture
def clean_env(monkeypatch: pytest.MonkeyPatch) -> pytest.MonkeyPatch:
    monkeypatch.delenv("AMENT_PREFIX_PATH", raising=False)
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    return monkeypatch


def _ament_prefix(root: Path, package: str) -> Path:
    """An install prefix whose ament index lists ``package`` (its share folder ``share/<package>``)."""
    (root / "share" / "ament_index" / "resource_index" / "packages").mkdir(parents=True)
    (root / "share" / "ament_index" / "resource_index" / "packages" / package).write_text("")
    (root / "share" / package / "urdf").mkdir(parents=True)
    return root


def test_package_paths_come_first_then_the_ament_index_then_ros_package_path(
    tmp_path: Path, clean_env: pytest.MonkeyPatch
) -> None:
    listed = tmp_path / "listed"
    (listed / PACKAGE).mkdir(parents=True)
    prefix = _ament_prefix(tmp_path / "install", PACKAGE)
    ros = tmp_path / "ros"
    (ros / PACKAGE).mkdir(parents=True)
    clean_env.setenv("AMENT_PREFIX_PATH", str(prefix))
    clean_env.setenv("ROS_PACKAGE_PATH", str(ros))
    assert resolve_package_uri(URI, [tmp_path / "other", listed]) == listed / PACKAGE / "urdf/arm.urdf"
    assert resolve_package_uri(URI, [tmp_path / "other"]) == prefix / "share" / PACKAGE / "urdf/arm.urdf"
    clean_env.delenv("AMENT_PREFIX_PATH")
    assert resolve_package_uri(URI) == ros / PACKAGE / "urdf/arm.urdf"
    clean_env.setenv("ROS_PACKAGE_PATH", f"{tmp_path / 'nothing'}{os.pathsep}{ros / PACKAGE}")  # the package itself
    assert resolve_package_uri(URI) == ros / PACKAGE / "urdf/arm.urdf"


def test_a_package_found_nowhere_names_it_and_the_three_ways(tmp_path: Path, clean_env: pytest.MonkeyPatch) -> None:
    clean_env.setenv("AMENT_PREFIX_PATH", str(_ament_prefix(tmp_path / "install", "another_package")))
    with pytest.raises(WorldError) as caught:
        resolve_package_uri(URI, [tmp_path])
    message = str(caught.value)
    assert message.startswith("world.robot.package_paths: package 'my_arm_description'")
    for way in ("world.robot.package_paths", "ament index", "ROS_PACKAGE_PATH"):
        assert way in message
    assert "\n" not in message
    with pytest.raises(WorldError, match="expected a list of folders"):
        package_paths_from_parameters({"package_paths": "src"}, tmp_path)


def test_meshes_and_the_urdf_load_through_package_paths_relative_to_the_parameter_file(
    tmp_path: Path, clean_env: pytest.MonkeyPatch
) -> None:
    urdf = write_description_package(tmp_path / "src", seed=1)
    tree = motion_world(tmp_path, urdf)["/**"]["ros__parameters"]["world"]["robot"]
    assert tree["package_paths"] == ["src"]
    robot = robot_from_parameters(tree, tmp_path)
    meshes = [g for link in robot.links for g in link.geometries]
    assert meshes
    assert all(g.kind == "mesh" and g.source.startswith(str(tmp_path / "src" / PACKAGE)) for g in meshes)
    # the node reads from its working directory: launch files make the folders absolute first
    world = {"robot": dict(tree)}
    absolute_paths(world, tmp_path)
    assert world["robot"]["package_paths"] == [str((tmp_path / "src").resolve())]


def _cli(module: str, *args: object, cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k not in ("AMENT_PREFIX_PATH", "ROS_PACKAGE_PATH")}
    return subprocess.run(
        [sys.executable, "-m", module, *map(str, args)], capture_output=True, text=True, timeout=300, cwd=cwd, env=env
    )


def test_clew_plan_and_clew_render_refuse_an_unknown_package_in_one_line_exit_2(tmp_path: Path) -> None:
    urdf = write_description_package(tmp_path / "src", seed=1)
    document = motion_world(tmp_path, urdf, initial=[0.0] * 6, goal=[0.1] * 6)
    del document["/**"]["ros__parameters"]["world"]["robot"]["package_paths"]
    world = write_world(tmp_path / "world.yaml", document)
    for module, args in (("clew_ros.cli.plan", ("-o", "plan.json")), ("clew_ros.cli.render", ("-o", "world.png"))):
        done = _cli(module, world, *args, cwd=tmp_path)
        assert done.returncode == 2, done.stderr
        lines = done.stderr.strip().splitlines()
        assert len(lines) == 1
        assert "package 'my_arm_description'" in lines[0]


def test_clew_render_says_why_it_cannot_write() -> None:
    assert "None" not in _os_reason(OSError("Environment variable 'X' is not set"), Path("a.png"))
    full = OSError(errno.ENOSPC, "No space left on device", "a.png")
    assert _os_reason(full, Path("a.png")) == "cannot write a.png: No space left on device"
    missing = OSError(errno.ENOENT, "No such file or directory", "mesh.stl")
    assert _os_reason(missing, Path("a.png")) == "cannot read mesh.stl: No such file or directory"
