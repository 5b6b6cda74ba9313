"""The viewpoint of a 3-D picture: where the camera stands, where it looks, and the perspective projection.

A :class:`View3D` is either spherical around a target (``azimuth_deg``, ``elevation_deg``, ``distance_m``)
or a camera pose (``eye`` and ``target``). Azimuth is measured in the world's x-y plane from +x towards +y,
elevation up from that plane: ``azimuth 0, elevation 0`` looks along -x from the +x side. Without a
``target`` the camera looks at the centre of the scene's bounding box; without a ``distance_m`` (or an
``eye``) it stands as close as lets every point of the scene into the picture with a margin.
:func:`parse_view` reads the command line's ``--view az,el[,dist]``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from clew_ros.render.errors import RenderError

__all__ = ["Camera", "View3D", "parse_view"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class View3D:
    """Where a 3-D picture is seen from, and its size.

    ``azimuth_deg`` / ``elevation_deg`` (degrees) place the camera on a sphere around ``target`` of radius
    ``distance_m`` (m; ``None``: as close as frames the scene); ``eye`` (m, in ``world``), when given,
    replaces the three. ``target`` ``None``: the centre of the scene's bounding box. ``fov_deg``: the
    vertical field of view. ``width`` / ``height``: the picture in pixels. ``margin``: the fraction of
    the half-picture kept free around the scene when the distance is chosen.
    """

    azimuth_deg: float = -50.0  # from the front right of an arm whose x points forward: its side and front
    elevation_deg: float = 28.0  # high enough to see a table's top, low enough to see an arm's height
    distance_m: float | None = None
    target: tuple[float, float, float] | None = None
    eye: tuple[float, float, float] | None = None
    fov_deg: float = 35.0  # a mild perspective: near links look near without distorting the far ones
    width: int = 800
    height: int = 600
    margin: float = 0.08

    def __post_init__(self) -> None:
        for name in ("azimuth_deg", "elevation_deg"):
            if not math.isfinite(getattr(self, name)):
                raise RenderError(f"view {name}: expected a finite number of degrees, got {getattr(self, name)!r}")
        if not -89.0 <= self.elevation_deg <= 89.0:
            raise RenderError(f"view elevation_deg: expected -89 to 89 degrees, got {self.elevation_deg}")
        if self.distance_m is not None and not (math.isfinite(self.distance_m) and self.distance_m > 0):
            raise RenderError(f"view distance_m: expected a positive number of metres, got {self.distance_m}")
        for name in ("target", "eye"):
            value = getattr(self, name)
            if value is not None and (len(value) != 3 or not all(math.isfinite(float(v)) for v in value)):
                raise RenderError(f"view {name}: expected 3 finite numbers [x, y, z] (m), got {value!r}")
        if not 5.0 <= self.fov_deg <= 120.0:
            raise RenderError(f"view fov_deg: expected 5 to 120 degrees, got {self.fov_deg}")
        for name in ("width", "height"):
            if not 16 <= getattr(self, name) <= 8192:
                raise RenderError(f"view {name}: expected 16 to 8192 pixels, got {getattr(self, name)}")
        if not 0.0 <= self.margin < 0.9:
            raise RenderError(f"view margin: expected a fraction from 0 to 0.9, got {self.margin}")

    def direction(self) -> Array:
        """The unit vector from the target towards the camera (from azimuth and elevation)."""
        az, el = math.radians(self.azimuth_deg), math.radians(self.elevation_deg)
        return np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])

    def camera(self, points: Array) -> Camera:
        """The camera that shows ``points`` (k, 3: the scene, m) from this view."""
        points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        if len(points) == 0:
            points = np.zeros((1, 3))
        low, high = points.min(axis=0), points.max(axis=0)
        target = np.asarray(self.target, dtype=np.float64) if self.target is not None else (low + high) / 2
        focal = (self.height / 2) / math.tan(math.radians(self.fov_deg) / 2)
        if self.eye is not None:
            eye = np.asarray(self.eye, dtype=np.float64)
            if np.linalg.norm(eye - target) < 1e-9:
                raise RenderError("view eye: expected a point away from the target")
            return Camera.look_at(eye, target, focal, self.width, self.height)
        direction = self.direction()
        if self.distance_m is not None:
            return Camera.look_at(target + self.distance_m * direction, target, focal, self.width, self.height)
        camera = Camera.look_at(target + direction, target, focal, self.width, self.height)
        for _ in range(3 if self.target is None else 1):
            distance = self._framing_distance(camera, points - target, focal)
            camera = Camera.look_at(target + distance * direction, target, focal, self.width, self.height)
            if self.target is not None:
                break
            # the scene's picture centred: the target moved across the view by the picture's off-centre
            screen = camera.project(points)
            shift_x = (screen[:, 0].min() + screen[:, 0].max()) / 2 - self.width / 2
            shift_y = (screen[:, 1].min() + screen[:, 1].max()) / 2 - self.height / 2
            target = target + (shift_x * camera.right - shift_y * camera.up) * distance / focal
        return camera

    def _framing_distance(self, probe: Camera, offsets: Array, focal: float) -> float:
        """The least distance from the target at which every offset (from the target) projects inside the
        picture less its margin: for a point at camera coordinates (x, y) and depth ``d + z`` (``z`` along
        the view from the target), ``|x| focal / (d + z) <= half width`` gives ``d >= |x| focal / half - z``."""
        x, y, z = offsets @ probe.right, offsets @ probe.up, offsets @ probe.forward
        half_w = (1.0 - self.margin) * self.width / 2
        half_h = (1.0 - self.margin) * self.height / 2
        need = np.maximum(np.abs(x) * focal / half_w, np.abs(y) * focal / half_h) - z
        # every point at least 10 cm in front of the camera: the rasteriser drops what crosses its near plane
        return max(float(need.max()), float((0.1 - z).max()), 0.1)


@dataclass(frozen=True, eq=False)
class Camera:
    """A pinhole camera: ``eye`` (m), its unit ``right``, ``up`` and ``forward`` axes, ``focal`` (px) and
    the picture's ``width`` / ``height`` (px)."""

    eye: Array
    target: Array
    right: Array
    up: Array
    forward: Array
    focal: float
    width: int
    height: int

    @classmethod
    def look_at(cls, eye: Array, target: Array, focal: float, width: int, height: int) -> Camera:
        forward = target - eye
        forward = forward / np.linalg.norm(forward)
        right = np.cross(forward, [0.0, 0.0, 1.0])
        if np.linalg.norm(right) < 1e-9:  # looking straight up or down: x of the world to the right
            right = np.cross(forward, [0.0, 1.0, 0.0])
        right = right / np.linalg.norm(right)
        up = np.cross(right, forward)
        return cls(eye, target, right, up, forward, focal, width, height)

    @property
    def distance(self) -> float:
        return float(np.linalg.norm(self.target - self.eye))

    def project(self, points: Array, scale: float = 1.0) -> Array:
        """Points (..., 3) in ``world`` as ``(x px, y px, depth m)`` (..., 3), x to the right, y down, in a
        picture ``scale`` times the camera's size (supersampling); depth <= 0 lies behind the camera."""
        offsets = np.asarray(points, dtype=np.float64) - self.eye
        depth = offsets @ self.forward
        safe = np.where(np.abs(depth) < 1e-12, 1e-12, depth)
        x = (self.width / 2 + self.focal * (offsets @ self.right) / safe) * scale
        y = (self.height / 2 - self.focal * (offsets @ self.up) / safe) * scale
        return np.stack([x, y, depth], axis=-1)

    def describe(self) -> str:
        """The view as ``--view`` would give it: azimuth, elevation (degrees) and distance (m)."""
        away = self.eye - self.target
        distance = float(np.linalg.norm(away))
        azimuth = math.degrees(math.atan2(away[1], away[0]))
        elevation = math.degrees(math.asin(max(-1.0, min(1.0, away[2] / distance))))
        return f"view {azimuth:.0f},{elevation:.0f},{distance:.2f}"


def parse_view(text: str, base: View3D | None = None) -> View3D:
    """``--view az,el[,dist]`` (degrees, degrees, metres) over ``base`` (its size and other fields); a
    :class:`RenderError` naming ``--view`` and what was expected otherwise."""
    base = base or View3D()
    parts = [part.strip() for part in str(text).split(",")]
    expected = "expected az,el[,dist]: azimuth and elevation in degrees, distance in metres (e.g. -50,28,2.5)"
    if len(parts) not in (2, 3):
        raise RenderError(f"--view: {expected}, got {text!r}")
    try:
        values = [float(part) for part in parts]
    except ValueError:
        raise RenderError(f"--view: {expected}, got {text!r}") from None
    if not all(math.isfinite(v) for v in values):
        raise RenderError(f"--view: {expected}, got {text!r}")
    if not -89.0 <= values[1] <= 89.0:
        raise RenderError(f"--view: elevation {values[1]:g}: expected -89 to 89 degrees")
    if len(values) == 3 and values[2] <= 0:
        raise RenderError(f"--view: distance {values[2]:g}: expected a positive number of metres")
    return View3D(
        azimuth_deg=values[0],
        elevation_deg=values[1],
        distance_m=values[2] if len(values) == 3 else None,
        target=base.target,
        fov_deg=base.fov_deg,
        width=base.width,
        height=base.height,
        margin=base.margin,
    )
