"""``clew_batch`` throughput: the same jobs in sequence in one process, on the local pool and on a local Ray;
identical plans; resume after a SIGKILL of the driver at about half way.

    python -m benchmarks.batch [--worlds config/figure1.yaml config/single_transfer.yaml] [--seeds 100]
                               [--time-limit 20] [--jobs 2] [--out DIR] [--no-ray] [--round-per-world]

* ``sequential``: one fresh process (imports, kernel warm-up, then every job
  with :func:`clew_ros.batch.worker.run_job` in a loop, as a pool worker runs
  them; plan files written like ``clew_batch``'s);
* ``pool``: ``clew_batch ... --jobs K`` (the local process pool);
* ``ray``: ``clew_batch ... --jobs K --ray`` (a local Ray with K CPUs), run in a
  private network namespace with only loopback up (``unshare --net``, root
  needed; skipped otherwise, or with ``--no-ray``);
* ``identical``: every plan file of the pool and of Ray against the
  sequential one, ``stats.time_s`` aside (jobs that hit their time limit stop
  at a moment the clock picks: counted apart);
* ``resume``: ``clew_batch`` on the pool, SIGKILLed once its index holds
  half the jobs, then the same command again: the jobs finished before the
  kill, those the rerun planned, and finished jobs planned again (index lines
  per job, plan files rewritten; 0 expected).

By default each mode runs all the jobs in one command (one start-up, as a
user's batch pays it); ``--round-per-world`` runs them world by world (one
round per world), the modes in turn and the order reversed every other
round, so that a load that drifts (other programs on the machine) falls on
each mode alike, at the cost of one start-up per world and mode. Throughput is jobs per second of the
commands' wall time (start-up included: workers, Ray, the kernel's
warm-up); ``cores_used`` is the CPU time of the command's processes over
its wall time and ``jobs_per_cpu_s`` the jobs per CPU second (for Ray only
the processes this one reaps count: a bound). On a machine shared with
other sessions, Linux's ``sched_autogroup`` gives each session an equal
share of the cores, whatever number of processes it runs: ``cores_used``
shows what this one got.
The load average is printed with the figures. Prints one JSON object.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_WORLDS = [ROOT / "config" / "figure1.yaml", ROOT / "config" / "single_transfer.yaml"]

#: Runs its arguments in a new network namespace with loopback up and no other interface (else exit 97).
IN_PRIVATE_NETWORK = [
    "unshare",
    "--net",
    "bash",
    "-c",
    'ip link set lo up && [ "$(ip -o link show | wc -l)" = 1 ] || exit 97; exec "$@"',
    "in_private_network",
]

_SEQUENTIAL = """
import sys
from pathlib import Path
from clew_ros.batch.jobs import collect_world_paths, load_worlds, make_jobs
from clew_ros.batch.runner import job_spec
from clew_ros.batch.worker import prepare, run_job
out, seeds, time_limit, worlds = Path(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3]), sys.argv[4:]
prepare()
for job in make_jobs(load_worlds(collect_world_paths(worlds)), range(seeds), time_limit_s=time_limit):
    outcome = run_job(job_spec(job, 60.0))
    path = out / job.plan_path
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(outcome.plan_json)
"""


def _batch(*args: Any) -> list[str]:
    return [sys.executable, "-m", "clew_ros.cli.batch", *map(str, args)]


def _timed(command: list[str], env: dict[str, str] | None = None) -> float:
    """Wall time (s) of ``command``, which must succeed."""
    start = time.perf_counter()
    done = subprocess.run(command, cwd=ROOT, env=env, capture_output=True, text=True, check=False)
    elapsed = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"{command[:6]}... failed ({done.returncode}):\n{done.stderr[-3000:]}")
    return elapsed


def _index(out: Path) -> list[dict[str, Any]]:
    path = out / "index.jsonl"
    return [json.loads(line) for line in path.read_text().splitlines()] if path.exists() else []


def _plans(out: Path) -> dict[str, dict[str, Any]]:
    plans = {}
    for path in sorted((out / "plans").rglob("*.json")):
        document = json.loads(path.read_text())
        document["stats"].pop("time_s", None)
        plans[str(path.relative_to(out))] = document
    return plans


def _compare(reference: dict[str, dict[str, Any]], other: dict[str, dict[str, Any]]) -> dict[str, int]:
    """Plans equal to the reference, different, and different ones that hit their time limit."""
    same = sum(other.get(key) == plan for key, plan in reference.items())
    limited = sum(
        other.get(key) != plan and "TIME_LIMIT" in (plan.get("code"), (other.get(key) or {}).get("code"))
        for key, plan in reference.items()
    )
    return {"same": same, "different": len(reference) - same - limited, "different_time_limit": limited}


def private_network_unavailable() -> str | None:
    """Why a private network namespace (:data:`IN_PRIVATE_NETWORK`) cannot be made here, or ``None``."""
    if shutil.which("unshare") is None or shutil.which("ip") is None:
        return "unshare or ip is not installed"
    probe = subprocess.run([*IN_PRIVATE_NETWORK, "true"], capture_output=True, text=True, check=False, timeout=60)
    if probe.returncode != 0:
        return f"cannot make a private network namespace (unshare --net needs root): {probe.stderr.strip()[:200]}"
    return None


def _private_network() -> str | None:
    """Why Ray cannot run in a private network namespace here, or ``None``."""
    try:
        import ray  # noqa: F401
    except ImportError:
        return "ray is not installed (pip install 'clew_ros[batch]')"
    return private_network_unavailable()


def group_alive(pgid: int) -> bool:
    """Whether a process of group ``pgid`` is still running."""
    try:
        os.killpg(pgid, 0)
    except ProcessLookupError:
        return False
    return True


def _resume(common: list[Any], out: Path, total: int) -> dict[str, Any]:
    """SIGKILL the driver once the index holds half the jobs; rerun; what was kept and what ran again."""
    command = _batch(*common, "--out", out)
    process = subprocess.Popen(
        command, cwd=ROOT, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    try:
        while len(_index(out)) < total // 2:
            if process.poll() is not None:
                raise SystemExit("the batch to kill ended first")
            time.sleep(0.05)
        process.kill()
        process.wait()
        while group_alive(process.pid):  # the orphaned workers finish their job and exit
            time.sleep(0.1)
    finally:
        if group_alive(process.pid):
            os.killpg(process.pid, signal.SIGKILL)
    kept = _index(out)
    mtimes = {r["plan"]: (out / r["plan"]).stat().st_mtime_ns for r in kept}
    rerun_s = _timed(command)
    lines = _index(out)
    rewritten = sum((out / plan).stat().st_mtime_ns != mtime for plan, mtime in mtimes.items())
    return {
        "jobs": total,
        "finished_before_kill": len(kept),
        "rerun_planned": len(lines) - len(kept),
        "finished_jobs_planned_again": len(lines) - len({r["job"] for r in lines}) + rewritten,
        "complete": len({r["job"] for r in lines}) == total,
        "rerun_s": round(rerun_s, 1),
    }


def _rounds(worlds: list[Path], per_world: bool) -> list[list[Path]]:
    """The worlds run per round (every mode runs every round): all at once, or one world per round."""
    return [[world] for world in worlds] if per_world else [list(worlds)]


def _mode_commands(mode: str, worlds: list[Path], args: argparse.Namespace, out: Path) -> tuple[list[str], dict]:
    """The command (and environment) of ``mode`` planning ``worlds`` x ``args.seeds`` into ``out / mode``."""
    common = [*worlds, "--seeds", args.seeds, "--time-limit", args.time_limit, "--jobs", args.jobs, "--quiet"]
    if mode == "sequential":
        command = [sys.executable, "-c", _SEQUENTIAL, str(out / mode), str(args.seeds), str(args.time_limit)]
        return command + [str(w) for w in worlds], dict(os.environ)
    if mode == "pool":
        return _batch(*common, "--out", out / mode), dict(os.environ)
    env = dict(os.environ, RAY_USAGE_STATS_ENABLED="0", RAY_TMPDIR=str(out / "ray_tmp"))
    return [*IN_PRIVATE_NETWORK, *_batch(*common, "--out", out / mode, "--ray")], env


def _children_cpu_s() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.batch", description=__doc__.split("\n\n")[0])
    parser.add_argument("--worlds", nargs="+", type=Path, default=DEFAULT_WORLDS)
    parser.add_argument("--seeds", type=int, default=100)
    parser.add_argument("--time-limit", type=float, default=20.0)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", type=Path, default=None, help="keep the outputs here (default: a temporary folder)")
    parser.add_argument("--no-ray", action="store_true")
    parser.add_argument(
        "--round-per-world",
        action="store_true",
        help="one command per world and mode, modes alternating (drifting load)",
    )
    args = parser.parse_args(argv)
    out = args.out or Path(tempfile.mkdtemp(prefix="clew_bench_batch_"))
    for part in ("sequential", "pool", "ray", "resume", "ray_tmp"):
        shutil.rmtree(out / part, ignore_errors=True)
    (out / "ray_tmp").mkdir(parents=True)
    total = len(args.worlds) * args.seeds
    figures: dict[str, Any] = {
        "jobs": total,
        "worlds": [w.name for w in args.worlds],
        "workers": args.jobs,
        "time_limit_s": args.time_limit,
        "rounds": "per world" if args.round_per_world else "one",
        "cores": os.cpu_count(),
        "load_average_before": [round(v, 2) for v in os.getloadavg()],
    }
    reason = "--no-ray" if args.no_ray else _private_network()
    modes = ["sequential", "pool"] + (["ray"] if reason is None else [])
    wall = dict.fromkeys(modes, 0.0)
    cpu = dict.fromkeys(modes, 0.0)
    for number, worlds in enumerate(_rounds(args.worlds, args.round_per_world)):
        for mode in modes if number % 2 == 0 else modes[::-1]:  # --round-per-world: alternate order
            command, env = _mode_commands(mode, worlds, args, out)
            before = _children_cpu_s()
            wall[mode] += _timed(command, env)
            cpu[mode] += _children_cpu_s() - before
    for mode in modes:
        figures[mode] = {
            "s": round(wall[mode], 1),
            "jobs_per_s": round(total / wall[mode], 3),
            "cores_used": round(cpu[mode] / wall[mode], 2),
            "jobs_per_cpu_s": round(total / cpu[mode], 3) if cpu[mode] else None,
        }
    figures["pool"]["x_sequential"] = round(wall["sequential"] / wall["pool"], 2)
    reference = _plans(out / "sequential")
    figures["identical"] = {"pool": _compare(reference, _plans(out / "pool"))}
    if reason is None:
        figures["ray"]["x_pool"] = round(wall["pool"] / wall["ray"], 2)
        figures["identical"]["ray"] = _compare(reference, _plans(out / "ray"))
    else:
        figures["ray"] = f"skipped: {reason}"
    common = [*args.worlds, "--seeds", args.seeds, "--time-limit", args.time_limit, "--jobs", args.jobs, "--quiet"]
    figures["resume"] = _resume(common, out / "resume", total)
    figures["load_average_after"] = [round(v, 2) for v in os.getloadavg()]
    print(json.dumps(figures, indent=1))
    if args.out is None:
        shutil.rmtree(out, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
