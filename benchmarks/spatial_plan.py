"""``python -m benchmarks.spatial_plan [--seeds 5] [--time-limit 20] [--problems NAME ...]``: the Ariadne's Clew
planner on spatial worlds (issue 44), a handful of problems.

Problems (with the shipped Panda, ``config/robots/panda``, but one with the UR5; mesh sphere models; a table
0.6 x 1.2 m in front of the arm):

- ``motion_post``: motion-only, from one side of a 0.9 m post on the table to the other, a shelf board above;
- ``motion_frame``: motion-only, from the hand down inside a gate (two posts and a bar on the table) to the
  hand down beside it;
- ``table``: pick a 4 x 4 x 12 cm box on the table and put it down 0.6 m away (top-down grasps);
- ``table_ur5``: the same with the shipped UR5 (6 joints);
- ``shelf``: from the table onto a shelf board beside the arm, under a roof;
- ``clutter``: a can (cylinder, 4 top-down grasps) carried across a table with four obstacles on it;
- ``on_side``: the box from standing to lying on its side (another face down: only the side grasps, from
  its +x face turned towards the arm, can do it; top-down grasps are offered too).

For each problem and seed (0 .. ``--seeds`` - 1): the outcome; then per problem the success rate, the median
and the largest planning time (s, wall, the first plan and its shortcuts), the median joint travel of the plan
(rad, the sum over joints of the absolute motion) and of the first plan before shortcuts, the transfers, and
the pieces of all plans with a configuration invalid at the validator's 0.002 rad (must be 0).
Each world is built once (its sphere model), the kernels compiled by a warm-up plan before timing.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from pathlib import Path
from typing import Any

import numpy as np

from clew_ros.core.clew import PlanResult
from clew_ros.core.settings import PlannerSettings
from clew_ros.spatial.space import SpatialSpace, plan
from clew_ros.spatial.validate import ValidationSettings, validate_transit, validation_samples
from clew_ros.spatial.world import SpatialWorld, spatial_world_from_parameters

CONFIG = Path(__file__).resolve().parents[1] / "config"
ROBOT: dict[str, Any] = {
    "urdf": str(CONFIG / "robots/panda/panda.urdf"),
    "srdf": str(CONFIG / "robots/panda/panda.srdf"),
    "base_link": "panda_link0",
    "tip_link": "panda_hand_tcp",
    "gripper_links": ["panda_hand", "panda_leftfinger", "panda_rightfinger"],
}
READY = [0.0, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8]
TABLE = {"shape": "box", "size": [0.6, 1.2, 0.04], "pose": [0.55, 0.0, 0.1, 0, 0, 0]}
BOX = {"shape": "box", "size": [0.04, 0.04, 0.12]}
TOP_DOWN = [0, 0, 0.02, math.pi, 0, 0, 0, 0, 0.02, math.pi, 0, math.pi / 2]
#: the hand from the box's +x side, its fingers across y, 2 cm from the centre towards +z
SIDE = [0.0, 0.0, 0.02, 0.0, -math.pi / 2, 0.0, 0.0, 0.0, -0.02, 0.0, -math.pi / 2, 0.0]


#: the shipped UR5 with a tcp 5 cm beyond its tool flange (no gripper geometry: the wrist's last links may
#: touch the object)
UR5: dict[str, Any] = {
    "urdf": str(CONFIG / "robots/ur5/ur5.urdf"),
    "srdf": str(CONFIG / "robots/ur5/ur5.srdf"),
    "base_link": "base_link",
    "tip_link": "tool0",
    "tcp": [0, 0, 0.05, 0, 0, 0],
    "gripper_links": ["wrist_3_link", "ee_link"],
    "initial": [0.0, -1.57, 1.57, -1.57, -1.57, 0.0],
}


def world(name: str, obstacles: dict[str, Any], **extra: Any) -> dict[str, Any]:
    arm = extra.pop("arm", ROBOT)
    robot = {**arm, "initial": extra.pop("initial", arm.get("initial", READY)), **extra.pop("robot", {})}
    return {
        "world": {
            "kind": "spatial",
            "name": name,
            "bounds": [-1.2, -1.2, -0.2, 1.2, 1.2, 1.6],
            "robot": robot,
            "obstacle_names": list(obstacles),
            "obstacles": obstacles,
            **extra,
        }
    }


PROBLEMS: dict[str, dict[str, Any]] = {
    "motion_post": world(
        "motion_post",
        {
            "table": TABLE,
            "post": {"shape": "box", "size": [0.08, 0.08, 0.9], "pose": [0.5, 0.0, 0.55, 0, 0, 0]},
            "shelf": {"shape": "box", "size": [0.4, 0.4, 0.04], "pose": [0.0, 0.6, 0.9, 0, 0, 0]},
        },
        initial=[0.8, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8],
        robot={"goal": [-0.8, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8]},
    ),
    "motion_frame": world(
        "motion_frame",
        {
            "table": TABLE,
            "left": {"shape": "box", "size": [0.06, 0.06, 0.7], "pose": [0.5, 0.3, 0.47, 0, 0, 0]},
            "right": {"shape": "box", "size": [0.06, 0.06, 0.7], "pose": [0.5, -0.3, 0.47, 0, 0, 0]},
            "bar": {"shape": "box", "size": [0.06, 0.66, 0.06], "pose": [0.5, 0.0, 0.85, 0, 0, 0]},
        },
        initial=[0.002, -0.042, -0.002, -2.334, 0.0, 2.293, 0.785],
        robot={"goal": [0.921, 0.45, -0.097, -1.649, 0.049, 2.097, 1.594]},
    ),
    "table": world(
        "table",
        {"table": TABLE},
        supports=["table"],
        object={**BOX, "initial": [0.5, 0.3, 0.18, 0, 0, 0.3], "goal": [0.5, -0.3, 0.18, 0, 0, 0], "grasps": TOP_DOWN},
    ),
    "table_ur5": world(
        "table_ur5",
        {"table": TABLE},
        arm=UR5,
        supports=["table"],
        object={**BOX, "initial": [0.5, 0.3, 0.18, 0, 0, 0.3], "goal": [0.5, -0.3, 0.18, 0, 0, 0], "grasps": TOP_DOWN},
    ),
    "shelf": world(
        "shelf",
        {
            "table": TABLE,
            "board": {"shape": "box", "size": [0.3, 0.3, 0.04], "pose": [0.0, 0.55, 0.4, 0, 0, 0]},
            "roof": {"shape": "box", "size": [0.3, 0.3, 0.04], "pose": [0.0, 0.55, 0.95, 0, 0, 0]},
        },
        supports=["table", "board"],
        object={**BOX, "initial": [0.5, 0.2, 0.18, 0, 0, 0], "goal": [0.0, 0.55, 0.48, 0, 0, 0], "grasps": TOP_DOWN},
    ),
    "clutter": world(
        "clutter",
        {
            "table": TABLE,
            "c1": {"shape": "box", "size": [0.08, 0.08, 0.2], "pose": [0.5, 0.0, 0.22, 0, 0, 0]},
            "c2": {"shape": "cylinder", "size": [0.25, 0.04], "pose": [0.6, 0.15, 0.245, 0, 0, 0]},
            "c3": {"shape": "box", "size": [0.06, 0.2, 0.15], "pose": [0.4, -0.15, 0.195, 0, 0, 0.3]},
            "c4": {"shape": "sphere", "size": [0.05], "pose": [0.65, -0.2, 0.17, 0, 0, 0]},
        },
        supports=["table"],
        object={
            "shape": "cylinder",
            "size": [0.1, 0.025],
            "initial": [0.45, 0.3, 0.17, 0, 0, 0],
            "goal": [0.55, -0.35, 0.17, 0, 0, 0],
            "grasps": [v for k in range(4) for v in (0, 0, 0.01, math.pi, 0, k * math.pi / 4)],
        },
    ),
    "on_side": world(
        "on_side",
        {"table": TABLE},
        supports=["table"],
        object={
            **BOX,
            "initial": [0.5, 0.25, 0.18, 0, 0, math.pi],
            "goal": [0.5, -0.25, 0.14, 0, -math.pi / 2, 0],
            "grasps": TOP_DOWN + SIDE,
        },
    ),
}


def invalid_pieces(built: SpatialWorld, result: PlanResult) -> int:
    """Pieces of the plan with a configuration its mode's checker calls invalid, at the validator's 0.002 rad
    (transits: :func:`validate_transit` with the object resting where it lies; transfers: the object held)."""
    space = SpatialSpace(built)
    resting = space.initial_object_pose
    steps = np.full(space.dof, ValidationSettings().step_rad)
    bad = 0
    for segment in result.segments:
        path = np.array(segment.waypoints)
        if segment.kind == "transit":
            bad += len(validate_transit(space.transit_checker(resting), path))
            continue
        assert segment.grasp is not None
        rel = space.grasp_rel(segment.grasp)
        checker = space.transfer_checker(rel)
        bad += sum(
            not checker.valid(validation_samples(path[i], path[i + 1], steps)).all() for i in range(len(path) - 1)
        )
        resting = space.held_object_poses(path[-1:], rel)[0]
    return bad


def run(name: str, built: SpatialWorld, seeds: int, time_limit: float) -> None:
    times, travel, first, transfers, ok, invalid = [], [], [], [], 0, 0
    for seed in range(seeds):
        start = time.perf_counter()
        result = plan(built, PlannerSettings(seed=seed, time_limit=time_limit))
        elapsed = time.perf_counter() - start
        times.append(elapsed)
        print(f"  {name:<13} seed {seed}: {result.outcome.name:<22} {elapsed:6.2f} s  {result.message[:90]}")
        if result.success:
            ok += 1
            travel.append(result.stats["joint_travel_rad"])
            first.append(result.stats["first_joint_travel_rad"])
            transfers.append(result.stats.get("transfers", 0))
            invalid += invalid_pieces(built, result)
    median = statistics.median
    print(
        f"{name:<13} success {ok}/{seeds}  time median {median(times):.2f} s max {max(times):.2f} s  "
        + (
            f"travel median {median(travel):.2f} rad (first plan {median(first):.2f})  "
            f"transfers {min(transfers)}-{max(transfers)}  invalid pieces {invalid}"
            if ok
            else ""
        )
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--time-limit", type=float, default=20.0)
    parser.add_argument("--problems", nargs="*", default=list(PROBLEMS), choices=list(PROBLEMS))
    args = parser.parse_args(argv)
    built = {name: spatial_world_from_parameters(PROBLEMS[name], CONFIG) for name in args.problems}
    for name in args.problems:  # compiles (or loads) the kernels: not timed
        plan(built[name], PlannerSettings(seed=99, time_limit=5.0))
        break
    for name in args.problems:
        run(name, built[name], args.seeds, args.time_limit)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
