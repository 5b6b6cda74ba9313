"""``open_reach``: a 2-joint arm and a small box, no obstacle, the goal a short carry away.

Shared by the improvement's tests (test/planar/test_improve.py) and the grid reference's
(test/benchmarks/test_reference.py): a world whose shortest plan is known to be one transfer.
"""

from __future__ import annotations

import copy
from typing import Any

_OPEN_REACH: dict[str, Any] = {
    "world": {
        "name": "open_reach",
        "bounds": [-2.5, -2.5, 2.5, 2.5],
        "robot": {
            "base": [0.0, 0.0],
            "link_lengths": [1.0, 0.8],
            "joint_lower": [-2.0, -2.5],
            "joint_upper": [2.0, 2.5],
            "initial": [-0.6, 1.2],
        },
        "object": {
            "polygon": [-0.05, -0.05, 0.05, -0.05, 0.05, 0.05, -0.05, 0.05],
            "initial": [1.2, 0.7, 0.0],
            "goal": [0.3, 1.3, 0.0],
            "grasps": [0.0, -0.05],
        },
    }
}


def open_reach(**world_changes: Any) -> dict[str, Any]:
    """A fresh copy of the world's parameter tree, with ``world_changes`` set under ``world``."""
    tree = copy.deepcopy(_OPEN_REACH)
    tree["world"].update(world_changes)
    return tree
