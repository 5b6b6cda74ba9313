"""The package metadata that colcon, rosdep and pip read."""

import ast
import importlib
import importlib.util
import runpy
import sys
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest
import setuptools

import clew_ros

ROOT = Path(__file__).resolve().parents[1]

REQUIRED_EXEC_DEPENDS = {
    "rclpy",
    "std_msgs",
    "std_srvs",
    "sensor_msgs",
    "geometry_msgs",
    "trajectory_msgs",
    "visualization_msgs",
    "diagnostic_msgs",
    "action_msgs",
    "python3-numpy",
    "python3-numba",
    "python3-shapely",
    "python3-yaml",
}

#: Python modules clew_ros imports -> their rosdep key (ROS packages are their own key).
ROSDEP_KEYS = {
    "numpy": "python3-numpy",
    "numba": "python3-numba",
    "shapely": "python3-shapely",
    "yaml": "python3-yaml",
    "PIL": "python3-pil",
    "urdf_parser_py": "urdfdom_py",  # a ROS package (clew_ros.spatial)
    "trimesh": "python3-trimesh",
}
#: Imported, but with no rosdep key (setup.py's install_requires), or optional (imported under try).
# foxglove: the live extra (clew_ros.live); ray: the batch extra (clew_batch --ray); zstandard, lz4: mcap's own
NO_ROSDEP_KEY = {"mcap", "mcap_ros2", "zstandard", "lz4", "rosbags", "foxglove", "ray"}

CONSOLE_SCRIPTS = {
    "clew_planner": "clew_ros.node.main:main",
    "clew_planners": "clew_ros.node.multi:main",
    "clew_plan": "clew_ros.cli.plan:main",
    "clew_replay": "clew_ros.cli.replay:main",
    "clew_render": "clew_ros.cli.render:main",
    "clew_batch": "clew_ros.cli.batch:main",
    "clew_world": "clew_ros.cli.world:main",
}


@pytest.fixture(scope="module")
def package_xml() -> ET.Element:
    return ET.parse(ROOT / "package.xml").getroot()


def run_setup_py(cwd: Path) -> dict[str, Any]:
    """Run setup.py in ``cwd`` with setup() replaced; return what it was given."""
    captured: dict[str, Any] = {}
    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(cwd)  # setup.py globs relative to where it runs, as under colcon
        mp.setattr(setuptools, "setup", lambda **kwargs: captured.update(kwargs))
        runpy.run_path(str(ROOT / "setup.py"), run_name="__main__")
    return captured


@pytest.fixture(scope="module")
def setup_kwargs() -> dict[str, Any]:
    """The arguments setup.py passes to setup() in this repository."""
    return run_setup_py(ROOT)


def test_package_xml_is_format_3_clew_ros(package_xml: ET.Element) -> None:
    assert package_xml.tag == "package"
    assert package_xml.get("format") == "3"
    assert package_xml.findtext("name") == "clew_ros"
    assert package_xml.findtext("version") == clew_ros.__version__
    assert package_xml.findtext("license") == "Apache-2.0"
    assert package_xml.find("maintainer").get("email")
    assert package_xml.findtext("export/build_type") == "ament_python"


def test_package_xml_depends(package_xml: ET.Element) -> None:
    exec_depends = {e.text for e in package_xml.findall("exec_depend")}
    assert exec_depends >= REQUIRED_EXEC_DEPENDS
    assert "python3-pytest" in {e.text for e in package_xml.findall("test_depend")}


def imported_top_level_modules(*folders: Path) -> set[str]:
    """The top-level modules the Python files below ``folders`` import (at any depth in the file)."""
    modules = set()
    for folder in folders:
        for path in folder.rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text(), str(path))):
                if isinstance(node, ast.Import):
                    modules.update(alias.name.split(".")[0] for alias in node.names)
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    modules.add(node.module.split(".")[0])
    return modules


def test_every_run_time_import_has_an_exec_depend(package_xml: ET.Element) -> None:
    exec_depends = {e.text for e in package_xml.findall("exec_depend")}
    imported = imported_top_level_modules(ROOT / "clew_ros", ROOT / "launch")
    third_party = imported - set(sys.stdlib_module_names) - {"clew_ros", "__future__"} - NO_ROSDEP_KEY
    assert "unique_identifier_msgs" in third_party  # the scan sees the node's imports
    missing = {ROSDEP_KEYS.get(module, module) for module in third_party} - exec_depends
    assert not missing, f"package.xml lacks <exec_depend> for {sorted(missing)}"


def test_package_xml_element_order(package_xml: ET.Element) -> None:
    # REP 149 (format 3) fixes the order of the leading elements and puts
    # export last.
    tags = [child.tag for child in package_xml if isinstance(child.tag, str)]
    assert tags[:5] == ["name", "version", "description", "maintainer", "license"]
    assert tags[-1] == "export"


def test_setup_py_matches_package_xml(setup_kwargs: dict[str, Any], package_xml: ET.Element) -> None:
    assert setup_kwargs["name"] == package_xml.findtext("name")
    assert setup_kwargs["version"] == package_xml.findtext("version")
    assert setup_kwargs["license"] == package_xml.findtext("license")


def test_setup_py_installs_ament_files(setup_kwargs: dict[str, Any]) -> None:
    data_files = dict(setup_kwargs["data_files"])
    assert data_files["share/ament_index/resource_index/packages"] == ["resource/clew_ros"]
    assert (ROOT / "resource" / "clew_ros").is_file()
    assert data_files["share/clew_ros"] == ["package.xml"]
    assert data_files["share/clew_ros/launch"] == [
        "launch/clew_planner.launch.py",
        "launch/clew_planners.launch.py",
        "launch/clew_spatial_planner.launch.py",
    ]


def test_setup_py_installs_config_worlds(tmp_path: Path) -> None:
    # In a scratch tree, so that the check does not depend on which worlds
    # config/ holds today.
    for name in ["config/a.yaml", "config/b.json", "config/notes.txt", "launch/x.launch.py", "config/sros2/p.xml"]:
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).touch()
    data_files = dict(run_setup_py(tmp_path)["data_files"])
    assert data_files["share/clew_ros/config"] == ["config/a.yaml", "config/b.json"]
    assert data_files["share/clew_ros/config/sros2"] == ["config/sros2/p.xml"]
    assert data_files["share/clew_ros/launch"] == ["launch/x.launch.py"]


def test_setup_py_console_scripts(setup_kwargs: dict[str, Any]) -> None:
    scripts = {
        name.strip(): target.strip()
        for name, target in (s.split("=") for s in setup_kwargs["entry_points"]["console_scripts"])
    }
    assert scripts == CONSOLE_SCRIPTS


@pytest.mark.parametrize("script", sorted(CONSOLE_SCRIPTS))
def test_console_script_target_is_callable(script: str) -> None:
    module_name, func = CONSOLE_SCRIPTS[script].split(":")
    if importlib.util.find_spec(module_name) is None:
        pytest.skip(f"{module_name} is not written yet")
    assert callable(getattr(importlib.import_module(module_name), func))


def test_setup_cfg_installs_scripts_where_ros2_run_looks() -> None:
    text = (ROOT / "setup.cfg").read_text()
    assert "script_dir=$base/lib/clew_ros" in text
    assert "install_scripts=$base/lib/clew_ros" in text
