"""clew_ros.spatial.scene: obstacles and bounds from parameters, refusals naming the parameter."""

from __future__ import annotations

import math
import re
from typing import Any

import numpy as np
import pytest

from clew_ros.core.errors import WorldError
from clew_ros.spatial.scene import bounds_from_parameters, obstacles_from_parameters


def world(**obstacles: Any) -> dict[str, Any]:
    return {"obstacle_names": list(obstacles), "obstacles": obstacles}


def test_obstacles_read_as_solid_primitives() -> None:
    read = obstacles_from_parameters(
        world(
            table={"shape": "box", "size": [1.2, 0.8, 0.04], "pose": [0.5, 0.0, -0.02, 0.0, 0.0, 0.0]},
            can={"shape": "cylinder", "size": [0.12, 0.03], "pose": [0.4, 0.1, 0.06, 0.0, 0.0, math.pi / 2]},
            ball={"shape": "sphere", "size": [0.05], "pose": [0.3, -0.2, 0.3, 0.0, 0.0, 0.0]},
        )
    )
    assert [(o.name, o.shape, o.size) for o in read] == [
        ("table", "box", (1.2, 0.8, 0.04)),
        ("can", "cylinder", (0.12, 0.03)),
        ("ball", "sphere", (0.05,)),
    ]
    np.testing.assert_allclose(read[1].pose[:3, 0], [0.0, 1.0, 0.0], atol=1e-12)  # yaw pi/2 turns x onto y


@pytest.mark.parametrize(
    ("entry", "parameter", "message"),
    [
        ({"shape": "cone", "size": [1.0], "pose": [0.0] * 6}, "world.obstacles.o.shape", "box, cylinder, sphere"),
        ({"shape": "box", "size": [1.0, 1.0], "pose": [0.0] * 6}, "world.obstacles.o.size", "[x, y, z] full extents"),
        ({"shape": "cylinder", "size": [1.0, -0.1], "pose": [0.0] * 6}, "world.obstacles.o.size", "positive"),
        ({"shape": "sphere", "size": [0.1], "pose": [0.0] * 5}, "world.obstacles.o.pose", "6 finite numbers"),
        ({"shape": "sphere", "size": [0.1]}, "world.obstacles.o.pose", "missing"),
        ("box", "world.obstacles.o", "expected shape, size and pose"),
    ],
)
def test_bad_obstacles_are_refused_by_name(entry: Any, parameter: str, message: str) -> None:
    with pytest.raises(WorldError, match=re.escape(message)) as error:
        obstacles_from_parameters(world(o=entry))
    assert error.value.parameter == parameter


def test_bounds() -> None:
    assert bounds_from_parameters({}) is None
    assert bounds_from_parameters({"bounds": [-1, -1, 0, 1, 1, 2]}).tolist() == [-1, -1, 0, 1, 1, 2]
    with pytest.raises(WorldError, match=re.escape("world.bounds: expected each minimum below its maximum")):
        bounds_from_parameters({"bounds": [-1, -1, 2, 1, 1, 0]})
    with pytest.raises(WorldError, match=re.escape("world.obstacle_names: expected distinct names")):
        obstacles_from_parameters({"obstacle_names": ["a", "a"], "obstacles": {}})
