"""A run's ``~/events`` fields and terminal ``GoalStatus`` (interface.md §3), shared by the node and
its recordings made offline (``clew_batch --record``); :func:`clew_ros.ros.messages.event_message` wraps
the fields into the message."""

from __future__ import annotations

from typing import Any

import numpy as np
from action_msgs.msg import GoalStatus

from clew_ros.core.settings import Outcome
from clew_ros.motion.playback import Track

__all__ = [
    "accepted_fields",
    "landmark_fields",
    "outcome_event",
    "outcome_fields",
    "outcome_status",
    "spatial_plan_fields",
]


def outcome_status(outcome: Outcome) -> int:
    """The terminal ``GoalStatus`` of an outcome: succeeded, canceled, else aborted."""
    status: int = {Outcome.SUCCEEDED: GoalStatus.STATUS_SUCCEEDED, Outcome.CANCELED: GoalStatus.STATUS_CANCELED}.get(
        outcome, GoalStatus.STATUS_ABORTED
    )
    return status


def outcome_event(outcome: Outcome) -> str:
    """The ``~/events`` name of an outcome: ``succeeded``, ``canceled``, else ``aborted``."""
    return {Outcome.SUCCEEDED: "succeeded", Outcome.CANCELED: "canceled"}.get(outcome, "aborted")


def outcome_fields(outcome: Outcome, message: str, *, landmarks: int, time_s: float, recording: str) -> dict[str, Any]:
    """The fields of a run's outcome event (``~/events``, besides ``run_id``, ``event`` and ``time``): the
    outcome's ``code`` and ``code_value``, ``message``, ``landmarks``, the planner's ``time_s`` and what
    the run's ``recording`` is."""
    return {
        "code": outcome.name,
        "code_value": outcome.value,
        "message": message,
        "landmarks": landmarks,
        "time_s": time_s,
        "recording": recording,
    }


def accepted_fields(*, source: str, world: str, goal: np.ndarray, seed: int, recording: str) -> dict[str, Any]:
    """The fields of a run's ``accepted`` event (``~/events``, besides ``run_id``, ``event`` and ``time``):
    what started it (``source``), the ``world``'s name, the object ``goal``, the planner's ``seed`` and
    what the run's ``recording`` is."""
    return {"source": source, "world": world, "goal": np.asarray(goal).tolist(), "seed": seed, "recording": recording}


def landmark_fields(landmark: Any) -> dict[str, Any]:
    """The fields of a ``landmark`` event (``~/events``) for ``landmark`` (a landmark of the tree or of a
    plan file: ``id``, ``parent``, ``grasp``, ``object_pose``, ``joints``)."""
    return {
        "id": landmark.id,
        "parent": landmark.parent,
        "grasp": landmark.grasp,
        "object_pose": landmark.object_pose,
        "joints": landmark.joints,
    }


def spatial_plan_fields(track: Track, *, has_object: bool) -> dict[str, object]:
    """What a spatial run's ``succeeded`` event adds, so that a client rebuilds the plan from
    ``~/trajectory`` alone (its points carry no ``gripper``): ``segments``, each ``kind``, ``grasp`` and
    the number of trajectory ``points`` it has (in order; together every point), and ``final_object_pose``
    (6 numbers; ``None`` in a motion-only world)."""
    segments = []
    for index, grasp in enumerate(track.grasps):
        segments.append(
            {
                "kind": "transit" if grasp is None else "transfer",
                "grasp": grasp,
                "points": int(np.count_nonzero(track.segment == index)),
            }
        )
    final = [float(v) for v in track.object_poses[-1]] if has_object else None
    return {"segments": segments, "final_object_pose": final}
