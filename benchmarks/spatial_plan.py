"""``python -m benchmarks.spatial_plan [--seeds 5] [--time-limit 20] [--problems NAME ...]``: the Ariadne's Clew
planner on spatial worlds (issue 44), a handful of Panda problems.

Problems (all with the shipped Panda, ``config/robots/panda``, its mesh sphere model; a table 0.6 x 1.2 m in
front of it):

- ``motion_post``: motion-only, from one side of a 0.9 m post on the table to the other, a shelf board above;
- ``motion_reach``: motion-only, from the arm folded up to reaching over the table between two posts;
- ``table``: pick a 4 x 4 x 12 cm box on the table and put it down 0.6 m away (top-down grasps);
- ``shelf``: from the table onto a shelf board beside the arm, under a roof;
- ``on_side``: the box from standing to lying on its side (another face down: only the side grasps, from
  its +x face turned towards the arm, can do it; top-down grasps are offered too).

For each problem and seed (0 .. ``--seeds`` - 1): the outcome; then per problem the success rate, the median
and the largest planning time (s, wall, the first plan and its shortcuts), the median joint travel of the plan
(rad, the sum over joints of the absolute motion) and of the first plan before shortcuts, and the transfers.
Each world is built once (its sphere model), the kernels compiled by a warm-up plan before timing.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from pathlib import Path
from typing import Any

from clew_ros.core.settings import PlannerSettings
from clew_ros.spatial.space import plan
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


def world(name: str, obstacles: dict[str, Any], **extra: Any) -> dict[str, Any]:
    robot = {**ROBOT, "initial": extra.pop("initial", READY), **extra.pop("robot", {})}
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
    "motion_reach": world(
        "motion_reach",
        {
            "table": TABLE,
            "left": {"shape": "box", "size": [0.06, 0.06, 0.5], "pose": [0.45, 0.2, 0.37, 0, 0, 0]},
            "right": {"shape": "box", "size": [0.06, 0.06, 0.5], "pose": [0.45, -0.2, 0.37, 0, 0, 0]},
        },
        initial=[0.0, -1.2, 0.0, -2.8, 0.0, 1.8, 0.8],
        robot={"goal": [0.0, 0.6, 0.0, -1.6, 0.0, 2.2, 0.8]},
    ),
    "table": world(
        "table",
        {"table": TABLE},
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


def run(name: str, built: SpatialWorld, seeds: int, time_limit: float) -> None:
    times, travel, first, transfers, ok = [], [], [], [], 0
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
    median = statistics.median
    print(
        f"{name:<13} success {ok}/{seeds}  time median {median(times):.2f} s max {max(times):.2f} s  "
        + (
            f"travel median {median(travel):.2f} rad (first plan {median(first):.2f})  "
            f"transfers {min(transfers)}-{max(transfers)}"
            if ok
            else ""
        )
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--time-limit", type=float, default=20.0)
    parser.add_argument("--problems", nargs="*", default=list(PROBLEMS), choices=list(PROBLEMS))
    args = parser.parse_args()
    built = {name: spatial_world_from_parameters(PROBLEMS[name], CONFIG) for name in args.problems}
    for name in args.problems:  # compiles (or loads) the kernels: not timed
        plan(built[name], PlannerSettings(seed=99, time_limit=5.0))
        break
    for name in args.problems:
        run(name, built[name], args.seeds, args.time_limit)


if __name__ == "__main__":
    main()
