"""The SVG back end: writes the shapes of a drawing as SVG elements, nothing more.

The same :class:`~clew_ros.render.shapes.Drawing` the PNG paints
(:func:`~clew_ros.render.draw.draw_still`), one element per shape, in order;
consecutive shapes of one layer are grouped as ``<g id="LAYER">``. Where SVG
and Pillow differ it follows Pillow: rectangle and circle outlines are inset by
half their width (Pillow draws them inside the shape, SVG on its edge); text
sits on the baseline that Pillow's anchor gives with Pillow's font metrics,
stretched to the width the layout measured (``textLength``), whatever
sans-serif font the viewer has.
"""

from __future__ import annotations

from collections.abc import Iterable
from itertools import groupby
from pathlib import Path
from xml.sax.saxutils import escape, quoteattr

from clew_ros.render.draw import draw_still
from clew_ros.render.scene import Scene
from clew_ros.render.shapes import Circle, Drawing, Paint, Point, Polygon, Polyline, Rect, Shape, Text
from clew_ros.render.text import font_metrics

__all__ = ["render_svg", "svg_text"]

_HORIZONTAL = {"l": "start", "m": "middle", "r": "end"}


def _colour(paint: Paint) -> str:
    r, g, b = paint.rgb
    return f"#{r:02x}{g:02x}{b:02x}"


def _fill(paint: Paint | None) -> str:
    if paint is None:
        return ' fill="none"'
    opacity = f' fill-opacity="{paint.opacity:.3g}"' if paint.alpha < 255 else ""
    return f' fill="{_colour(paint)}"{opacity}'


def _stroke(paint: Paint | None, width: float, dash: float | None = None) -> str:
    if paint is None:
        return ""
    opacity = f' stroke-opacity="{paint.opacity:.3g}"' if paint.alpha < 255 else ""
    dashes = f' stroke-dasharray="{dash:g} {dash:g}"' if dash is not None else ""
    return f' stroke="{_colour(paint)}"{opacity} stroke-width="{width:g}"{dashes}'


def _points(points: tuple[Point, ...]) -> str:
    return " ".join(f"{x:.1f},{y:.1f}" for x, y in points)


def _element(shape: Shape) -> str:
    """One shape as one SVG element."""
    if isinstance(shape, Polygon):
        head = f'<polygon points="{_points(shape.points)}"{_fill(shape.fill)}'
        head += _stroke(shape.outline, shape.width, shape.dash)
        if shape.outline is not None:
            head += ' stroke-linejoin="round"'
    elif isinstance(shape, Polyline):
        head = f'<polyline points="{_points(shape.points)}" fill="none"{_stroke(shape.stroke, shape.width)}'
        if shape.rounded:
            head += ' stroke-linejoin="round" stroke-linecap="round"'
    elif isinstance(shape, Rect):
        inset = shape.width / 2 if shape.outline is not None else 0.0
        head = (
            f'<rect x="{shape.x0 + inset:.1f}" y="{shape.y0 + inset:.1f}" '
            f'width="{max(0.0, shape.x1 - shape.x0 - 2 * inset):.1f}" '
            f'height="{max(0.0, shape.y1 - shape.y0 - 2 * inset):.1f}"'
            f"{_fill(shape.fill)}{_stroke(shape.outline, shape.width)}"
        )
    elif isinstance(shape, Circle):
        inset = shape.width / 2 if shape.outline is not None else 0.0
        (x, y), r = shape.centre, max(0.0, shape.radius - inset)
        head = f'<circle cx="{x:.1f}" cy="{y:.1f}" r="{r:.2f}"{_fill(shape.fill)}{_stroke(shape.outline, shape.width)}'
    elif isinstance(shape, Text):
        (x, y), anchor = shape.position, shape.anchor
        ascent, descent = font_metrics(shape.size)
        baseline = y + (ascent if anchor[1] == "a" else (ascent - descent) / 2)  # Pillow's anchors, on the baseline
        head = (
            f'<text x="{x:.1f}" y="{baseline:.1f}" font-size="{shape.size}"{_fill(shape.paint)} '
            f'text-anchor="{_HORIZONTAL[anchor[0]]}"'
        )
        if shape.length > 0:
            head += f' textLength="{shape.length:.1f}" lengthAdjust="spacingAndGlyphs"'
        title = f"<title>{escape(shape.title)}</title>" if shape.title else ""
        return f"{head}>{title}{escape(shape.text)}</text>"
    else:  # pragma: no cover - Shape is closed
        raise TypeError(f"not a shape: {shape!r}")
    if shape.title:
        tag = head.split(" ", 1)[0][1:]
        return f"{head}><title>{escape(shape.title)}</title></{tag}>"
    return head + "/>"


def _layers(shapes: Iterable[Shape]) -> list[str]:
    """The elements of ``shapes``, runs of one layer grouped with the layer's name as id (unique)."""
    out: list[str] = []
    used: dict[str, int] = {}
    for layer, run in groupby(shapes, key=lambda shape: shape.layer):
        elements = [_element(shape) for shape in run]
        if not layer:
            out += elements
            continue
        used[layer] = used.get(layer, 0) + 1
        name = layer if used[layer] == 1 else f"{layer}-{used[layer]}"
        out += [f"<g id={quoteattr(name)}>", *elements, "</g>"]
    return out


def svg_text(drawing: Drawing) -> str:
    """The drawing as an SVG document."""
    width, height = drawing.width, drawing.height
    lines = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        (
            f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
            f'viewBox="0 0 {width} {height}" font-family="sans-serif">'
        ),
    ]
    if drawing.title:
        lines.append(f"<title>{escape(drawing.title)}</title>")
    lines.append(f'<rect width="{width}" height="{height}"{_fill(drawing.background)}/>')
    lines += _layers(drawing.shapes)
    lines.append("</svg>")
    return "\n".join(lines) + "\n"


def render_svg(scene: Scene, path: str | Path, size: int = 800) -> Path:
    """Write the scene's filmstrip (:func:`~clew_ros.render.draw.draw_still`, the PNG's shapes) as SVG."""
    path = Path(path)
    path.write_text(svg_text(draw_still(scene, size)), encoding="utf-8")
    return path
