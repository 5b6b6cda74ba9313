"""Before and after by work, not time: ``python -m benchmarks.work_ab --baseline REV [--only WORLDS] ...``.

On a shared machine wall time says more about the neighbours than about a
change. The work a plan takes does not: free intervals computed (the
``collision_checks`` stat), GA evaluations and landmarks are the same for
the same code, world and seed whatever the machine's load. This plans every
world with the code of git revision ``REV`` (exported with ``git archive``)
and with this checkout, world by world, one process each
(:mod:`benchmarks.worker`, the kernel on one thread so that runs do not
fight over cores), and prints per world: found, median free intervals,
median landmarks, median wall time (for what it is worth) before → after.
A generous ``--time-limit`` keeps the success rate a property of the
algorithm rather than of the load.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

from benchmarks.families import all_worlds, select
from benchmarks.run import ROOT, _export


def _runs(tree: Path, world: str, seeds: int, time_limit_s: float) -> list[dict]:
    env = dict(os.environ, PYTHONPATH=str(tree), NUMBA_NUM_THREADS="1")
    command = [sys.executable, "-m", "benchmarks.worker", world, "--seeds", str(seeds)]
    command += ["--time-limit", str(time_limit_s), "--no-validate"]
    done = subprocess.run(command, cwd=tree, env=env, capture_output=True, text=True, check=False)
    if done.returncode:
        raise SystemExit(f"work_ab: {world} in {tree}: {done.stderr.strip()[-2000:]}")
    runs: list[dict] = json.loads(done.stdout.strip().splitlines()[-1])["runs"]
    return runs


def _summary(runs: list[dict]) -> tuple[str, float, float, float]:
    found = sum(r["success"] for r in runs)
    return (
        f"{found}/{len(runs)}",
        statistics.median(r["collision_checks"] for r in runs),
        statistics.median(r["landmarks"] for r in runs),
        statistics.median(r["wall_s"] for r in runs),
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.work_ab", description=__doc__.split("\n\n")[0])
    parser.add_argument("--baseline", required=True, help="git revision to compare with")
    parser.add_argument("--only", default="figure1,single_transfer,arm3_regrasp,arm5_regrasp,joints_*,obstacles_*")
    parser.add_argument("--seeds", type=int, default=6)
    parser.add_argument("--time-limit", type=float, default=20.0, help="per run (s), generous on purpose")
    args = parser.parse_args(argv)
    worlds = [w.name for w in select(all_worlds(), args.only)]
    before = _export(args.baseline)
    print(f"work_ab: {args.baseline} -> this checkout, {args.seeds} seeds, limit {args.time_limit:g} s", flush=True)
    print("| world | found | free intervals (median) | landmarks (median) | wall s (median) |")
    print("|---|--:|--:|--:|--:|")
    for world in worlds:
        a = _summary(_runs(before, world, args.seeds, args.time_limit))
        b = _summary(_runs(ROOT, world, args.seeds, args.time_limit))
        ratio = a[1] / b[1] if b[1] else float("nan")
        print(
            f"| {world} | {a[0]} → {b[0]} | {a[1]:,.0f} → {b[1]:,.0f} (x{ratio:.2f}) | {a[2]:.0f} → {b[2]:.0f} "
            f"| {a[3]:.2f} → {b[3]:.2f} |",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
