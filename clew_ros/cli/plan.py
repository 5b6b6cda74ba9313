"""``clew_plan WORLD.yaml --output PLAN.json [--seed N] [--time-limit S] [--improve-time S]``: plan offline,
no ROS needed.

Exit 0: a plan was found; 1: no plan (the file is still written with
``success: false`` and the outcome ``code``); 2: invalid input, with a
message naming the parameter. Ctrl-C (SIGINT) or SIGTERM cancels the run:
the file is written with code ``CANCELED`` and the exit code is 1; a second
signal aborts at once (exit 130, no file).
"""

from __future__ import annotations

import argparse
import signal
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

from clew_ros.core.clew import PlanResult, Progress, plan
from clew_ros.core.collision import check_start_and_goal
from clew_ros.core.errors import ParameterError
from clew_ros.core.kernel import warm_up
from clew_ros.core.plan import Plan, checked_plan
from clew_ros.core.settings import Outcome, PlannerSettings, Termination
from clew_ros.core.tree import LandmarkTree
from clew_ros.core.world import read_parameter_file, world_from_parameters

EXIT_ABORTED = 130


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="clew_plan", description=__doc__.split("\n\n")[0])
    parser.add_argument("world", type=Path, help="ROS 2 parameter file holding world.* (and planner.*)")
    parser.add_argument("--output", "-o", type=Path, required=True, help="plan file to write (clew-plan/1 JSON)")
    parser.add_argument("--seed", type=int, default=None, help="overrides planner.seed")
    parser.add_argument("--time-limit", type=float, default=None, help="overrides planner.time_limit (s)")
    parser.add_argument(
        "--improve-time", type=float, default=None, help="overrides planner.improve_time (s; 0: the first plan)"
    )
    parser.add_argument("--quiet", "-q", action="store_true", help="no progress line on stderr")
    return parser


class _ProgressLine:
    """One updating line on stderr, shown once a run has lasted a second."""

    def __init__(self, enabled: bool) -> None:
        self.enabled = enabled
        self.shown = False

    def __call__(self, progress: Progress) -> None:
        if not self.enabled or progress.elapsed < 1.0:
            return
        self.shown = True
        end = "\r" if sys.stderr.isatty() else "\n"
        print(
            f"clew_plan: {progress.elapsed:6.1f} s  landmarks {progress.landmarks:3d}  "
            f"best goal distance {progress.best_distance:.4f} m",
            end=end,
            file=sys.stderr,
            flush=True,
        )

    def close(self) -> None:
        if self.shown and sys.stderr.isatty():
            print(file=sys.stderr)


def _cancel_on_signals(cancel: threading.Event) -> Callable[[], None]:
    """SIGINT / SIGTERM set ``cancel`` (the planner stops and reports CANCELED); a second one aborts.

    Returns a function that restores the previous handlers. Outside the main thread it does nothing.
    """

    def handler(signum: int, _frame) -> None:
        if cancel.is_set():
            raise KeyboardInterrupt
        cancel.set()
        print(f"clew_plan: {signal.Signals(signum).name}: canceling the run (again to abort)", file=sys.stderr)

    previous = {}
    try:
        for sig in (signal.SIGINT, signal.SIGTERM):
            previous[sig] = signal.signal(sig, handler)
    except ValueError:  # not the main thread
        pass

    def restore() -> None:
        for sig, old in previous.items():
            signal.signal(sig, old)

    return restore


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        parameters = read_parameter_file(args.world)
        world = check_start_and_goal(world_from_parameters(parameters))
        settings = PlannerSettings.from_parameters(
            parameters, seed=args.seed, time_limit=args.time_limit, improve_time=args.improve_time
        )
    except ParameterError as error:
        print(f"clew_plan: invalid input: {error}", file=sys.stderr)
        return 2
    progress = _ProgressLine(not args.quiet)
    warm_up()  # compile the kernel (or load numba's cache) before the clock starts: no plan pays for it
    started = time.monotonic()
    cancel = threading.Event()
    restore = _cancel_on_signals(cancel)
    try:
        result = plan(world, settings, termination=Termination(settings.time_limit, cancel), progress=progress)
        planned = checked_plan(world, result)
    except KeyboardInterrupt:  # a second signal
        print("clew_plan: aborted; no plan file written", file=sys.stderr)
        return EXIT_ABORTED
    except Exception as error:  # noqa: BLE001 - a bug in the planner: reported in the plan file, exit 1
        result = PlanResult(
            Outcome.INTERNAL_ERROR,
            f"internal error: {error!r}",
            [],
            None,
            LandmarkTree(world.robot.initial, world.object.initial),
            {"time_s": round(time.monotonic() - started, 4), "seed": settings.seed},
        )
        planned = Plan.from_result(world, result)
    finally:
        restore()
        progress.close()
    try:
        planned.write(args.output)
    except OSError as error:
        print(f"clew_plan: cannot write --output {args.output}: {error.strerror}", file=sys.stderr)
        return 2
    elapsed = time.monotonic() - started
    print(
        f"clew_plan: {planned.code}: {planned.message.splitlines()[0]} ({elapsed:.2f} s, "
        f"{len(result.tree)} landmarks{_quality(planned)}) -> {args.output}",
        file=sys.stderr,
    )
    return 0 if planned.success else 1


def _quality(planned: Plan) -> str:
    """``, joint travel X rad, N transfers`` for a plan that has them (its stats), else nothing."""
    stats = planned.stats
    if not planned.success or "joint_travel_rad" not in stats:
        return ""
    return f", joint travel {stats['joint_travel_rad']:.2f} rad, {stats['transfers']} transfer(s)"


if __name__ == "__main__":
    raise SystemExit(main())
