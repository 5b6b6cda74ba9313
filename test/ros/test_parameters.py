"""The node's parameters: start values, checks and descriptors (no ROS graph)."""

from __future__ import annotations

import array
import json
import math
import re
from pathlib import Path

import pytest

pytest.importorskip("rclpy")

from clew_ros.core.errors import ParameterError, WorldError
from clew_ros.core.parameters import PLANNER_PARAMETERS, WORLD_PARAMETERS
from clew_ros.planar.world import read_parameter_file
from clew_ros.ros import parameters
from clew_ros.ros.node_parameters import NODE_PARAMETERS
from clew_ros.ros.parameters import (
    NodeSettings,
    configuration_from_values,
    default_world_file,
    descriptor_for,
    flatten,
    initial_values,
    nest,
)

WORLDS = Path(__file__).parents[1] / "worlds"
RING = Path(__file__).parents[2] / "config" / "unreachable.yaml"  # four named obstacles
#: Every descriptor as the node declares it without parameters.allow_runtime_changes (saved when the
#: specification was introduced; updated with each deliberate change: the read-only locks and the caps).
DESCRIPTORS_BEFORE = Path(__file__).parents[1] / "data" / "parameter_descriptors.json"


def file_values(name: str) -> dict:
    return flatten(read_parameter_file(WORLDS / name))


def test_flatten_and_nest_are_inverse() -> None:
    tree = read_parameter_file(WORLDS / "node_behind_wall.yaml")
    assert nest(flatten(tree)) == tree
    assert nest({"a.b": 1, "a.c": None}) == {"a": {"b": 1}}


def test_without_world_parameters_the_default_file_is_served() -> None:
    assert default_world_file().is_file()
    values = initial_values({"planner.seed": 5})
    expected = flatten(read_parameter_file(default_world_file()))
    for name, value in expected.items():
        if name.startswith("world."):
            assert values[name] == value, name
    assert values["planner.seed"] == 5
    assert configuration_from_values(values).world.name == expected["world.name"]


def test_world_parameters_replace_the_default_world() -> None:
    values = initial_values(file_values("node_quick.yaml"))
    config = configuration_from_values(values)
    assert config.world.name == "node_quick"
    assert not config.world.obstacles
    assert values["world.obstacle_names"] is None  # absent: no obstacles of the default world leak in
    assert config.world.robot.link_width == 0.0
    assert config.world.goal_angle_tolerance == pytest.approx(math.pi)
    # a lone world.* override is a world of its own: the required keys are missing
    with pytest.raises(WorldError, match=r"world\.bounds"):
        configuration_from_values(initial_values({"world.object.goal": [0.5, 0.5, 0.0]}))


def test_every_parameter_has_a_start_value() -> None:
    values = initial_values(file_values("node_quick.yaml"))
    expected = (
        {f"world.{k}" for k in WORLD_PARAMETERS} | {f"planner.{k}" for k in PLANNER_PARAMETERS} | set(NODE_PARAMETERS)
    )
    assert expected <= set(values)
    assert values["record.enabled"] is True
    assert values["playback.rate"] == 20.0


@pytest.mark.parametrize(
    ("name", "value", "fault"),
    [
        ("world.robot.initial", [9.0, 0.0], "world.robot.initial"),
        ("world.bounds", "wide", "world.bounds"),
        ("world.goal_tolerence", 0.1, "world.goal_tolerence"),
        ("world.obstacles.stray", [0.0, 0.0, 1.0, 0.0, 1.0, 1.0], "world.obstacles.stray"),
        ("planner.time_limit", -1.0, "planner.time_limit"),
        ("planner.population", "many", "planner.population"),
        ("planner.speed", 1.0, "planner.speed"),
        ("record.enabled", "yes", "record.enabled"),
        ("record.directory", "", "record.directory"),
        ("playback.rate", 0.0, "playback.rate"),
        ("trajectory.joint_speed", math.nan, "trajectory.joint_speed"),
        ("record.bogus", 1, "record.bogus"),
    ],
)
def test_faults_name_the_parameter(name: str, value, fault: str) -> None:
    values = initial_values(file_values("node_quick.yaml"))
    values[name] = value
    with pytest.raises(ParameterError) as error:
        configuration_from_values(values)
    assert str(error.value).startswith(fault + ":")


def test_numbers_may_be_integers() -> None:
    values = initial_values(file_values("node_quick.yaml"))
    values.update({"planner.time_limit": 5, "playback.rate": 10, "world.robot.base": [0, 0]})
    config = configuration_from_values(values)
    assert config.planner.time_limit == 5.0
    assert config.node.playback_rate_hz == 10.0


def test_unlisted_obstacles_are_ignored_after_start_only() -> None:
    values = initial_values(flatten(read_parameter_file(RING)))
    values["world.obstacle_names"] = ["ring_south", "ring_north", "ring_west"]  # ring_east retired
    config = configuration_from_values(values, listed_obstacles_only=True)
    assert [o.name for o in config.world.obstacles] == ["ring_south", "ring_north", "ring_west"]
    with pytest.raises(WorldError, match=r"world\.obstacles\.ring_east"):
        configuration_from_values(values)


def test_descriptors() -> None:
    seed = descriptor_for("planner.seed")
    assert seed.dynamic_typing
    assert seed.integer_range[0].to_value == 2**31 - 1
    assert seed.description
    limit = descriptor_for("planner.time_limit")
    assert limit.floating_point_range[0].from_value == pytest.approx(0.01)
    assert "required" in descriptor_for("world.bounds").additional_constraints
    assert descriptor_for("world.obstacles.anything").description
    assert descriptor_for("playback.rate").floating_point_range[0].to_value == 1000.0
    assert descriptor_for("record.directory").description


def test_descriptors_are_unchanged() -> None:
    """Every parameter keeps its descriptor: description, constraints text, ranges, dynamic typing."""
    saved = json.loads(DESCRIPTORS_BEFORE.read_text(encoding="utf-8"))
    assert {name for name in initial_values({}) if not name.startswith("world.obstacles.")} <= set(saved)
    for name, expected in saved.items():
        d = descriptor_for(name)
        assert {
            "description": d.description,
            "additional_constraints": d.additional_constraints,
            "type": d.type,
            "read_only": d.read_only,
            "dynamic_typing": d.dynamic_typing,
            "floating_point_range": [[r.from_value, r.to_value, r.step] for r in d.floating_point_range],
            "integer_range": [[r.from_value, r.to_value, r.step] for r in d.integer_range],
        } == expected, name


def test_descriptors_follow_the_specification() -> None:
    for table in (WORLD_PARAMETERS, PLANNER_PARAMETERS, NODE_PARAMETERS):
        for spec in table.values():
            d = descriptor_for(spec.name)
            assert d.name == spec.name
            assert d.description == spec.description
            assert d.dynamic_typing
            ranges = [(r.from_value, r.to_value) for r in (*d.integer_range, *d.floating_point_range)]
            assert ranges == ([spec.limits] if spec.limits else []), spec.name


def test_node_settings_take_the_specified_defaults() -> None:
    assert NodeSettings() == NodeSettings(
        **{field: NODE_PARAMETERS[name].default for field, name in parameters.SETTINGS_FIELDS.items()}
    )
    config = configuration_from_values(initial_values(file_values("node_quick.yaml")))
    assert config.node == NodeSettings()


def test_trajectory_limits_and_the_deprecated_joint_speed() -> None:
    values = initial_values(file_values("node_quick.yaml"))
    assert values["trajectory.joint_speed"] is None  # unset: declared without a value
    node = configuration_from_values(values).node
    assert (node.max_velocity_rad_s, node.max_acceleration_rad_s2, node.joint_speed_rad_s) == (1.0, 2.0, None)
    assert node.velocity_limit_rad_s == 1.0
    values.update({"trajectory.max_velocity": 3, "trajectory.max_acceleration": 7.5})
    node = configuration_from_values(values).node
    assert (node.velocity_limit_rad_s, node.max_acceleration_rad_s2) == (3.0, 7.5)
    # a parameter file that still sets trajectory.joint_speed loads, and its value is the velocity limit
    values["trajectory.joint_speed"] = 20
    assert configuration_from_values(values).node.velocity_limit_rad_s == 20.0
    for name, bad in [("trajectory.max_velocity", 0.0), ("trajectory.max_acceleration", -1.0)]:
        with pytest.raises(ParameterError, match=rf"^{name}: expected a value in"):
            configuration_from_values({**values, name: bad})
    assert "unset by default" in descriptor_for("trajectory.joint_speed").additional_constraints


def test_trajectory_limits_may_be_given_per_joint() -> None:
    values = initial_values(file_values("node_quick.yaml"))  # two joints
    values.update({"trajectory.max_velocity": [1.5, 3], "trajectory.max_acceleration": array.array("d", [4.0, 0.5])})
    node = configuration_from_values(values).node
    assert node.max_velocity_rad_s == (1.5, 3.0)
    assert node.velocity_limit_rad_s == (1.5, 3.0)
    assert node.max_acceleration_rad_s2 == (4.0, 0.5)
    values["trajectory.joint_speed"] = [2.0, 2.5]  # the deprecated alias takes a list too, and wins
    assert configuration_from_values(values).node.velocity_limit_rad_s == (2.0, 2.5)
    # one value per joint of this world, each in the parameter's range
    expected = "expected a number for every joint or a list with one per joint (2: joint_1, joint_2)"
    for name, bad, message in [
        ("trajectory.max_velocity", [1.0, 2.0, 3.0], f"{expected}, got a list of 3"),
        ("trajectory.max_acceleration", [1.0], f"{expected}, got a list of 1"),
        ("trajectory.joint_speed", [1.0, 2.0, 3.0], f"{expected}, got a list of 3"),
        ("trajectory.max_velocity", [1.0, 0.0], "expected a value in [0.001, 1000.0] for joint_2, got 0.0"),
        ("trajectory.max_acceleration", [-4.0, 1.0], "expected a value in [0.001, 100000.0] for joint_1, got -4.0"),
    ]:
        with pytest.raises(ParameterError) as error:
            configuration_from_values({**values, name: bad})
        assert str(error.value) == f"{name}: {message}"
    # a world of another number of joints needs lists of its length (set together, atomically)
    arm3 = flatten(read_parameter_file(Path(__file__).parents[2] / "config" / "arm3_regrasp.yaml"))
    with pytest.raises(ParameterError, match=r"^trajectory\.max_velocity: .*\(3: joint_1, joint_2, joint_3\)"):
        configuration_from_values({**values, **arm3})
    three = {"trajectory.max_velocity": [1.0, 1.0, 2.0], "trajectory.max_acceleration": 2.0}
    three["trajectory.joint_speed"] = None
    assert configuration_from_values({**values, **arm3, **three}).node.velocity_limit_rad_s == (1.0, 1.0, 2.0)


CHECKER_CASES = [
    ("record.enabled", "yes", "record.enabled: expected true or false, got 'yes'"),
    ("record.directory", 5, "record.directory: expected a non-empty string, got 5"),
    ("playback.rate", "fast", "playback.rate: expected a number, got 'fast'"),
    ("playback.rate", 0.5, "playback.rate: expected a value in [1.0, 1000.0], got 0.5"),
    ("trajectory.grasp_dwell", math.nan, "trajectory.grasp_dwell: expected a value in [0.001, 60.0], got nan"),
    (
        "trajectory.joint_speed",
        10**400,
        "trajectory.joint_speed: expected a value in [0.001, 1000.0], got " + "1" + "0" * 76 + "...",
    ),
    (
        "trajectory.joint_speed",
        10**5000,
        "trajectory.joint_speed: expected a value in [0.001, 1000.0], got an integer of about 5000 digits",
    ),
    ("planner.seed", 1.5, "planner.seed: expected an integer, got 1.5"),
]


@pytest.mark.parametrize(
    ("name", "value", "message"), CHECKER_CASES, ids=[f"{c[0]}-{i}" for i, c in enumerate(CHECKER_CASES)]
)
def test_node_and_planner_values_share_one_checker(name: str, value, message: str) -> None:
    values = initial_values(file_values("node_quick.yaml"))
    values[name] = value
    with pytest.raises(ParameterError) as error:
        configuration_from_values(values)
    assert str(error.value) == message


def test_record_directory_expands_home(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("HOME", str(tmp_path))
    assert NodeSettings(record_directory="~/runs").record_path == tmp_path.resolve() / "runs"


def test_record_directory_is_resolved_once(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.chdir(tmp_path)
    assert NodeSettings(record_directory="a/../b").record_path == tmp_path.resolve() / "b"
    with pytest.raises(ParameterError, match=r"^record\.directory: expected a path without '\$'"):
        NodeSettings(record_directory="$HOME/runs")


@pytest.mark.parametrize("name", ["state.joint_states", "state.object_pose", "state.obstacles", "state.points"])
def test_the_world_as_it_is_now_needs_a_spatial_world_and_is_fixed_at_start(name: str) -> None:
    values = initial_values(file_values("node_quick.yaml"))
    values[name] = True
    with pytest.raises(ParameterError, match=f"^{name}: expected false: .*spatial world"):
        configuration_from_values(values)
    assert descriptor_for(name).read_only
    assert descriptor_for(name, allow_runtime_changes=True).read_only
    values[name] = False
    values["state.max_age"] = 0.0
    with pytest.raises(ParameterError, match=r"^state\.max_age: expected a value in \[0\.001, 3600\.0\]"):
        configuration_from_values(values)


# --------------------------------------------------------------------------- spatial worlds' world.*

SPATIAL_WORLD = Path(__file__).parents[2] / "config" / "spatial" / "panda_table_to_table.yaml"


def spatial_values() -> dict:
    from clew_ros.ros.spatial import resolved_parameters

    return initial_values(flatten(resolved_parameters(SPATIAL_WORLD)))


def test_a_spatial_worlds_descriptors_come_from_its_specification() -> None:
    """Each spatial world.* parameter is declared read-only (locked, as the planar world's) with its spec's
    description and range; the development switch lifts the lock."""
    from clew_ros.spatial.parameters import SPATIAL_OBSTACLE_PARAMETERS, SPATIAL_WORLD_PARAMETERS

    specs = [*SPATIAL_WORLD_PARAMETERS.values(), *SPATIAL_OBSTACLE_PARAMETERS.values()]
    for spec in specs:
        name = spec.name.replace("<name>", "table")
        d = descriptor_for(name, spatial=True)
        assert d.name == name
        assert d.read_only, name
        assert d.dynamic_typing
        assert d.description == spec.description, name
        assert "fixed at start" in d.additional_constraints
        ranges = [(r.from_value, r.to_value) for r in (*d.integer_range, *d.floating_point_range)]
        assert ranges == ([spec.limits] if spec.limits else []), name
        assert not descriptor_for(name, spatial=True, allow_runtime_changes=True).read_only
    padding = descriptor_for("world.robot.padding", spatial=True)
    assert padding.description.startswith("How far (m) every link's collision geometry is grown")
    assert padding.additional_constraints.startswith("double; default 0.0;")
    assert descriptor_for("world.robot.initial", spatial=True).additional_constraints.startswith("double[]; required;")
    # the same name in a planar world is the planar world's
    assert descriptor_for("world.robot.initial").description == WORLD_PARAMETERS["robot.initial"].description
    with pytest.raises(KeyError):
        descriptor_for("world.robot.link_lengths", spatial=True)


def test_the_node_declares_each_given_spatial_parameter_with_a_descriptor() -> None:
    values = spatial_values()
    world = [name for name in values if name.startswith("world.")]
    assert "world.robot.base_link" in world
    assert "world.obstacles.table_a.shape" in world
    for name in world:
        assert descriptor_for(name, spatial=True).description, name


@pytest.mark.parametrize("name", ["world.robot.tcpp", "world.robot.link_lengths", "world.obstacles.table_a.colour"])
def test_an_unknown_spatial_parameter_is_refused_naming_the_known_ones(name: str) -> None:
    values = spatial_values()
    values[name] = [0.0]
    with pytest.raises(WorldError, match=rf"^{re.escape(name)}: unknown parameter of a spatial world; known: ") as e:
        configuration_from_values(values)
    assert "world.robot.padding" in str(e.value)
    assert "world.obstacles.<name>.pose" in str(e.value)


def test_world_kind_planar_is_the_default_kind_and_any_other_is_refused() -> None:
    values = initial_values(file_values("node_quick.yaml"))
    values["world.kind"] = "planar"
    assert (
        configuration_from_values(values).world.name
        == configuration_from_values({k: v for k, v in values.items() if k != "world.kind"}).world.name
    )
    assert descriptor_for("world.kind").read_only
    values["world.kind"] = "mobile"
    with pytest.raises(WorldError, match=r"^world\.kind: expected planar or spatial, got 'mobile'$"):
        configuration_from_values(values)
