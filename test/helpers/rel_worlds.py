"""Hypothesis strategies for malformed (and valid) worlds, for the reliability tests.

A world is the ``ros__parameters`` tree of interface.md §1 (``{"world": {...},
"planner": {...}}``). :func:`bad_worlds` starts from a small valid world and
breaks it in one or more places: a key removed, a value of the wrong type,
NaN / inf / huge / tiny numbers, lists of odd or wrong length, empty lists,
self-intersecting or degenerate polygons, grasps off the boundary, unknown
keys, thousands of obstacles. :func:`random_trees` produces arbitrary
JSON-like trees under ``world``. Pure data: no rclpy, no planner.
"""

from __future__ import annotations

import copy
import math
from typing import Any

from hypothesis import strategies as st

__all__ = [
    "BASE_WORLD",
    "FIXED_BAD_WORLDS",
    "bad_values",
    "bad_worlds",
    "many_obstacles",
    "random_trees",
    "world_paths",
]

#: A small valid world (node_quick with one obstacle); every mutation starts from it.
BASE_WORLD: dict[str, Any] = {
    "world": {
        "name": "rel_base",
        "bounds": [-2.0, -2.0, 2.0, 2.0],
        "robot": {
            "base": [0.0, 0.0],
            "link_lengths": [1.0, 0.8],
            "link_width": 0.0,
            "joint_lower": [-3.14159, -3.0],
            "joint_upper": [3.14159, 3.0],
            "initial": [0.0, 0.0],
            "self_collision": True,
        },
        "obstacle_names": ["block"],
        "obstacles": {"block": [-1.5, -1.5, -1.2, -1.5, -1.2, -1.2, -1.5, -1.2]},
        "object": {
            "polygon": [-0.1, -0.05, 0.1, -0.05, 0.1, 0.05, -0.1, 0.05],
            "initial": [0.9, 0.9, 0.0],
            "goal": [0.6, 1.1, 0.0],
            "grasps": [0.0, -0.05, 0.0, 0.05, -0.1, 0.0, 0.1, 0.0],
        },
        "grasp_tolerance": 0.005,
        "goal_tolerance": 0.05,
        "goal_angle_tolerance": 3.14159,
    },
    "planner": {"seed": 0, "time_limit": 5.0},
}


def world_paths(tree: dict | None = None, prefix: tuple[str, ...] = ()) -> list[tuple[str, ...]]:
    """Every key path in ``tree`` (mappings and leaves), e.g. ``("world", "robot", "base")``."""
    tree = BASE_WORLD if tree is None else tree
    paths = []
    for key, value in tree.items():
        path = (*prefix, key)
        paths.append(path)
        if isinstance(value, dict):
            paths.extend(world_paths(value, path))
    return paths


WORLD_PATHS = [p for p in world_paths() if p[0] == "world" and len(p) > 1]

_SPECIAL_FLOATS = [math.nan, math.inf, -math.inf, 1e308, -1e308, 1e-320, -1e-320, 0.0, -0.0, 1e154, 5e-324]
_HUGE_INT = 10**400  # YAML reads a 400-digit literal as an int: float() overflows on it

numbers = st.one_of(
    st.sampled_from(_SPECIAL_FLOATS),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.just(_HUGE_INT),
    st.just(-_HUGE_INT),
)

scalars = st.one_of(
    numbers,
    st.booleans(),
    st.none(),
    st.text(max_size=8),
    st.just(""),
    st.binary(max_size=4),
)


def bad_values() -> st.SearchStrategy[Any]:
    """Values that are wrong (or odd) for most world parameters."""
    return st.one_of(
        scalars,
        st.lists(numbers, max_size=12),
        st.lists(scalars, max_size=6),
        st.just([]),
        st.lists(st.floats(-3.0, 3.0), min_size=1, max_size=9),  # plausible numbers, random length
        st.dictionaries(st.text(max_size=4), scalars, max_size=3),
        st.lists(st.lists(numbers, max_size=2), max_size=3),  # nested lists
    )


# Polygons (flat lists) that are wrong in shape rather than in type.
BAD_POLYGONS = [
    [0.0, 0.0, 1.0, 1.0, 1.0, 0.0, 0.0, 1.0],  # bow tie (self-intersecting)
    [0.0, 0.0, 1.0, 0.0, 2.0, 0.0],  # collinear: zero area
    [0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],  # repeated points, zero area
    [0.0, 0.0, 1.0, 0.0],  # two points
    [0.0, 0.0, 1.0, 0.0, 1.0],  # odd length
    [0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0, 0.0, 0.0],  # closed ring, valid
    [0.0, 0.0, 2.0, 0.0, 2.0, 2.0, 1.0, 1.0, 1.0, 3.0, 0.0, 2.0],  # spike touching itself? (valid)
    [0.0, 0.0, 2.0, 0.0, 0.0, 2.0, 2.0, 2.0, 1.0, -1.0],  # star crossing
    [-1e308, -1e308, 1e308, -1e308, 1e308, 1e308, -1e308, 1e308],  # huge: area overflows to inf
    [0.0, 0.0, 1e-9, 0.0, 1e-9, 1e-9, 0.0, 1e-9],  # tiny
    [0.0, 0.0, 1.0, 0.0, math.nan, 1.0],
    [0.0, 0.0, math.inf, 0.0, 0.0, 1.0],
]


@st.composite
def polygons(draw) -> list[float]:
    """A flat polygon list: a known bad one or random points (often self-intersecting)."""
    if draw(st.booleans()):
        return list(draw(st.sampled_from(BAD_POLYGONS)))
    count = draw(st.integers(3, 9))
    return draw(st.lists(st.floats(-2.5, 2.5, allow_nan=False), min_size=2 * count, max_size=2 * count))


def many_obstacles(count: int, *, overlap_robot: bool = False) -> tuple[list[str], dict[str, list[float]]]:
    """``count`` small squares in a grid over the lower half of the bounds (or everywhere)."""
    names, polys = [], {}
    side = max(1, math.ceil(math.sqrt(count)))
    cell = 3.6 / side
    size = cell * 0.3
    for k in range(count):
        i, j = divmod(k, side)
        x0 = -1.8 + j * cell
        y0 = (-1.8 + i * cell) if overlap_robot else (-1.8 + i * cell * 0.4)
        names.append(f"o{k}")
        polys[f"o{k}"] = [x0, y0, x0 + size, y0, x0 + size, y0 + size * 0.4, x0, y0 + size * 0.4]
    return names, polys


def _set(tree: dict, path: tuple[str, ...], value: Any) -> None:
    node = tree
    for key in path[:-1]:
        child = node.get(key)
        if not isinstance(child, dict):
            child = {}
            node[key] = child
        node = child
    node[path[-1]] = value


def _delete(tree: dict, path: tuple[str, ...]) -> None:
    node = tree
    for key in path[:-1]:
        node = node.get(key)
        if not isinstance(node, dict):
            return
    node.pop(path[-1], None)


@st.composite
def mutations(draw, tree: dict) -> None:
    """Apply one mutation to ``tree`` in place."""
    kind = draw(
        st.sampled_from(
            ["value", "delete", "polygon", "grasps", "length", "unknown", "obstacles", "special_number", "pose"]
        )
    )
    if kind == "value":
        _set(tree, draw(st.sampled_from(WORLD_PATHS)), draw(bad_values()))
    elif kind == "delete":
        _delete(tree, draw(st.sampled_from(WORLD_PATHS)))
    elif kind == "polygon":
        target = draw(st.sampled_from([("world", "object", "polygon"), ("world", "obstacles", "block")]))
        _set(tree, target, draw(polygons()))
    elif kind == "grasps":
        # grasps near but off the boundary, or on it
        count = draw(st.integers(0, 4))
        offsets = draw(st.lists(st.floats(-0.2, 0.2, allow_nan=False), min_size=2 * count, max_size=2 * count))
        _set(tree, ("world", "object", "grasps"), offsets)
    elif kind == "length":
        path = draw(st.sampled_from([p for p in WORLD_PATHS if isinstance(_get(BASE_WORLD, p), list)]))
        current = _get(tree, path)
        value = list(current) if isinstance(current, list) else list(_get(BASE_WORLD, path))
        n = draw(st.integers(0, 3))
        value = (
            value[:-n]
            if draw(st.booleans()) and n
            else value + draw(st.lists(st.floats(-3, 3, allow_nan=False), min_size=n, max_size=n))
        )
        _set(tree, path, value)
    elif kind == "unknown":
        parent = draw(st.sampled_from([("world",), ("world", "robot"), ("world", "object"), ("world", "obstacles")]))
        _set(tree, (*parent, draw(st.sampled_from(["colour", "extra", "goal_tolerence", "7"]))), draw(bad_values()))
    elif kind == "obstacles":
        count = draw(st.sampled_from([0, 1, 50, 2000]))
        names, polys = many_obstacles(count, overlap_robot=draw(st.booleans()))
        if draw(st.booleans()) and names:
            names = [*names[:-1], names[0]]  # a duplicate name, one polygon unlisted
        tree["world"]["obstacle_names"] = names
        tree["world"]["obstacles"] = polys
    elif kind == "special_number":
        path = draw(st.sampled_from([p for p in WORLD_PATHS if isinstance(_get(BASE_WORLD, p), (list, float))]))
        value = copy.deepcopy(_get(BASE_WORLD, path))
        special = draw(st.sampled_from([*_SPECIAL_FLOATS, _HUGE_INT, 2**63, -(2**63)]))
        if isinstance(value, list):
            value[draw(st.integers(0, len(value) - 1))] = special
        else:
            value = special
        _set(tree, path, value)
    elif kind == "pose":
        which = draw(st.sampled_from(["initial", "goal"]))
        pose = [
            draw(st.floats(-5, 5, allow_nan=False)),
            draw(st.floats(-5, 5, allow_nan=False)),
            draw(st.floats(-100, 100, allow_nan=False)),
        ]
        _set(tree, ("world", "object", which), pose)


def _get(tree: dict, path: tuple[str, ...]) -> Any:
    node: Any = tree
    for key in path:
        if not isinstance(node, dict):
            return None
        node = node.get(key)
    return node


@st.composite
def bad_worlds(draw, max_mutations: int = 3) -> dict:
    """A parameter tree: :data:`BASE_WORLD` with 1..``max_mutations`` mutations."""
    tree = copy.deepcopy(BASE_WORLD)
    for _ in range(draw(st.integers(1, max_mutations))):
        draw(mutations(tree))
    return tree


json_leaves = st.one_of(scalars, st.lists(numbers, max_size=8))
random_trees = st.recursive(
    json_leaves,
    lambda children: st.one_of(
        st.lists(children, max_size=4),
        st.dictionaries(
            st.sampled_from(
                [
                    "name",
                    "bounds",
                    "robot",
                    "object",
                    "obstacles",
                    "obstacle_names",
                    "base",
                    "polygon",
                    "grasps",
                    "initial",
                    "goal",
                    "link_lengths",
                    "x",
                ]
            ),
            children,
            max_size=6,
        ),
    ),
    max_leaves=20,
)
"""Arbitrary JSON-like values: used as the whole ``world`` tree."""

#: Fixed malformed worlds: (label, tree mutation path, value, parameter expected in the message).
FIXED_BAD_WORLDS: list[tuple[str, tuple[str, ...], Any, str]] = [
    ("nan_bounds", ("world", "bounds"), [math.nan, -2.0, 2.0, 2.0], "world.bounds"),
    ("inf_link", ("world", "robot", "link_lengths"), [math.inf, 0.8], "world.robot.link_lengths"),
    ("odd_polygon", ("world", "object", "polygon"), [0.0, 0.0, 1.0, 0.0, 1.0], "world.object.polygon"),
    ("bowtie_obstacle", ("world", "obstacles", "block"), BAD_POLYGONS[0], "world.obstacles.block"),
    ("grasp_off_boundary", ("world", "object", "grasps"), [0.0, 0.3], "world.object.grasps"),
    ("empty_grasps", ("world", "object", "grasps"), [], "world.object.grasps"),
    ("string_bounds", ("world", "bounds"), "wide", "world.bounds"),
    ("huge_int_base", ("world", "robot", "base"), [_HUGE_INT, 0], "world.robot.base"),
    ("missing_robot", ("world", "robot"), None, "world.robot"),
    ("goal_in_obstacle", ("world", "object", "goal"), [-1.35, -1.35, 0.0], "world.object.goal"),
]
