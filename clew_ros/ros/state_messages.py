"""The inputs of the world as it is now (interface.md section 3c) read from their standard messages.

- :func:`joint_positions`: a ``sensor_msgs/JointState``'s positions by name, and its stamp.
- :func:`object_matrix`: a ``geometry_msgs/PoseStamped`` of the object as a 4x4 pose (frame ``world``).
- :func:`apply_markers`: a ``visualization_msgs/MarkerArray`` applied to the obstacles added so far (``CUBE``,
  ``SPHERE``, ``CYLINDER``; ``ADD``/``MODIFY``, ``DELETE``, ``DELETEALL``), named ``<ns>/<id>``.
- :func:`cloud_xyz`: a ``sensor_msgs/PointCloud2``'s float32 ``x y z`` as an (N, 3) array, read over the whole
  buffer at once.

Each raises :class:`StateInputError` saying what is wrong with the message (the node logs it and keeps the
previous state).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from clew_ros.ros.messages import FRAME_ID, QUATERNION_TOLERANCE, quoted_text
from clew_ros.spatial.snapshot import POINTS_PREFIX, AddedObstacle
from clew_ros.spatial.transforms import matrix_pose, quaternion_matrix

__all__ = ["StateInputError", "apply_markers", "cloud_xyz", "joint_positions", "object_matrix", "stamp_ns"]

#: ``visualization_msgs/Marker`` types and actions (numbers, so that this module reads without the message).
_CUBE, _SPHERE, _CYLINDER = 1, 2, 3
_ADD, _DELETE, _DELETEALL = 0, 2, 3  # MODIFY is ADD (0)
#: ``sensor_msgs/PointField.FLOAT32``.
_FLOAT32 = 7


class StateInputError(ValueError):
    """A state message the node cannot use; the message says why."""


def stamp_ns(header: Any) -> int:
    """A header's stamp (ns)."""
    return int(header.stamp.sec) * 10**9 + int(header.stamp.nanosec)


def _frame(header: Any, topic: str) -> None:
    frame = header.frame_id
    if frame not in ("", FRAME_ID):
        raise StateInputError(f"{topic}: header.frame_id must be '{FRAME_ID}' (or empty), got '{quoted_text(frame)}'")


def joint_positions(msg: Any) -> dict[str, float]:
    """The finite positions of a ``JointState`` by joint name (a name without a position, or with a
    non-finite one, is left out)."""
    out = {}
    for name, value in zip(msg.name, msg.position, strict=False):
        if math.isfinite(value):
            out[str(name)] = float(value)
    return out


def _matrix(pose: Any, what: str) -> NDArray[np.float64]:
    p, q = pose.position, pose.orientation
    values = [p.x, p.y, p.z, q.x, q.y, q.z, q.w]
    if not all(math.isfinite(v) for v in values):
        raise StateInputError(f"{what}: position and orientation must be finite numbers")
    norm = math.sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w)
    if abs(norm - 1.0) > QUATERNION_TOLERANCE:
        raise StateInputError(f"{what}: orientation must be a unit quaternion, got norm {norm:.6g}")
    return quaternion_matrix([p.x, p.y, p.z], [q.x / norm, q.y / norm, q.z / norm, q.w / norm])


def object_matrix(msg: Any) -> NDArray[np.float64]:
    """The object's pose of an ``~/object`` ``PoseStamped`` (4x4 in ``world``)."""
    _frame(msg.header, "object")
    return _matrix(msg.pose, "object")


def _marker_obstacle(marker: Any, name: str) -> AddedObstacle:
    s = marker.scale
    if not all(math.isfinite(v) and v > 0.0 for v in (s.x, s.y, s.z)):
        raise StateInputError(f"obstacles: marker {name}: scale must be positive, got ({s.x}, {s.y}, {s.z})")
    pose = tuple(float(v) for v in matrix_pose(_matrix(marker.pose, f"obstacles: marker {name}")))
    if marker.type == _CUBE:
        return AddedObstacle(name, "box", (float(s.x), float(s.y), float(s.z)), pose)
    if marker.type == _SPHERE:  # RViz draws an ellipsoid of diameters scale: the sphere that holds it
        return AddedObstacle(name, "sphere", (max(s.x, s.y, s.z) / 2,), pose)
    if marker.type == _CYLINDER:  # diameters scale.x, scale.y, height scale.z
        return AddedObstacle(name, "cylinder", (float(s.z), max(s.x, s.y) / 2), pose)
    raise StateInputError(f"obstacles: marker {name}: type {marker.type} is not CUBE (1), SPHERE (2) or CYLINDER (3)")


def apply_markers(
    msg: Any, obstacles: Mapping[str, AddedObstacle], reserved: frozenset[str] = frozenset()
) -> tuple[dict[str, AddedObstacle], list[str]]:
    """The added obstacles after ``msg`` (a ``MarkerArray``), in order, and what was refused in it (one line a
    marker; the others apply). ``reserved``: names that are taken (the parameters' obstacles)."""
    out = dict(obstacles)
    refused = []
    for marker in msg.markers:
        name = f"{marker.ns}/{marker.id}"
        try:
            if marker.action == _DELETEALL:
                out.clear()
                continue
            _frame(marker.header, f"obstacles: marker {name}")
            if marker.action == _DELETE:
                out.pop(name, None)
            elif marker.action == _ADD:
                if name in reserved or name.startswith(POINTS_PREFIX):
                    raise StateInputError(f"obstacles: marker {name}: the name is taken by an obstacle of the world")
                out[name] = _marker_obstacle(marker, name)
            else:
                raise StateInputError(f"obstacles: marker {name}: action {marker.action} is not ADD, DELETE, DELETEALL")
        except StateInputError as error:
            refused.append(str(error))
    return out, refused


def cloud_xyz(msg: Any, max_points: int) -> NDArray[np.float32]:
    """The points (N, 3) of a ``PointCloud2`` with float32 fields ``x``, ``y``, ``z`` (any point step, either
    byte order), in frame ``world``; more than ``max_points`` is refused naming ``state.max_points``."""
    _frame(msg.header, "points")
    count = int(msg.width) * int(msg.height)
    if count > max_points:
        raise StateInputError(f"points: {count} points exceed state.max_points {max_points}; the cloud is refused")
    fields = {f.name: f for f in msg.fields}
    for axis in "xyz":
        if axis not in fields or fields[axis].datatype != _FLOAT32 or fields[axis].count not in (0, 1):
            raise StateInputError("points: expected float32 fields x, y and z")
    step, row = int(msg.point_step), int(msg.row_step)
    if step < 12 or any(fields[a].offset + 4 > step for a in "xyz"):
        raise StateInputError(f"points: point_step {step} does not hold the x, y, z fields")
    data = bytes(msg.data) if not isinstance(msg.data, (bytes, bytearray, memoryview)) else msg.data
    if row < step * int(msg.width) or len(data) < row * int(msg.height):
        raise StateInputError(f"points: data holds {len(data)} bytes, expected {row} x {msg.height} rows")
    if count == 0:
        return np.zeros((0, 3), dtype=np.float32)
    order = ">" if msg.is_bigendian else "<"
    dtype = np.dtype(
        {"names": ["x", "y", "z"], "formats": [order + "f4"] * 3, "offsets": [fields[a].offset for a in "xyz"],
         "itemsize": step}
    )  # fmt: skip
    rows = np.frombuffer(data, dtype=np.uint8, count=row * int(msg.height)).reshape(int(msg.height), row)
    packed = np.ascontiguousarray(rows[:, : step * int(msg.width)]).view(dtype).reshape(-1)
    out = np.empty((count, 3), dtype=np.float32)
    out[:, 0], out[:, 1], out[:, 2] = packed["x"], packed["y"], packed["z"]
    return out
