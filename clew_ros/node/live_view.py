"""The node's Foxglove live view (``live.foxglove_port``), started with the node."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rclpy.node import Node

    from clew_ros.live import LiveView
    from clew_ros.ros.parameters import Configuration

__all__ = ["start_live_view"]


def start_live_view(node: Node, config: Configuration) -> LiveView | None:
    """The Foxglove live view on ``live.foxglove_port`` (0: none); a failure is logged, the node serves on."""
    settings = config.node
    if settings.foxglove_port == 0:
        return None
    from clew_ros.live import LiveView, LiveViewError

    live = LiveView(
        port=settings.foxglove_port,
        namespace=node.get_fully_qualified_name(),
        name=node.get_name(),
        rate_hz=settings.playback_rate_hz,
        max_velocity_rad_s=settings.velocity_limit_rad_s,
        max_acceleration_rad_s2=settings.max_acceleration_rad_s2,
        grasp_dwell_s=settings.grasp_dwell_s,
        spatial=config.spatial is not None,
    )
    try:
        live.start()
    except LiveViewError as error:
        node.get_logger().error(f"live.foxglove_port: {error}; runs are not served live")
        return None
    node.get_logger().info(f"serving runs live to Foxglove at {live.url}")
    return live
