"""Before and after on the generated families, in one run: ``python -m benchmarks compare --baseline REV
generated_families [--families A,B] [--config-worlds figure1,...] [--worlds 3] [--first-world 0] [--seeds 2]
[--time-limit 10] [--jobs 2] [--out DIR]``.

The worlds of ``config/`` named (default figure1), each a row of its own, and the generated families' worlds,
generated once by this checkout (:mod:`benchmarks.generated`, as ``clew_world`` writes
them), then every (world, seed) is planned twice, by ``clew_plan`` of git revision ``REV`` (exported with
``git archive``) and by this checkout's, one right after the other, each in a process of its own with the
kernel on one thread (``NUMBA_NUM_THREADS=1``), ``--jobs`` such pairs at a time. ``clew_plan`` is the
entry point every revision has, so the baseline needs nothing newer than its own code. Times are the
planner's own (``stats.time_s``: process start-up left out). The table per family, before → after:
success, median time (a failed run on a solvable world counts at the limit), median landmarks, and over
the plans found, median transfers and joint travel; and, over the runs that neither side ended at the time
limit (a run stopped by the clock stops wherever the load let it get), how many gave the same plan file before and
after (every field but ``stats.time_s``: same seed, same plan). ``DIR/families_ab.json`` keeps every run.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarks.compare import ROOT, export
from benchmarks.families_run import _fmt, summarise
from benchmarks.generated import add_first_world, build_world, reference_world, world_seeds
from benchmarks.report import command_line, header, write_report
from clew_ros.worlds import FAMILIES


def plan_with(tree: Path, world: str, seed: int, time_limit_s: float, output: Path) -> dict:
    """``clew_plan WORLD --seed S --time-limit T`` with the code of ``tree``; the run's figures."""
    env = dict(os.environ, PYTHONPATH=str(tree), NUMBA_NUM_THREADS="1")
    command = [sys.executable, "-m", "clew_ros.cli.plan", world, "-o", str(output), "--seed", str(seed)]
    command += ["--time-limit", str(time_limit_s), "-q"]
    done = subprocess.run(command, cwd=tree, env=env, capture_output=True, text=True, check=False)
    if done.returncode not in (0, 1):
        raise SystemExit(f"families_ab: {' '.join(command)} in {tree}: {done.stderr.strip()[-2000:]}")
    plan = json.loads(output.read_text())
    stats = plan["stats"]
    success = bool(plan["success"])
    return {
        "world": Path(world).stem,
        "seed": seed,
        "outcome": plan.get("code", "SUCCEEDED" if success else "FAILED"),
        "success": success,
        "wall_s": float(stats["time_s"]),
        "cpu_s": None,
        "landmarks": stats.get("landmarks"),
        "transfers": sum(s["kind"] == "transfer" for s in plan["segments"]) if success else None,
        "travel_rad": stats.get("joint_travel_rad") if success else None,
    }


def same_plan(before: Path, after: Path) -> bool:
    """Whether two plan files are the same but for the clock (``stats.time_s``)."""
    plans = [json.loads(path.read_text()) for path in (before, after)]
    for plan in plans:
        plan.get("stats", {}).pop("time_s", None)
    return bool(plans[0] == plans[1])


def _change(before: float | None, after: float | None, digits: int = 2) -> str:
    return f"{_fmt(before, digits)} → {_fmt(after, digits)}"


def _success(row: dict) -> str:
    if row["solvable"]:
        return f"{row['successes']}/{row['runs']}"
    return f"{row['no_path']}/{row['runs']} NO_PATH"


def markdown(before: list[dict], after: list[dict]) -> str:
    """The before → after table in Markdown."""
    lines = [
        "| family | n | success | median s | landmarks | transfers | travel rad | same plan file |",
        "|---|--:|--:|--:|--:|--:|--:|--:|",
    ]
    for a, b in zip(before, after, strict=True):
        lines.append(
            f"| {a['family']} | {a['joints']} | {_success(a)} → {_success(b)} "
            f"| {_change(a['median_s'], b['median_s'])} "
            f"| {_change(a['landmarks_median'], b['landmarks_median'], 0)} "
            f"| {_change(a['transfers_median'], b['transfers_median'], 0)} "
            f"| {_change(a['travel_median'], b['travel_median'], 1)} "
            f"| {b.get('same_plans', 0)}/{b.get('compared', 0)} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks compare --baseline REV generated_families", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("--baseline", required=True, help="git revision to compare with")
    parser.add_argument("--families", default=",".join(FAMILIES), help="comma-separated (default: all)")
    parser.add_argument(
        "--config-worlds", default="figure1", help="comma-separated worlds of config/, each a row (default figure1)"
    )
    parser.add_argument("--worlds", type=int, default=3, help="worlds per family, seeds K..K+W-1")
    add_first_world(parser)
    parser.add_argument("--seeds", type=int, default=2, help="planner seeds per world, 0..S-1")
    parser.add_argument("--time-limit", type=float, default=10.0, help="per run, s")
    parser.add_argument("--jobs", type=int, default=2, help="(world, seed) pairs planned at once")
    parser.add_argument("--out", type=Path, default=Path("bench_out"), help="where families_ab.json/.md go")
    args = parser.parse_args(argv)
    families = [f for f in args.families.split(",") if f]
    unknown = [f for f in families if f not in FAMILIES]
    if unknown:
        parser.error(f"--families: unknown {unknown}; expected some of {list(FAMILIES)}")
    baseline = export(args.baseline)
    started, load = time.monotonic(), os.getloadavg()[0]
    with tempfile.TemporaryDirectory(prefix="clew_families_ab_") as scratch:
        directory = Path(scratch)
        configs = [reference_world(name) for name in args.config_worlds.split(",") if name]
        worlds = configs + [build_world(f, s, directory) for s in world_seeds(args, args.worlds) for f in families]
        tasks = [(w, seed) for seed in range(args.seeds) for w in worlds]

        def pair(index: int) -> tuple[dict, dict]:
            world, seed = tasks[index]
            outputs = [directory / f"plan_{index}_{side}.json" for side in ("before", "after")]
            before = plan_with(baseline, world.path, seed, args.time_limit, outputs[0])
            after = plan_with(ROOT, world.path, seed, args.time_limit, outputs[1])
            after["same_plan"] = same_plan(*outputs)
            return before, after

        with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
            pairs = []
            for done, result in enumerate(pool.map(pair, range(len(tasks))), start=1):
                pairs.append(result)
                if done % 10 == 0:
                    print(f"  {done}/{len(tasks)} pairs, {time.monotonic() - started:.0f} s", file=sys.stderr)
    rows: dict[str, list[dict]] = {"before": [], "after": []}
    for family in [*(w.family for w in configs), *families]:
        chosen = [w for w in worlds if w.family == family]
        indices = [i for i, (w, _) in enumerate(tasks) if w.family == family]
        for side, column in (("before", 0), ("after", 1)):
            rows[side].append(summarise(family, chosen, [pairs[i][column] for i in indices], args.time_limit))
        compared = [i for i in indices if "TIME_LIMIT" not in (pairs[i][0]["outcome"], pairs[i][1]["outcome"])]
        rows["after"][-1]["compared"] = len(compared)
        rows["after"][-1]["same_plans"] = sum(bool(pairs[i][1]["same_plan"]) for i in compared)
    command = command_line("benchmarks.families_ab", argv)
    first = args.first_world
    what = f"{args.worlds} worlds (from {first}) x {args.seeds} seeds per family, limit {args.time_limit:g} s"
    text = f"{header(command, started, load, what, prefix=f'{args.baseline} → this checkout; ')}\n\n"
    text += f"{markdown(rows['before'], rows['after'])}\n"
    runs = [{"before": before, "after": after} for before, after in pairs]
    write_report(args.out, "families_ab", text, {"command": command, "rows": rows, "runs": runs})
    return 0


if __name__ == "__main__":
    sys.exit(main())
