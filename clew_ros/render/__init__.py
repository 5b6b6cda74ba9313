"""Pictures of worlds, plans and recorded runs: PNG, GIF and SVG, without matplotlib.

A :class:`Scene` (world, optional plan, optional landmark tree) is built from
a world file, a plan file or a recording (:mod:`clew_ros.render.scene`). It is
drawn once, into back-end-neutral shapes (:mod:`clew_ros.render.shapes`), by
:mod:`clew_ros.render.draw`: :func:`draw_still` for the filmstrip of fading
poses along the plan, :func:`draw_animation` for the animation that holds at
each grasp and ungrasp. The back ends only paint those shapes:
:mod:`clew_ros.render.raster` (Pillow: :func:`render_png`, :func:`render_gif`)
and :mod:`clew_ros.render.svg` (:func:`render_svg`, the PNG's shapes as SVG).
"""

from clew_ros.render.draw import draw_animation, draw_still
from clew_ros.render.errors import RenderError
from clew_ros.render.raster import render_gif, render_png
from clew_ros.render.scene import (
    LandmarkGraph,
    Motion,
    Scene,
    landmarks_from_events,
    scene_from_plan,
    scene_from_recording,
    scene_from_world,
    world_from_yaml_text,
)
from clew_ros.render.shapes import Animation, Drawing
from clew_ros.render.svg import render_svg

__all__ = [
    "Animation",
    "Drawing",
    "LandmarkGraph",
    "Motion",
    "RenderError",
    "Scene",
    "draw_animation",
    "draw_still",
    "landmarks_from_events",
    "render_gif",
    "render_png",
    "render_svg",
    "scene_from_plan",
    "scene_from_recording",
    "scene_from_world",
    "world_from_yaml_text",
]
