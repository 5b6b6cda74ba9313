"""The launch files describe the nodes they mean to start.

ROS 2 launch cannot be installed here (pip has no ``launch`` / ``launch_ros``),
so each file is run against stand-ins of the few launch classes it uses,
which keep their arguments: what the test reads is exactly what the file
hands to launch (package, executable, name, namespace, parameters,
remappings, launch arguments). The launch API itself was checked against
its documentation, not here.
"""

from __future__ import annotations

import py_compile
import runpy
import sys
import types
from pathlib import Path
from typing import Any

import pytest
import yaml

from clew_ros.core.parameters import NODE_PARAMETERS
from clew_ros.core.world import read_parameter_file
from clew_ros.node.namespaces import DEMO_WORLDS

ROOT = Path(__file__).resolve().parents[1]
LAUNCH = ROOT / "launch"
CONFIG = ROOT / "config"


class Recorded:
    """A launch class stand-in: keeps its arguments."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self.args = args
        self.kwargs = kwargs


class LaunchConfiguration(Recorded):
    def perform(self, context: dict[str, str]) -> str:
        return context[self.args[0]]


@pytest.fixture
def launch_api(monkeypatch: pytest.MonkeyPatch) -> None:
    """Stand-ins for launch and launch_ros; the package's share directory is the source tree."""
    modules = {
        "launch": {"LaunchDescription": type("LaunchDescription", (Recorded,), {})},
        "launch.actions": {
            "DeclareLaunchArgument": type("DeclareLaunchArgument", (Recorded,), {}),
            "OpaqueFunction": type("OpaqueFunction", (Recorded,), {}),
        },
        "launch.conditions": {
            "IfCondition": type("IfCondition", (Recorded,), {}),
            "UnlessCondition": type("UnlessCondition", (Recorded,), {}),
        },
        "launch.substitutions": {
            "LaunchConfiguration": LaunchConfiguration,
            "PythonExpression": type("PythonExpression", (Recorded,), {}),
        },
        "launch_ros": {},
        "launch_ros.actions": {"Node": type("Node", (Recorded,), {})},
    }
    for name, members in modules.items():
        module = types.ModuleType(name)
        module.__dict__.update(members)
        monkeypatch.setitem(sys.modules, name, module)
    import ament_index_python.packages

    monkeypatch.setattr(ament_index_python.packages, "get_package_share_directory", lambda _package: str(ROOT))


def describe(path: Path) -> list[Recorded]:
    """The entities of the launch file's description."""
    description = runpy.run_path(str(path))["generate_launch_description"]()
    return list(description.args[0])


def of_type(entities: list[Recorded], name: str) -> list[Recorded]:
    return [e for e in entities if type(e).__name__ == name]


@pytest.mark.parametrize("path", sorted(LAUNCH.glob("*.launch.py")), ids=lambda p: p.name)
def test_launch_files_compile(path: Path, tmp_path: Path) -> None:
    py_compile.compile(str(path), cfile=str(tmp_path / "compiled.pyc"), doraise=True)


@pytest.mark.usefixtures("launch_api")
def test_clew_planner_launch_starts_one_node_with_or_without_a_parameter_file() -> None:
    entities = describe(LAUNCH / "clew_planner.launch.py")
    (argument,) = of_type(entities, "DeclareLaunchArgument")
    assert argument.args == ("params_file",)
    nodes = of_type(entities, "Node")
    assert len(nodes) == 2  # one of them, by condition
    for node in nodes:
        assert (node.kwargs["package"], node.kwargs["executable"], node.kwargs["name"]) == (
            "clew_ros",
            "clew_planner",
            "clew_planner",
        )
    assert {type(node.kwargs["condition"]).__name__ for node in nodes} == {"IfCondition", "UnlessCondition"}


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
