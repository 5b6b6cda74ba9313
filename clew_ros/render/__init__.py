"""Pictures of worlds, plans and recorded runs: PNG, GIF and SVG, without matplotlib.

A :class:`Scene` (world, optional plan, optional landmark tree) is built from
a world file, a plan file or a recording; :func:`render_png` overlays fading
poses along the plan (a filmstrip), :func:`render_gif` animates it with the
grasps and ungrasps marked, :func:`render_svg` writes the filmstrip as SVG.
"""

from clew_ros.render.errors import RenderError
from clew_ros.render.raster import render_gif, render_png
from clew_ros.render.scene import (
    LandmarkGraph,
    Motion,
    Scene,
    scene_from_plan,
    scene_from_recording,
    scene_from_world,
    world_from_yaml_text,
)
from clew_ros.render.svg import render_svg

__all__ = [
    "RenderError",
    "Scene",
    "Motion",
    "LandmarkGraph",
    "scene_from_world",
    "scene_from_plan",
    "scene_from_recording",
    "world_from_yaml_text",
    "render_png",
    "render_gif",
    "render_svg",
]
