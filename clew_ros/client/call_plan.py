"""Ask a running ``clew_planner`` for a plan and print the outcome: a small program on :mod:`clew_ros.client`.

    python -m clew_ros.client.call_plan [--node /clew_planner] [--goal X,Y,YAW] [--timeout S] [--wait-playback]

Plans to the planner's own goal (its ``world.object.goal`` parameter, a motion-only query's
``world.robot.goal_pose`` or, through ``~/plan``, its ``world.robot.goal``), or to ``--goal`` (``X,Y,YAW``; a
spatial planner's ``X,Y,Z,ROLL,PITCH,YAW``: the object's goal placement, or a motion-only query's tcp pose), the
way ``ros2 service call /clew_planner/plan std_srvs/srv/Trigger`` does, usable without the ``ros2`` CLI (pip
installs have none). With ``--wait-playback`` it returns only after the node has
played the plan back, so that the run's recording is complete.

Prints ``success: True|False``, ``outcome: <CODE>``, ``message: run <id>:
<CODE>: <message>`` and ``recording: <directory or why not>``.
Exit codes: 0 a plan was found; 1 no plan (the outcome says why); 2 no
planner, or no answer in time.
"""

from __future__ import annotations

import argparse
import sys

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from std_srvs.srv import Trigger

from clew_ros.client import PlannerClient, PlannerNotFoundError, RunTimeoutError, goal_argument

EXIT_SUCCESS, EXIT_NO_PLAN, EXIT_NO_ANSWER = 0, 1, 2


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="call_plan", description=__doc__.splitlines()[0])
    parser.add_argument("--node", default="/clew_planner", help="the planner node's name (default /clew_planner)")
    parser.add_argument(
        "--goal",
        type=goal_argument,
        default=None,
        help="object goal X,Y,YAW or X,Y,Z,ROLL,PITCH,YAW (default: the planner's)",
    )
    parser.add_argument(
        "--timeout", type=float, default=120.0, help="seconds to wait for the planner and for the answer (default 120)"
    )
    parser.add_argument(
        "--wait-playback", action="store_true", help="after a success, wait until the node has played the plan back"
    )
    args = parser.parse_args(argv)

    rclpy.init()
    node = rclpy.create_node("clew_call_plan")
    client = PlannerClient(node, args.node)
    try:
        client.wait_for_planner(timeout_s=args.timeout)
        goal = args.goal
        if goal is None:
            try:
                goal = client.default_goal()
            except PlannerNotFoundError as error:
                if "~/plan" not in str(error):
                    raise
                return _plan_service(node, client, args.node, args.timeout)  # a joint goal: the node's own
        result = client.send_goal(goal).wait(args.timeout, playback=args.wait_playback)
    except (PlannerNotFoundError, RunTimeoutError) as error:
        print(f"call_plan: {error}", file=sys.stderr)
        return EXIT_NO_ANSWER
    except (KeyboardInterrupt, ExternalShutdownException):
        return EXIT_NO_ANSWER
    finally:
        client.destroy()
        node.destroy_node()
        rclpy.try_shutdown()
    print(f"success: {result.succeeded}")
    print(f"outcome: {result.outcome.name}")
    print(f"message: run {result.run_id}: {result.outcome.name}: {result.message}")
    print(f"recording: {result.recording or result.recording_note}")
    if result.plan is not None:
        print(f"plan: {len(result.plan.segments)} segments, {result.plan.grasp_count} grasps, {result.time_s:.2f} s")
    return EXIT_SUCCESS if result.succeeded else EXIT_NO_PLAN


def _plan_service(node: Node, client: PlannerClient, planner: str, timeout_s: float) -> int:
    """Call the planner's ``~/plan`` (a motion-only query to joint values, which no ``~/goal_pose`` carries) and
    print its answer as :func:`main` prints a run's; the code is the answer's ``run <id>: <CODE>: ...``."""
    service = node.create_client(Trigger, f"{planner.rstrip('/')}/plan")
    try:
        if not service.wait_for_service(timeout_sec=timeout_s):
            print(f"call_plan: {planner}/plan did not answer within {timeout_s} s", file=sys.stderr)
            return EXIT_NO_ANSWER
        future = service.call_async(Trigger.Request())
        if not client.wait_until(future.done, timeout_s) or future.result() is None:
            print(f"call_plan: {planner}/plan did not answer within {timeout_s} s", file=sys.stderr)
            return EXIT_NO_ANSWER
        response = future.result()
    finally:
        node.destroy_client(service)
    head, _, recording = response.message.partition("; recording ")
    parts = head.split(": ", 2)
    code = parts[1] if len(parts) > 1 and parts[0].startswith("run ") else ("SUCCEEDED" if response.success else "?")
    print(f"success: {response.success}")
    print(f"outcome: {code}")
    print(f"message: {response.message}")
    print(f"recording: {recording or 'not recorded'}")
    return EXIT_SUCCESS if response.success else EXIT_NO_PLAN


if __name__ == "__main__":
    sys.exit(main())
