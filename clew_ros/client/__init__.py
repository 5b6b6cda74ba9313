"""Call ``clew_planner`` from your own rclpy node, as ``nav2_simple_commander`` does for Nav2.

- :class:`PlannerClient` sends goals to one planner (by node name, with its
  namespace) and follows the runs they start;
- :class:`RunHandle` is one goal: its run id, :class:`RunStatus`, latest
  :class:`Feedback`, and when it ends a :class:`RunResult` (outcome code,
  message, the :class:`~clew_ros.core.plan.Plan` and its timed trajectory,
  the recording directory);
- :class:`PlannerNotFoundError` and :class:`RunTimeoutError` say that no
  planner answered, or not in time; everything else is an outcome code
  (``BUSY``, ``TIME_LIMIT``, ...), never text to parse.

Which calls may block where: see :mod:`clew_ros.client.planner_client`.
:mod:`clew_ros.client.call_plan` is a small program on it (``python -m
clew_ros.client.call_plan``): one plan asked for, its outcome printed.
"""

from clew_ros.client.planner_client import PlannerClient
from clew_ros.client.run import (
    Feedback,
    PlannerNotFoundError,
    RunHandle,
    RunResult,
    RunStatus,
    RunTimeoutError,
    goal_argument,
)

__all__ = [
    "Feedback",
    "PlannerClient",
    "PlannerNotFoundError",
    "RunHandle",
    "RunResult",
    "RunStatus",
    "RunTimeoutError",
    "goal_argument",
]
