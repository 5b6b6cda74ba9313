"""``clew_planner``: run the planning node (``ros2 run clew_ros clew_planner``).

    clew_planner [--ros-args --params-file WORLD.yaml -p planner.seed:=3 ...]

Exit codes: 0 after a clean shutdown (Ctrl-C / SIGINT or SIGTERM: the
running plan is canceled and its recording closed first); 2 when the
parameters are invalid at start (one error log names the parameter).
"""

from __future__ import annotations

import sys

import rclpy
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
from rclpy.signals import SignalHandlerOptions

from clew_ros.node.planner_node import PlannerNode, StartupError

EXIT_OK = 0
EXIT_INVALID_PARAMETERS = 2
#: Executor threads: a blocked ~/plan, a refused second call, ~/cancel,
#: ~/goal_pose, the timer and the parameter services can all run at once.
EXECUTOR_THREADS = 6


def main(argv: list[str] | None = None) -> int:
    """Start ``clew_planner``, spin until shutdown; return the exit code."""
    args = sys.argv if argv is None else argv
    # SIGINT and SIGTERM both shut the context down, which makes spin() raise
    # ExternalShutdownException (or KeyboardInterrupt for SIGINT).
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.ALL)
    try:
        node = PlannerNode()
    except StartupError:
        rclpy.try_shutdown()
        return EXIT_INVALID_PARAMETERS
    except (KeyboardInterrupt, ExternalShutdownException):  # stopped while starting
        rclpy.try_shutdown()
        return EXIT_OK
    executor = MultiThreadedExecutor(num_threads=EXECUTOR_THREADS)
    executor.add_node(node)
    try:
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.shutdown_runs()
        executor.shutdown(timeout_sec=5.0)
        node.destroy_node()
        rclpy.try_shutdown()
    return EXIT_OK


if __name__ == "__main__":
    raise SystemExit(main())
