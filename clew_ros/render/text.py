"""The one font of every picture (Pillow's default font) and how wide text set in it is.

The drawing lays out the caption's legend with :func:`text_width`; the PNG
and GIF back end sets text in :func:`font`; the SVG back end names a
sans-serif family of the same size, stretched to the width measured here and
placed on the baseline :func:`font_metrics` gives, so a viewer's font fills
the place the layout gave the text.
"""

from __future__ import annotations

import functools

from PIL import ImageFont

__all__ = ["font", "font_height", "font_metrics", "text_width"]


@functools.lru_cache(maxsize=16)
def font(size: int) -> ImageFont.FreeTypeFont | ImageFont.ImageFont:
    """Pillow's default font at ``size`` pixels (Pillow < 10.1: its fixed bitmap font)."""
    try:
        return ImageFont.load_default(size=size)
    except TypeError:  # Pillow < 10.1 has no sized default font
        return ImageFont.load_default()


def font_height(size: int) -> int | None:
    """The size (px) the font of ``size`` really has; ``None`` for the fixed bitmap font."""
    value = getattr(font(size), "size", None)
    return None if value is None else int(value)


def text_width(text: str, size: int) -> float:
    """Width (px) of ``text`` set in :func:`font` at ``size``."""
    return float(font(size).getlength(text, "L"))


def font_metrics(size: int) -> tuple[float, float]:
    """Ascent and descent (px, both positive) of :func:`font` at ``size``."""
    face = font(size)
    if hasattr(face, "getmetrics"):
        ascent, descent = face.getmetrics()
        return float(ascent), float(descent)
    return 0.8 * size, 0.2 * size  # the fixed bitmap font: about right
