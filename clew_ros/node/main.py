"""``clew_planner``: run the planning node (``ros2 run clew_ros clew_planner``).

    clew_planner [--ros-args --params-file WORLD.yaml -p planner.seed:=3 ...]

Exit codes: 0 after a clean shutdown (Ctrl-C / SIGINT or SIGTERM: the
running plan is canceled and its recording closed first); 2 when the
parameters are invalid at start (one error log names the parameter).
``kill -USR1 PID`` prints every thread's Python stack to stderr (for a hang).

Signals are handled here rather than by rclpy: a handler only sets a flag,
the main thread notices it between two executor waits and then tears down in
order (runs, executor, node, context) from that one thread. rclpy's own
handler would shut the context down from its signal thread while the main
thread may still be building the node, a race that can end in a crash.
:func:`serve` does all this for any number of nodes; ``clew_planners``
(:mod:`clew_ros.node.multi`) serves several with it.
"""

from __future__ import annotations

import faulthandler
import os
import signal
import sys
import threading
import time
from collections.abc import Callable

import rclpy
from rclpy.executors import MultiThreadedExecutor
from rclpy.signals import SignalHandlerOptions

from clew_ros.node.planner_node import PlannerNode, StartupError
from clew_ros.planar.kernel import warm_up

EXIT_OK = 0
EXIT_INVALID_PARAMETERS = 2
#: Executor threads per node: a blocked ~/plan, a refused second call, ~/cancel,
#: ~/goal_pose, the timer and the parameter services can all run at once.
EXECUTOR_THREADS = 6
#: Longest wait between two looks at the stop flag (the shutdown latency).
SPIN_PERIOD_S = 0.05
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
#: Longest wait (s) at shutdown for the callbacks still running to answer (a ~/plan call returns within
#: 0.5 s of its run's cancel), and how often to look.
DRAIN_TIMEOUT_S = 3.0
DRAIN_POLL_S = 0.01


def main(argv: list[str] | None = None) -> int:
    """Start ``clew_planner``, spin until SIGINT / SIGTERM or context shutdown; return the exit code."""
    return serve(sys.argv if argv is None else argv, lambda: [PlannerNode()])


def serve(args: list[str], make_nodes: Callable[[], list[PlannerNode]]) -> int:
    """Serve the planners ``make_nodes()`` builds, in one ``MultiThreadedExecutor``; return the exit code.

    ``args`` initialise rclpy (the process's ROS arguments). The kernel is
    warmed up first; then the nodes are built (a :class:`StartupError`:
    exit code 2, the nodes built so far destroyed by ``make_nodes``) and
    spun with :data:`EXECUTOR_THREADS` threads per node until SIGINT /
    SIGTERM or context shutdown, then torn down in order: every node's runs,
    the executor, the nodes, the context.
    """
    faulthandler.enable()  # a crash in a native library prints the Python stacks, not just "-11"
    faulthandler.register(signal.SIGUSR1, all_threads=True)  # `kill -USR1 PID`: where is it stuck?
    stop = threading.Event()
    warming = [True]

    def on_stop(_signum: int, _frame: object) -> None:
        stop.set()
        if warming[0]:  # nothing started yet (no ROS context, no run, no recording): nothing to tidy up
            os._exit(EXIT_OK)

    previous = {sig: signal.signal(sig, on_stop) for sig in STOP_SIGNALS}
    try:
        # compile the planning kernel (or load numba's cache) before anything else, so no plan pays
        # for it; the first start after an install compiles for several seconds, and a stop signal
        # meanwhile exits as soon as Python gets control back (between two compiler passes)
        warm_up()
        warming[0] = False
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    except BaseException:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        raise
    try:
        try:
            nodes = make_nodes()
        except StartupError:
            return EXIT_INVALID_PARAMETERS
        executor = MultiThreadedExecutor(num_threads=EXECUTOR_THREADS * len(nodes))
        for node in nodes:
            executor.add_node(node)
        try:
            while not stop.is_set() and rclpy.ok():
                executor.spin_once(timeout_sec=SPIN_PERIOD_S)
        finally:
            for node in nodes:
                node.shutdown_runs()
            drain(executor)
            executor.shutdown(timeout_sec=5.0)
            for node in nodes:
                node.destroy_node()
        return EXIT_OK
    finally:
        rclpy.try_shutdown()
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def drain(executor: MultiThreadedExecutor, timeout_s: float = DRAIN_TIMEOUT_S) -> bool:
    """Wait until the callbacks still running have returned and sent their answers, while the nodes and
    their services still exist (a ~/plan call answers that its run was canceled); ``False`` when some are
    still running after ``timeout_s``. rclpy's ``MultiThreadedExecutor.shutdown`` (Jazzy) does not wait
    for them: a node destroyed under a callback made its answer fail, printed at exit as "The following
    exception was never retrieved: cannot use Destroyable because destruction was requested". Each
    finished callback's exception is retrieved here, so none is printed so."""
    tasks = list(getattr(executor, "_futures", ()))  # the callbacks handed to its thread pool
    deadline = time.monotonic() + timeout_s
    while any(not task.done() for task in tasks) and time.monotonic() < deadline:
        time.sleep(DRAIN_POLL_S)
    for task in tasks:
        if task.done():
            task.exception()
    return all(task.done() for task in tasks)


if __name__ == "__main__":
    raise SystemExit(main())
