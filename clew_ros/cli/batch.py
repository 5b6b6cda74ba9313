"""``clew_batch WORLD.yaml|DIR|@LIST... --seeds N --out DIR [--time-limit S] [--jobs K] [--ray [ADDRESS]]
[--record]``: plan many (world, seed) jobs and write a dataset, no ROS needed.

Every world file given (a folder: each ``.yaml`` in it; ``@LIST``: a file
naming one world file or folder per line) is planned with seeds ``0..N-1``
(or ``N`` seeds derived from ``--batch-seed B``), each job exactly as
``clew_plan WORLD --seed S`` would plan it. Under ``--out DIR``: one plan
file per job (``plans/<world file name>/seed_<S>.json``) and the index
``index.jsonl`` (one line per job); a summary table is printed at the end.
Rerunning the same command skips the jobs done and runs the rest. With
``--record`` (the ``ros`` extra: ``pip install 'clew_ros[ros]'``), each job's
run is also recorded as the node would have recorded it, under
``recordings/<world file name>/seed_<S>/`` (a rosbag2 folder with one MCAP).

Jobs run on a local pool of processes (``--jobs K``, all cores by default),
or with ``--ray`` on a local Ray (127.0.0.1 only) or with ``--ray ADDRESS``
on an existing Ray cluster (the ``batch`` extra: ``pip install
'clew_ros[batch]'``). A job whose worker fails (an exception, a dead worker,
no result by its time limit + ``--grace``) is recorded as ``INTERNAL_ERROR``
with the reason, after ``--retries`` more attempts.

Exit 0: every job ran (whatever its outcome); 1: the workers could not run
any job; 2: invalid input, with a message naming the argument; 130: stopped
by Ctrl-C (SIGINT) or SIGTERM, which finish the jobs written so far, drop the
ones in flight and print the command that resumes (a second signal aborts).
"""

from __future__ import annotations

import argparse
import re
import shlex
import signal
import sys
import threading
from collections.abc import Callable, Sequence
from pathlib import Path
from types import FrameType

from clew_ros.batch.errors import BatchInputError, ExecutorError, ExecutorUnavailableError
from clew_ros.batch.executors import Executor, LocalPool, RayExecutor, default_workers, network_interfaces_up
from clew_ros.batch.index import INDEX_NAME
from clew_ros.batch.jobs import collect_world_paths, derived_seeds, generated_world_paths, load_worlds, make_jobs
from clew_ros.batch.progress import ProgressBar
from clew_ros.batch.recording import check_recording_parameters, recording_unavailable
from clew_ros.batch.runner import DEFAULT_GRACE_S, BatchReport, run_batch
from clew_ros.batch.summary import summary_table
from clew_ros.batch.worker import JobFunction, run_job

__all__ = ["main"]

EXIT_STOPPED = 130
#: ``--ray`` with no value: a local Ray.
_LOCAL_RAY = ""
_RAY_ADDRESS = re.compile(r"^(auto|(ray://)?[A-Za-z0-9_.\-]+:\d+|(ray://)?\[[0-9A-Fa-f:.]+\]:\d+)$")


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="clew_batch",
        description=__doc__.split("\n\n")[0],
        epilog="Exit 0: every job ran; 1: no worker could run; 2: invalid input; 130: stopped (rerun to resume).",
    )
    parser.add_argument(
        "worlds", nargs="*", metavar="WORLD", help="world parameter file, folder of .yaml world files, or @LIST file"
    )
    parser.add_argument(
        "--generate",
        action="append",
        default=[],
        metavar="FAMILY:COUNT",
        help="also plan COUNT generated worlds of FAMILY (clew_world FAMILY --seed 0..COUNT-1), written to "
        "DIR/worlds/ with their witnesses (repeatable; clew_world --list shows the families)",
    )
    parser.add_argument("--seeds", type=int, required=True, metavar="N", help="seeds per world: 0..N-1")
    parser.add_argument("--out", type=Path, required=True, metavar="DIR", help="output folder (created; resumed)")
    parser.add_argument(
        "--batch-seed",
        type=int,
        default=None,
        metavar="B",
        help="derive the N seeds from B with numpy.random.SeedSequence instead of 0..N-1",
    )
    parser.add_argument("--time-limit", type=float, default=None, metavar="S", help="overrides planner.time_limit (s)")
    parser.add_argument(
        "--improve-time", type=float, default=None, metavar="S", help="overrides planner.improve_time (s)"
    )
    parser.add_argument(
        "--jobs",
        type=int,
        default=None,
        metavar="K",
        help="jobs at a time (default: every core; on a cluster its CPUs)",
    )
    parser.add_argument(
        "--ray",
        nargs="?",
        const=_LOCAL_RAY,
        default=None,
        metavar="ADDRESS",
        help="run on Ray: a local Ray on 127.0.0.1, or the cluster at ADDRESS (HOST:PORT, ray://HOST:PORT, auto)",
    )
    parser.add_argument(
        "--ray-allow-network",
        action="store_true",
        help="let --ray without ADDRESS start a local Ray on a machine with network interfaces up (by default "
        "it is refused outside a private network namespace: Ray probes outside addresses as it starts)",
    )
    parser.add_argument(
        "--retries", type=int, default=0, metavar="N", help="further attempts of a job whose worker failed (default 0)"
    )
    parser.add_argument(
        "--grace",
        type=float,
        default=DEFAULT_GRACE_S,
        metavar="S",
        help=f"seconds a job may run past its time limit before it is stopped (default {DEFAULT_GRACE_S:g})",
    )
    parser.add_argument(
        "--record",
        action="store_true",
        help="also record each job's run as clew_planner would, into DIR/recordings/<world>/seed_<S>/ (rosbag2, "
        "MCAP; needs the ros extra)",
    )
    parser.add_argument("--quiet", "-q", action="store_true", help="no progress bar")
    return parser


def _check_arguments(args: argparse.Namespace) -> None:
    """:class:`BatchInputError` for the first option out of range (or ``--record`` that cannot record here)."""
    if args.record and (reason := recording_unavailable()) is not None:
        raise BatchInputError("--record", reason)
    if not args.worlds and not args.generate:
        taken = " (--ray took the one given as its ADDRESS: put --ray after the world files)" if args.ray else ""
        raise BatchInputError(
            "WORLD", f"expected at least one world file, folder, @LIST file or --generate FAMILY:COUNT{taken}"
        )
    if args.seeds < 1:
        raise BatchInputError("--seeds", f"expected an integer >= 1, got {args.seeds}")
    if args.jobs is not None and args.jobs < 1:
        raise BatchInputError("--jobs", f"expected an integer >= 1, got {args.jobs}")
    if args.retries < 0:
        raise BatchInputError("--retries", f"expected an integer >= 0, got {args.retries}")
    if not args.grace > 0:
        raise BatchInputError("--grace", f"expected seconds > 0, got {args.grace}")
    if args.out.exists() and not args.out.is_dir():
        raise BatchInputError("--out", f"expected a folder (created if missing), but {args.out} is a file")
    if args.ray == _LOCAL_RAY and not args.ray_allow_network and (interfaces := network_interfaces_up()):
        raise BatchInputError(
            "--ray",
            f"a local Ray probes outside addresses as it starts, and this machine has network interfaces up "
            f"({', '.join(interfaces[:5])}): run it in a private network namespace (unshare --net, only loopback "
            "up), or pass --ray-allow-network if this network is trusted",
        )
    if args.ray not in (None, _LOCAL_RAY) and not _RAY_ADDRESS.match(args.ray):
        hint = (
            "; --ray took it as its ADDRESS: put --ray after the world files for a local Ray"
            if Path(args.ray).exists()
            else ""
        )
        raise BatchInputError(
            "--ray", f"expected a Ray address (HOST:PORT, ray://HOST:PORT or auto), got {args.ray!r}{hint}"
        )


def _executor(args: argparse.Namespace, jobs: int, job_function: JobFunction) -> Executor:
    if args.ray is None:
        return LocalPool(min(args.jobs or default_workers(), jobs), job_function=job_function)
    address = None if args.ray == _LOCAL_RAY else args.ray
    return RayExecutor(address, args.jobs, job_function=job_function)


def _stop_on_signals(stop: threading.Event) -> Callable[[], None]:
    """SIGINT / SIGTERM set ``stop``; a second one aborts (KeyboardInterrupt). Returns the restorer."""

    def handler(signum: int, _frame: FrameType | None) -> None:
        if stop.is_set():
            raise KeyboardInterrupt
        stop.set()
        name = signal.Signals(signum).name
        print(f"\nclew_batch: {name}: stopping; the jobs in flight are dropped (again to abort)", file=sys.stderr)

    previous = {sig: signal.signal(sig, handler) for sig in (signal.SIGINT, signal.SIGTERM)}

    def restore() -> None:
        for sig, old in previous.items():
            signal.signal(sig, old)

    return restore


def _resume_hint(argv: Sequence[str]) -> str:
    return f"clew_batch: resume with the same command:\n  {shlex.join(['clew_batch', *argv])}"


def _report(report: BatchReport, out: Path) -> None:
    """The summary table (stdout) and the counts (stderr)."""
    if report.repaired_bytes:
        print(f"clew_batch: cut off a torn last line of the index ({report.repaired_bytes} bytes)", file=sys.stderr)
    if report.skipped_lines:
        print(f"clew_batch: skipped {report.skipped_lines} index line(s) that are not job records", file=sys.stderr)
    if report.records:
        print(summary_table(report.records))
    retried = f", {report.retried} attempt(s) repeated" if report.retried else ""
    print(
        f"clew_batch: {len(report.records)} of {report.total} jobs done ({report.done_before} by an earlier run, "
        f"{report.ran} now{retried}); index {out / INDEX_NAME}",
        file=sys.stderr,
    )


def main(argv: Sequence[str] | None = None, *, job_function: JobFunction = run_job) -> int:
    """Run ``clew_batch`` with ``argv`` (default ``sys.argv[1:]``); the exit code.

    ``job_function`` runs each job in its worker (:func:`~clew_ros.batch.worker.run_job`).
    """
    argv = list(sys.argv[1:] if argv is None else argv)
    args = _parser().parse_args(argv)
    try:
        _check_arguments(args)
        generated = generated_world_paths(args.generate, args.out)
        worlds = load_worlds(collect_world_paths([*args.worlds, *(str(path) for path in generated)]))
        if args.record:
            check_recording_parameters(worlds)
        seeds = list(range(args.seeds)) if args.batch_seed is None else derived_seeds(args.batch_seed, args.seeds)
        jobs = make_jobs(worlds, seeds, time_limit_s=args.time_limit, improve_time_s=args.improve_time)
        executor = _executor(args, len(jobs), job_function)
    except (BatchInputError, ExecutorUnavailableError) as error:
        print(f"clew_batch: invalid input: {error}", file=sys.stderr)
        return 2
    print(
        f"clew_batch: {len(jobs)} jobs ({len(worlds)} world(s) x {len(seeds)} seed(s)) on {executor.description} "
        f"-> {args.out}",
        file=sys.stderr,
    )
    stop = threading.Event()
    restore = _stop_on_signals(stop)
    progress = ProgressBar(len(jobs), enabled=not args.quiet)
    try:
        report = run_batch(
            jobs,
            args.out,
            executor,
            retries=args.retries,
            grace_s=args.grace,
            stop=stop,
            progress=progress,
            record=args.record,
        )
    except (BatchInputError, ExecutorUnavailableError) as error:
        print(f"clew_batch: invalid input: {error}", file=sys.stderr)
        return 2
    except ExecutorError as error:
        print(f"clew_batch: the workers cannot run: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"clew_batch: aborted; the index holds every job finished so far\n{_resume_hint(argv)}", file=sys.stderr)
        return EXIT_STOPPED
    finally:
        restore()
    _report(report, args.out)
    if report.stopped:
        print(
            f"clew_batch: stopped with {report.total - len(report.records)} job(s) left "
            f"({report.dropped} dropped in flight)\n{_resume_hint(argv)}",
            file=sys.stderr,
        )
        return EXIT_STOPPED
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
