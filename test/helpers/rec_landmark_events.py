"""``landmark`` events as the node sends them, for recordings built with :mod:`rec_messages`.

The node announces each landmark on ``~/events`` with ``id``, ``parent``,
``grasp``, ``object_pose`` and ``joints`` (README, ``~/events``), all but
the root (``clew_ros/node``: "landmarks already announced (the root)");
:func:`rec_messages.sample_run` writes only the landmark's index, the root's too. These
helpers rewrite its ``(topic, message, time_ns)`` triples.
"""

from __future__ import annotations

import json

from std_msgs.msg import String

EVENTS = "/clew_planner/events"


def _is_landmark_event(topic: str, msg) -> bool:
    return topic == EVENTS and json.loads(msg.data).get("event") == "landmark"


def with_landmark_events(triples, landmarks: list[dict], *, announce_root: bool = False) -> list:
    """``triples`` with each ``landmark`` event (``landmark=K``) carrying landmark ``K`` of ``landmarks`` in full.

    Like the node, the root (the landmark without a parent) is not announced,
    unless ``announce_root``.
    """
    out = []
    for topic, msg, time_ns in triples:
        if not _is_landmark_event(topic, msg):
            out.append((topic, msg, time_ns))
            continue
        data = json.loads(msg.data)
        landmark = landmarks[data.pop("landmark")]
        if landmark["parent"] is None and not announce_root:
            continue
        data.update({key: landmark[key] for key in ("id", "parent", "grasp", "object_pose", "joints")})
        out.append((topic, String(data=json.dumps(data)), time_ns))
    return out


def without_landmark_events(triples) -> list:
    """``triples`` without any ``landmark`` event (the ``~/landmarks`` markers stay)."""
    return [(topic, msg, time_ns) for topic, msg, time_ns in triples if not _is_landmark_event(topic, msg)]
