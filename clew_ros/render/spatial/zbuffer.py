"""A z-buffer rasteriser in numpy: flat-coloured triangles in pixel coordinates, vectorised over triangles
and pixels (no Python loop per pixel or per triangle; one per group of triangles of a like size).

Triangles come as ``(x px, y px, depth m)`` per corner (:meth:`~clew_ros.render.spatial.camera.Camera.project`).
A pixel is covered when its centre lies inside a triangle (edges shared by two triangles are covered by
both, so no cracks); depth is compared as inverse depth, which is linear across the picture. Opaque
triangles go into a :class:`Canvas`; see-through ones (the ghosted poses of a still) into a layer of their
own that is blended where it lies in front of the canvas (:meth:`Canvas.blend`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["Canvas", "RasterSettings"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class RasterSettings:
    """How the rasteriser trades memory for speed."""

    near_m: float = 0.01  # triangles with a corner nearer the camera than this are dropped (never projected)
    batch_candidates: int = 1 << 20  # pixels tested per numpy batch: ~60 MB of temporaries at most
    edge_tolerance: float = 1e-7  # barycentric slack: a pixel centre on a shared edge is covered by both


@dataclass
class Canvas:
    """An RGB picture (``colour`` (h, w, 3), 0-255 floats) with its inverse depth (``inverse_depth``
    (h, w), 1/m; 0 where nothing was drawn)."""

    colour: NDArray[np.float32]
    inverse_depth: Array
    settings: RasterSettings

    @classmethod
    def blank(cls, width: int, height: int, rgb: tuple[int, int, int], settings: RasterSettings) -> Canvas:
        colour = np.empty((height, width, 3), dtype=np.float32)
        colour[:] = rgb
        return cls(colour, np.zeros((height, width)), settings)

    @property
    def width(self) -> int:
        return int(self.colour.shape[1])

    @property
    def height(self) -> int:
        return int(self.colour.shape[0])

    def copy(self) -> Canvas:
        return Canvas(self.colour.copy(), self.inverse_depth.copy(), self.settings)

    def draw(self, triangles: Array, rgb: Array) -> None:
        """Draw triangles (m, 3, 3: corners' x px, y px, depth m) of colours ``rgb`` (m, 3), nearest wins."""
        for pixel, inverse_depth, which in self._fragments(np.asarray(triangles, dtype=np.float64)):
            flat_depth = self.inverse_depth.reshape(-1)
            np.maximum.at(flat_depth, pixel, inverse_depth)
            won = inverse_depth >= flat_depth[pixel]
            self.colour.reshape(-1, 3)[pixel[won]] = rgb[which[won]]

    def blend(self, triangles: Array, rgb: Array, alpha: float) -> None:
        """Draw triangles see-through: their nearest surface, at opacity ``alpha`` (0-1), wherever it lies in
        front of what the canvas holds (hidden behind it elsewhere); the canvas's depth is unchanged."""
        layer = Canvas.blank(self.width, self.height, (0, 0, 0), self.settings)
        layer.draw(triangles, rgb)
        front = layer.inverse_depth > self.inverse_depth * (1.0 + 1e-9)
        self.colour[front] = (1.0 - alpha) * self.colour[front] + alpha * layer.colour[front]

    def _fragments(self, triangles: Array) -> list[tuple[NDArray[np.int64], Array, NDArray[np.int64]]]:
        """Every covered pixel of every triangle, in batches: (flat pixel index, inverse depth, triangle)."""
        width, height = self.width, self.height
        if len(triangles) == 0:
            return []
        x, y, depth = triangles[:, :, 0], triangles[:, :, 1], triangles[:, :, 2]
        keep = np.all(depth > self.settings.near_m, axis=1) & np.all(np.isfinite(triangles), axis=(1, 2))
        x0 = np.ceil(x.min(axis=1) - 0.5)
        x1 = np.floor(x.max(axis=1) - 0.5)
        y0 = np.ceil(y.min(axis=1) - 0.5)
        y1 = np.floor(y.max(axis=1) - 0.5)
        x0, y0 = np.maximum(x0, 0), np.maximum(y0, 0)
        x1, y1 = np.minimum(x1, width - 1), np.minimum(y1, height - 1)
        # twice the signed area; edge k runs from corner k+1 to corner k+2 and weighs corner k
        area2 = (x[:, 1] - x[:, 0]) * (y[:, 2] - y[:, 0]) - (x[:, 2] - x[:, 0]) * (y[:, 1] - y[:, 0])
        keep &= (x1 >= x0) & (y1 >= y0) & (np.abs(area2) > 1e-12)
        index = np.flatnonzero(keep)
        if len(index) == 0:
            return []
        x, y, depth, area2 = x[index], y[index], depth[index], area2[index]
        x0, y0 = x0[index].astype(np.int64), y0[index].astype(np.int64)
        span_x, span_y = x1[index].astype(np.int64) - x0 + 1, y1[index].astype(np.int64) - y0 + 1
        nxt, far = [1, 2, 0], [2, 0, 1]
        a = (y[:, nxt] - y[:, far]) / area2[:, None]  # (m, 3): the barycentric weight of corner k is
        b = (x[:, far] - x[:, nxt]) / area2[:, None]  # a_k px + b_k py + c_k at the pixel centre (px, py)
        c = (x[:, nxt] * y[:, far] - x[:, far] * y[:, nxt]) / area2[:, None]
        inverse = 1.0 / depth
        # groups of triangles whose bounding boxes fit the same power-of-two rectangle
        bits_x = np.ceil(np.log2(span_x)).astype(np.int64)
        bits_y = np.ceil(np.log2(span_y)).astype(np.int64)
        group = bits_x * 64 + bits_y
        out = []
        for key in np.unique(group):
            members = np.flatnonzero(group == key)
            box_w, box_h = 1 << int(key // 64), 1 << int(key % 64)
            dx = np.tile(np.arange(box_w), box_h)
            dy = np.repeat(np.arange(box_h), box_w)
            batch = max(1, self.settings.batch_candidates // (box_w * box_h))
            for start in range(0, len(members), batch):
                t = members[start : start + batch]
                inside = (dx[None, :] < span_x[t, None]) & (dy[None, :] < span_y[t, None])
                px = x0[t, None] + dx[None, :]
                py = y0[t, None] + dy[None, :]
                cx, cy = px + 0.5, py + 0.5
                weights = [a[t, k, None] * cx + b[t, k, None] * cy + c[t, k, None] for k in range(3)]
                tolerance = -self.settings.edge_tolerance
                inside &= (weights[0] >= tolerance) & (weights[1] >= tolerance) & (weights[2] >= tolerance)
                rows, cols = np.nonzero(inside)
                if len(rows) == 0:
                    continue
                z = sum(weights[k][rows, cols] * inverse[t[rows], k] for k in range(3))
                pixel = py[rows, cols] * width + px[rows, cols]
                out.append((pixel, np.asarray(z, dtype=np.float64), index[t[rows]]))
        return out
