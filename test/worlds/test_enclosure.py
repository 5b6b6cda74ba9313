"""The separation proof: eroded free space between start and goal."""

from __future__ import annotations

import copy
from pathlib import Path

from clew_ros.core.world import read_parameter_file, world_from_parameters
from clew_ros.worlds.enclosure import separation

CONFIG = Path(__file__).resolve().parents[2] / "config"


def test_the_closed_ring_of_unreachable_is_proven() -> None:
    reason = separation(world_from_parameters(read_parameter_file(CONFIG / "unreachable.yaml")))
    assert reason is not None
    assert "inscribed disc" in reason


def test_solvable_worlds_are_never_refused() -> None:
    for name in ("figure1", "single_transfer", "arm3_regrasp", "arm5_regrasp"):
        assert separation(world_from_parameters(read_parameter_file(CONFIG / f"{name}.yaml"))) is None


def test_an_opening_wider_than_the_object_proves_nothing_and_a_narrower_one_does() -> None:
    tree = copy.deepcopy(read_parameter_file(CONFIG / "unreachable.yaml"))
    # the object is 0.2 x 0.1 m: its inscribed disc is 0.1 m across; cut a window into the ring's north wall
    obstacles = tree["world"]["obstacles"]
    for width, proven in ((0.16, False), (0.06, True)):
        left, right = 1.1 - width / 2, 1.1 + width / 2
        obstacles["ring_north"] = [0.7, -0.9, left, -0.9, left, -0.8, 0.7, -0.8]
        obstacles["ring_north_b"] = [right, -0.9, 1.5, -0.9, 1.5, -0.8, right, -0.8]
        tree["world"]["obstacle_names"] = [
            *read_parameter_file(CONFIG / "unreachable.yaml")["world"]["obstacle_names"],
            "ring_north_b",
        ]
        assert (separation(world_from_parameters(tree)) is not None) == proven, width
