"""The benchmark suite: ``python -m benchmarks.run [--quick] [--seeds N] [--out DIR] [--only PATTERN]``.

Run from the repository root with the package's venv. Steps, each in
subprocesses of its own so that memory figures belong to one world:

1. planner runs: every selected world (``config/*.yaml`` and the generated
   families of :mod:`benchmarks.families`), N seeds each, one worker process
   per world (:mod:`benchmarks.worker`), per-run time limit = the world's
   ``planner.time_limit`` (generated worlds: 30 s) unless ``--time-limit``;
2. collision throughput on figure1 and obstacles_32 (:mod:`benchmarks.throughput`);
3. the OMPL peer on transit sub-problems (:mod:`benchmarks.peer`);
4. a cProfile of one figure1 run (:mod:`benchmarks.profile`);

then prints a table and writes ``DIR/benchmarks.json``, ``DIR/benchmarks.csv``,
``DIR/benchmarks_scaling.png`` and ``DIR/profile_figure1.txt``. See docs/benchmarks.md.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import csv
import hashlib
import json
import os
import platform
import subprocess
import sys
import time
from importlib import metadata
from pathlib import Path

import numpy as np

from benchmarks.families import BenchWorld, all_worlds, select
from benchmarks.plot import plot_scaling

ROOT = Path(os.path.abspath(__file__)).parents[1]

#: Worlds of --quick: a fast one, the default one, a generated one.
QUICK_WORLDS = "single_transfer,figure1,obstacles_8"
#: Worlds of the peer comparison by default: one or two of each kind.
PEER_WORLDS = "figure1,arm5_regrasp,unreachable,joints_7,joints_10,obstacles_32"
THROUGHPUT_WORLDS = ("figure1", "obstacles_32")

COLUMNS = [
    "world", "family", "joints", "obstacles", "same_as", "seeds", "time_limit_s", "success_rate", "median_s", "p90_s",
    "median_success_s", "median_cpu_s", "p90_cpu_s", "landmarks_median", "evaluations_median",
    "collision_checks_median", "checks_per_s", "checks_per_cpu_s",
    "grasps_median", "valid_plans", "peak_rss_mb", "rss_growth_mb",
    "peer_problems", "project_success_rate", "ompl_success_rate", "project_median_s", "ompl_median_s",
    "time_ratio_project_over_ompl", "project_median_cpu_s", "ompl_median_cpu_s", "cpu_ratio_project_over_ompl",
    "peer_note",
]


def _environment() -> dict[str, str]:
    env = dict(os.environ)
    for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        env[name] = "1"
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT)] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p])
    return env


def _child(module: str, *args: str, timeout: float) -> dict:
    """Run ``python -m module args`` and return the JSON object it prints (or an error record)."""
    command = [sys.executable, "-m", module, *args]
    try:
        done = subprocess.run(command, cwd=ROOT, env=_environment(), capture_output=True, text=True,
                              timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"error": f"{' '.join(command[2:])}: no answer within {timeout:.0f} s"}
    lines = [line for line in done.stdout.splitlines() if line.startswith("{")]
    if done.returncode != 0 or not lines:
        tail = done.stderr.strip().splitlines()[-3:]
        return {"error": f"{' '.join(command[2:])}: exit {done.returncode}: {' | '.join(tail)}"}
    return json.loads(lines[-1])


def _machine() -> dict:
    model = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    versions = {}
    for name in ("numpy", "shapely", "ompl", "matplotlib"):
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    import shapely

    return {"nproc": os.cpu_count(), "cpu_model": model, "python": platform.python_version(),
            "platform": platform.platform(), "geos": shapely.geos_version_string, **versions,
            "loadavg_start": os.getloadavg()}


def _provenance() -> dict:
    """Which planner code was measured: the clew_ros imported by the workers, its core's hash, git state."""
    import clew_ros

    package = Path(clew_ros.__file__).parent
    digest = hashlib.sha256()
    for path in sorted((package / "core").glob("*.py")):
        digest.update(path.name.encode() + path.read_bytes())
    out = {"clew_ros": str(package), "core_sha256": digest.hexdigest()[:16], "git_head": None, "core_dirty": None}
    try:
        out["git_head"] = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=package, capture_output=True,
                                         text=True, check=True).stdout.strip()
        status = subprocess.run(["git", "status", "--porcelain", "--", "core"], cwd=package, capture_output=True,
                                text=True, check=True).stdout
        out["core_dirty"] = bool(status.strip())
    except (OSError, subprocess.CalledProcessError):
        pass
    return out


def _dedupe(worlds: list[BenchWorld], limits: dict[str, float]) -> dict[str, str]:
    """``{name: first name}`` for worlds equal to an earlier one (world tree but its name, and limit)."""
    seen: dict[str, str] = {}
    same: dict[str, str] = {}
    for world in worlds:
        tree = dict(world.parameters["world"])
        tree.pop("name", None)
        key = json.dumps(tree, sort_keys=True) + f"|{limits[world.name]}"
        if key in seen:
            same[world.name] = seen[key]
        else:
            seen[key] = world.name
    return same


def _percentile(values: list[float], q: float) -> float | None:
    return float(np.percentile(values, q)) if values else None


def _median(values: list[float]) -> float | None:
    return float(np.median(values)) if values else None


def _summarise_world(world: BenchWorld, record: dict, same_as: str | None) -> dict:
    row = {"world": world.name, "family": world.family, "joints": world.joints, "obstacles": world.obstacles,
           "same_as": same_as or ""}
    if "error" in record:
        row.update(seeds=0, time_limit_s=None, success_rate=None, peer_note="", error=record["error"])
        return row
    runs = record["runs"]
    walls = [r["wall_s"] for r in runs]
    cpus = [r["cpu_s"] for r in runs]
    checks = sum(r["collision_checks"] for r in runs)
    successes = [r for r in runs if r["success"]]
    validated = [r["valid"] for r in successes if r["valid"] is not None]
    row.update(
        seeds=len(runs),
        time_limit_s=record["time_limit_s"],
        success_rate=len(successes) / len(runs) if runs else None,
        median_s=_median(walls),
        p90_s=_percentile(walls, 90),
        median_success_s=_median([r["wall_s"] for r in successes]),
        median_cpu_s=_median(cpus),
        p90_cpu_s=_percentile(cpus, 90),
        landmarks_median=_median([r["landmarks"] for r in runs]),
        evaluations_median=_median([r["evaluations"] for r in runs]),
        collision_checks_median=_median([r["collision_checks"] for r in runs]),
        checks_per_s=checks / sum(walls) if sum(walls) > 0 else None,
        checks_per_cpu_s=checks / sum(cpus) if sum(cpus) > 0 else None,
        grasps_median=_median([r["grasps"] for r in successes]),
        valid_plans=f"{sum(validated)}/{len(validated)}" if validated else "",
        peak_rss_mb=record["peak_rss_mb"],
        rss_growth_mb=record["peak_rss_mb"] - record["rss_before_mb"],
    )
    return row


def _summarise_peer(record: dict) -> dict:
    if "error" in record:
        return {"peer_problems": None, "peer_note": record["error"][:200]}
    project = record["project"]
    out = {"peer_problems": record["problems"],
           "project_success_rate": sum(r["success"] for r in project) / max(1, len(project)),
           "project_median_s": _median([r["wall_s"] for r in project]),
           "project_median_cpu_s": _median([r["cpu_s"] for r in project])}
    if not record["ompl_available"]:
        out.update(ompl_success_rate="n/a", ompl_median_s="n/a", time_ratio_project_over_ompl="n/a",
                   ompl_median_cpu_s="n/a", cpu_ratio_project_over_ompl="n/a",
                   peer_note=f"OMPL n/a: {record['ompl_reason']}")
        return out
    ompl = record["ompl"]
    out["ompl_success_rate"] = sum(r["success"] for r in ompl) / max(1, len(ompl))
    out["ompl_median_s"] = _median([r["wall_s"] for r in ompl])
    out["time_ratio_project_over_ompl"] = (out["project_median_s"] / out["ompl_median_s"]
                                           if out["ompl_median_s"] else None)
    out["ompl_median_cpu_s"] = _median([r["cpu_s"] for r in ompl])
    out["cpu_ratio_project_over_ompl"] = (out["project_median_cpu_s"] / out["ompl_median_cpu_s"]
                                          if out["ompl_median_cpu_s"] else None)
    both = [(p["wall_s"], o["wall_s"]) for p, o in zip(project, ompl) if p["success"] and o["success"]]
    out["peer_note"] = (f"both solved {len(both)}; median per-problem ratio "
                        f"{np.median([p / o for p, o in both]):.2f}" if both else "no problem solved by both")
    return out


def _format(value, digits: int = 2) -> str:
    if value is None or value == "":
        return "-"
    if isinstance(value, float):
        return f"{value:.{digits}f}" if abs(value) < 1e5 else f"{value:.3g}"
    return str(value)


def print_table(rows: list[dict], file=sys.stdout) -> None:
    header = ["world", "n", "obs", "seeds", "limit", "success", "median s", "p90 s", "cpu s", "landmarks", "evals",
              "intervals", "intervals/cpu s", "RSS MB", "peer proj/ompl"]
    lines = [header]
    for r in rows:
        if r.get("error"):
            lines.append([r["world"], str(r["joints"]), str(r["obstacles"])] + ["error"] + [""] * 11)
            continue
        peer = "-"
        if r.get("peer_problems"):
            o = r.get("ompl_success_rate")
            ompl = f"{100 * o:.0f}%" if isinstance(o, float) else "n/a"
            ratio = r.get("time_ratio_project_over_ompl")
            peer = f"{100 * r['project_success_rate']:.0f}%/{ompl} x{_format(ratio)}"
        lines.append([r["world"] + (f" (={r['same_as']})" if r["same_as"] else ""), str(r["joints"]),
                      str(r["obstacles"]), str(r["seeds"]), _format(r["time_limit_s"], 0),
                      f"{100 * r['success_rate']:.0f}%", _format(r["median_s"]), _format(r["p90_s"]),
                      _format(r["median_cpu_s"]), _format(r["landmarks_median"], 0),
                      _format(r["evaluations_median"], 0), _format(r["collision_checks_median"], 0),
                      _format(r["checks_per_cpu_s"], 0),
                      _format(r["peak_rss_mb"], 0), peer])
    widths = [max(len(line[i]) for line in lines) for i in range(len(header))]
    for index, line in enumerate(lines):
        print("  ".join(cell.ljust(w) if i == 0 else cell.rjust(w) for i, (cell, w) in enumerate(zip(line, widths))),
              file=file)
        if index == 0:
            print("  ".join("-" * w for w in widths), file=file)


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.run", description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help=f"2 seeds on {QUICK_WORLDS}, 5 s limit, small throughput and peer samples")
    parser.add_argument("--seeds", type=int, default=None, help="seeds per world (default 20; --quick 2)")
    parser.add_argument("--seeds-for", action="append", default=[], metavar="WORLD=N",
                        help="seeds for one world, e.g. figure1=20 (repeatable)")
    parser.add_argument("--out", type=Path, default=Path("bench_out"), help="output directory (default bench_out)")
    parser.add_argument("--only", default=None, help="worlds to run: glob(s), comma-separated (e.g. 'joints_*')")
    parser.add_argument("--time-limit", type=float, default=None, help="per-run limit (s) for every world")
    parser.add_argument("--jobs", type=int, default=1,
                        help="worlds planned (and peer worlds compared) at once; default 1. 2 on a 2-core "
                             "machine halves the wall time, at some cost in per-run timing")
    parser.add_argument("--peer-only", default=None, help=f"worlds of the OMPL comparison (default {PEER_WORLDS})")
    parser.add_argument("--peer-problems", type=int, default=None, help="transit sub-problems per world (default 20)")
    parser.add_argument("--peer-time-limit", type=float, default=None,
                        help="per sub-problem and planner (default 10 s)")
    parser.add_argument("--peer-step-rad", type=float, default=0.002, help="OMPL motion-check step (rad, L2)")
    parser.add_argument("--throughput-configs", type=int, default=None, help="random configurations (default 100000)")
    parser.add_argument("--no-peer", action="store_true")
    parser.add_argument("--no-throughput", action="store_true")
    parser.add_argument("--no-profile", action="store_true")
    parser.add_argument("--no-validate", action="store_true", help="skip validate_plan on successful plans")
    return parser


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    quick = args.quick
    seeds = args.seeds if args.seeds is not None else (2 if quick else 20)
    seeds_for = {}
    for item in args.seeds_for:
        name, _, count = item.partition("=")
        seeds_for[name] = int(count)
    worlds = select(all_worlds(), args.only or (QUICK_WORLDS if quick else None))
    if not worlds:
        print(f"benchmarks.run: no world matches --only {args.only!r}", file=sys.stderr)
        return 2
    limits = {w.name: args.time_limit or (min(w.time_limit_s, 5.0) if quick else w.time_limit_s) for w in worlds}
    same = _dedupe(worlds, limits)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    started = time.monotonic()
    report: dict = {"command": " ".join(["python -m benchmarks.run"] + (argv if argv is not None else sys.argv[1:])),
                    "machine": _machine(), "code": _provenance(), "started": time.strftime("%Y-%m-%d %H:%M:%S")}

    # 1. planner runs, one worker process per distinct world
    to_run = [w for w in worlds if w.name not in same]
    # longest first (seeds x limit), so that --jobs 2 packs well
    to_run.sort(key=lambda w: -seeds_for.get(w.name, seeds) * limits[w.name])
    print(f"planner: {len(to_run)} world(s), {seeds} seed(s) each, jobs {args.jobs}", file=sys.stderr)

    def work(world: BenchWorld) -> tuple[str, dict]:
        count = seeds_for.get(world.name, seeds)
        limit = limits[world.name]
        t0 = time.monotonic()
        flags = ["--no-validate"] if args.no_validate else []
        record = _child("benchmarks.worker", world.name, "--seeds", str(count), "--time-limit", str(limit), *flags,
                        timeout=count * (limit * 1.5 + 30) + 120)
        record["loadavg_end"] = os.getloadavg()
        print(f"  {world.name}: {time.monotonic() - t0:.0f} s", file=sys.stderr)
        return world.name, record

    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        planner = dict(pool.map(work, to_run))
    report["planner"] = planner
    report["planner_wall_s"] = time.monotonic() - started

    # 2. collision throughput
    throughput = {}
    if not args.no_throughput:
        configs = args.throughput_configs or (5_000 if quick else 100_000)
        for name in THROUGHPUT_WORLDS:
            t0 = time.monotonic()
            throughput[name] = _child("benchmarks.throughput", name, "--configs", str(configs), timeout=1200)
            print(f"throughput {name}: {time.monotonic() - t0:.0f} s", file=sys.stderr)
    report["throughput"] = throughput

    # 3. peer comparison
    peer = {}
    if not args.no_peer:
        problems = args.peer_problems or (3 if quick else 20)
        peer_limit = args.peer_time_limit or (2.0 if quick else 10.0)
        chosen = select(worlds, args.peer_only or ("figure1" if quick else PEER_WORLDS))

        def compare(world: BenchWorld) -> tuple[str, dict]:
            t0 = time.monotonic()
            record = _child("benchmarks.peer", world.name, "--problems", str(problems), "--time-limit",
                            str(peer_limit), "--step-rad", str(args.peer_step_rad),
                            timeout=problems * 2 * (peer_limit + 5) + 120)
            print(f"peer {world.name}: {time.monotonic() - t0:.0f} s", file=sys.stderr)
            return world.name, record

        with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
            peer = dict(pool.map(compare, chosen))
    report["peer"] = peer

    # 4. profile
    if not args.no_profile and not quick and select(worlds, "figure1"):
        t0 = time.monotonic()
        prof = _child("benchmarks.profile", "figure1", "--seed", "0", "--time-limit", str(limits["figure1"]),
                      timeout=limits["figure1"] * 3 + 60)
        report["profile"] = prof
        if "error" not in prof:
            (out / "profile_figure1.txt").write_text(
                f"cProfile of figure1, seed 0: {prof['outcome']}, {prof['stats']}\n\n"
                f"Top by cumulative time:\n{prof['cumulative']}\n\nTop by own time (tottime):\n{prof['tottime']}\n")
        print(f"profile figure1: {time.monotonic() - t0:.0f} s", file=sys.stderr)

    # summary
    rows = []
    for world in worlds:
        source = same.get(world.name, world.name)
        row = _summarise_world(world, planner.get(source, {"error": "not run"}), same.get(world.name))
        if world.name in peer:
            row.update(_summarise_peer(peer[world.name]))
        else:
            row.update(peer_problems=None, peer_note="peer not run" if args.no_peer else "not in the peer selection")
        rows.append(row)
    report["rows"] = rows
    report["machine"]["loadavg_end"] = os.getloadavg()
    report["total_wall_s"] = time.monotonic() - started

    (out / "benchmarks.json").write_text(json.dumps(report, indent=1, default=str) + "\n")
    with open(out / "benchmarks.csv", "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=COLUMNS, extrasaction="ignore")
        writer.writeheader()
        for row in rows:
            writer.writerow({c: ("" if row.get(c) is None else row.get(c)) for c in COLUMNS})
    plot = plot_scaling([r for r in rows if not r.get("error") and r.get("median_s") is not None],
                        out / "benchmarks_scaling.png")

    print_table(rows)
    for name, t in throughput.items():
        if "error" in t:
            print(f"throughput {name}: {t['error']}")
            continue
        iv = t["intervals"]
        print(f"throughput {name}: batched is_valid {t['batched']['per_s']:,.0f}/s, per-config loop "
              f"{t['loop']['per_s']:,.0f}/s (x{t['ratio_batched_over_loop']:.1f}), is_valid batch of 1 "
              f"{t['batch1']['per_s']:,.0f}/s; agree {t['agree']}/{t['configs']}; free intervals/s transit "
              f"{iv['transit_b24']['per_s']:,.0f} (batch 24) {iv['transit_b1024']['per_s']:,.0f} (1024), "
              f"transfer {iv['transfer_b24']['per_s']:,.0f} / {iv['transfer_b1024']['per_s']:,.0f}")
    errors = [r for r in rows if r.get("error")] + [{"world": k, "error": v["error"]} for k, v in peer.items()
                                                    if "error" in v]
    for r in errors:
        print(f"error {r['world']}: {r['error']}", file=sys.stderr)
    print(f"wrote {out / 'benchmarks.json'}, {out / 'benchmarks.csv'}"
          + (f", {plot}" if plot else "") + f" in {report['total_wall_s']:.0f} s")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
