"""The inputs of the world as it is now read from their messages (``clew_ros.ros.state_messages``): a
PointCloud2's float32 x y z at any point step, row padding and byte order, refused beyond state.max_points;
markers added, replaced, deleted and cleared by ``<ns>/<id>``, each shape at RViz's scale; a joint state's
finite positions by name."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("rclpy")

from geometry_msgs.msg import Point, Pose, Quaternion, Vector3
from sensor_msgs.msg import JointState, PointCloud2, PointField
from std_msgs.msg import Header
from visualization_msgs.msg import Marker, MarkerArray

from clew_ros.ros.state_messages import (
    StateInputError,
    apply_markers,
    cloud_xyz,
    joint_positions,
)


def _cloud(points: np.ndarray, *, big: bool = False, width: int | None = None, pad_row: int = 0) -> PointCloud2:
    """A cloud with fields intensity (float32), x, y, z at offsets 0, 8, 12, 16 of a 24-byte point."""
    width = len(points) if width is None else width
    height = len(points) // width
    order = ">" if big else "<"
    dtype = np.dtype(
        {"names": ["i", "x", "y", "z"], "formats": [order + "f4"] * 4, "offsets": [0, 8, 12, 16], "itemsize": 24}
    )
    packed = np.zeros(len(points), dtype=dtype)
    packed["x"], packed["y"], packed["z"], packed["i"] = points[:, 0], points[:, 1], points[:, 2], 7.0
    rows = packed.tobytes()
    row_step = 24 * width + pad_row
    data = b"".join(rows[r * 24 * width : (r + 1) * 24 * width] + b"\0" * pad_row for r in range(height))
    fields = [PointField(name="intensity", offset=0, datatype=PointField.FLOAT32, count=1)] + [
        PointField(name=n, offset=8 + 4 * k, datatype=PointField.FLOAT32, count=1) for k, n in enumerate("xyz")
    ]
    return PointCloud2(
        header=Header(frame_id="world"), height=height, width=width, fields=fields, is_bigendian=big,
        point_step=24, row_step=row_step, data=data, is_dense=True,
    )  # fmt: skip


POINTS = np.arange(36, dtype=np.float32).reshape(12, 3) / 10


@pytest.mark.parametrize(("big", "width", "pad"), [(False, None, 0), (True, None, 0), (False, 4, 8)])
def test_a_cloud_reads_as_its_points(big: bool, width: int | None, pad: int) -> None:
    assert np.array_equal(cloud_xyz(_cloud(POINTS, big=big, width=width, pad_row=pad), 100), POINTS)


def test_a_cloud_over_the_cap_or_in_another_frame_is_refused() -> None:
    with pytest.raises(StateInputError, match=r"state\.max_points 11"):
        cloud_xyz(_cloud(POINTS), 11)
    other = _cloud(POINTS)
    other.header.frame_id = "camera"
    with pytest.raises(StateInputError, match="frame_id"):
        cloud_xyz(other, 100)
    short = _cloud(POINTS)
    short.data = bytes(short.data)[:-1]
    with pytest.raises(StateInputError, match="bytes"):
        cloud_xyz(short, 100)


def _marker(ns: str, key: int, kind: int, action: int = Marker.ADD, scale: tuple = (0.1, 0.2, 0.3)) -> Marker:
    return Marker(
        header=Header(frame_id="world"), ns=ns, id=key, type=kind, action=action,
        pose=Pose(position=Point(x=1.0, y=2.0, z=3.0), orientation=Quaternion(w=1.0)),
        scale=Vector3(x=scale[0], y=scale[1], z=scale[2]),
    )  # fmt: skip


def test_markers_add_replace_delete_and_clear_obstacles() -> None:
    added, refused = apply_markers(
        MarkerArray(
            markers=[
                _marker("a", 1, Marker.CUBE),
                _marker("a", 2, Marker.SPHERE),
                _marker("b", 1, Marker.CYLINDER),
                _marker("c", 1, Marker.ARROW),
                _marker("table", 0, Marker.CUBE),
            ]
        ),
        {},
        frozenset({"table/0"}),
    )
    assert list(added) == ["a/1", "a/2", "b/1"]
    assert added["a/1"].shape == "box"
    assert added["a/1"].size == pytest.approx((0.1, 0.2, 0.3))
    assert added["a/2"].shape == "sphere"
    assert added["a/2"].size == pytest.approx((0.15,))
    assert added["b/1"].shape == "cylinder"
    assert added["b/1"].size == pytest.approx((0.3, 0.1))
    assert added["a/1"].pose == pytest.approx((1.0, 2.0, 3.0, 0.0, 0.0, 0.0))
    assert len(refused) == 2
    assert "c/1" in refused[0]
    assert "table/0" in refused[1]
    replaced, _ = apply_markers(MarkerArray(markers=[_marker("a", 1, Marker.CUBE, scale=(0.5, 0.5, 0.5))]), added)
    assert replaced["a/1"].size == pytest.approx((0.5, 0.5, 0.5))
    assert "a/1" in added
    deleted, _ = apply_markers(MarkerArray(markers=[_marker("a", 2, Marker.CUBE, Marker.DELETE)]), replaced)
    assert list(deleted) == ["a/1", "b/1"]
    cleared, _ = apply_markers(MarkerArray(markers=[Marker(action=Marker.DELETEALL)]), deleted)
    assert cleared == {}


def test_a_joint_state_gives_its_finite_positions_by_name() -> None:
    msg = JointState(name=["a", "b", "c"], position=[0.5, float("nan"), -1.0])
    assert joint_positions(msg) == {"a": 0.5, "c": -1.0}
