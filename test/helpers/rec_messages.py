"""Messages of every clew_planner topic (interface.md section 3), built in-process.

Used by the recording, replay and render tests to write realistic recordings
without running the node: :func:`sample_run` returns ``(topic, message,
time_ns)`` triples for one run, in publishing order.
"""

from __future__ import annotations

import json
import math
import uuid
from pathlib import Path

from action_msgs.msg import GoalInfo, GoalStatus, GoalStatusArray
from builtin_interfaces.msg import Duration, Time
from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion
from sensor_msgs.msg import JointState
from std_msgs.msg import ColorRGBA, Header, String
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
from unique_identifier_msgs.msg import UUID
from visualization_msgs.msg import Marker, MarkerArray

NODE = "/clew_planner"

#: Topic -> message type name of everything the node publishes (and records).
TOPIC_TYPES = {
    f"{NODE}/status": "action_msgs/msg/GoalStatusArray",
    f"{NODE}/feedback": "diagnostic_msgs/msg/DiagnosticStatus",
    f"{NODE}/events": "std_msgs/msg/String",
    f"{NODE}/landmarks": "visualization_msgs/msg/MarkerArray",
    f"{NODE}/trajectory": "trajectory_msgs/msg/JointTrajectory",
    f"{NODE}/joint_states": "sensor_msgs/msg/JointState",
    f"{NODE}/object_pose": "geometry_msgs/msg/PoseStamped",
    f"{NODE}/world_markers": "visualization_msgs/msg/MarkerArray",
    f"{NODE}/world_yaml": "std_msgs/msg/String",
}
LATCHED = {f"{NODE}/{name}" for name in ("status", "trajectory", "landmarks", "world_markers", "world_yaml")}


def stamp(time_ns: int) -> Time:
    return Time(sec=time_ns // 10**9, nanosec=time_ns % 10**9)


def header(time_ns: int, frame: str = "world") -> Header:
    return Header(stamp=stamp(time_ns), frame_id=frame)


def quaternion(yaw: float) -> Quaternion:
    return Quaternion(z=math.sin(yaw / 2), w=math.cos(yaw / 2))


def status(run: uuid.UUID, code: int, time_ns: int) -> GoalStatusArray:
    info = GoalInfo(goal_id=UUID(uuid=list(run.bytes)), stamp=stamp(time_ns))
    return GoalStatusArray(status_list=[GoalStatus(goal_info=info, status=code)])


def feedback(run: uuid.UUID, landmarks: int, best: float, elapsed: float) -> DiagnosticStatus:
    values = [
        KeyValue(key="run_id", value=run.hex),
        KeyValue(key="landmarks", value=str(landmarks)),
        KeyValue(key="best_distance", value=f"{best:.4f}"),
        KeyValue(key="elapsed", value=f"{elapsed:.3f}"),
    ]
    return DiagnosticStatus(level=DiagnosticStatus.OK, name="clew_planner", message="planning", values=values)


def event(run: uuid.UUID, name: str, time_s: float, **fields) -> String:
    return String(data=json.dumps({"run_id": run.hex, "event": name, "time": time_s, **fields}))


def _marker(ns: str, kind: int, time_ns: int, points, rgb=(0.25, 0.5, 1.0), marker_id: int = 0) -> Marker:
    # colours are float32: values exact in float32 keep messages equal after a round trip
    marker = Marker(
        header=header(time_ns),
        ns=ns,
        id=marker_id,
        type=kind,
        action=Marker.ADD,
        color=ColorRGBA(r=rgb[0], g=rgb[1], b=rgb[2], a=1.0),
    )
    marker.pose.orientation.w = 1.0
    marker.scale.x = marker.scale.y = marker.scale.z = 0.02
    marker.points = [Point(x=float(x), y=float(y)) for x, y in points]
    return marker


def landmark_markers(landmarks: list[dict], time_ns: int) -> MarkerArray:
    """DELETEALL, then a SPHERE_LIST of resting positions and a LINE_LIST of parent -> child edges."""
    nodes = [lm["object_pose"][:2] for lm in landmarks]
    index = {lm["id"]: i for i, lm in enumerate(landmarks)}
    edges = []
    for lm in landmarks:
        if lm["parent"] is not None:
            edges += [nodes[index[lm["parent"]]], lm["object_pose"][:2]]
    return MarkerArray(
        markers=[
            Marker(header=header(time_ns), action=Marker.DELETEALL),
            _marker("landmarks", Marker.SPHERE_LIST, time_ns, nodes),
            _marker("tree_edges", Marker.LINE_LIST, time_ns, edges),
        ]
    )


def world_markers(world, time_ns: int) -> MarkerArray:
    xmin, ymin, xmax, ymax = world.bounds
    corners = [(xmin, ymin), (xmax, ymin), (xmax, ymax), (xmin, ymax), (xmin, ymin)]
    markers = [_marker("bounds", Marker.LINE_STRIP, time_ns, corners, (0.625, 0.625, 0.625))]
    for i, obstacle in enumerate(world.obstacles):
        ring = [*list(obstacle.vertices), obstacle.vertices[0]]
        markers.append(_marker("obstacles", Marker.LINE_STRIP, time_ns, ring, (0.375, 0.375, 0.375), marker_id=i))
    return MarkerArray(markers=markers)


def trajectory(plan: dict, time_ns: int, step_s: float = 0.5) -> JointTrajectory:
    """The plan as ``~/trajectory``: waypoints in order, ``gripper`` 1.0 on transfer points."""
    msg = JointTrajectory(header=header(time_ns), joint_names=[*list(plan["joint_names"]), "gripper"])
    t = 0.0
    for segment in plan["segments"]:
        gripper = 1.0 if segment["kind"] == "transfer" else 0.0
        for waypoint in segment["waypoints"]:
            ns = round(t * 1e9)
            msg.points.append(
                JointTrajectoryPoint(
                    positions=[float(v) for v in waypoint] + [gripper],
                    time_from_start=Duration(sec=ns // 10**9, nanosec=ns % 10**9),
                )
            )
            t += step_s
    return msg


def sample_run(
    world,
    world_text: str,
    plan: dict | None,
    run: uuid.UUID | None = None,
    start_ns: int = 1_700_000_000_000_000_000,
    outcome: str = "succeeded",
):
    """``(topic, message, time_ns)`` for one run, 10 ms apart, in publishing order."""
    run = run or uuid.UUID(int=0x1234)
    out = []
    clock = iter(range(start_ns, start_ns + 10**12, 10_000_000))

    def put(name, msg):
        out.append((f"{NODE}/{name}", msg, next(clock)))

    put("world_yaml", String(data=world_text))
    put("world_markers", world_markers(world, start_ns))
    put("status", status(run, GoalStatus.STATUS_ACCEPTED, start_ns))
    put("events", event(run, "accepted", 0.0))
    put("status", status(run, GoalStatus.STATUS_EXECUTING, start_ns))
    landmarks = (plan or {}).get("landmarks") or [{"id": 0, "parent": None, "object_pose": list(world.object.initial)}]
    for count in range(1, len(landmarks) + 1):
        put("feedback", feedback(run, count, 1.0 / count, 0.1 * count))
        put("landmarks", landmark_markers(landmarks[:count], start_ns))
        put("events", event(run, "landmark", 0.1 * count, landmark=count - 1))
    if plan is not None and plan.get("success") and outcome == "succeeded":
        put("trajectory", trajectory(plan, start_ns))
        t = 0.0
        for segment in plan["segments"]:
            if segment["kind"] == "transfer":
                put("events", event(run, "grasp", t, grasp=segment["grasp"]))
            for waypoint in segment["waypoints"]:
                gripper = 1.0 if segment["kind"] == "transfer" else 0.0
                put(
                    "joint_states",
                    JointState(
                        header=header(start_ns, ""),
                        name=[*list(plan["joint_names"]), "gripper"],
                        position=[float(v) for v in waypoint] + [gripper],
                    ),
                )
                t += 0.5
            if segment["kind"] == "transfer":
                put("events", event(run, "ungrasp", t, grasp=segment["grasp"]))
        pose = plan["final_object_pose"]
        put(
            "object_pose",
            PoseStamped(
                header=header(start_ns),
                pose=Pose(position=Point(x=pose[0], y=pose[1]), orientation=quaternion(pose[2])),
            ),
        )
        code = GoalStatus.STATUS_SUCCEEDED
    else:
        code = GoalStatus.STATUS_CANCELED if outcome == "canceled" else GoalStatus.STATUS_ABORTED
        pose = list(world.object.initial)
        put(
            "object_pose",
            PoseStamped(
                header=header(start_ns),
                pose=Pose(position=Point(x=pose[0], y=pose[1]), orientation=quaternion(pose[2])),
            ),
        )
    put("events", event(run, outcome, 1.0, code=code, message=f"run {outcome}"))
    put("status", status(run, code, start_ns))
    return out


def counts(triples) -> dict[str, int]:
    result: dict[str, int] = {}
    for topic, _msg, _t in triples:
        result[topic] = result.get(topic, 0) + 1
    return result


def world_text(path: str | Path) -> str:
    return Path(path).read_text()


__all__ = ["LATCHED", "TOPIC_TYPES", "counts", "sample_run", "trajectory", "world_text"]
