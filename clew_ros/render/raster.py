"""The PNG and GIF back end (Pillow): paints the shapes of a drawing, nothing more.

What a picture shows is decided in :mod:`clew_ros.render.draw`; this module
only turns shapes into pixels (and a dashed outline into dashes).
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from clew_ros.render.draw import draw_animation, draw_still
from clew_ros.render.scene import Scene
from clew_ros.render.shapes import Circle, Drawing, Paint, Point, Polygon, Polyline, Rect, Shape, Text
from clew_ros.render.text import font

__all__ = ["paint", "rasterize", "render_gif", "render_png"]


def _ink(paint: Paint | None) -> tuple[int, int, int, int] | None:
    return None if paint is None else paint.rgba


def _dashed(
    draw: ImageDraw.ImageDraw, points: tuple[Point, ...], ink: tuple[int, ...], width: int, dash: float
) -> None:
    """A closed dashed outline: dashes and gaps ``dash`` pixels long, the pattern running on round the corners."""
    pts = np.asarray(points + points[:1], dtype=float)
    carry = 0.0
    for a, b in itertools.pairwise(pts):
        length = float(np.hypot(*(b - a)))
        if length == 0:
            continue
        direction = (b - a) / length
        t = -carry
        while t < length:
            start, end = max(t, 0.0), min(t + dash, length)
            if end > start:
                (x0, y0), (x1, y1) = a + direction * start, a + direction * end
                draw.line([(float(x0), float(y0)), (float(x1), float(y1))], fill=ink, width=width)
            t += 2 * dash
        carry = t - length


def _paint_one(draw: ImageDraw.ImageDraw, shape: Shape) -> None:
    if isinstance(shape, Polygon):
        points = list(shape.points)
        if shape.dash is None:
            draw.polygon(points, fill=_ink(shape.fill), outline=_ink(shape.outline), width=shape.width)
        else:
            if shape.fill is not None:
                draw.polygon(points, fill=shape.fill.rgba)
            if shape.outline is not None:
                _dashed(draw, shape.points, shape.outline.rgba, shape.width, shape.dash)
    elif isinstance(shape, Polyline):
        draw.line(
            list(shape.points), fill=shape.stroke.rgba, width=shape.width, joint="curve" if shape.rounded else None
        )
    elif isinstance(shape, Rect):
        draw.rectangle(
            [shape.x0, shape.y0, shape.x1, shape.y1],
            fill=_ink(shape.fill),
            outline=_ink(shape.outline),
            width=shape.width,
        )
    elif isinstance(shape, Circle):
        (x, y), r = shape.centre, shape.radius
        draw.ellipse(
            [x - r, y - r, x + r, y + r], fill=_ink(shape.fill), outline=_ink(shape.outline), width=shape.width
        )
    elif isinstance(shape, Text):
        draw.text(
            shape.position,
            shape.text,
            fill=shape.paint.rgba,
            font=font(shape.size),
            anchor=None if shape.anchor == "la" else shape.anchor,
        )  # "la" is Pillow's default
    else:  # pragma: no cover - Shape is closed
        raise TypeError(f"not a shape: {shape!r}")


def paint(image: Image.Image, shapes: Iterable[Shape]) -> Image.Image:
    """Paint ``shapes`` over ``image`` in order (alpha-blended); returns ``image``."""
    draw = ImageDraw.Draw(image, "RGBA")
    for shape in shapes:
        _paint_one(draw, shape)
    return image


def rasterize(drawing: Drawing) -> Image.Image:
    """The drawing as an RGB image."""
    image = Image.new("RGB", (drawing.width, drawing.height), drawing.background.rgb)
    return paint(image, drawing.shapes)


def render_png(scene: Scene, path: str | Path, size: int = 800) -> Path:
    """Write the scene's filmstrip (:func:`~clew_ros.render.draw.draw_still`) as a PNG ``size`` pixels wide."""
    path = Path(path)
    rasterize(draw_still(scene, size)).save(path, format="PNG", optimize=True)
    return path


def render_gif(scene: Scene, path: str | Path, size: int = 600) -> Path:
    """Write the scene's animation (:func:`~clew_ros.render.draw.draw_animation`) as a looping GIF."""
    animation = draw_animation(scene, size)
    base = rasterize(animation.base)
    frames = [paint(base.copy(), frame.shapes) for frame in animation.frames]
    palette = _palette(frames, animation.base.background)
    quantized = [f.quantize(palette=palette, dither=Image.Dither.NONE) for f in frames]
    path = Path(path)
    quantized[0].save(
        path,
        format="GIF",
        save_all=True,
        append_images=quantized[1:],
        duration=[frame.duration_ms for frame in animation.frames],
        loop=0,
        optimize=False,
        disposal=1,
    )
    return path


def _palette(frames: list[Image.Image], background: Paint) -> Image.Image:
    """One palette for every frame (no flicker): quantised from a few frames side by side."""
    picks = [frames[i] for i in sorted({0, len(frames) // 3, 2 * len(frames) // 3, len(frames) - 1})]
    strip = Image.new("RGB", (sum(f.width for f in picks), max(f.height for f in picks)), background.rgb)
    x = 0
    for frame in picks:
        strip.paste(frame, (x, 0))
        x += frame.width
    return strip.quantize(colors=256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
