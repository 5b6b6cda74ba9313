"""The specification of a spatial world's parameters (clew_ros.spatial.parameters), and the parser that follows it."""

from __future__ import annotations

import ast
import copy
import math
import re
from pathlib import Path
from typing import Any

import pytest
import yaml

from clew_ros.core.errors import ParameterError, WorldError
from clew_ros.core.parameters import ParameterType, check_value
from clew_ros.spatial.parameters import (
    SPATIAL_OBSTACLE_PARAMETERS,
    SPATIAL_WORLD_PARAMETERS,
    spatial_spec,
    unknown_keys,
)
from clew_ros.spatial.robot import RobotModel, robot_from_parameters
from clew_ros.spatial.spheres import SphereModel
from clew_ros.spatial.world import TOLERANCES, spatial_world_from_parameters

from .conftest import CONFIG, PANDA
from .test_world import PANDA_ON_A_TABLE

ROOT = Path(__file__).resolve().parents[2]
SPECS = [*SPATIAL_WORLD_PARAMETERS.values(), *SPATIAL_OBSTACLE_PARAMETERS.values()]
#: The modules that read a spatial world's parameters.
PARSERS = ("world.py", "robot.py", "scene.py", "placements.py", "packages.py")


def _flat(tree: dict[str, Any], prefix: str = "world.") -> list[str]:
    names = []
    for key, value in tree.items():
        if isinstance(value, dict) and key != "obstacles":
            names += _flat(value, f"{prefix}{key}.")
        elif key == "obstacles":
            names += [f"{prefix}obstacles.{name}.{leaf}" for name, entry in value.items() for leaf in entry]
        else:
            names.append(f"{prefix}{key}")
    return names


def test_every_key_of_the_contract_has_a_spec() -> None:
    """Each ``world.*`` name docs/interface.md section 1b writes is a key of the specification (or a group of
    them, ``world.object``), and each key's last name is written in the contract."""
    text = (ROOT / "docs" / "interface.md").read_text(encoding="utf-8")
    section = text[text.index("## 1b.") : text.index("## 2.")]
    names = set(re.findall(r"`(world\.[A-Za-z_.<>]+)`", section))
    assert {"world.robot.urdf", "world.obstacles.<name>.shape", "world.placement_tolerance"} <= names
    for name in names:
        assert spatial_spec(name) is not None or any(spec.name.startswith(name + ".") for spec in SPECS), name
    for spec in SPECS:
        assert spec.name.rpartition(".")[2] in text, spec.name


def test_every_key_the_parser_names_has_a_spec() -> None:
    """The parser's modules name no ``world.*`` parameter the specification lacks (read with ast)."""
    found = set()
    for module in PARSERS:
        tree = ast.parse((ROOT / "clew_ros" / "spatial" / module).read_text(encoding="utf-8"))
        found |= {
            node.value
            for node in ast.walk(tree)
            if isinstance(node, ast.Constant)
            and isinstance(node.value, str)
            and re.fullmatch(r"world(\.[a-z_]+)+", node.value)
        }
    assert {"world.robot.padding", "world.scene_file", "world.object.grasps"} <= found
    groups = {"world.robot", "world.object", "world.obstacles"}
    assert unknown_keys(found - groups) == []


@pytest.mark.parametrize("path", sorted((ROOT / "config" / "spatial").glob("*.yaml")), ids=lambda p: p.name)
def test_every_key_of_the_shipped_worlds_has_a_spec(path: Path) -> None:
    document = yaml.safe_load(path.read_text(encoding="utf-8"))
    parameters = [v["ros__parameters"] for v in document.values() if isinstance(v, dict) and "ros__parameters" in v]
    if not parameters:
        pytest.skip("not a parameter file (a planning scene)")
    world = parameters[0]["world"]
    assert unknown_keys(_flat(world)) == []


def test_a_spec_is_found_by_its_full_name() -> None:
    assert spatial_spec("world.obstacles.table.size") is SPATIAL_OBSTACLE_PARAMETERS["size"]
    assert spatial_spec("world.obstacles.a.b.pose") is SPATIAL_OBSTACLE_PARAMETERS["pose"]  # a name with a dot
    assert spatial_spec("world.robot.padding") is SPATIAL_WORLD_PARAMETERS["robot.padding"]
    assert spatial_spec("world.robot.tcpp") is None
    assert spatial_spec("world.obstacles.table") is None  # a planar obstacle's polygon, not a spatial key
    assert spatial_spec("planner.seed") is None
    assert unknown_keys(["world.robot.urdf", "world.robot.link_lengths", "world.obstacles.t.colour"]) == [
        "world.robot.link_lengths",
        "world.obstacles.t.colour",
    ]


def test_the_specs_are_well_formed() -> None:
    for table in (SPATIAL_WORLD_PARAMETERS, SPATIAL_OBSTACLE_PARAMETERS):
        for key, spec in table.items():
            assert spec.name == table.prefix + key
            assert spec.locked  # world.*: fixed at start, as the planar world's
            assert spec.description.endswith(".")
            assert "\n" not in spec.description
            if spec.type is ParameterType.DOUBLE:
                assert spec.limits is not None, spec.name
                assert check_value(spec, spec.default) == spec.default  # the default passes its own check


# --------------------------------------------------------------------------- the parser follows the table


@pytest.fixture(scope="module")
def prepared(panda: RobotModel, panda_spheres: SphereModel) -> tuple[RobotModel, SphereModel]:
    return panda, panda_spheres


def _world(change: dict[str, Any], prepared: tuple[RobotModel, SphereModel]) -> Any:
    tree = copy.deepcopy(PANDA_ON_A_TABLE)
    for name, value in change.items():
        *parents, leaf = name.removeprefix("world.").split(".")
        part = tree["world"]
        for key in parents:
            part = part[key]
        if value is None:
            del part[leaf]
        else:
            part[leaf] = value
    return spatial_world_from_parameters(tree, CONFIG, prepared=prepared)


def test_defaults_come_from_the_table(prepared: tuple[RobotModel, SphereModel]) -> None:
    world = _world({"world.name": None}, prepared)
    assert world.name == SPATIAL_WORLD_PARAMETERS.default("name")
    assert world.tolerances == {key: SPATIAL_WORLD_PARAMETERS.default(key) for key in TOLERANCES}
    robot = robot_from_parameters(PANDA, CONFIG)
    assert robot.padding == SPATIAL_WORLD_PARAMETERS.default("robot.padding")


def _bad_values(spec: Any) -> list[Any]:
    """Values of the wrong type, and (for a number) beyond its limits."""
    if spec.type is ParameterType.STRING:
        return [5, ""]
    assert spec.limits is not None
    return [True, "0.1", math.nan, spec.limits[1] * 2 + 1, spec.limits[0] - 1]


#: The scalars the table checks (check_value), with the part of the parameters that reads them.
WORLD_SCALARS = ["world.name", "world.scene_file", "world.object.shape", *(f"world.{key}" for key in TOLERANCES)]
ROBOT_SCALARS = [
    "world.robot.urdf",
    "world.robot.srdf",
    "world.robot.base_link",
    "world.robot.tip_link",
    "world.robot.padding",
]
CASES = [(name, bad) for name in (*WORLD_SCALARS, *ROBOT_SCALARS) for bad in _bad_values(spatial_spec(name))]


@pytest.mark.parametrize(("name", "bad"), CASES, ids=[f"{n}={b!r}" for n, b in CASES])
def test_a_bad_scalar_gets_the_one_checkers_error_naming_it(
    name: str, bad: Any, prepared: tuple[RobotModel, SphereModel]
) -> None:
    spec = spatial_spec(name)
    assert spec is not None
    with pytest.raises(ParameterError) as expected:
        check_value(spec, bad)

    def parse() -> object:
        if name.startswith("world.robot."):
            return robot_from_parameters({**PANDA, name.rpartition(".")[2]: bad}, CONFIG)
        return _world({name: bad}, prepared)

    with pytest.raises(WorldError) as caught:
        parse()
    assert caught.value.parameter == name
    assert str(caught.value) == str(expected.value)  # "<name>: expected ..., got ...", as for planar ones


def test_padding_beyond_its_limits_is_refused_naming_it() -> None:
    with pytest.raises(WorldError, match=r"^world\.robot\.padding: expected a value in \[0\.0, 1\.0\], got 2$"):
        robot_from_parameters({**PANDA, "padding": 2}, CONFIG)


REQUIRED_CASES = [
    "world.robot.initial",
    "world.object.shape",
    "world.object.size",
    "world.object.initial",
    "world.object.goal",
    "world.object.grasps",
    "world.obstacles.table.shape",
    "world.obstacles.table.size",
    "world.obstacles.table.pose",
]


@pytest.mark.parametrize("name", REQUIRED_CASES)
def test_a_missing_required_key_is_refused_naming_it(name: str, prepared: tuple[RobotModel, SphereModel]) -> None:
    spec = spatial_spec(name)
    assert spec is not None
    assert spec.required
    with pytest.raises(WorldError) as caught:
        _world({name: None}, prepared)
    assert caught.value.parameter == name
    assert str(caught.value) == f"{name}: missing (required): {spec.description}"


@pytest.mark.parametrize("key", ["base_link", "tip_link"])
def test_a_missing_link_is_refused_naming_it(key: str) -> None:
    robot = {k: v for k, v in PANDA.items() if k != key}
    with pytest.raises(WorldError, match=rf"^world\.robot\.{key}: missing \(required\)"):
        robot_from_parameters(robot, CONFIG)


def test_too_many_grasps_are_refused_naming_the_cap(prepared: tuple[RobotModel, SphereModel]) -> None:
    grasps = [0.0, 0.0, 0.0, math.pi, 0.0, 0.0] * 257
    with pytest.raises(WorldError, match=r"^world\.object\.grasps: expected at most 256 grasps \(Limits\.max_grasps\)"):
        _world({"world.object.grasps": grasps}, prepared)


def test_a_long_name_is_refused_naming_the_cap(prepared: tuple[RobotModel, SphereModel]) -> None:
    with pytest.raises(WorldError, match=r"^world\.name: expected a name of at most 256 characters"):
        _world({"world.name": "n" * 257}, prepared)
