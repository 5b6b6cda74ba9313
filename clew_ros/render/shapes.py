"""What a picture is made of: back-end-neutral shapes in pixel coordinates.

:mod:`clew_ros.render.draw` draws a scene once into a :class:`Drawing` (a
still) or an :class:`Animation`; the back ends (:mod:`clew_ros.render.raster`
for PNG and GIF, :mod:`clew_ros.render.svg`) write those shapes as they are
and know nothing of worlds, plans or arms.

Coordinates are pixels, x to the right and y down, origin at the picture's
top-left corner. Colours are keys of the scene's palette (:data:`COLORS`) with an opacity
(:class:`Paint`); widths and sizes are pixels. ``layer`` names the part of the
picture a shape belongs to (``"obstacles"``, ``"poses"``, ...: the SVG groups
and ids); ``title`` is an optional tooltip (SVG only).
"""

from __future__ import annotations

from dataclasses import dataclass

from clew_ros.scene.palette import PALETTE

__all__ = [
    "COLORS",
    "Animation",
    "Circle",
    "Drawing",
    "Frame",
    "Paint",
    "Point",
    "Polygon",
    "Polyline",
    "Rect",
    "Shape",
    "Text",
]

#: RGB colours of every picture, by key: the scene's palette (:data:`clew_ros.scene.palette.PALETTE`).
COLORS: dict[str, tuple[int, int, int]] = {key: colour.rgb for key, colour in PALETTE.items()}

#: A point in pixels ``(x, y)``.
Point = tuple[float, float]


@dataclass(frozen=True)
class Paint:
    """A colour of :data:`COLORS` (``key``) with an opacity ``alpha`` from 0 (clear) to 255 (opaque)."""

    key: str
    alpha: int = 255

    def __post_init__(self) -> None:
        if self.key not in COLORS:
            raise ValueError(f"{self.key!r} is not a colour, must be one of {sorted(COLORS)}")
        if not 0 <= self.alpha <= 255:
            raise ValueError(f"alpha: expected 0 to 255, got {self.alpha}")

    @property
    def rgb(self) -> tuple[int, int, int]:
        return COLORS[self.key]

    @property
    def rgba(self) -> tuple[int, int, int, int]:
        return (*COLORS[self.key], self.alpha)

    @property
    def opacity(self) -> float:
        """``alpha`` as a fraction (0 to 1)."""
        return self.alpha / 255


@dataclass(frozen=True)
class Polygon:
    """A closed polygon; its outline solid, or dashed with dashes and gaps ``dash`` pixels long."""

    points: tuple[Point, ...]
    fill: Paint | None = None
    outline: Paint | None = None
    width: int = 1
    dash: float | None = None
    layer: str = ""
    title: str = ""


@dataclass(frozen=True)
class Polyline:
    """An open line through ``points``; ``rounded``: round joints (the arm, the tip's path)."""

    points: tuple[Point, ...]
    stroke: Paint
    width: int = 1
    rounded: bool = False
    layer: str = ""
    title: str = ""


@dataclass(frozen=True)
class Rect:
    """An axis-aligned rectangle from ``(x0, y0)`` (top-left) to ``(x1, y1)`` (bottom-right), edges included."""

    x0: float
    y0: float
    x1: float
    y1: float
    fill: Paint | None = None
    outline: Paint | None = None
    width: int = 1
    layer: str = ""
    title: str = ""


@dataclass(frozen=True)
class Circle:
    """A disc of ``radius`` pixels around ``centre``; ``outline`` is ``width`` pixels wide."""

    centre: Point
    radius: float
    fill: Paint | None = None
    outline: Paint | None = None
    width: int = 1
    layer: str = ""
    title: str = ""


@dataclass(frozen=True)
class Text:
    """One line of text, ``size`` pixels high, placed at ``position`` by ``anchor``.

    ``anchor`` is two letters as Pillow reads them: horizontal ``l`` (left),
    ``m`` (middle) or ``r`` (right); vertical ``a`` (ascender, the top of the
    text) or ``m`` (middle, halfway between ascender and descender).
    ``length`` is the width (px) the layout measured for the text
    (:func:`clew_ros.render.text.text_width`), 0 if unknown; a back end whose
    font differs stretches the text to it.
    """

    position: Point
    text: str
    paint: Paint
    size: int
    anchor: str = "la"
    length: float = 0.0
    layer: str = ""
    title: str = ""

    def __post_init__(self) -> None:
        if len(self.anchor) != 2 or self.anchor[0] not in "lmr" or self.anchor[1] not in "am":
            raise ValueError(f"{self.anchor!r} is not a valid anchor, must be one of l|m|r then a|m")


#: Anything a drawing holds.
Shape = Polygon | Polyline | Rect | Circle | Text


@dataclass(frozen=True)
class Drawing:
    """A still picture: ``width`` x ``height`` pixels of ``background``, then ``shapes`` painted in order."""

    width: int
    height: int
    shapes: tuple[Shape, ...]
    background: Paint = Paint("background")
    title: str = ""


@dataclass(frozen=True)
class Frame:
    """One frame of an animation: shapes painted over the animation's base, shown ``duration_ms``."""

    shapes: tuple[Shape, ...]
    duration_ms: int


@dataclass(frozen=True)
class Animation:
    """Frames that share a base (what does not move: the world, the landmark tree, the whole path)."""

    base: Drawing
    frames: tuple[Frame, ...]
