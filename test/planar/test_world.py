"""World parsing and the start/goal check: every fault names the parameter at fault."""

import copy
import math
from pathlib import Path

import pytest

from clew_ros.core.errors import WorldError
from clew_ros.core.parameters import WORLD_PARAMETERS
from clew_ros.planar.collision import check_start_and_goal
from clew_ros.planar.world import (
    Robot,
    World,
    load_world,
    read_parameter_file,
    world_from_parameters,
    world_to_parameters,
)

CONFIG = Path(__file__).resolve().parents[2] / "config"
WORLDS = sorted(CONFIG.glob("*.yaml"))


def base_tree() -> dict:
    return copy.deepcopy(read_parameter_file(CONFIG / "figure1.yaml"))


def checked_world(tree) -> World:
    """What the node, ``clew_plan`` and the benchmarks do: parse, then check the start and the goal."""
    return check_start_and_goal(world_from_parameters(tree))


@pytest.mark.parametrize("path", WORLDS, ids=lambda p: p.stem)
def test_config_worlds_load(path):
    world = check_start_and_goal(load_world(path))
    assert world.name == path.stem
    assert world.robot.dof >= 2


def test_round_trip_parameters():
    world = load_world(CONFIG / "figure1.yaml")
    again = world_from_parameters(world_to_parameters(world))
    assert again.object.grasps.tolist() == world.object.grasps.tolist()
    assert [o.name for o in again.obstacles] == [o.name for o in world.obstacles]


def _set(tree, dotted, value):
    node = tree["world"]
    keys = dotted.split(".")[1:]
    for key in keys[:-1]:
        node = node[key]
    if value is _DELETE:
        del node[keys[-1]]
    else:
        node[keys[-1]] = value


_DELETE = object()

BAD = [
    ("world.bounds", [0, 0, 1], "4 numbers"),
    ("world.bounds", [1, 0, 0, 1], "xmin < xmax"),
    ("world.robot.link_lengths", [1.0], "at least 2"),
    ("world.robot.link_lengths", [1.0, -0.7], "> 0"),
    ("world.robot.link_lengths", [1.0, float("nan")], "finite"),
    ("world.robot.joint_lower", [-3.0], "2 values"),
    ("world.robot.joint_lower", [3.5, -2.8], "joint_lower <= joint_upper"),
    ("world.robot.initial", [0.0, 3.0], "within"),
    ("world.robot.initial", ["a", 0.0], "list of numbers"),
    ("world.robot.link_width", -0.1, ">= 0"),
    ("world.robot.self_collision", "yes", "true or false"),
    ("world.object.polygon", [0, 0, 1, 0, 1], "at least 6"),
    ("world.object.polygon", [0, 0, 1, 0, 1, 1, 0], "even number"),
    ("world.object.polygon", [0, 0, 2, 2, 2, 0, 0, 1], "simple polygon"),
    ("world.object.polygon", [0, 0, 1, 0, 2, 0], "non-zero area"),
    ("world.object.grasps", [0.0, 0.0], "boundary"),
    ("world.object.goal", [0.0, 0.0, float("inf")], "finite"),
    ("world.object.goal", [2.1, 0.0, 0.0], "collision-free placement"),
    ("world.object.initial", [0.0, 2.6, 0.0], "collision-free placement"),
    ("world.obstacle_names", ["left_block", "left_block"], "unique"),
    ("world.obstacles.left_block", [-2.4, -0.1, -1.8, -0.1, -1.8], "at least 6"),
    ("world.grasp_tolerance", 0.0, "> 0"),
    ("world.goal_tolerance", True, "a number"),
    ("world.robot.initial", [1.5708, 0.0], "valid start configuration"),
]


@pytest.mark.parametrize(("parameter", "value", "expected"), BAD, ids=[f"{p}={v!r}" for p, v, _ in BAD])
def test_bad_world_names_the_parameter(parameter, value, expected):
    tree = base_tree()
    _set(tree, parameter, value)
    with pytest.raises(WorldError) as caught:
        checked_world(tree)
    assert caught.value.parameter.startswith(parameter.rsplit(".", 1)[0])
    message = str(caught.value)
    assert message.startswith("world.")
    if expected:
        assert expected in message


def test_unknown_obstacle_is_named():
    tree = base_tree()
    tree["world"]["obstacles"]["ghost"] = [0, 0, 0.1, 0, 0.1, 0.1]
    with pytest.raises(WorldError, match=r"world\.obstacles\.ghost: unknown obstacle"):
        world_from_parameters(tree)


def test_listed_obstacle_missing_is_named():
    tree = base_tree()
    del tree["world"]["obstacles"]["left_block"]
    with pytest.raises(WorldError, match=r"world\.obstacles\.left_block: is required"):
        world_from_parameters(tree)


def test_start_in_collision_says_which_link_hits_what():
    tree = base_tree()
    # link 2 swings onto the right block
    tree["world"]["robot"]["initial"] = [0.0, 0.0]
    tree["world"]["robot"]["link_lengths"] = [1.0, 0.85]
    with pytest.raises(WorldError, match=r"world\.robot\.initial: .*link 2 hits obstacle 'right_block'"):
        checked_world(tree)


COLLIDING = [
    (
        "world.object.initial",
        [0.0, 2.6, 0.0],
        "world.object.initial: expected a collision-free placement, but the object leaves world.bounds",
    ),
    (
        "world.object.goal",
        [-2.0, 0.0, 0.0],
        "world.object.goal: expected a collision-free placement, but the object hits obstacle 'left_block'",
    ),
    (
        "world.robot.initial",
        [1.5708, 0.0],
        (
            "world.robot.initial: expected a valid start configuration, but "
            "link 2 goes into the object (deeper than world.grasp_tolerance)"
        ),
    ),
]


@pytest.mark.parametrize(("parameter", "value", "message"), COLLIDING, ids=[c[0] for c in COLLIDING])
def test_parsing_is_pure_and_the_collision_check_is_separate(parameter, value, message):
    """world_from_parameters parses without any geometry test; check_start_and_goal then refuses
    the start or goal, naming the parameter; it returns a valid world itself."""
    tree = base_tree()
    _set(tree, parameter, value)
    world = world_from_parameters(tree)
    assert isinstance(world, World)
    with pytest.raises(WorldError) as caught:
        check_start_and_goal(world)
    assert caught.value.parameter == parameter
    assert str(caught.value) == message
    valid = world_from_parameters(base_tree())
    assert check_start_and_goal(valid) is valid


def test_defaults_apply_when_keys_are_absent():
    tree = base_tree()
    for key in ("grasp_tolerance", "goal_tolerance", "goal_angle_tolerance"):
        tree["world"].pop(key, None)
    tree["world"]["robot"].pop("link_width", None)
    tree["world"]["robot"].pop("self_collision", None)
    world = world_from_parameters(tree)
    assert world.grasp_tolerance == 0.005
    assert world.goal_tolerance == 0.02
    assert world.goal_angle_tolerance == pytest.approx(math.pi)
    assert world.robot.link_width == 0.0
    assert world.robot.self_collision is True
    tree["world"].pop("name")
    assert world_from_parameters(tree).name == "world"


def test_the_defaults_are_the_specified_ones():
    """World and Robot take their defaults from the parameter specification, as the parser does."""
    defaults = {key: spec.default for key, spec in WORLD_PARAMETERS.items() if not spec.required}
    assert defaults == {
        "name": "world",
        "robot.link_width": 0.0,
        "robot.self_collision": True,
        "obstacle_names": None,
        "grasp_tolerance": 0.005,
        "goal_tolerance": 0.02,
        "goal_angle_tolerance": math.pi,
    }
    world = load_world(CONFIG / "figure1.yaml")
    robot = Robot(
        world.robot.base,
        world.robot.link_lengths,
        world.robot.joint_lower,
        world.robot.joint_upper,
        world.robot.initial,
    )
    assert (robot.link_width, robot.self_collision) == (defaults["robot.link_width"], defaults["robot.self_collision"])
    bare = World(world.name, world.bounds, robot, (), world.object)
    assert (bare.grasp_tolerance, bare.goal_tolerance, bare.goal_angle_tolerance) == (
        defaults["grasp_tolerance"],
        defaults["goal_tolerance"],
        defaults["goal_angle_tolerance"],
    )


def test_every_required_key_is_refused_when_absent():
    for spec in WORLD_PARAMETERS.values():
        if not spec.required:
            continue
        tree = base_tree()
        _set(tree, spec.name, _DELETE)
        with pytest.raises(WorldError, match=rf"^{spec.name}: is required"):
            world_from_parameters(tree)


def test_world_without_obstacles_and_wildcard_key(tmp_path):
    tree = base_tree()
    del tree["world"]["obstacle_names"], tree["world"]["obstacles"]
    import yaml

    path = tmp_path / "w.yaml"
    path.write_text(yaml.safe_dump({"/**": {"ros__parameters": tree}}))
    assert load_world(path).obstacles == ()


def test_unreadable_file_is_named(tmp_path):
    with pytest.raises(WorldError, match="cannot read"):
        load_world(tmp_path / "missing.yaml")
