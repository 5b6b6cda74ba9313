"""The benchmark suite: ``python -m benchmarks.run [--quick] [--out DIR] [--doc docs/benchmarks.md] ...``.

Run from the repository root with the package's venv (the ``bench`` extra
adds OMPL and matplotlib: ``pip install -e '.[bench]'``). Steps, each in
subprocesses of its own so that memory figures belong to one world:

1. planner runs: every selected world (``config/*.yaml`` and the scaling
   series of :mod:`benchmarks.worlds`), N seeds each (default 20), one
   worker process per world (:mod:`benchmarks.worker`), ``--jobs`` worlds at
   once (default 2); per-run time limit: the world's ``planner.time_limit``
   capped at 5 s (``--full-limits``: uncapped; ``--time-limit S``: S for all);
2. collision throughput on figure1 and obstacles_32 (:mod:`benchmarks.throughput`);
3. the OMPL peer on transit sub-problems (:mod:`benchmarks.peer`);
4. a cProfile of one figure1 run (:mod:`benchmarks.profile`);

then prints a table and writes ``DIR/benchmarks.json``, ``DIR/benchmarks.csv``,
``DIR/benchmarks.md`` (the report in Markdown), ``DIR/benchmarks_scaling.png``
and ``DIR/profile_figure1.txt``. ``--doc PATH`` also puts the Markdown report
between the ``<!-- benchmarks:begin -->`` / ``<!-- benchmarks:end -->`` markers
of PATH and copies the plot next to it. See docs/benchmarks.md.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import csv
import hashlib
import json
import math
import os
import platform
import shutil
import subprocess
import sys
import time
from collections import Counter
from importlib import metadata
from pathlib import Path

import numpy as np

from benchmarks.compare import export
from benchmarks.plot import plot_scaling
from benchmarks.worlds import BenchWorld, all_worlds, select

ROOT = Path(__file__).absolute().parents[1]

#: Worlds of --quick: a fast one, the default one, one of each scaling series (obstacles_2 = joints_3).
QUICK_WORLDS = "single_transfer,figure1,joints_3,obstacles_2,obstacles_8"
#: Worlds of the peer comparison by default: one or two of each kind.
PEER_WORLDS = "figure1,arm5_regrasp,behind_wall,joints_7,joints_10,obstacles_32"
THROUGHPUT_WORLDS = ("figure1", "obstacles_32")
#: Processes whose free-interval figures are taken the median of (one process is one draw of a bimodal machine).
INTERVAL_PROCESSES = 3
#: Seeds of a full run for these worlds when ``--seeds`` is not given (issue 11's figure1 targets are over 40).
DEFAULT_SEEDS_FOR = {"figure1": 40}
#: Default per-run cap (s) on a world's own time limit: 20 seeds x 12 worlds fit in 10 min on 2 cores.
LIMIT_CAP_S = 5.0
QUICK_LIMIT_S = 3.0
#: Default time limit (s) of the profiled figure1 run (figure1's own limit is 60 s).
PROFILE_LIMIT_S = 30.0
DOC_BEGIN = "<!-- benchmarks:begin -->"
DOC_END = "<!-- benchmarks:end -->"

COLUMNS = [
    "world",
    "series",
    "joints",
    "obstacles",
    "same_as",
    "seeds",
    "time_limit_s",
    "success_rate",
    "median_s",
    "p90_s",
    "median_success_s",
    "first_plan_median_s",
    "first_plan_p90_s",
    "median_cpu_s",
    "p90_cpu_s",
    "landmarks_median",
    "evaluations_median",
    "collision_checks_median",
    "checks_per_s",
    "checks_per_cpu_s",
    "grasps_median",
    "travel_median",
    "first_travel_median",
    "valid_plans",
    "outcomes",
    "peak_rss_mb",
    "rss_growth_mb",
    "peer_problems",
    "project_success_rate",
    "ompl_success_rate",
    "project_median_s",
    "ompl_median_s",
    "time_ratio_project_over_ompl",
    "project_median_cpu_s",
    "ompl_median_cpu_s",
    "cpu_ratio_project_over_ompl",
    "peer_note",
]


def _environment() -> dict[str, str]:
    env = dict(os.environ)
    for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        env[name] = "1"
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT)] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p])
    return env


def _child(module: str, *args: str, timeout: float, tree: Path = ROOT) -> dict:
    """Run ``python -m module args`` in the checkout ``tree`` (default this one) and return the JSON
    object it prints (or an error record)."""
    command = [sys.executable, "-m", module, *args]
    env = _environment()
    if tree != ROOT:  # the baseline's own package and benchmarks first on the path
        env["PYTHONPATH"] = os.pathsep.join([str(tree), *env["PYTHONPATH"].split(os.pathsep)[1:]])
    try:
        done = subprocess.run(command, check=False, cwd=tree, env=env, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"error": f"{' '.join(command[2:])}: no answer within {timeout:.0f} s"}
    lines = [line for line in done.stdout.splitlines() if line.startswith("{")]
    if done.returncode != 0 or not lines:
        tail = done.stderr.strip().splitlines()[-3:]
        return {"error": f"{' '.join(command[2:])}: exit {done.returncode}: {' | '.join(tail)}"}
    try:
        return json.loads(lines[-1])
    except json.JSONDecodeError as error:
        return {"error": f"{' '.join(command[2:])}: unreadable output ({error})"}


def _git(*args: str) -> str:
    return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True, check=True).stdout.strip()


def _machine() -> dict:
    model = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    versions: dict[str, str | None] = {}
    for name in ("numpy", "shapely", "ompl", "matplotlib"):
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    import shapely

    return {
        "nproc": os.cpu_count(),
        "cpu_model": model,
        "python": platform.python_version(),
        "platform": platform.platform(),
        "geos": shapely.geos_version_string,
        **versions,
        "loadavg_start": os.getloadavg(),
    }


def _provenance() -> dict:
    """Which planner code was measured: the clew_ros imported by the workers, the hash of the planner's
    packages (``core`` and ``planar``), git state."""
    import clew_ros

    package = Path(clew_ros.__file__).parent
    digest = hashlib.sha256()
    for path in sorted([*(package / "core").rglob("*.py"), *(package / "planar").rglob("*.py")]):
        digest.update(str(path.relative_to(package)).encode() + path.read_bytes())
    out: dict[str, str | bool | None] = {
        "clew_ros": str(package),
        "core_sha256": digest.hexdigest()[:16],
        "git_head": None,
        "core_dirty": None,
    }
    try:
        out["git_head"] = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], cwd=package, capture_output=True, text=True, check=True
        ).stdout.strip()
        status = subprocess.run(
            ["git", "status", "--porcelain", "--", "core", "planar"],
            cwd=package,
            capture_output=True,
            text=True,
            check=True,
        ).stdout
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
    row = {
        "world": world.name,
        "series": world.series,
        "joints": world.joints,
        "obstacles": world.obstacles,
        "same_as": same_as or "",
    }
    if "error" in record:
        row.update(seeds=0, time_limit_s=None, success_rate=None, peer_note="", error=record["error"])
        return row
    runs = record["runs"]
    walls = [r["wall_s"] for r in runs]
    cpus = [r["cpu_s"] for r in runs]
    checks = sum(r["collision_checks"] for r in runs)
    successes = [r for r in runs if r["success"]]
    validated = [r["valid"] for r in successes if r["valid"] is not None]
    # the time to the first plan, before planner.improve_time's improvement (a failed run at its wall time);
    # None from code that did not report it (a baseline older than this column)
    firsts = [r.get("first_plan_s") if r["success"] else r["wall_s"] for r in runs]
    known = all(f is not None for f in firsts)
    row.update(
        first_plan_median_s=_median(firsts) if known and runs else None,
        first_plan_p90_s=_percentile(firsts, 90) if known and runs else None,
    )
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
        travel_median=_median([r["travel_rad"] for r in successes if r.get("travel_rad") is not None]),
        first_travel_median=_median(
            [r["first_travel_rad"] for r in successes if r.get("first_travel_rad") is not None]
        ),
        valid_plans=f"{sum(validated)}/{len(validated)}" if validated else "",
        outcomes=" ".join(
            f"{name}:{count}"
            for name, count in sorted(Counter(r["outcome"] for r in runs).items(), key=lambda item: -item[1])
        ),
        peak_rss_mb=record["peak_rss_mb"],
        rss_growth_mb=record["peak_rss_mb"] - record["rss_before_mb"],
    )
    return row


def _summarise_peer(record: dict) -> dict:
    if "error" in record:
        return {"peer_problems": None, "peer_note": record["error"][:200]}
    project = record["project"]
    out = {
        "peer_problems": record["problems"],
        "project_success_rate": sum(r["success"] for r in project) / max(1, len(project)),
        "project_median_s": _median([r["wall_s"] for r in project]),
        "project_median_cpu_s": _median([r["cpu_s"] for r in project]),
    }
    if not record["ompl_available"]:
        out.update(
            ompl_success_rate="n/a",
            ompl_median_s="n/a",
            time_ratio_project_over_ompl="n/a",
            ompl_median_cpu_s="n/a",
            cpu_ratio_project_over_ompl="n/a",
            peer_note=f"OMPL n/a: {record['ompl_reason']}",
        )
        return out
    ompl = record["ompl"]
    out["ompl_success_rate"] = sum(r["success"] for r in ompl) / max(1, len(ompl))
    out["ompl_median_s"] = _median([r["wall_s"] for r in ompl])
    out["time_ratio_project_over_ompl"] = (
        out["project_median_s"] / out["ompl_median_s"] if out["ompl_median_s"] else None
    )
    out["ompl_median_cpu_s"] = _median([r["cpu_s"] for r in ompl])
    out["cpu_ratio_project_over_ompl"] = (
        out["project_median_cpu_s"] / out["ompl_median_cpu_s"] if out["ompl_median_cpu_s"] else None
    )
    both = [(p["wall_s"], o["wall_s"]) for p, o in zip(project, ompl, strict=True) if p["success"] and o["success"]]
    out["peer_both_solved"] = len(both)
    out["peer_median_problem_ratio"] = float(np.median([p / o for p, o in both])) if both else None
    valid = {
        name: (sum(bool(r["valid"]) for r in runs if r["success"]), sum(r["success"] for r in runs))
        for name, runs in (("project", project), ("ompl", ompl))
    }
    out["peer_note"] = (
        (
            f"both solved {len(both)}, median per-problem ratio {out['peer_median_problem_ratio']:.2f}"
            if both
            else "no problem solved by both"
        )
        + f"; paths valid at 0.002 rad: project {valid['project'][0]}/{valid['project'][1]}, "
        f"OMPL {valid['ompl'][0]}/{valid['ompl'][1]}; OMPL checker "
        f"{record.get('ompl_checker', 'is_valid')}"
    )
    return out


def _format(value, digits: int = 2) -> str:
    if value is None or value == "":
        return "-"
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        return f"{value:,.{digits}f}" if abs(value) < 1e5 else f"{value:,.0f}"
    if isinstance(value, int):
        return f"{value:,}"
    return str(value)


def _percent(value) -> str:
    return f"{100 * value:.0f}%" if isinstance(value, float) else ("-" if value in (None, "") else str(value))


_SHORT = {
    "TIME_LIMIT": "limit",
    "NO_PATH_AT_RESOLUTION": "no path",
    "GOAL_OUT_OF_REACH": "out of reach",
    "INTERNAL_ERROR": "error",
}


def _failures(outcomes: str) -> str:
    """``"TIME_LIMIT:9 SUCCEEDED:11"`` -> ``"9 limit"``."""
    parts = [item.rpartition(":") for item in outcomes.split()]
    text = ", ".join(f"{count} {_SHORT.get(name, name.lower())}" for name, _, count in parts if name != "SUCCEEDED")
    return text or "-"


#: The printed (and Markdown) table: header, cell of a row.
TABLE = [
    ("world", lambda r: r["world"] + (f" (={r['same_as']})" if r["same_as"] else "")),
    ("n", lambda r: str(r["joints"])),
    ("obs", lambda r: str(r["obstacles"])),
    ("seeds", lambda r: str(r["seeds"])),
    ("limit s", lambda r: _format(r["time_limit_s"], 0)),
    ("success", lambda r: _percent(r["success_rate"])),
    ("median s", lambda r: _format(r["median_s"])),
    ("p90 s", lambda r: _format(r["p90_s"])),
    ("median ok s", lambda r: _format(r["median_success_s"])),
    (
        "first plan s median (p90)",
        lambda r: f"{_format(r.get('first_plan_median_s'))} ({_format(r.get('first_plan_p90_s'))})",
    ),
    ("median CPU s", lambda r: _format(r["median_cpu_s"])),
    ("landmarks", lambda r: _format(r["landmarks_median"], 0)),
    ("GA evals", lambda r: _format(r["evaluations_median"], 0)),
    ("checks", lambda r: _format(r["collision_checks_median"], 0)),
    ("checks/s", lambda r: _format(r["checks_per_s"], 0)),
    ("checks/CPU s", lambda r: _format(r["checks_per_cpu_s"], 0)),
    ("grasps", lambda r: _format(r["grasps_median"], 0)),
    (
        "travel rad (first plan)",
        lambda r: f"{_format(r.get('travel_median'), 1)} ({_format(r.get('first_travel_median'), 1)})",
    ),
    ("peak RSS MB", lambda r: _format(r["peak_rss_mb"], 0)),
    ("valid", lambda r: r["valid_plans"] or "-"),
    ("failures", lambda r: _failures(r["outcomes"])),
    (
        "peer success proj/OMPL",
        lambda r: (
            f"{_percent(r['project_success_rate'])}/{_percent(r['ompl_success_rate'])}"
            if r.get("peer_problems")
            else "-"
        ),
    ),
    (
        "peer time proj/OMPL",
        lambda r: (
            f"x{_format(r.get('time_ratio_project_over_ompl'))}"
            if r.get("peer_problems") and isinstance(r.get("time_ratio_project_over_ompl"), float)
            else ("n/a" if r.get("peer_problems") else "-")
        ),
    ),
]


def _cells(row: dict) -> list[str]:
    if row.get("error"):
        return [row["world"], str(row["joints"]), str(row["obstacles"]), "error"] + ["-"] * (len(TABLE) - 4)
    return [cell(row) for _, cell in TABLE]


def print_table(rows: list[dict], file=sys.stdout) -> None:
    lines = [[h for h, _ in TABLE]] + [_cells(r) for r in rows]
    widths = [max(len(line[i]) for line in lines) for i in range(len(TABLE))]
    for index, line in enumerate(lines):
        cells = enumerate(zip(line, widths, strict=True))
        print("  ".join(cell.ljust(w) if i == 0 else cell.rjust(w) for i, (cell, w) in cells), file=file)
        if index == 0:
            print("  ".join("-" * w for w in widths), file=file)


def _markdown_table(header: list[str], rows: list[list[str]], left: tuple[str, ...] = ("note",)) -> str:
    """A Markdown table; the first column and those named in ``left`` left-aligned, the others right-aligned."""
    align = ["---" if i == 0 or h in left else "--:" for i, h in enumerate(header)]
    return "\n".join("| " + " | ".join(cells) + " |" for cells in [header, align, *rows])


def throughput_line(name: str, t: dict) -> str:
    if "error" in t:
        return f"throughput {name}: {t['error']}"
    iv = t["intervals"]
    return (
        f"throughput {name}: batched is_valid {t['batched']['per_s']:,.0f}/s, per-config shapely loop "
        f"{t['loop']['per_s']:,.0f}/s (batched x{t['ratio_batched_over_loop']:.1f}), is_valid batch of 1 "
        f"{t['batch1']['per_s']:,.0f}/s; agree {t['agree']}/{t['configs']}; free intervals/s transit "
        f"{iv['transit_b24']['per_s']:,.0f} (batch 24) {iv['transit_b1024']['per_s']:,.0f} (1024), "
        f"transfer {iv['transfer_b24']['per_s']:,.0f} / {iv['transfer_b1024']['per_s']:,.0f}; decoded by a "
        f"population of 24: transit {iv['transit_decode24']['per_s']:,.0f}, "
        f"transfer {iv['transfer_decode24']['per_s']:,.0f}"
    )


def markdown_report(report: dict, plot_name: str | None) -> str:
    """The report as Markdown: machine, command, tables, plot, profile (what docs/benchmarks.md holds)."""
    m, code = report["machine"], report["code"]
    out = [
        (
            f"Generated by `{report['command']}` on {report['started']} in {report['total_wall_s'] / 60:.1f} min "
            f"(planner runs {report['planner_wall_s'] / 60:.1f} min)."
        ),
        "",
    ]
    out += [
        "| machine | |",
        "|---|---|",
        f"| CPU | {m['cpu_model']}, {m['nproc']} cores (`os.cpu_count()`) |",
        f"| load average (1 min) at start / end | {m['loadavg_start'][0]:.2f} / {m['loadavg_end'][0]:.2f} |",
        f"| Python | {m['python']} ({m['platform']}) |",
        f"| numpy / shapely / GEOS | {m['numpy']} / {m['shapely']} / {m['geos']} |",
        f"| ompl / matplotlib | {m['ompl'] or 'not installed'} / {m['matplotlib'] or 'not installed'} |",
        (
            f"| code | git {code['git_head']}{' + uncommitted core changes' if code['core_dirty'] else ''}, "
            f"`clew_ros/core` + `clew_ros/planar` sha256 {code['core_sha256']} |"
        ),
        "",
    ]
    rows = report["rows"]
    out += [
        "### Planner runs",
        "",
        (
            "Per world: seeds, per-run wall-clock limit, success rate, median and p90 wall time of all runs "
            "(a failed run counts at the limit), median wall time of the successful runs, median and p90 time "
            "to the first plan (before `planner.improve_time`'s improvement; a failed run at its wall time), "
            "median CPU time; "
            "medians of landmarks, GA evaluations and collision checks (free intervals: one configuration, "
            "one joint swept); checks per wall and per CPU second (all runs); of the successful runs, the median "
            "grasps and joint travel (sum over joints of |motion|, rad) of the plan returned and, in brackets, of "
            "the first plan found before `planner.improve_time`'s improvement; peak RSS of the world's worker; "
            "plans passing `validate_plan`; the failed runs by outcome (limit: `TIME_LIMIT`, no path: "
            "`NO_PATH_AT_RESOLUTION`); and, for the peer worlds, the transit comparison (success rates, "
            "ratio of median wall times project / OMPL)."
        ),
        "",
        _markdown_table([h for h, _ in TABLE], [_cells(r) for r in rows]),
        "",
    ]
    if plot_name:
        out += [f"![median time against joints and obstacles]({plot_name})", ""]
    if report.get("baseline", {}).get("rows"):
        out += [before_after(report), ""]
    out += _throughput_section(report.get("throughput") or {})
    out += _cold_start_section(report.get("cold_start") or {})
    out += _peer_section(report.get("peer") or {}, rows, m)
    out += _profile_section(report.get("profile"))
    return "\n".join(out)


def _throughput_section(throughput: dict) -> list[str]:
    out: list[str] = []
    if throughput:
        out += [
            "### Collision throughput (one core, CPU time)",
            "",
            (
                "Random configurations within the joint limits, object at its start pose. *batched*: "
                "`clew_ros.planar.collision.is_valid` on chunks of 10,000 configurations; *loop*: "
                "`benchmarks.throughput.PerStateChecker`, a Python loop over the configurations testing "
                "each link against prepared shapely geometry; *batch of 1*: `is_valid` called once per "
                "configuration; *free intervals*: `clew_ros.planar.manhattan.free_intervals`, the test the "
                "planner actually uses, per configuration and joint, called for one joint of a batch of 24 "
                "or 1024 configurations; *decoded 24*: the same intervals as the planner computes them, "
                "a population of 24 decoding its Manhattan paths of order 2 (24 x 2 x n intervals) in one "
                "`run_manhattan` call. Each free-interval figure is the median over "
                f"{INTERVAL_PROCESSES} processes of each one's fastest of 3 repeats (between processes "
                "the same loop runs up to 1.7x faster or slower on this machine); the range follows the table."
            ),
            "",
        ]
        header = [
            "world",
            "configs",
            "valid",
            "batched /s",
            "loop /s",
            "batched / loop",
            "batch of 1 /s",
            "agree",
            "intervals/s transit b24",
            "b1024",
            "decoded 24",
            "transfer b24",
            "b1024",
            "decoded 24",
        ]
        lines = []
        for name, t in throughput.items():
            if "error" in t:
                lines.append([name, "error"] + ["-"] * (len(header) - 2))
                continue
            iv = t["intervals"]
            lines.append(
                [
                    name,
                    f"{t['configs']:,}",
                    f"{100 * t['valid_fraction']:.0f}%",
                    f"{t['batched']['per_s']:,.0f}",
                    f"{t['loop']['per_s']:,.0f}",
                    f"x{t['ratio_batched_over_loop']:.2f}",
                    f"{t['batch1']['per_s']:,.0f}",
                    f"{t['agree']:,}/{t['configs']:,}",
                ]
                + [
                    f"{iv[k]['per_s']:,.0f}" if k in iv else "-"
                    for k in (
                        "transit_b24",
                        "transit_b1024",
                        "transit_decode24",
                        "transfer_b24",
                        "transfer_b1024",
                        "transfer_decode24",
                    )
                ]
            )
        out += [_markdown_table(header, lines), ""]
        for name, t in throughput.items():
            spread = t.get("intervals", {}).get("transit_b24", {}).get("per_s_processes")
            if spread and len(spread) > 1:
                rates = ", ".join(f"{r:,.0f}" for r in sorted(spread))
                out += [f"{name}, transit b24, per process: {rates}.", ""]
    return out


def _cold_start_section(cold: dict) -> list[str]:
    out: list[str] = []
    if cold and "error" not in cold:
        out += [
            "### Cold start (`python -m benchmarks.cold_start`)",
            "",
            (
                "The compiled kernel's cost at start, each in a fresh process: compiling it with an empty "
                "numba cache (the first start after an install), loading it from the cache (every later "
                "start), and, after that warm-up, figure1 seed 0 planned twice in one process (what the "
                "first plan still pays)."
            ),
            "",
            _markdown_table(
                ["compile s", "load from cache s", "import s", "first plan s", "second plan s", "first / second"],
                [
                    [
                        f"{cold['compile_s']:.1f}",
                        f"{cold['load_s']:.2f}",
                        f"{cold['import_s']:.2f}",
                        f"{cold['first_plan_s']:.3f}",
                        f"{cold['second_plan_s']:.3f}",
                        f"{cold['first_over_second']:.2f}",
                    ]
                ],
            ),
            "",
        ]
        if "node_first_plan_s" in cold:
            out += [
                (
                    f"The node `clew_planner` on its default world, `~/plan` called twice after a fresh start: "
                    f"first plan {cold['node_first_plan_s']:.3f} s, second {cold['node_second_plan_s']:.3f} s "
                    f"(first / second {cold['node_first_over_second']:.2f})."
                ),
                "",
            ]
        elif "node" in cold:
            out += [f"The node's first and second plan: not measured ({cold['node']}).", ""]
    elif cold:
        out += ["### Cold start", "", f"error: {cold['error']}", ""]
    return out


def _peer_section(peer: dict, rows: list[dict], m: dict) -> list[str]:
    out: list[str] = []
    if peer:
        settings: dict = next((p for p in peer.values() if "error" not in p), {})
        out += [
            "### Peer: OMPL RRTConnect on transit sub-problems",
            "",
            (
                f"{settings.get('problems', '-')} sub-problems per world (random valid start and goal "
                f"configurations at least 1 rad apart, object at rest), {settings.get('time_limit_s', '-')} s "
                f"per problem and planner. OMPL {m['ompl'] or 'not installed'}: RRTConnect, states checked by "
                f"the project's `is_valid`, motions every {settings.get('step_rad', '-')} rad by one batched "
                "`is_valid` call. Project: SEARCH (GA over Manhattan paths with free intervals, then "
                "refinement) towards the goal configuration, EXPLORE landmarks when it fails. "
                "Times are medians over all problems (failures at the limit)."
            ),
            "",
        ]
        header = [
            "world",
            "problems",
            "project success",
            "OMPL success",
            "project median s",
            "OMPL median s",
            "ratio project/OMPL",
            "project median CPU s",
            "OMPL median CPU s",
            "note",
        ]
        lines = []
        for name in peer:
            r = next(row for row in rows if row["world"] == name)
            lines.append(
                [
                    name,
                    _format(r.get("peer_problems")),
                    _percent(r.get("project_success_rate")),
                    _percent(r.get("ompl_success_rate")),
                    _format(r.get("project_median_s"), 3),
                    _format(r.get("ompl_median_s"), 3),
                    _format(r.get("time_ratio_project_over_ompl")),
                    _format(r.get("project_median_cpu_s"), 3),
                    _format(r.get("ompl_median_cpu_s"), 3),
                    r.get("peer_note", ""),
                ]
            )
        out += [_markdown_table(header, lines), ""]
    return out


def _profile_section(prof: dict | None) -> list[str]:
    out: list[str] = []
    if prof and "error" not in prof:
        stats = prof["stats"]
        out += [
            "### Profile of one figure1 run",
            "",
            (
                f"`python -m benchmarks.profile figure1 --seed {prof['seed']} --time-limit {prof['time_limit_s']:g}`"
                f": {prof['outcome']} in {stats.get('time_s', float('nan')):.2f} s "
                f"(under cProfile), {stats.get('landmarks')} landmarks, {stats.get('evaluations'):,} GA evaluations, "
                f"{stats.get('collision_checks'):,} free intervals. Own time by file (share of the profiled "
                f"{prof['profiled_s']:.1f} s):"
            ),
            "",
            _markdown_table(
                ["own time in", "s", "share"],
                [[f"`{f}`", f"{s:.2f}", f"{100 * share:.0f}%"] for f, s, share in prof["by_file"]],
            ),
            "",
            "The top functions by own and by cumulative time: `profile_figure1.txt` in the run's `--out` directory.",
            "",
        ]
    elif prof:
        out += ["### Profile of one figure1 run", "", f"error: {prof['error']}", ""]
    return out


def update_doc(doc: Path, markdown: str, plot: Path | None) -> None:
    """Put ``markdown`` between the markers of ``doc`` (appended when missing) and copy the plot next to it."""
    text = doc.read_text() if doc.exists() else ""
    block = f"{DOC_BEGIN}\n{markdown.rstrip()}\n{DOC_END}"
    if DOC_BEGIN in text and DOC_END in text:
        text = text[: text.index(DOC_BEGIN)] + block + text[text.index(DOC_END) + len(DOC_END) :]
    else:
        text = text.rstrip() + ("\n\n" if text else "") + block + "\n"
    doc.write_text(text)
    if plot is not None and plot.resolve() != (doc.parent / plot.name).resolve():
        shutil.copyfile(plot, doc.parent / plot.name)


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.run", description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--quick",
        action="store_true",
        help=f"2 seeds on {QUICK_WORLDS}, {QUICK_LIMIT_S:g} s limit, small throughput, peer and "
        "profile samples (the CI smoke test; about 40 s)",
    )
    parser.add_argument("--seeds", type=int, default=None, help="seeds per world (default 20; --quick 2)")
    parser.add_argument(
        "--seeds-for",
        action="append",
        default=[],
        metavar="WORLD=N",
        help=f"seeds for one world, e.g. figure1=20 (repeatable; a full run without --seeds: {DEFAULT_SEEDS_FOR})",
    )
    parser.add_argument("--out", type=Path, default=Path("bench_out"), help="output directory (default bench_out)")
    parser.add_argument(
        "--doc",
        type=Path,
        default=None,
        help="also write the Markdown report into this file between its markers, and copy the "
        "plot next to it (e.g. docs/benchmarks.md)",
    )
    parser.add_argument(
        "--render",
        type=Path,
        default=None,
        metavar="JSON",
        help="plan nothing: re-write table, CSV, Markdown, plot (and --doc) from a saved "
        "benchmarks.json with this version of the summary code",
    )
    parser.add_argument("--only", default=None, help="worlds to run: glob(s), comma-separated (e.g. 'joints_*')")
    parser.add_argument("--time-limit", type=float, default=None, help="per-run limit (s) for every world")
    parser.add_argument(
        "--full-limits",
        action="store_true",
        help=f"each world's own planner.time_limit (default: capped at {LIMIT_CAP_S:g} s)",
    )
    parser.add_argument(
        "--baseline",
        default=None,
        metavar="REV",
        help="also plan every world with the code of git revision REV (exported to a temporary "
        "directory), world by world alternating with this code, and report before/after",
    )
    parser.add_argument(
        "--jobs",
        type=int,
        default=1,
        help="worlds planned (and peer worlds compared) at once; default 1: the planner's kernel "
        "uses every core (planner.threads 0), and one world at a time gives steadier times",
    )
    parser.add_argument("--peer-only", default=None, help=f"worlds of the OMPL comparison (default {PEER_WORLDS})")
    parser.add_argument(
        "--peer-problems", type=int, default=None, help="transit sub-problems per world (default 20; --quick 3)"
    )
    parser.add_argument(
        "--peer-time-limit", type=float, default=None, help="per sub-problem and planner (default 5 s; --quick 2 s)"
    )
    parser.add_argument("--peer-step-rad", type=float, default=0.002, help="OMPL motion-check step (rad, L2)")
    parser.add_argument(
        "--peer-checker",
        choices=("is_valid", "loop"),
        default="is_valid",
        help="OMPL's validity test: the project's is_valid (default) or the per-state shapely loop",
    )
    parser.add_argument(
        "--throughput-configs", type=int, default=None, help="random configurations (default 100000; --quick 2000)"
    )
    parser.add_argument(
        "--profile-time-limit",
        type=float,
        default=None,
        help=f"time limit of the profiled figure1 run (default {PROFILE_LIMIT_S:g} s; --quick {QUICK_LIMIT_S:g} s)",
    )
    parser.add_argument("--no-peer", action="store_true")
    parser.add_argument("--no-throughput", action="store_true")
    parser.add_argument("--no-cold-start", action="store_true", help="skip benchmarks.cold_start (--quick skips it)")
    parser.add_argument("--no-profile", action="store_true")
    parser.add_argument("--no-validate", action="store_true", help="skip validate_plan on successful plans")
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    args = _parser().parse_args(argv)
    if args.render:
        return render(args.render, args.out, args.doc)
    quick = args.quick
    worlds = select(all_worlds(), args.only or (QUICK_WORLDS if quick else None))
    if not worlds:
        print(f"benchmarks.run: no world matches --only {args.only!r}", file=sys.stderr)
        return 2
    limits = {w.name: _time_limit(args, w) for w in worlds}
    same = _dedupe(worlds, limits)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    started = time.monotonic()
    report: dict = {
        "command": " ".join(["python -m benchmarks.run", *argv]),
        "machine": _machine(),
        "code": _provenance(),
        "started": time.strftime("%Y-%m-%d %H:%M:%S"),
    }

    # 1. planner runs, one worker process per distinct world
    planner, baseline = _planner_runs(args, [w for w in worlds if w.name not in same], limits)
    report["planner"] = planner
    report["planner_wall_s"] = time.monotonic() - started
    if baseline is not None:
        report["baseline"] = {
            "revision": args.baseline,
            "commit": _git("rev-parse", "--short", args.baseline),
            "planner": baseline,
        }

    # 2. collision throughput (one process at a time: figures per core)
    report["throughput"] = {} if args.no_throughput else _throughput_runs(args)

    # 2b. cold start: compiling the kernel, loading it from the cache, first plan against second
    if not (args.no_cold_start or quick):
        t0 = time.monotonic()
        report["cold_start"] = _child("benchmarks.cold_start", timeout=900)
        print(f"cold start: {time.monotonic() - t0:.0f} s", file=sys.stderr)

    # 3. peer comparison
    peer = {} if args.no_peer else _peer_runs(args, limits)
    report["peer"] = peer

    # 4. profile of one figure1 run (alone on the machine, as far as this suite goes)
    if not args.no_profile and "figure1" in limits:
        report["profile"] = _profile_run(args, out)

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
    if "baseline" in report:
        report["baseline"]["rows"] = _baseline_rows(worlds, same, report["baseline"]["planner"])
    report["machine"]["loadavg_end"] = os.getloadavg()
    report["total_wall_s"] = time.monotonic() - started

    return write_outputs(report, out, args.doc)


def _time_limit(args: argparse.Namespace, world: BenchWorld) -> float:
    """The per-run time limit (s) of ``world``: ``--time-limit``, its own, or its own capped."""
    if args.time_limit:
        return args.time_limit
    if args.full_limits:
        return world.time_limit_s
    return min(world.time_limit_s, QUICK_LIMIT_S if args.quick else LIMIT_CAP_S)


def _planner_runs(
    args: argparse.Namespace, to_run: list[BenchWorld], limits: dict[str, float]
) -> tuple[dict, dict | None]:
    """Plan every world of ``to_run`` (each in a worker process, ``--jobs`` at once): the records by world,
    and with ``--baseline`` the baseline code's records by world (else ``None``)."""
    seeds = args.seeds if args.seeds is not None else (2 if args.quick else 20)
    seeds_for = {} if args.quick or args.seeds is not None else dict(DEFAULT_SEEDS_FOR)
    for item in args.seeds_for:
        name, _, count = item.partition("=")
        seeds_for[name] = int(count)
    # longest first (seeds x limit), so that --jobs 2 packs well
    to_run = sorted(to_run, key=lambda w: -seeds_for.get(w.name, seeds) * limits[w.name])
    print(f"planner: {len(to_run)} world(s), {seeds} seed(s) each, jobs {args.jobs}", file=sys.stderr)

    baseline_tree = export(args.baseline) if args.baseline else None
    baseline: dict = {}

    def work(world: BenchWorld) -> tuple[str, dict]:
        count = seeds_for.get(world.name, seeds)
        limit = limits[world.name]
        flags = ["--no-validate"] if args.no_validate else []
        trees = [("", ROOT)] + ([(f" (baseline {args.baseline})", baseline_tree)] if baseline_tree else [])
        records = []
        for label, tree in trees:  # this code, then the baseline's, on the same world back to back
            t0 = time.monotonic()
            record = _child(
                "benchmarks.worker",
                world.name,
                "--seeds",
                str(count),
                "--time-limit",
                str(limit),
                *flags,
                timeout=count * (limit * 1.5 + 30) + 120,
                tree=tree,
            )
            record["loadavg_end"] = os.getloadavg()
            print(f"  {world.name}{label}: {time.monotonic() - t0:.0f} s", file=sys.stderr)
            records.append(record)
        if baseline_tree:
            baseline[world.name] = records[1]
        return world.name, records[0]

    try:
        with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
            planner = dict(pool.map(work, to_run))
    finally:
        if baseline_tree:
            shutil.rmtree(baseline_tree, ignore_errors=True)
    return planner, (baseline if baseline_tree else None)


def _throughput_runs(args: argparse.Namespace) -> dict:
    """Collision throughput on :data:`THROUGHPUT_WORLDS`, one process at a time."""
    throughput = {}
    configs = args.throughput_configs or (2_000 if args.quick else 100_000)
    for name in THROUGHPUT_WORLDS:
        t0 = time.monotonic()
        throughput[name] = _child(
            "benchmarks.throughput",
            name,
            "--configs",
            str(configs),
            *(["--interval-budget", "2000"] if args.quick else []),
            timeout=1200,
        )
        more = [
            _child("benchmarks.throughput", name, "--configs", "20000", timeout=1200)
            for _ in range(1, 1 if args.quick else INTERVAL_PROCESSES)
        ]
        _median_intervals(throughput[name], more)
        print(f"throughput {name}: {time.monotonic() - t0:.0f} s", file=sys.stderr)
    return throughput


def _median_intervals(first: dict, more: list[dict]) -> None:
    """The free-interval figures of ``first`` (one process) become the median over it and ``more``
    (other processes): the same loop runs up to 1.7x faster in one process than in the next on this
    machine, so one process is one draw (each process's figure is already its fastest repeat)."""
    if "error" in first:
        return
    for key, figure in first["intervals"].items():
        rates = [figure["per_s"]] + [m["intervals"][key]["per_s"] for m in more if "error" not in m]
        figure["per_s_processes"] = rates
        figure["per_s"] = float(np.median(rates))


def _peer_runs(args: argparse.Namespace, limits: dict[str, float]) -> dict:
    """The OMPL comparison on the peer worlds of this run, ``--jobs`` at once."""
    problems = args.peer_problems or (3 if args.quick else 20)
    peer_limit = args.peer_time_limit or (2.0 if args.quick else 5.0)
    chosen = select(all_worlds(), args.peer_only or ("figure1" if args.quick else PEER_WORLDS))
    chosen = [w for w in chosen if w.name in limits]  # only worlds of this run get a row

    def compare(world: BenchWorld) -> tuple[str, dict]:
        t0 = time.monotonic()
        record = _child(
            "benchmarks.peer",
            world.name,
            "--problems",
            str(problems),
            "--time-limit",
            str(peer_limit),
            "--step-rad",
            str(args.peer_step_rad),
            "--checker",
            args.peer_checker,
            timeout=problems * 2 * (peer_limit + 5) + 120,
        )
        print(f"peer {world.name}: {time.monotonic() - t0:.0f} s", file=sys.stderr)
        return world.name, record

    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        return dict(pool.map(compare, chosen))


def _profile_run(args: argparse.Namespace, out: Path) -> dict:
    """cProfile of one figure1 run; its summary also goes to ``out/profile_figure1.txt``."""
    t0 = time.monotonic()
    limit = args.profile_time_limit or (QUICK_LIMIT_S if args.quick else PROFILE_LIMIT_S)
    prof = _child("benchmarks.profile", "figure1", "--seed", "0", "--time-limit", str(limit), timeout=limit * 4 + 60)
    if "error" not in prof:
        (out / "profile_figure1.txt").write_text(
            f"cProfile of figure1, seed 0, limit {limit:g} s: {prof['outcome']}, {prof['stats']}\n\n"
            f"Own time by file:\n"
            + "\n".join(f"{s:8.2f} s {100 * share:4.0f}%  {f}" for f, s, share in prof["by_file"])
            + f"\n\nTop by cumulative time:\n{prof['cumulative']}\n\nTop by own time (tottime):\n"
            f"{prof['tottime']}\n"
        )
    print(f"profile figure1: {time.monotonic() - t0:.0f} s", file=sys.stderr)
    return prof


def write_outputs(report: dict, out: Path, doc: Path | None) -> int:
    """Write JSON, CSV, Markdown, plot (and ``doc``) of ``report``, print the table; 1 when anything failed."""
    rows, throughput, peer = report["rows"], report.get("throughput") or {}, report.get("peer") or {}
    out.mkdir(parents=True, exist_ok=True)
    (out / "benchmarks.json").write_text(json.dumps(report, indent=1, default=str) + "\n")
    with (out / "benchmarks.csv").open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=COLUMNS, extrasaction="ignore")
        writer.writeheader()
        for row in rows:
            writer.writerow({c: ("" if row.get(c) is None else row.get(c)) for c in COLUMNS})
    plot = plot_scaling([r for r in rows if not r.get("error")], out / "benchmarks_scaling.png")
    markdown = markdown_report(report, plot.name if plot else None)
    (out / "benchmarks.md").write_text(markdown + "\n")
    if doc:
        update_doc(doc, markdown, plot)

    print_table(rows)
    for name, t in throughput.items():
        print(throughput_line(name, t))
    errors = (
        [r for r in rows if r.get("error")]
        + [{"world": k, "error": v["error"]} for k, v in {**peer, **throughput}.items() if "error" in v]
        + (
            [{"world": "profile", "error": report["profile"]["error"]}]
            if "error" in (report.get("profile") or {})
            else []
        )
    )
    for r in errors:
        print(f"error {r['world']}: {r['error']}", file=sys.stderr)
    print(
        f"wrote {out / 'benchmarks.json'}, .csv, .md"
        + (f", {plot}" if plot else "")
        + (f" and {doc}" if doc else "")
        + f" (suite run: {report['total_wall_s']:.0f} s)"
    )
    return 1 if errors else 0


def render(path: Path, out: Path, doc: Path | None) -> int:
    """Re-summarise and re-write the outputs of a saved ``benchmarks.json`` (no planning)."""
    report = json.loads(Path(path).read_text())
    worlds = {w.name: w for w in all_worlds()}
    rows = []
    for old in report["rows"]:
        world, same_as = worlds[old["world"]], old.get("same_as") or None
        row = _summarise_world(world, report["planner"].get(same_as or world.name, {"error": "not run"}), same_as)
        if world.name in report.get("peer", {}):
            row.update(_summarise_peer(report["peer"][world.name]))
        else:
            row.update(peer_problems=None, peer_note=old.get("peer_note", ""))
        rows.append(row)
    report["rows"] = rows
    if "baseline" in report:
        same = {r["world"]: r["same_as"] for r in rows if r.get("same_as")}
        report["baseline"]["rows"] = _baseline_rows(
            [worlds[r["world"]] for r in rows], same, report["baseline"]["planner"]
        )
    return write_outputs(report, out, doc)


def _baseline_rows(worlds: list[BenchWorld], same: dict, planner: dict) -> list[dict]:
    return [
        _summarise_world(
            world, planner.get(same.get(world.name, world.name), {"error": "not run"}), same.get(world.name)
        )
        for world in worlds
    ]


def before_after(report: dict) -> str:
    """Markdown: the baseline's planner runs next to this code's, world by world."""
    base = report["baseline"]
    before = {r["world"]: r for r in base["rows"]}
    lines = []
    for row in report["rows"]:
        old = before.get(row["world"], {})
        if row.get("same_as"):
            continue
        ratio = (
            old.get("median_s") / row["median_s"]
            if isinstance(old.get("median_s"), float) and isinstance(row.get("median_s"), float) and row["median_s"] > 0
            else None
        )
        lines.append(
            [
                row["world"],
                f"{_percent(old.get('success_rate'))} → {_percent(row.get('success_rate'))}",
                f"{_format(old.get('median_s'))} → {_format(row.get('median_s'))}",
                f"x{ratio:.1f}" if ratio else "-",
                f"{_format(old.get('p90_s'))} → {_format(row.get('p90_s'))}",
                f"{_format(old.get('landmarks_median'), 0)} → {_format(row.get('landmarks_median'), 0)}",
                f"{_format(old.get('checks_per_cpu_s'), 0)} → {_format(row.get('checks_per_cpu_s'), 0)}",
            ]
        )
    header = ["world", "success", "median s", "median before / after", "p90 s", "landmarks", "checks/CPU s"]
    return "\n".join(
        [
            f"### Before and after: baseline {base['revision']} (git {base['commit']}) → this code",
            "",
            (
                "The same worlds, seeds and limits, each world planned by the baseline's code right after "
                "this code's, in the same run (`--baseline`). Failed runs count at the limit."
            ),
            "",
            _markdown_table(header, lines),
            "",
        ]
    )


if __name__ == "__main__":
    sys.exit(main())
