"""``NAMESPACE:=WORLD.yaml`` pairs, each planner's world file and recording directory (no ROS graph)."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from clew_ros.node.namespaces import (
    DEMO_WORLDS,
    PlannerArgumentError,
    PlannerSpec,
    demo_pairs,
    launch_parameters,
    namespaced_directory,
    parse_planner_pairs,
    world_parameters,
)
from clew_ros.planar.world import read_parameter_file
from clew_ros.ros.node_parameters import NODE_PARAMETERS

CONFIG = Path(__file__).resolve().parents[2] / "config"


def test_pairs_become_specs_in_order() -> None:
    specs = parse_planner_pairs(["arm_a:=a.yaml", "/robots/arm_b/:=dir/b.yaml", "_c:=c:=odd.yaml"])
    assert specs == [
        PlannerSpec("/arm_a", Path("a.yaml")),
        PlannerSpec("/robots/arm_b", Path("dir/b.yaml")),
        PlannerSpec("/_c", Path("c:=odd.yaml")),  # the first := separates
    ]
    assert specs[1].node_name == "/robots/arm_b/clew_planner"


@pytest.mark.parametrize(
    ("argument", "expected"),
    [
        ("arm_a", "expected NAMESPACE:=WORLD.yaml"),
        ("arm_a:=", "expected NAMESPACE:=WORLD.yaml"),
        (":=a.yaml", "expected a namespace"),
        ("/:=a.yaml", "expected a namespace"),
        ("1arm:=a.yaml", "not starting with a digit"),
        ("arm-a:=a.yaml", "letters, digits and single underscores"),
        ("arm__a:=a.yaml", "single underscores"),
        ("robots//a:=a.yaml", "expected a namespace"),
        ("~/arm:=a.yaml", "expected a namespace"),
    ],
)
def test_a_bad_pair_is_refused_naming_it(argument: str, expected: str) -> None:
    with pytest.raises(PlannerArgumentError) as error:
        parse_planner_pairs(["ok:=a.yaml", argument])
    assert repr(argument) in str(error.value)
    assert expected in str(error.value)


def test_a_namespace_given_twice_is_refused() -> None:
    with pytest.raises(PlannerArgumentError, match=r"namespace /arm_a is given twice.*one planner per namespace"):
        parse_planner_pairs(["arm_a:=a.yaml", "/arm_a:=b.yaml"])


def test_recording_directories_differ_per_namespace() -> None:
    assert namespaced_directory("~/runs", "/arm_a") == "~/runs/arm_a"
    assert namespaced_directory("/data/runs/", "/robots/arm_a") == "/data/runs/robots/arm_a"
    assert namespaced_directory("/", "/arm_a") == "/arm_a"
    directories = {namespaced_directory("runs", spec.namespace) for spec in parse_planner_pairs(["a:=x", "b:=x"])}
    assert len(directories) == 2


def test_the_demo_pairs_name_the_config_worlds() -> None:
    specs = parse_planner_pairs(demo_pairs(CONFIG))
    assert [spec.namespace for spec in specs] == [f"/{name}" for name in DEMO_WORLDS]
    for spec in specs:
        assert spec.world_file.is_file()
        assert world_parameters(spec)["world"]["name"] == spec.namespace.strip("/")


def test_world_parameters_read_any_node_key(tmp_path: Path) -> None:
    tree = read_parameter_file(CONFIG / "figure1.yaml")
    for key in ("clew_planner", "/**", "/robots/arm_a/clew_planner"):
        path = tmp_path / "world.yaml"
        path.write_text(yaml.safe_dump({key: {"ros__parameters": tree}}))
        assert world_parameters(PlannerSpec("/arm_a", path)) == tree


def test_an_unreadable_world_file_names_its_pair(tmp_path: Path) -> None:
    with pytest.raises(PlannerArgumentError, match=r"^arm_a:=.*missing\.yaml: .*cannot read the parameter file"):
        world_parameters(PlannerSpec("/arm_a", tmp_path / "missing.yaml"))
    wrong = tmp_path / "wrong.yaml"
    wrong.write_text(yaml.safe_dump({"other_node": {"ros__parameters": {}}}))
    with pytest.raises(PlannerArgumentError, match=r"^robots/b:=.*wrong\.yaml: .*'clew_planner' or '/\*\*' key"):
        world_parameters(PlannerSpec("/robots/b", wrong))


def test_launch_parameters_put_the_recordings_in_the_namespace(tmp_path: Path) -> None:
    spec = PlannerSpec("/robots/arm_a", CONFIG / "figure1.yaml")
    default = NODE_PARAMETERS.default("record.directory")
    parameters = launch_parameters(spec)
    assert parameters["record"] == {"directory": f"{default}/robots/arm_a"}
    assert parameters["world"] == read_parameter_file(spec.world_file)["world"]
    assert launch_parameters(spec, "/data/runs")["record"]["directory"] == "/data/runs/robots/arm_a"
    # the world file's own record.* stay, its directory gets the namespace (unless the argument gives one)
    tree = {**read_parameter_file(spec.world_file), "record": {"directory": "/own", "enabled": False}}
    own = tmp_path / "own.yaml"
    own.write_text(yaml.safe_dump({"clew_planner": {"ros__parameters": tree}}))
    spec = PlannerSpec("/arm_a", own)
    assert launch_parameters(spec)["record"] == {"directory": "/own/arm_a", "enabled": False}
    assert launch_parameters(spec, "runs")["record"] == {"directory": "runs/arm_a", "enabled": False}


def test_a_spatial_world_names_its_files_relative_to_the_world_file() -> None:
    """The URDF, SRDF and scene file a spatial world names are read relative to its file, wherever the planners
    start (the node reads the parameters it is given from its working directory)."""
    spec = PlannerSpec("/arm", CONFIG / "spatial" / "panda_table_to_table.yaml")
    robot = world_parameters(spec)["world"]["robot"]
    assert read_parameter_file(spec.world_file)["world"]["robot"]["urdf"] == "../robots/panda/panda.urdf"
    assert Path(robot["urdf"]) == (CONFIG / "robots" / "panda" / "panda.urdf").resolve()
    assert Path(robot["urdf"]).is_file()
