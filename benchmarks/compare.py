"""Two revisions compared on any benchmark command: ``python -m benchmarks compare --baseline REV [--rounds N]
[--threads T] [--keep-output DIR] COMMAND [ARGS]``.

The one way to compare two revisions. Revision ``REV`` is exported with ``git archive`` into a temporary
directory; then ``python -m benchmarks.MODULE ARGS`` (``MODULE``: the command's module in
:data:`benchmarks.__main__.COMMANDS`, called by module so that revisions older than this entry run too) runs in
that tree and in this checkout, each with its own package first on ``PYTHONPATH`` and its own directory as the
working directory, before then after, ``--rounds`` times (the runs of a round follow each other, so both see
the same load), the compiled kernel on ``--threads`` threads (default 1: the two never compete for the cores).
Each run's output is printed; when both print a JSON object (its last line starting with ``{``: ``planner_runs``,
``ompl_peer``, ``profile``, ``cold_start`` among others), every number found at the
same place in both is listed with its median before, after, and after / before. A path ``ARGS`` names relative
to the repository root is read from each tree's own copy; give an absolute path to use one file for both.

Three commands are compared run by run instead, by their module's own ``--baseline`` mode
(:data:`RUN_BY_RUN`), as the same line: ``compare --baseline REV suite [ARGS]`` (each benchmark world
planned by both in turn, a before/after table in the report), ``compare --baseline REV generated_families
[ARGS]`` (every (world, seed) of the generated families by both ``clew_plan``'s in turn, and whether they
made the same plan file) and ``compare --baseline REV collision_throughput [ARGS]`` (both compiled kernels
in one process, taking turns, and whether they give the same numbers bit for bit); ``ARGS`` are then that
mode's options (``compare --baseline REV COMMAND --help``), and ``--rounds``, ``--threads`` and
``--keep-output`` do not apply.
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

__all__ = ["ROOT", "RUN_BY_RUN", "export", "main", "numbers", "ratios"]

#: The repository root (this checkout).
ROOT = Path(__file__).resolve().parents[1]

#: Commands compared run by run: command -> the module whose ``main(["--baseline", REV, *ARGS])`` does it.
RUN_BY_RUN = {"suite": "run", "generated_families": "families_ab", "collision_throughput": "kernel_ab"}


def export(revision: str, root: Path = ROOT) -> Path:
    """The files of git revision ``revision`` of the repository at ``root`` in a new temporary directory
    (``git archive``); the caller removes it. A revision git does not know raises ``ValueError`` naming it."""
    archive = subprocess.run(["git", "archive", "--format=tar", revision], cwd=root, capture_output=True, check=False)
    if archive.returncode != 0:
        message = archive.stderr.decode(errors="replace").strip()
        raise ValueError(f"--baseline: git revision {revision!r} cannot be exported: {message}")
    tree = Path(tempfile.mkdtemp(prefix="clew_baseline_"))
    subprocess.run(["tar", "-x", "-C", str(tree)], input=archive.stdout, check=True)
    return tree


def numbers(value: Any, path: str = "") -> Iterator[tuple[str, float]]:
    """Every number of a JSON value with its place (``key.key[index]``); booleans are not numbers."""
    if isinstance(value, bool):
        return
    if isinstance(value, (int, float)):
        if math.isfinite(value):
            yield path, float(value)
    elif isinstance(value, dict):
        for key, item in value.items():
            yield from numbers(item, f"{path}.{key}" if path else str(key))
    elif isinstance(value, list):
        for index, item in enumerate(value):
            yield from numbers(item, f"{path}[{index}]")


def ratios(before: list[dict[str, Any]], after: list[dict[str, Any]]) -> list[tuple[str, float, float, float | None]]:
    """Per place found in every run of both sides: the median before, the median after and after / before
    (``None`` when the median before is 0), in the order of the first run's output."""
    sides = [[dict(numbers(run)) for run in runs] for runs in (before, after)]
    rows: list[tuple[str, float, float, float | None]] = []
    for place in sides[0][0] if sides[0] else {}:
        if not all(place in run for side in sides for run in side):
            continue
        old = statistics.median(run[place] for run in sides[0])
        new = statistics.median(run[place] for run in sides[1])
        rows.append((place, old, new, new / old if old != 0 else None))
    return rows


def _run(tree: Path, module: str, args: list[str], threads: int) -> tuple[int, str, str]:
    """``python -m benchmarks.MODULE ARGS`` in ``tree``: exit code, standard output and standard error."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(tree), *[p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p]])
    env["NUMBA_NUM_THREADS"] = str(threads)
    for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        env[name] = "1"
    command = [sys.executable, "-m", f"benchmarks.{module}", *args]
    done = subprocess.run(command, cwd=tree, env=env, capture_output=True, text=True, check=False)
    return done.returncode, done.stdout, done.stderr


def _json(stdout: str) -> dict[str, Any] | None:
    lines = [line for line in stdout.splitlines() if line.startswith("{")]
    if not lines:
        return None
    try:
        value = json.loads(lines[-1])
    except json.JSONDecodeError:
        return None
    return value if isinstance(value, dict) else None


def _format(value: float) -> str:
    return f"{value:.6g}"


def _rounds(args: argparse.Namespace, module: str, baseline: Path) -> tuple[dict[str, list[dict[str, Any]]], bool]:
    """Every round, before then after: the JSON objects each side printed, and whether a run failed."""
    results: dict[str, list[dict[str, Any]]] = {"before": [], "after": []}
    failed = False
    for round_ in range(args.rounds):
        for side, tree in (("before", baseline), ("after", ROOT)):
            code, stdout, stderr = _run(tree, module, args.args, args.threads)
            label = f"{args.baseline}" if side == "before" else "this checkout"
            print(f"## {side} ({label}), round {round_ + 1}: exit {code}", flush=True)
            print(stdout, end="" if stdout.endswith("\n") or not stdout else "\n", flush=True)
            if code != 0:
                print(stderr, end="", file=sys.stderr, flush=True)
                failed = True
            if args.keep_output is not None:
                args.keep_output.mkdir(parents=True, exist_ok=True)
                (args.keep_output / f"{side}_{round_ + 1}.txt").write_text(stdout)
            parsed = _json(stdout)
            if parsed is not None:
                results[side].append(parsed)
    return results, failed


def _whole_run_options(args: argparse.Namespace) -> list[tuple[str, Any, Any]]:
    """The options of whole-run comparisons: flag, value given, default."""
    return [("--rounds", args.rounds, 1), ("--threads", args.threads, 1), ("--keep-output", args.keep_output, None)]


def main(argv: list[str] | None = None) -> int:
    from benchmarks.__main__ import COMMANDS

    parser = argparse.ArgumentParser(prog="python -m benchmarks compare", description=__doc__.split("\n\n")[0])
    parser.add_argument("--baseline", required=True, help="git revision compared with this checkout (before)")
    parser.add_argument("--rounds", type=int, default=1, help="runs of each side, taking turns (default 1)")
    parser.add_argument("--threads", type=int, default=1, help="NUMBA_NUM_THREADS of every run (default 1)")
    parser.add_argument("--keep-output", type=Path, help="write each run's output to DIR/{before,after}_K.txt")
    parser.add_argument("command", choices=[name for name in COMMANDS if name != "compare"], metavar="COMMAND")
    parser.add_argument("args", nargs=argparse.REMAINDER, help="the command's own arguments")
    args = parser.parse_args(argv)
    if args.command in RUN_BY_RUN:
        given = [flag for flag, value, default in _whole_run_options(args) if value != default]
        if given:
            parser.error(f"{', '.join(given)}: not used by {args.command!r}, which is compared run by run")
        paired = importlib.import_module(f"benchmarks.{RUN_BY_RUN[args.command]}")
        return int(paired.main(["--baseline", args.baseline, *args.args]) or 0)
    if args.rounds < 1:
        parser.error(f"--rounds: expected at least 1, got {args.rounds}")
    if args.threads < 1:
        parser.error(f"--threads: expected at least 1, got {args.threads}")
    module = COMMANDS[args.command].module
    try:
        baseline = export(args.baseline)
    except ValueError as error:
        parser.error(str(error))
    try:
        if not (baseline / "benchmarks" / f"{module}.py").exists():
            parser.error(f"COMMAND: revision {args.baseline} has no benchmarks/{module}.py for {args.command!r}")
        results, failed = _rounds(args, module, baseline)
    finally:
        shutil.rmtree(baseline, ignore_errors=True)
    if failed:
        return 1
    if len(results["before"]) == len(results["after"]) == args.rounds:
        rows = ratios(results["before"], results["after"])
        print(f"## {args.command}: before = {args.baseline}, after = this checkout (medians over {args.rounds} rounds)")
        print("| figure | before | after | after / before |")
        print("|---|---|---|---|")
        for place, old, new, ratio in rows:
            print(f"| {place} | {_format(old)} | {_format(new)} | {'n/a' if ratio is None else f'{ratio:.3f}'} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
