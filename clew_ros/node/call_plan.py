"""Call a running ``clew_planner``'s ``~/plan`` and print the answer.

    python -m clew_ros.node.call_plan [--node /clew_planner] [--timeout S] [--wait-playback]

The command-line twin of
``ros2 service call /clew_planner/plan std_srvs/srv/Trigger``, usable
without the ``ros2`` CLI (pip installs have none). With
``--wait-playback`` it returns only after the node has played the plan back
(its ``~/feedback`` says ``playback_done`` or ``playback_stopped`` for the
run), so that the run's recording is complete.

Exit codes: 0 a plan was found; 1 no plan (the node's message says why);
2 the node did not answer in time.
"""

from __future__ import annotations

import argparse
import re
import sys
import time

import rclpy
from diagnostic_msgs.msg import DiagnosticStatus
from rclpy.executors import SingleThreadedExecutor
from std_srvs.srv import Trigger

from clew_ros.node.qos import STREAM_QOS

EXIT_SUCCESS, EXIT_NO_PLAN, EXIT_NO_ANSWER = 0, 1, 2
RUN_ID = re.compile(r"run ([0-9a-f]{32})")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="call_plan", description=__doc__.splitlines()[0])
    parser.add_argument("--node", default="/clew_planner", help="the planner node's name (default /clew_planner)")
    parser.add_argument(
        "--timeout", type=float, default=120.0, help="seconds to wait for the service and for the answer (default 120)"
    )
    parser.add_argument(
        "--wait-playback", action="store_true", help="after a success, wait until the node has played the plan back"
    )
    args = parser.parse_args(argv)

    rclpy.init()
    node = rclpy.create_node("clew_call_plan")
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    playback_over: dict[str, str] = {}  # run id -> playback_done / playback_stopped

    def on_feedback(msg: DiagnosticStatus) -> None:
        values = {kv.key: kv.value for kv in msg.values}
        if values.get("phase", "").startswith("playback_"):
            playback_over[values.get("run_id", "")] = values["phase"]

    node.create_subscription(DiagnosticStatus, f"{args.node}/feedback", on_feedback, STREAM_QOS)
    client = node.create_client(Trigger, f"{args.node}/plan")
    try:
        deadline = time.monotonic() + args.timeout
        while not client.wait_for_service(timeout_sec=0.5):
            if time.monotonic() > deadline:
                print(f"call_plan: {args.node}/plan not found within {args.timeout} s", file=sys.stderr)
                return EXIT_NO_ANSWER
        future = client.call_async(Trigger.Request())
        executor.spin_until_future_complete(future, timeout_sec=max(0.1, deadline - time.monotonic()))
        if not future.done():
            print(f"call_plan: no answer from {args.node}/plan within {args.timeout} s", file=sys.stderr)
            return EXIT_NO_ANSWER
        response = future.result()
        print(f"success: {response.success}")
        print(f"message: {response.message}")
        if response.success and args.wait_playback:
            match = RUN_ID.search(response.message)
            run_id = match.group(1) if match else ""
            while run_id not in playback_over and time.monotonic() < deadline:
                executor.spin_once(timeout_sec=0.2)
            print(f"playback: {playback_over.get(run_id, 'not finished within the timeout')}")
        return EXIT_SUCCESS if response.success else EXIT_NO_PLAN
    except KeyboardInterrupt:
        return EXIT_NO_ANSWER
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    raise SystemExit(main())
