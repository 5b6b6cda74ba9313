"""Pick and place in a loop: each goal planned from where the arm and the object are now (interface.md
section 3c), a point cloud of a table-top obstacle added midway.

    python -m clew_ros.examples.pick_and_place_loop [--planner /clew_planner] [--cloud-after K]
        [--obstacle X,Y,Z,EDGE] [--summary FILE] GOAL [GOAL ...]

Each GOAL is the object's placement ``X,Y,Z,ROLL,PITCH,YAW``. For a planner with ``state.joint_states`` and
``state.advance`` on, and an arm that follows its ``~/trajectory`` and publishes ``joint_states``
(:mod:`clew_ros.examples.simulated_arm`, or a real driver): the goals are sent one after the other with
:class:`~clew_ros.client.PlannerClient`; after each success the script waits until the arm rests at the
trajectory's last point, so the next run plans from there, with the object where the last plan left it.
Before goal ``--cloud-after`` (counted from 0) it publishes on ``<planner>/points`` a cloud of the faces of a
cube standing at ``--obstacle`` (its bottom centre and edge, m): the planner turns it into occupied cubes
(``state.points``) and plans the remaining goals around it. Prints one line a goal (``goal 2/3 (...):
SUCCEEDED, 2 segments, 1 grasps, 0.41 s, recording <dir>``), writes the runs to ``--summary`` (JSON), and exits
0 when every goal was planned and executed, 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import rclpy
from rclpy.duration import Duration
from rclpy.node import Node
from sensor_msgs.msg import JointState, PointCloud2, PointField
from std_msgs.msg import Header

from clew_ros.client import PlannerClient, goal_argument
from clew_ros.core.settings import Outcome
from clew_ros.ros.qos import CLOUD_QOS, STATE_QOS

__all__ = ["cube_cloud", "main"]

#: Spacing (m) of the points on the obstacle's faces.
POINT_SPACING_M = 0.005


def cube_cloud(bottom: np.ndarray, edge: float, stamp_ns: int) -> PointCloud2:
    """A ``PointCloud2`` (frame ``world``, float32 x y z) of the four sides and the top of a cube of ``edge``
    standing with its bottom face centred at ``bottom``: what a camera above it sees."""
    steps = np.arange(0.0, edge + 1e-9, POINT_SPACING_M) - edge / 2
    u, v = (a.ravel() for a in np.meshgrid(steps, steps))
    half = edge / 2
    faces = [
        np.column_stack([u, v, np.full_like(u, half)]),  # top
        np.column_stack([np.full_like(u, half), u, v]),
        np.column_stack([np.full_like(u, -half), u, v]),
        np.column_stack([u, np.full_like(u, half), v]),
        np.column_stack([u, np.full_like(u, -half), v]),
    ]
    points = (np.concatenate(faces) + bottom + np.array([0.0, 0.0, half])).astype(np.float32)
    msg = PointCloud2(
        header=Header(frame_id="world"),
        height=1,
        width=len(points),
        fields=[PointField(name=n, offset=4 * k, datatype=PointField.FLOAT32, count=1) for k, n in enumerate("xyz")],
        is_bigendian=False,
        point_step=12,
        row_step=12 * len(points),
        data=points.tobytes(),
        is_dense=True,
    )
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, 10**9)
    return msg


class ArmWatch:
    """The latest ``joint_states`` positions by name, from ``topic``."""

    def __init__(self, node: Node, topic: str) -> None:
        self.positions: dict[str, float] = {}
        self.count = 0  # messages heard
        node.create_subscription(JointState, topic, self._on_state, STATE_QOS)

    def _on_state(self, msg: JointState) -> None:
        self.positions.update(zip(msg.name, msg.position, strict=False))
        self.count += 1

    def at(self, names: list[str], values: list[float], tolerance: float = 1e-6) -> bool:
        return all(abs(self.positions.get(n, np.inf) - v) <= tolerance for n, v in zip(names, values, strict=True))


def _send_cloud(node: Node, client: PlannerClient, topic: str, msg: PointCloud2) -> None:
    publisher = node.create_publisher(PointCloud2, topic, CLOUD_QOS)
    if not client.wait_until(lambda: publisher.get_subscription_count() > 0, 10.0):
        raise RuntimeError(f"nobody subscribes to {topic}: is the planner's state.points true?")
    publisher.publish(msg)
    if not publisher.wait_for_all_acked(Duration(seconds=10.0)):
        raise RuntimeError(f"the planner did not acknowledge the cloud on {topic}")


def _obstacle(text: str) -> tuple[float, ...]:
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != 4:
        raise argparse.ArgumentTypeError(f"expected X,Y,Z,EDGE, got {text!r}")
    return values


def _plan(client: PlannerClient, goal: Any, timeout_s: float) -> Any:
    """A run to ``goal``, asked again (20 times at most, a quarter second apart) while the planner has no joint
    state yet (the arm's driver just started: ``START_STATE_UNKNOWN``)."""
    result = client.plan(goal, timeout_s=timeout_s)
    for _ in range(20):
        if result.outcome is not Outcome.START_STATE_UNKNOWN:
            break
        client.wait_until(lambda: False, 0.25)
        result = client.plan(goal, timeout_s=timeout_s)
    return result


def _settled(client: PlannerClient, arm: ArmWatch, trajectory: Any, states: int) -> bool:
    """Whether the arm came to rest at ``trajectory``'s last point (within 300 s); then ``states`` more joint
    states heard at rest, so the planner has heard them too before the next goal (its snapshot is the arm at
    rest)."""
    names = list(trajectory.joint_names)
    end = [float(v) for v in trajectory.points[-1].positions]
    if not client.wait_until(lambda: arm.at(names, end), 300.0):
        return False
    heard = arm.count + states
    client.wait_until(lambda: arm.count >= heard, 10.0)
    return True


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="pick_and_place_loop", description=__doc__.splitlines()[0])
    parser.add_argument("goals", type=goal_argument, nargs="+", help="X,Y,Z,ROLL,PITCH,YAW: the object's placements")
    parser.add_argument("--planner", default="/clew_planner", help="the planner node (default /clew_planner)")
    parser.add_argument("--cloud-after", type=int, default=1, help="publish the cloud before this goal (from 0)")
    parser.add_argument(
        "--obstacle", type=_obstacle, default=(0.39, 0.41, 0.12, 0.06), help="X,Y,Z,EDGE of the cube seen"
    )
    parser.add_argument("--timeout", type=float, default=120.0, help="seconds a goal may take (default 120)")
    parser.add_argument("--summary", type=Path, help="write the runs (id, outcome, recording) here as JSON")
    parser.add_argument(
        "--settle-states", type=int, default=25, help="joint states heard at rest before the next goal (default 25)"
    )
    args, ros_args = parser.parse_known_args(argv)
    rclpy.init(args=ros_args)
    node = rclpy.create_node("clew_pick_and_place")
    client = PlannerClient(node, args.planner)
    namespace = args.planner.rstrip("/").rsplit("/", 1)[0]
    arm = ArmWatch(node, f"{namespace}/joint_states")
    runs = []
    ok = True
    try:
        client.wait_for_planner(timeout_s=30.0)
        # the arm's driver up first: a goal sent before any joint state has come is refused START_STATE_UNKNOWN
        if not client.wait_until(lambda: bool(arm.positions), 30.0):
            print(f"no joint state on {namespace}/joint_states within 30 s: is the arm's driver running?")
            return 1
        for k, goal in enumerate(args.goals):
            if k == args.cloud_after:
                x, y, z, edge = args.obstacle
                cloud = cube_cloud(np.array([x, y, z]), edge, time.time_ns())
                _send_cloud(node, client, f"{args.planner}/points", cloud)
                print(f"cloud: a {edge} m cube standing at ({x}, {y}, {z}) published on {args.planner}/points")
            result = _plan(client, goal, args.timeout)
            text = f"goal {k + 1}/{len(args.goals)} {tuple(round(v, 3) for v in goal)}: {result.outcome.name}"
            runs.append({"goal": list(goal), "run_id": result.run_id, "outcome": result.outcome.name,
                         "recording": result.recording, "message": result.message})  # fmt: skip
            if not result.succeeded or result.plan is None or result.trajectory is None:
                print(f"{text}: {result.message}", flush=True)
                ok = False
                break
            plan = result.plan
            print(
                f"{text}, {len(plan.segments)} segments, {plan.grasp_count} grasps, {result.time_s:.2f} s, "
                f"recording {result.recording}",
                flush=True,
            )
            if not _settled(client, arm, result.trajectory, args.settle_states):
                print("the arm did not reach the end of the trajectory", flush=True)
                ok = False
                break
    except KeyboardInterrupt:
        ok = False
    finally:
        if args.summary is not None:
            args.summary.write_text(json.dumps(runs, indent=1))
        client.destroy()
        node.destroy_node()
        rclpy.try_shutdown()
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
