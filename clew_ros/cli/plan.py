"""``clew_plan WORLD.yaml --output PLAN.json [--seed N] [--time-limit S] [--improve-time S]``: plan offline,
no ROS needed.

Exit 0: a plan was found; 1: no plan (the file is still written with
``success: false`` and the outcome ``code``); 2: invalid input, with a
message naming the parameter. Ctrl-C (SIGINT) or SIGTERM cancels the run:
the file is written with code ``CANCELED`` and the exit code is 1; a second
signal aborts at once (exit 130, no file).

``--foxglove [PORT]`` (the ``live`` extra) also serves the run to Foxglove
over a WebSocket on 127.0.0.1 (PORT 8765; 0: any free port, printed): it
waits for a client, shows the world and the landmark tree as it grows, writes
the plan file as usual, then plays the plan back again and again until
Ctrl-C (SIGINT) or SIGTERM; the exit code is the run's. The live view only
observes: same seed, same plan. A spatial world is served in 3-D (its links
and their transforms too). Channels: :mod:`clew_ros.live.view`.
"""

from __future__ import annotations

import argparse
import signal
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from clew_ros.core.clew import Progress
from clew_ros.core.errors import ParameterError
from clew_ros.core.plan import FORMAT, Plan
from clew_ros.kinds import AnyProblem, kind_of, plan_problem, problem_from_parameters, warm_up
from clew_ros.live import DEFAULT_PORT, HOST, INSTALL_HINT, LiveView, LiveViewError, LiveViewUnavailableError
from clew_ros.planar.world import read_parameter_file

if TYPE_CHECKING:
    from clew_ros.planar.world import World
    from clew_ros.spatial.world import SpatialWorld

EXIT_ABORTED = 130


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="clew_plan", description=__doc__.split("\n\n")[0])
    parser.add_argument("world", type=Path, help="ROS 2 parameter file holding world.* (and planner.*)")
    parser.add_argument("--output", "-o", type=Path, required=True, help=f"plan file to write ({FORMAT} JSON)")
    parser.add_argument("--seed", type=int, default=None, help="overrides planner.seed")
    parser.add_argument("--time-limit", type=float, default=None, help="overrides planner.time_limit (s)")
    parser.add_argument(
        "--improve-time", type=float, default=None, help="overrides planner.improve_time (s; 0: the first plan)"
    )
    parser.add_argument("--quiet", "-q", action="store_true", help="no progress line on stderr")
    parser.add_argument(
        "--foxglove",
        nargs="?",
        type=int,
        const=DEFAULT_PORT,
        default=None,
        metavar="PORT",
        help=f"serve the run live to Foxglove on ws://{HOST}:PORT (default {DEFAULT_PORT}; 0: any free port) "
        f"and play the plan back until Ctrl-C; needs the live extra ({INSTALL_HINT})",
    )
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


def _cancel_on_signals(cancel: threading.Event, doing: str = "canceling the run") -> Callable[[], None]:
    """SIGINT / SIGTERM set ``cancel`` (the planner stops and reports CANCELED); a second one aborts.

    Returns a function that restores the previous handlers. Outside the main thread it does nothing.
    """

    def handler(signum: int, _frame) -> None:
        if cancel.is_set():
            raise KeyboardInterrupt
        cancel.set()
        print(f"clew_plan: {signal.Signals(signum).name}: {doing} (again to abort)", file=sys.stderr)

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


def _start_live_view(parameters: dict, port: int, joints: int, *, in_3d: bool) -> LiveView | str:
    """The started live view (timed for a robot of ``joints`` joints; ``in_3d``: drawing a world in 3-D),
    or why it cannot start (a message for stderr)."""
    try:
        return LiveView.from_parameters(parameters, port=port, joints=joints, spatial=in_3d).start()
    except LiveViewUnavailableError:
        return f"--foxglove needs foxglove-sdk, which is not installed: {INSTALL_HINT}"
    except (LiveViewError, ParameterError) as error:
        return f"--foxglove: {error}"


def _serve_until_signal(view: LiveView, planned: Plan) -> None:
    """Show the outcome, then play the plan back (a failed one: keep showing the tree) until SIGINT / SIGTERM."""
    stop = threading.Event()
    restore = _cancel_on_signals(stop, "stopping the live view")
    try:
        view.publish_outcome(planned)
        print(f"clew_plan: playing the plan back on {view.url} until Ctrl-C", file=sys.stderr)
        while not stop.is_set():
            if not planned.segments or view.play(planned, stop=stop):
                stop.wait(1.0)
    except KeyboardInterrupt:  # a second signal
        pass
    finally:
        restore()


def _show_world(view: LiveView, world: World | SpatialWorld, cancel: threading.Event) -> bool:
    """Publish the world, then wait for a Foxglove client or ``cancel``; ``False``: aborted (a second signal)."""
    view.publish_world(world)
    print(f"clew_plan: live view on {view.url}: waiting for a Foxglove client (Ctrl-C to stop)", file=sys.stderr)
    try:
        while not view.wait_for_client(0.2) and not cancel.is_set():
            pass
    except KeyboardInterrupt:
        return False
    return True


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        parameters = read_parameter_file(args.world)
        problem = problem_from_parameters(
            parameters,
            Path(args.world).resolve().parent,
            seed=args.seed,
            time_limit=args.time_limit,
            improve_time=args.improve_time,
        )
    except ParameterError as error:
        print(f"clew_plan: invalid input: {error}", file=sys.stderr)
        return 2
    if args.foxglove is None:
        return _plan(args, problem, None)
    in_3d = kind_of(problem).live_in_3d
    view = _start_live_view(parameters, args.foxglove, problem.world.robot.dof, in_3d=in_3d)
    if isinstance(view, str):
        print(f"clew_plan: {view}", file=sys.stderr)
        return 2
    try:
        return _plan(args, problem, view)
    finally:
        view.stop()


def _plan(args: argparse.Namespace, problem: AnyProblem, view: LiveView | None) -> int:
    """Plan, write the plan file, and with a live view play the plan back until a signal; the exit code."""
    progress = _ProgressLine(not args.quiet)

    def observe(update: Progress) -> None:
        progress(update)
        if view is not None:
            view.on_progress(update)

    warm_up(problem)  # compile the kernels (or load numba's cache) before the clock starts: no plan pays for it
    cancel = threading.Event()
    restore = _cancel_on_signals(cancel)
    if view is not None and not _show_world(view, problem.world, cancel):
        restore()
        print("clew_plan: aborted; no plan file written", file=sys.stderr)
        return EXIT_ABORTED
    started = time.monotonic()
    try:
        planned = plan_problem(problem, cancel=cancel, progress=observe)  # a planner bug: INTERNAL_ERROR, exit 1
    except KeyboardInterrupt:  # a second signal
        print("clew_plan: aborted; no plan file written", file=sys.stderr)
        return EXIT_ABORTED
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
        f"{len(planned.landmarks)} landmarks{_quality(planned)}) -> {args.output}",
        file=sys.stderr,
    )
    if view is not None:
        _serve_until_signal(view, planned)
    return 0 if planned.success else 1


def _quality(planned: Plan) -> str:
    """``, joint travel X rad, N transfers`` for a plan that has them (its stats), else nothing."""
    stats = planned.stats
    if not planned.success or "joint_travel_rad" not in stats:
        return ""
    return f", joint travel {stats['joint_travel_rad']:.2f} rad, {stats['transfers']} transfer(s)"


if __name__ == "__main__":
    raise SystemExit(main())
