"""Security: caps a user can read (:data:`clew_ros.core.parameters.LIMITS`), each refused naming the limit.

The world parser (and so ``clew_plan``, ``clew_batch`` and the node) refuses
a world beyond a cap (links, obstacles, vertices of one polygon and of all,
grasps, name lengths) before it does any work on it, with a ``WorldError``
naming the parameter and ``Limits.<cap>``; the planner's ranges are ones a
2-core and a 64-core machine both survive; the node holds the parameter
count and name lengths (:func:`check_parameter_names`). No ROS graph.
"""

from __future__ import annotations

import copy
import math
from typing import Any

import pytest

from clew_ros.cli.parameter_tables import limits_table, markdown_tables
from clew_ros.core.errors import ParameterError, WorldError
from clew_ros.core.parameters import (
    LIMITS,
    PLANNER_PARAMETERS,
    check_value,
)
from clew_ros.planar.world import world_from_parameters
from clew_ros.ros.node_parameters import NODE_PARAMETERS

#: A tiny valid world (two links, one obstacle), changed by each case.
BASE: dict[str, Any] = {
    "world": {
        "name": "caps",
        "bounds": [-2.0, -2.0, 2.0, 2.0],
        "robot": {
            "base": [0.0, 0.0],
            "link_lengths": [1.0, 0.8],
            "joint_lower": [-3.0, -3.0],
            "joint_upper": [3.0, 3.0],
            "initial": [0.0, 0.0],
        },
        "obstacle_names": ["block"],
        "obstacles": {"block": [-1.9, -1.9, -1.7, -1.9, -1.7, -1.7, -1.9, -1.7]},
        "object": {
            "polygon": [-0.1, -0.05, 0.1, -0.05, 0.1, 0.05, -0.1, 0.05],
            "initial": [1.2, 0.0, 0.0],
            "goal": [0.0, 1.2, 0.0],
            "grasps": [-0.1, 0.0, 0.1, 0.0],
        },
    }
}


def circle(count: int, radius: float = 0.05, x: float = 1.2) -> list[float]:
    """A ``count``-gon (flat x, y list) around ``(x, 0)``."""
    flat: list[float] = []
    for i in range(count):
        angle = 2 * math.pi * i / count
        flat += [x + radius * math.cos(angle), radius * math.sin(angle)]
    return flat


def arm(links: int) -> dict[str, Any]:
    tree = copy.deepcopy(BASE)
    tree["world"]["robot"].update(
        link_lengths=[1.7 / links] * links, joint_lower=[-3.0] * links, joint_upper=[3.0] * links, initial=[0.0] * links
    )
    return tree


def with_obstacles(count: int, vertices: int = 4) -> dict[str, Any]:
    tree = copy.deepcopy(BASE)
    names = [f"o{i}" for i in range(count)]
    tree["world"]["obstacle_names"] = names
    tree["world"]["obstacles"] = {name: circle(vertices, 0.001, -1.9 + 0.0001 * i) for i, name in enumerate(names)}
    return tree


def changed(path: tuple[str, ...], value: Any) -> dict[str, Any]:
    tree = copy.deepcopy(BASE)
    node = tree
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return tree


CASES: list[tuple[str, Any, str, str]] = [
    ("links", lambda: arm(LIMITS.max_links + 1), "world.robot.link_lengths", "max_links"),
    ("obstacles", lambda: with_obstacles(LIMITS.max_obstacles + 1), "world.obstacle_names", "max_obstacles"),
    (
        "obstacle vertices",
        lambda: changed(("world", "obstacles", "block"), circle(LIMITS.max_polygon_vertices + 1, 0.05, -1.8)),
        "world.obstacles.block",
        "max_polygon_vertices",
    ),
    (
        "object vertices",
        lambda: changed(("world", "object", "polygon"), circle(LIMITS.max_polygon_vertices + 1, 0.1, 0.0)),
        "world.object.polygon",
        "max_polygon_vertices",
    ),
    (
        "world vertices",
        lambda: with_obstacles(
            LIMITS.max_world_vertices // LIMITS.max_polygon_vertices + 1, LIMITS.max_polygon_vertices
        ),
        "world.obstacles",
        "max_world_vertices",
    ),
    (
        "grasps",
        lambda: changed(("world", "object", "grasps"), [0.1, 0.0] * (LIMITS.max_grasps + 1)),
        "world.object.grasps",
        "max_grasps",
    ),
    (
        "world name",
        lambda: changed(("world", "name"), "w" * (LIMITS.max_name_chars + 1)),
        "world.name",
        "max_name_chars",
    ),
    (
        "obstacle name",
        lambda: changed(("world", "obstacle_names"), ["b" * (LIMITS.max_name_chars + 1)]),
        "world.obstacle_names",
        "max_name_chars",
    ),
]


@pytest.mark.parametrize(("case", "make", "parameter", "cap"), CASES, ids=[c[0] for c in CASES])
def test_a_world_beyond_a_cap_is_refused_naming_it(case: str, make: Any, parameter: str, cap: str) -> None:
    tree = make()
    with pytest.raises(WorldError) as caught:
        world_from_parameters(tree)
    assert caught.value.parameter == parameter, caught.value
    assert f"Limits.{cap}" in str(caught.value), caught.value
    assert f"at most {getattr(LIMITS, cap)}" in str(caught.value), caught.value
    assert len(str(caught.value)) < 300


def test_the_caps_allow_what_users_need() -> None:
    """64 links (the generated 15-40-link arms and more), and a world at each cap, load."""
    assert LIMITS.max_links >= 64
    assert world_from_parameters(arm(64)).robot.dof == 64
    assert world_from_parameters(arm(LIMITS.max_links)).robot.dof == LIMITS.max_links
    polygon = circle(LIMITS.max_polygon_vertices, 0.1, 0.0)
    grasps = polygon[: 2 * LIMITS.max_grasps]
    loaded = world_from_parameters(
        changed(("world", "object"), {**BASE["world"]["object"], "polygon": polygon, "grasps": grasps})
    )
    assert len(loaded.object.grasps) == LIMITS.max_grasps


@pytest.mark.parametrize(
    ("name", "too_much"),
    [("time_limit", 86400.0), ("population", 10_000), ("generations", 10_000), ("threads", 1024)],
)
def test_planner_ranges_a_small_machine_survives(name: str, too_much: float) -> None:
    spec = PLANNER_PARAMETERS[name]
    assert spec.limits is not None
    with pytest.raises(ParameterError, match=rf"^planner\.{name}: expected a value in \["):
        check_value(spec, too_much)
    assert check_value(spec, spec.limits[1]) == spec.limits[1]
    # a 64-core machine may use all its cores
    assert PLANNER_PARAMETERS["threads"].limits is not None
    assert PLANNER_PARAMETERS["threads"].limits[1] >= 64


def test_parameter_count_and_name_lengths() -> None:
    pytest.importorskip("rclpy")
    from clew_ros.ros.parameters import check_parameter_names

    check_parameter_names([f"p{i}" for i in range(LIMITS.max_parameters)])
    with pytest.raises(ParameterError, match=r"Limits\.max_parameters"):
        check_parameter_names([f"p{i}" for i in range(LIMITS.max_parameters + 1)])
    with pytest.raises(ParameterError, match=r"Limits\.max_name_chars"):
        check_parameter_names(["world.obstacles." + "x" * LIMITS.max_name_chars])
    with pytest.raises(ParameterError, match=r"^record\.directory: expected at most 4096 characters"):
        check_value(NODE_PARAMETERS["record.directory"], "/" * 5000)


def test_a_goal_frame_id_is_quoted_short_and_printable() -> None:
    pytest.importorskip("rclpy")
    from geometry_msgs.msg import PoseStamped

    from clew_ros.planar.world import world_from_parameters as load
    from clew_ros.ros.messages import GoalPoseError, goal_from_pose_stamped

    msg = PoseStamped()
    msg.header.frame_id = "\x1b]0;owned\x07" + "f" * 100_000
    msg.pose.orientation.w = 1.0
    with pytest.raises(GoalPoseError) as caught:
        goal_from_pose_stamped(msg, load(BASE))
    text = str(caught.value)
    assert len(text) < 200, text
    assert text.isprintable(), text
    assert f"({len(msg.header.frame_id)} characters)" in text


def test_the_caps_are_documented() -> None:
    """docs/parameters.md's tables (generated) name each cap: the limits table, and the world parameters they cap."""
    table = limits_table()
    for field in ("max_links", "max_obstacles", "max_grasps", "max_parameters", "max_name_chars"):
        assert f"| `{field}` | `{getattr(LIMITS, field)}` |" in table
    world = markdown_tables()["world"]
    assert f"at most {LIMITS.max_links}" in world
    assert f"At most {LIMITS.max_obstacles} names" in world
    assert f"at most {LIMITS.max_grasps}" in world
