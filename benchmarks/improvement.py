"""``python -m benchmarks.improvement [--seeds N] [--improve-time S]``: what the anytime improvement gains.

For figure1, arm3_regrasp and arm5_regrasp, seeds ``0..N-1``: each seed planned
with ``planner.improve_time: 0`` (the first plan) and with the given budget;
prints a Markdown table row per world: plans found, median joint travel of
the first and the improved plan (rad), the gain, median transfers, and the
wall time the improvement added (median / max, s). docs/algorithm.md quotes it.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from clew_ros.core.clew import plan
from clew_ros.core.kernel import warm_up
from clew_ros.core.settings import PlannerSettings
from clew_ros.core.world import load_world

ROOT = Path(__file__).resolve().parents[1]
WORLDS = ("figure1", "arm3_regrasp", "arm5_regrasp")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--improve-time", type=float, default=None, help="default: planner.improve_time's default")
    args = parser.parse_args(argv)
    warm_up()
    for name in WORLDS:
        world = load_world(ROOT / "config" / f"{name}.yaml")
        rows: list[tuple[float, ...]] = []
        for seed in range(args.seeds):
            started = time.monotonic()
            first = plan(world, PlannerSettings(seed=seed, time_limit=120, improve_time=0.0))
            first_s = time.monotonic() - started
            started = time.monotonic()
            improving = {} if args.improve_time is None else {"improve_time": args.improve_time}
            better = plan(world, PlannerSettings(seed=seed, time_limit=120, **improving))
            added = time.monotonic() - started - first_s
            if first.success and better.success:
                s = better.stats
                rows.append(
                    (s["first_joint_travel_rad"], s["joint_travel_rad"], s["first_transfers"], s["transfers"], added)
                )

        def median(i: int, rows: list[tuple[float, ...]] = rows) -> float:
            return statistics.median(r[i] for r in rows)

        if not rows:
            print(f"| {name} | 0/{args.seeds} | | | | | |")
            continue
        print(
            f"| {name} | {len(rows)}/{args.seeds} | {median(0):.1f} | {median(1):.1f} | {median(0) / median(1):.2f}x "
            f"| {median(2):g} / {median(3):g} | {median(4):.2f} / {max(r[4] for r in rows):.2f} |",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
