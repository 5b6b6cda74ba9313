"""The launch files describe the nodes they mean to start.

ROS 2 launch cannot be installed here (pip has no ``launch`` / ``launch_ros``),
so each file is run against stand-ins of the few launch classes it uses
(``helpers.launch_api``), which keep their arguments: what the test reads is
exactly what the file hands to launch (package, executable, name, namespace,
parameters, remappings, launch arguments), and the conditions evaluate as
launch's do. The launch API itself was checked against its source, not here.
"""

from __future__ import annotations

import py_compile
from pathlib import Path

import pytest
import yaml
from helpers.launch_api import Recorded, describe, install, of_type, started_nodes

from clew_ros.node.namespaces import DEMO_WORLDS
from clew_ros.planar.world import read_parameter_file
from clew_ros.ros.node_parameters import NODE_PARAMETERS

ROOT = Path(__file__).resolve().parents[1]
LAUNCH = ROOT / "launch"
CONFIG = ROOT / "config"


@pytest.fixture
def launch_api(monkeypatch: pytest.MonkeyPatch) -> None:
    """Stand-ins for launch and launch_ros; the package's share directory is the source tree."""
    install(monkeypatch, ROOT)


@pytest.mark.parametrize("path", sorted(LAUNCH.glob("*.launch.py")), ids=lambda p: p.name)
def test_launch_files_compile(path: Path, tmp_path: Path) -> None:
    py_compile.compile(str(path), cfile=str(tmp_path / "compiled.pyc"), doraise=True)


@pytest.mark.usefixtures("launch_api")
def test_clew_planner_launch_starts_one_node_with_or_without_a_parameter_file() -> None:
    path = LAUNCH / "clew_planner.launch.py"
    (argument,) = of_type(describe(path), "DeclareLaunchArgument")
    assert argument.args == ("params_file",)
    for params_file, parameters in [("", []), ("/worlds/figure1.yaml", ["/worlds/figure1.yaml"])]:
        ((node, performed),) = started_nodes(path, {"params_file": params_file})
        assert (node.kwargs["package"], node.kwargs["executable"], node.kwargs["name"]) == (
            "clew_ros",
            "clew_planner",
            "clew_planner",
        )
        assert performed == parameters


def planners_nodes(context: dict[str, str]) -> list[Recorded]:
    entities = describe(LAUNCH / "clew_planners.launch.py")
    assert [a.args[0] for a in of_type(entities, "DeclareLaunchArgument")] == ["planners", "record_directory"]
    (function,) = of_type(entities, "OpaqueFunction")
    return list(function.kwargs["function"](context))


@pytest.mark.usefixtures("launch_api")
def test_clew_planners_launch_starts_one_node_per_namespace(tmp_path: Path) -> None:
    own = tmp_path / "own.yaml"
    tree = {**read_parameter_file(CONFIG / "single_transfer.yaml"), "record": {"directory": "/own"}}
    own.write_text(yaml.safe_dump({"/**": {"ros__parameters": tree}}))
    planners = f"arm_a:={CONFIG / 'figure1.yaml'}  robots/arm_b:={own}"
    nodes = planners_nodes({"planners": planners, "record_directory": ""})
    assert [node.kwargs["namespace"] for node in nodes] == ["/arm_a", "/robots/arm_b"]
    for node in nodes:
        assert (node.kwargs["package"], node.kwargs["executable"], node.kwargs["name"]) == (
            "clew_ros",
            "clew_planner",
            "clew_planner",
        )
        assert node.kwargs["remappings"] == [("/tf", "tf"), ("/tf_static", "tf_static")]
    (first,) = nodes[0].kwargs["parameters"]
    assert first["world"] == read_parameter_file(CONFIG / "figure1.yaml")["world"]
    assert first["planner"] == read_parameter_file(CONFIG / "figure1.yaml")["planner"]
    assert first["record"] == {"directory": NODE_PARAMETERS.default("record.directory") + "/arm_a"}
    (second,) = nodes[1].kwargs["parameters"]
    assert second["world"]["name"] == "single_transfer"
    assert second["record"] == {"directory": "/own/robots/arm_b"}
    # the record_directory argument wins over the world files
    nodes = planners_nodes({"planners": planners, "record_directory": "/data/runs"})
    assert [node.kwargs["parameters"][0]["record"]["directory"] for node in nodes] == [
        "/data/runs/arm_a",
        "/data/runs/robots/arm_b",
    ]


@pytest.mark.usefixtures("launch_api")
def test_clew_planners_launch_defaults_to_the_demo_worlds() -> None:
    nodes = planners_nodes({"planners": "", "record_directory": "runs"})
    assert [node.kwargs["namespace"] for node in nodes] == [f"/{name}" for name in DEMO_WORLDS]
    assert [node.kwargs["parameters"][0]["world"]["name"] for node in nodes] == list(DEMO_WORLDS)


@pytest.mark.usefixtures("launch_api")
def test_clew_planners_launch_refuses_a_bad_pair() -> None:
    with pytest.raises(ValueError, match=r"'arm_a': expected NAMESPACE:=WORLD.yaml"):
        planners_nodes({"planners": "arm_a", "record_directory": ""})
