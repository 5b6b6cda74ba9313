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
        """Every covered pixel of every triangle, in batches: (flat pixel index, inverse depth, triangle).

        Scanline by scanline, vectorised: for each (triangle, pixel row) pair the span of pixel centres
        inside all three edges, then the pixels of every span; no pixel outside a triangle is visited."""
        width, height = self.width, self.height
        if len(triangles) == 0:
            return []
        x, y, depth = triangles[:, :, 0], triangles[:, :, 1], triangles[:, :, 2]
        keep = np.all(depth > self.settings.near_m, axis=1) & np.all(np.isfinite(triangles), axis=(1, 2))
        x0 = np.maximum(np.ceil(x.min(axis=1) - 0.5), 0)
        x1 = np.minimum(np.floor(x.max(axis=1) - 0.5), width - 1)
        y0 = np.maximum(np.ceil(y.min(axis=1) - 0.5), 0)
        y1 = np.minimum(np.floor(y.max(axis=1) - 0.5), height - 1)
        # twice the signed area; edge k runs from corner k+1 to corner k+2 and weighs corner k
        area2 = (x[:, 1] - x[:, 0]) * (y[:, 2] - y[:, 0]) - (x[:, 2] - x[:, 0]) * (y[:, 1] - y[:, 0])
        keep &= (x1 >= x0) & (y1 >= y0) & (np.abs(area2) > 1e-12)
        index = np.flatnonzero(keep)
        if len(index) == 0:
            return []
        x, y, area2 = x[index], y[index], area2[index]
        x0, x1 = x0[index].astype(np.int64), x1[index].astype(np.int64)
        y0, rows = y0[index].astype(np.int64), (y1[index] - y0[index]).astype(np.int64) + 1
        nxt, far = [1, 2, 0], [2, 0, 1]
        a = (y[:, nxt] - y[:, far]) / area2[:, None]  # (m, 3): the barycentric weight of corner k is
        b = (x[:, far] - x[:, nxt]) / area2[:, None]  # a_k px + b_k py + c_k at the pixel centre (px, py)
        c = (x[:, nxt] * y[:, far] - x[:, far] * y[:, nxt]) / area2[:, None]
        inverse = 1.0 / depth[index]
        plane = np.stack([(a * inverse).sum(axis=1), (b * inverse).sum(axis=1), (c * inverse).sum(axis=1)], axis=1)
        # batches of triangles whose bounding boxes hold at most batch_candidates pixels together
        boxes = np.cumsum(rows * (x1 - x0 + 1))
        cuts = np.searchsorted(
            boxes, np.arange(1, boxes[-1] // self.settings.batch_candidates + 1) * self.settings.batch_candidates
        )
        out = []
        for t in np.split(np.arange(len(index)), np.unique(cuts[(cuts > 0) & (cuts < len(index))])):
            if len(t) == 0:
                continue
            # one (triangle, row) pair per pixel row of each bounding box
            pair_t = np.repeat(t, rows[t])
            pair_y = y0[pair_t] + np.arange(len(pair_t)) - np.repeat(np.cumsum(rows[t]) - rows[t], rows[t])
            cy = pair_y + 0.5
            low = np.full(len(pair_t), -np.inf)
            high = np.full(len(pair_t), np.inf)
            for k in range(3):
                ak, rest = a[pair_t, k], b[pair_t, k] * cy + c[pair_t, k] + self.settings.edge_tolerance
                # a_k cx + rest >= 0: cx >= -rest / a_k when a_k > 0, cx <= -rest / a_k when a_k < 0
                with np.errstate(divide="ignore", invalid="ignore"):
                    bound = -rest / ak
                low = np.where(ak > 0, np.maximum(low, bound), low)
                high = np.where(ak < 0, np.minimum(high, bound), high)
                high = np.where((ak == 0) & (rest < 0), -np.inf, high)
            first = np.maximum(np.ceil(low - 0.5), x0[pair_t])
            last = np.minimum(np.floor(high - 0.5), x1[pair_t])
            count = np.maximum(last - first + 1, 0).astype(np.int64)
            total = int(count.sum())
            if total == 0:
                continue
            pixel_pair = np.repeat(np.arange(len(pair_t)), count)
            px = first.astype(np.int64)[pixel_pair] + np.arange(total) - np.repeat(np.cumsum(count) - count, count)
            py = pair_y[pixel_pair]
            which = pair_t[pixel_pair]
            z = plane[which, 0] * (px + 0.5) + plane[which, 1] * (py + 0.5) + plane[which, 2]
            out.append((py * width + px, z, index[which]))
        return out
