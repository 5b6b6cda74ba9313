"""Pictures of spatial worlds (interface.md section 1b) with Pillow and numpy only: no display, no GPU.

- :mod:`~clew_ros.render.spatial.camera`: the viewpoint (:class:`View3D`: azimuth, elevation, distance or a
  camera pose; by default framing the scene) and the perspective projection;
- :mod:`~clew_ros.render.spatial.meshes`: triangles of primitives, of the robot's links (large meshes
  simplified once per link and cached), of the robot at a configuration;
- :mod:`~clew_ros.render.spatial.zbuffer`: the numpy z-buffer rasteriser, with see-through layers;
- :mod:`~clew_ros.render.spatial.picture`: stills (:func:`draw_spatial_frames`, :func:`draw_spatial_world`)
  and GIFs (:func:`write_spatial_gif`);
- :mod:`~clew_ros.render.spatial.frames`: frames from a spatial plan file or a frames file.
"""

from clew_ros.render.spatial.camera import Camera, View3D, parse_view
from clew_ros.render.spatial.picture import (
    SpatialStyle,
    draw_spatial_frames,
    draw_spatial_world,
    spatial_gif_frames,
    write_spatial_gif,
)

__all__ = [
    "Camera",
    "SpatialStyle",
    "View3D",
    "draw_spatial_frames",
    "draw_spatial_world",
    "parse_view",
    "spatial_gif_frames",
    "write_spatial_gif",
]
