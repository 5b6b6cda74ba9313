"""Spatial worlds where a regrasp is necessary because the object must be turned, proved by construction as
:mod:`~clew_ros.worlds.spatial_regrasp`'s are, each with a two-transfer witness:

- **flip** (``spatial_flip``): a bar (a box 2-5 times longer than wide) lies on its ``-z`` face on a table and
  must end on its ``+z`` face on another (turned over about its long axis). It has two grasps only: into its
  ``+z`` face and into its ``-z`` face, the fingers closing across its width. At the start the ``-z`` grasp's
  hand is inside the table, at the goal the ``+z`` grasp's (the tables are thick enough that a hand without
  fingers meets them too). The witness takes the bar from above, stands it on its end on a third table (both
  grasps then come from the side, from opposite sides), takes it with the other grasp and lays it down turned
  over.
- **laid down** (``spatial_laid_down``): a tall box (12-20 cm, too tall to stand in the goal's cubby) stands on a
  shelf under its lid, 2-3 cm above it (grasps from the side only), and must end lying on one of its sides in a
  low cubby, its long axis pointing in, where only the grasps into its end face fit: the ceiling, the board and
  the side walls a few mm away (6 cm thick: a hand without fingers meets them too) refuse the others; the cubby
  ends 2.5 cm short of the box's end, so the hand holding it there stays out. The witness takes it out from the
  side, stands it on a table, takes it from above (its end) and pushes it in lying down.

The proof that no single transfer exists is
:func:`~clew_ros.worlds.spatial_regrasp.single_grasp_refutation`; a world where one grasp escapes it is not kept.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from clew_ros.core.plan import Plan
from clew_ros.spatial.placements import MovableObject
from clew_ros.worlds.spatial_holds import Hold, grasp_pose, grasps_of, hold_from
from clew_ros.worlds.spatial_regrasp import (
    CUBBY_LIFT_M,
    RegraspLayout,
    RejectedError,
    cubby_around,
    enclosure_clear,
    witness_holds,
    witness_world,
)

__all__ = ["TURNED_WORLDS", "flip_world", "laid_down_world"]

#: A flip's bar: its length (m, along x), its width (across which the fingers close; the Panda opens 8 cm)
#: and its thickness (z), drawn per world.
BAR_LENGTH_M = (0.1, 0.16)
BAR_WIDTH_M = (0.03, 0.05)
BAR_THICKNESS_M = (0.03, 0.05)
#: A flip's start and goal tables are this thick (m): the hand of the grasp from below (a wrist without fingers
#: too, the UR5's tool 5 cm behind its tcp) meets them.
THICK_SUPPORT_M = 0.1
#: A laid-down box: its height (m, along z: it cannot stand in the goal's cubby) and its two other sides.
TALL_M = (0.12, 0.2)
TALL_SIDE_M = (0.03, 0.06)
#: The board, ceiling and walls of its goal cubby are this thick (m): the hand of a grasp from below or through a
#: wall meets them (the UR5's tool, 5 cm behind its tcp, at most 4.4 cm beyond the box's face).
LOW_CUBBY_WALL_M = 0.06
#: Its goal cubby ends this far (m) behind its end face: the hand holding it by its end (the tcp 1.5 cm inside)
#: stays out of the cubby.
LOW_CUBBY_RECESS_M = 0.025
#: Its holds back off along the hand's approach this far (m) beyond its height (at least the settings' approach).
LAID_CLEAR_M = 0.06


def _thicken(builder: Any, name: str, thickness: float) -> None:
    """Table ``name`` made ``thickness`` thick downwards (its top where it was)."""
    entry = builder.obstacles[name]
    top = entry["pose"][2] + entry["size"][2] / 2
    entry["size"][2] = round(thickness, 6)
    entry["pose"][2] = round(top - thickness / 2, 6)


def _check_clear(builder: Any, holds: tuple[Hold, Hold, Hold, Hold]) -> None:
    for name, entry in builder.obstacles.items():
        if not enclosure_clear(builder.arm, holds, {name: entry}):
            raise RejectedError(f"{name} is in the way of the witness's holds")


def flip_world(builder: Any) -> tuple[dict[str, Any], Plan, list[str]]:
    """Build one flip world on ``builder`` (a :class:`clew_ros.worlds.spatial._Builder`): its parameter tree,
    its witness (two transfers) and notes; :class:`RejectedError` when this stream gives none."""
    arm, rng, settings = builder.arm, builder.rng, builder.settings
    if arm.robot.dof < 6:
        raise RejectedError("the regrasp at the table needs an arm of 6 joints or more")
    size = [round(float(rng.uniform(*r)), 3) for r in (BAR_LENGTH_M, BAR_WIDTH_M, BAR_THICKNESS_M)]
    builder.thing = MovableObject("box", tuple(size))
    half = size[2] / 2
    reach = half - min(settings.grasp_depth_m, 0.4 * half)
    ez, ex = np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0])
    builder.grasps = [("top", grasp_pose(ez, ex, reach)), ("bottom", grasp_pose(-ez, ex, reach))]
    end = str(rng.choice(["+x", "-x"]))  # on the table, standing on one of its ends
    first, holds = witness_holds(builder, RegraspLayout("table", "table"), [0], 1, faces=("-z", end, "+z"))
    start, _, on_table, goal = holds
    builder.table("table_a", start)
    builder.table("table", on_table)
    builder.table("table_b", goal)
    for name in ("table_a", "table_b"):
        _thicken(builder, name, THICK_SUPPORT_M)
    _check_clear(builder, holds)
    tree, plan, refutation = witness_world(
        builder, (first, 1), holds, "witness: taken from above, stood on its end on a table, regrasped, turned over"
    )
    notes = [
        (
            f"flip: grasp 0 (into +z) from above, the bar stood on its {end} end on the table, grasp 1 (into -z) "
            "lays it down on its +z face"
        ),
        "No single transfer: " + "; ".join(refutation),
    ]
    return tree, plan, notes


def laid_down_world(builder: Any) -> tuple[dict[str, Any], Plan, list[str]]:
    """Build one laid-down world on ``builder``: its parameter tree, its witness (two transfers) and notes;
    :class:`RejectedError` when this stream gives none."""
    arm, rng, settings, solver = builder.arm, builder.rng, builder.settings, builder.solver
    if arm.robot.dof < 6:
        raise RejectedError("the regrasp at the table needs an arm of 6 joints or more")
    sides = [round(float(rng.uniform(*TALL_SIDE_M)), 3) for _ in range(2)]
    tall = round(float(rng.uniform(*TALL_M)), 3)
    builder.thing = MovableObject("box", (*sides, tall))
    builder.grasps = grasps_of(builder.thing, settings.grasp_depth_m)
    kinds = [kind for kind, _ in builder.grasps]
    firsts = [int(i) for i in rng.permutation([i for i, k in enumerate(kinds) if k == "side"])]
    second = int(rng.choice([i for i, k in enumerate(kinds) if k == "top"]))  # into its end face
    lying = str(rng.choice(["+x", "-x", "+y", "-y"]))
    first, holds = witness_holds(builder, RegraspLayout("cubby", "cubby"), firsts, second, faces=("-z", "-z", lying))
    # at the goal the hand backs off past the object's length: at its approach the object is out of the cubby
    solver.settings = replace(settings, approach_m=max(settings.approach_m, tall + LAID_CLEAR_M))
    goal = hold_from(solver, arm, holds[3].q, holds[3].pose, lying, rng=rng, lift_m=CUBBY_LIFT_M)
    solver.settings = settings
    if goal is None:
        raise RejectedError("the hand cannot back off the goal past the object's length")
    start, holds = holds[0], (*holds[:3], goal)
    for hold, thickness, shelf in ((start, settings.board_thickness_m, True), (goal, LOW_CUBBY_WALL_M, False)):
        approach = solver.kinematics.tcp_poses(hold.q[None])[0][:3, 2]
        recess = 0.0 if shelf else LOW_CUBBY_RECESS_M
        builder.obstacles.update(
            cubby_around(builder.thing, hold, approach, rng, thickness, shelf=shelf, recess=recess)
        )
    builder.table("table", holds[1])
    _check_clear(builder, holds)
    builder.supports[:] = ["shelf_board", "table", "cubby_board"]
    tree, plan, refutation = witness_world(
        builder,
        (first, second),
        holds,
        "witness: out of the cubby from the side, stood on a table, taken by its end, pushed in lying down",
    )
    notes = [
        (
            f"laid down: grasp {first} (side) out of the cubby, stood on the table, grasp {second} (into its end) "
            f"lays it on its {lying} face in the low cubby"
        ),
        "No single transfer: " + "; ".join(refutation),
    ]
    return tree, plan, notes


#: The regrasp families built here, by their ``SpatialFamily.regrasp`` key.
TURNED_WORLDS: dict[str, Callable[[Any], tuple[dict[str, Any], Plan, list[str]]]] = {
    "flip": flip_world,
    "laid_down": laid_down_world,
}
