"""Plan to a sequence of object goals with :class:`~clew_ros.client.PlannerClient`, logging each result.

    python -m clew_ros.examples.goal_sequence [--planner /clew_planner] X,Y,YAW [X,Y,YAW ...]

(a spatial planner's goals: X,Y,Z,ROLL,PITCH,YAW.)

A node of its own, spun by a ``SingleThreadedExecutor``: it never blocks in a
callback. A timer sends the next goal once the planner is there and the
previous run has ended; :meth:`RunHandle.add_done_callback` logs the result.
Prints one line per goal, ``goal 1/3 (0.6, 1.1, 0.0): SUCCEEDED, 4 segments,
2 grasps, 0.31 s``, and exits 0 when every goal was planned, 1 otherwise.
"""

from __future__ import annotations

import argparse
import sys

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

from clew_ros.client import PlannerClient, RunHandle, goal_argument


class GoalSequence(Node):
    """Sends ``goals`` to the planner one after the other."""

    def __init__(self, goals: list[tuple[float, float, float]], planner: str = "/clew_planner") -> None:
        super().__init__("clew_goal_sequence")
        self.client = PlannerClient(self, planner)
        self.goals = goals
        self.results: list[RunHandle] = []
        self.current: RunHandle | None = None
        self.create_timer(0.1, self._send_next)

    @property
    def finished(self) -> bool:
        return len(self.results) == len(self.goals)

    def _send_next(self) -> None:
        if self.current is not None or self.finished or not self.client.planner_ready():
            return
        goal = self.goals[len(self.results)]
        self.current = self.client.send_goal(goal)
        self.current.add_done_callback(self._on_done)

    def _on_done(self, handle: RunHandle) -> None:
        result = handle.result
        assert result is not None
        self.results.append(handle)
        self.current = None
        text = f"goal {len(self.results)}/{len(self.goals)} {handle.goal}: {result.outcome.name}"
        if result.plan is not None:
            text += f", {len(result.plan.segments)} segments, {result.plan.grasp_count} grasps, {result.time_s:.2f} s"
        else:
            text += f": {result.message}"
        self.get_logger().info(text)
        print(text, flush=True)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="goal_sequence", description=__doc__.splitlines()[0])
    parser.add_argument(
        "goals",
        nargs="+",
        type=goal_argument,
        help="object goals X,Y,YAW (spatial: X,Y,Z,ROLL,PITCH,YAW) in frame world",
    )
    parser.add_argument("--planner", default="/clew_planner", help="the planner node (default /clew_planner)")
    args, ros_args = parser.parse_known_args(argv)
    rclpy.init(args=ros_args)
    node = GoalSequence(args.goals, args.planner)
    try:
        while rclpy.ok() and not node.finished:
            rclpy.spin_once(node, timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        return 1
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0 if all(h.result is not None and h.result.succeeded for h in node.results) else 1


if __name__ == "__main__":
    sys.exit(main())
