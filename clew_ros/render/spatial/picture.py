"""Pictures of a spatial world (interface.md section 1b): the arm, the object, the obstacles and supports, a
ground grid, from a chosen viewpoint; a still (PNG) with ghosted poses along the frames, or a GIF, frame by
frame. Pillow and numpy only: no display, no GPU.

- :func:`draw_spatial_frames`: the arm at poses fading in along frames (joints (T, n), the object's pose per
  frame or at rest), the last solid, the tool centre point's path, as a still.
- :func:`draw_spatial_world`: the world alone: the arm at its start, the object at its start and its goal
  placement ghosted, or the goal configuration of a motion-only query ghosted.
- :func:`spatial_gif_frames` / :func:`write_spatial_gif`: one picture per frame, written as a looping GIF.

Everything is drawn as flat-shaded triangles (:mod:`~clew_ros.render.spatial.meshes`), lit from the
camera's upper left, into a numpy z-buffer (:mod:`~clew_ros.render.spatial.zbuffer`) at ``supersample``
times the picture's size and scaled down (smooth edges). Colours are the scene's palette
(:mod:`clew_ros.scene.palette`): ``obstacle``, ``arm``, ``open`` / ``closed`` for the gripper links,
``start`` / ``goal`` / ``object_rest`` / ``object_held`` for the object, ``transit`` / ``transfer`` for the
path. The static part of a picture (ground, obstacles, supports, path) is drawn once per GIF.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from PIL import Image, ImageDraw

from clew_ros.render.errors import RenderError
from clew_ros.render.spatial.camera import Camera, View3D
from clew_ros.render.spatial.meshes import (
    MeshSettings,
    box_mesh,
    cylinder_mesh,
    robot_mesh,
    sphere_mesh,
    transform,
)
from clew_ros.render.spatial.zbuffer import Canvas, RasterSettings
from clew_ros.render.text import font
from clew_ros.scene.palette import colour
from clew_ros.spatial.transforms import pose_matrix
from clew_ros.spatial.world import SpatialWorld

__all__ = [
    "SpatialStyle",
    "draw_spatial_frames",
    "draw_spatial_world",
    "spatial_gif_frames",
    "write_spatial_gif",
]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class SpatialStyle:
    """How a spatial picture looks; every size in pixels of the final picture unless it says otherwise."""

    supersample: int = 2  # drawn at twice the size and scaled down: smooth edges for 4x the pixels
    ghosts: int = 6  # poses along the frames in a still, the last solid: as many as the planar filmstrip
    ghost_alpha: tuple[float, float] = (0.16, 0.5)  # opacity of the first and the last ghost: faint early
    goal_alpha: float = 0.35  # the goal placement or configuration, ghosted over the start
    ambient: float = 0.55  # share of a colour a face turned away from the light keeps
    highlight: float = 0.3  # how far a face turned to the light goes towards white (lights up dark links)
    light: tuple[float, float, float] = (-0.45, 0.65, 0.62)  # towards the light: camera's right, up, backwards
    ground_cells: int = 14  # about this many grid cells along the ground's longer side
    ground_margin: float = 0.2  # the ground reaches this fraction of the scene's size beyond it
    grid_line: float = 0.035  # a grid line's width as a fraction of a cell
    shadows: bool = True  # each solid thing's shadow straight down on the ground: where it stands
    path_width: float = 2.0  # the tool centre point's path
    #: a world alone: each grasp at the object's start drawn as its approach (blue, this long along the tcp's
    #: z, m, ending at the tcp) and its fingers' closing axis (orange, as long each way); 0: not drawn
    grasp_axis_m: float = 0.08
    caption: bool = True  # a band under the picture: the world, what is shown, the view
    frame_ms: int = 80  # a GIF frame
    event_ms: int = 500  # a GIF frame where the gripper closes or opens
    end_ms: int = 1500  # the last GIF frame
    mesh: MeshSettings = field(default_factory=MeshSettings)
    raster: RasterSettings = field(default_factory=RasterSettings)


@dataclass
class _Triangles:
    """Triangles in ``world`` (m, 3, 3) and their unshaded colours (m, 3), 0-255."""

    corners: Array
    rgb: Array

    @classmethod
    def join(cls, parts: Sequence[_Triangles]) -> _Triangles:
        if not parts:
            return cls(np.zeros((0, 3, 3)), np.zeros((0, 3)))
        return cls(np.concatenate([p.corners for p in parts]), np.concatenate([p.rgb for p in parts]))

    @classmethod
    def of(cls, vertices: Array, faces: NDArray[np.int64], rgb: Sequence[float] | Array) -> _Triangles:
        corners = vertices[faces]
        colours = np.broadcast_to(np.asarray(rgb, dtype=np.float64), (len(faces), 3)).copy()
        return cls(corners, colours)


@dataclass
class _Pose:
    """The arm at ``joints``, the gripper closed when ``held``."""

    joints: Array
    held: bool


@dataclass
class _Thing:
    """The object at a 4x4 ``pose``, in palette colour ``key``, at opacity ``alpha``."""

    pose: Array
    key: str
    alpha: float


def _rgb(key: str) -> Array:
    return np.asarray(colour(key).rgb, dtype=np.float64)


def _mix(a: str, b: str, t: float) -> Array:
    """Palette colour ``a`` moved a fraction ``t`` towards ``b``."""
    return (1.0 - t) * _rgb(a) + t * _rgb(b)


# ------------------------------------------------------------------------------------------- triangles


def _primitive(shape: str, size: Sequence[float], pose: Array, rgb: Array, mesh: MeshSettings) -> _Triangles:
    if shape == "box":
        vertices, faces = box_mesh(size)
    elif shape == "cylinder":
        vertices, faces = cylinder_mesh(size[0], size[1], mesh.cylinder_sides)
    else:
        vertices, faces = sphere_mesh(size[0], mesh.sphere_subdivisions)
    return _Triangles.of(transform(pose, vertices), faces, rgb)


def _obstacles(world: SpatialWorld, mesh: MeshSettings) -> _Triangles:
    """Obstacles in ``obstacle``; supports a lighter tone of it, so the tables read apart from the rest."""
    supports = {s.name for s in world.supports}
    support_rgb = _mix("obstacle", "field", 0.45)
    return _Triangles.join(
        [
            _primitive(o.shape, o.size, o.pose, support_rgb if o.name in supports else _rgb("obstacle"), mesh)
            for o in world.obstacles
        ]
    )


def _arm(world: SpatialWorld, joints: Array, held: bool, mesh: MeshSettings) -> _Triangles:
    """The robot's links at ``joints``: ``arm``, and the gripper links ``closed`` when holding, else ``open``."""
    robot = world.robot
    model = robot_mesh(robot, mesh)
    vertices = model.at(robot.frames(joints.tolist()))
    grippers = np.array([link.name in robot.gripper_links for link in robot.links], dtype=bool)
    rgb = np.where(
        grippers[model.link][:, None] if len(grippers) else np.zeros((len(model.faces), 1), dtype=bool),
        _rgb("closed" if held else "open"),
        _rgb("arm"),
    )
    return _Triangles(vertices[model.faces], rgb)


def _object(world: SpatialWorld, thing: _Thing, mesh: MeshSettings) -> _Triangles:
    assert world.object is not None
    shape = world.object.shape
    return _primitive(shape.shape, shape.size, thing.pose, _rgb(thing.key), mesh)


def _shade(triangles: _Triangles, camera: Camera, style: SpatialStyle) -> Array:
    """Flat shading: each face's colour by how squarely it faces the light (its side towards the camera)."""
    corners = triangles.corners
    if len(corners) == 0:
        return np.zeros((0, 3))
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    normal = normal / np.where(length > 0, length, 1.0)
    towards_camera = camera.eye - corners.mean(axis=1)
    normal *= np.where(np.sum(normal * towards_camera, axis=1, keepdims=True) < 0, -1.0, 1.0)
    lx, ly, lz = style.light
    light = lx * camera.right + ly * camera.up - lz * camera.forward
    light = light / np.linalg.norm(light)
    lit = np.clip(normal @ light, 0.0, 1.0)[:, None]
    rgb = triangles.rgb
    shaded = rgb * (style.ambient + (1.0 - style.ambient) * lit) + (255.0 - rgb) * style.highlight * lit**2
    out: Array = np.clip(shaded, 0.0, 255.0)
    return out


def _shadow(triangles: _Triangles, ground: float) -> Array:
    """The triangles flattened straight down onto the ground (a hair above it, so they cover the grid)."""
    flat = triangles.corners.copy()
    flat[:, :, 2] = ground + 1e-3
    return flat


@dataclass(frozen=True)
class _Ground:
    """The ground plane at height ``z`` (m): a square grid of ``step`` (m) cells over ``low``..``high``."""

    z: float
    low: tuple[float, float]
    high: tuple[float, float]
    step: float

    @classmethod
    def under(cls, points: Array, style: SpatialStyle) -> _Ground:
        low, high = points[:, :2].min(axis=0), points[:, :2].max(axis=0)
        size = float(max(high - low)) or 1.0
        low, high = low - style.ground_margin * size, high + style.ground_margin * size
        raw = float(max(high - low)) / style.ground_cells
        step = min((s for s in (0.02, 0.05, 0.1, 0.2, 0.25, 0.5, 1.0, 2.0, 5.0) if s >= raw), default=10.0)
        low = np.floor(low / step) * step
        high = np.ceil(high / step) * step
        # the ground under everything, at z = 0 unless something reaches below it
        z = min(0.0, float(points[:, 2].min()))
        return cls(z, (float(low[0]), float(low[1])), (float(high[0]), float(high[1])), step)

    def paint(self, canvas: Canvas, camera: Camera, scale: int, style: SpatialStyle) -> None:
        """The grid painted onto the canvas's colour, cell by cell (a line-coloured square, the cell inset over
        it), without depth: the ground lies under everything, so whatever is drawn after covers it. Cells
        reaching behind the camera are left out."""
        xs = np.arange(self.low[0], self.high[0] - 1e-9, self.step)
        ys = np.arange(self.low[1], self.high[1] - 1e-9, self.step)
        gx, gy = (a.ravel() for a in np.meshgrid(xs, ys))
        inset = style.grid_line * self.step / 2
        z = np.full_like(gx, self.z)
        squares = []
        for x0, y0, x1, y1 in (
            (gx, gy, gx + self.step, gy + self.step),
            (gx + inset, gy + inset, gx + self.step - inset, gy + self.step - inset),
        ):
            corners = np.stack([np.stack(p, axis=1) for p in ((x0, y0, z), (x1, y0, z), (x1, y1, z), (x0, y1, z))], 1)
            squares.append(camera.project(corners, scale))
        image = Image.fromarray(np.clip(canvas.colour + 0.5, 0, 255).astype(np.uint8), "RGB")
        draw = ImageDraw.Draw(image)
        line = tuple(int(v) for v in np.round(_mix("field", "field_edge", 0.22)))
        cell = colour("field").rgb
        in_front = np.all(squares[0][:, :, 2] > canvas.settings.near_m, axis=1)
        for whole, inner in zip(squares[0][in_front], squares[1][in_front], strict=True):
            draw.polygon([(float(x), float(y)) for x, y, _ in whole], fill=line)
            draw.polygon([(float(x), float(y)) for x, y, _ in inner], fill=cell)
        canvas.colour[:] = np.asarray(image, dtype=np.float32)


# ------------------------------------------------------------------------------------------- the picture


def _check_joints(world: SpatialWorld, joints: Any, parameter: str = "joints") -> Array:
    try:
        out = np.asarray(joints, dtype=np.float64)
    except (TypeError, ValueError):
        raise RenderError(f"{parameter}: expected numbers, an array (T, {world.robot.dof})") from None
    if out.ndim == 1:
        out = out[None]
    if out.ndim != 2 or out.shape[1] != world.robot.dof or len(out) == 0 or not np.all(np.isfinite(out)):
        raise RenderError(
            f"{parameter}: expected finite values of shape (T, {world.robot.dof}) "
            f"({', '.join(world.robot.joint_names)}), got shape {out.shape}"
        )
    return out


def _check_object_poses(world: SpatialWorld, object_poses: Any, count: int) -> Array | None:
    """The object's 4x4 pose per frame (count, 4, 4), or ``None`` when the world has no object."""
    if world.object is None:
        if object_poses is not None:
            raise RenderError("object_poses: the world has no object (a motion-only query); expected None")
        return None
    if object_poses is None:
        return np.repeat(pose_matrix(world.object.initial)[None], count, axis=0)
    try:
        poses = np.asarray(object_poses, dtype=np.float64)
    except (TypeError, ValueError):
        poses = np.zeros(0)
    expected = f"expected a pose (6 numbers or 4x4) or one per frame ({count}, 6) / ({count}, 4, 4)"
    if poses.shape in ((6,), (4, 4)):
        poses = poses[None]
    if poses.ndim == 2 and poses.shape[1] == 6:
        poses = np.array([pose_matrix(p) for p in poses])
    if poses.ndim != 3 or poses.shape[1:] != (4, 4) or not np.all(np.isfinite(poses)):
        raise RenderError(f"object_poses: {expected}, got shape {poses.shape}")
    if len(poses) == 1:
        poses = np.repeat(poses, count, axis=0)
    if len(poses) != count:
        raise RenderError(f"object_poses: {expected}, got {len(poses)} poses for {count} frames")
    return poses


def _check_held(held: Any, count: int) -> NDArray[np.bool_]:
    if held is None:
        return np.zeros(count, dtype=bool)
    out = np.asarray(held, dtype=bool).reshape(-1)
    if len(out) != count:
        raise RenderError(f"held: expected one flag per frame ({count}), got {len(out)}")
    return out


class _Painter:
    """One camera over one world: draws the static part once, the poses and objects over it."""

    def __init__(
        self,
        world: SpatialWorld,
        view: View3D,
        style: SpatialStyle,
        *,
        sample: Sequence[_Pose],
        things: Sequence[_Thing],
        path: Array | None,
    ) -> None:
        if style.supersample not in (1, 2, 3, 4):
            raise RenderError(f"style supersample: expected 1 to 4, got {style.supersample}")
        self.world, self.view, self.style = world, view, style
        self.static = _obstacles(world, style.mesh)
        shown = [self.static.corners.reshape(-1, 3)]
        shown += [_arm(world, pose.joints, pose.held, style.mesh).corners.reshape(-1, 3) for pose in sample]
        if world.object is not None:
            shown += [_object(world, thing, style.mesh).corners.reshape(-1, 3) for thing in things]
        if path is not None:
            shown.append(path)
        points = np.concatenate(shown)
        self.camera = view.camera(points)
        self.ground = _Ground.under(points, style)
        self.scale = style.supersample

    def _project(self, corners: Array) -> Array:
        return self.camera.project(corners, self.scale)

    def background(self, path: Array | None, path_held: NDArray[np.bool_] | None) -> Canvas:
        """The canvas with the ground grid, the obstacles' shadows, the obstacles and the path drawn."""
        style = self.style
        canvas = Canvas.blank(
            self.view.width * self.scale, self.view.height * self.scale, colour("background").rgb, style.raster
        )
        if self.camera.eye[2] > self.ground.z:  # seen from above: the ground, and shadows on it
            self.ground.paint(canvas, self.camera, self.scale, style)
            if style.shadows:
                self._shadows(canvas, self.static)
        canvas.draw(self._project(self.static.corners), _shade(self.static, self.camera, style))
        if path is not None and path_held is not None and len(path) > 1:
            canvas.draw(*self._ribbons(path, path_held))
        return canvas

    def _shadows(self, canvas: Canvas, triangles: _Triangles) -> None:
        if len(triangles.corners) and self.camera.eye[2] > self.ground.z:
            shade = np.broadcast_to(_mix("field", "field_edge", 0.35), (len(triangles.corners), 3))
            canvas.draw(self._project(_shadow(triangles, self.ground.z)), shade)

    def _ribbons(self, path: Array, held: NDArray[np.bool_]) -> tuple[Array, Array]:
        """The path as screen-space quads ``path_width`` wide: transit or transfer by the frame it ends at."""
        screen = self._project(path)
        a, b = screen[:-1], screen[1:]
        along = b[:, :2] - a[:, :2]
        length = np.linalg.norm(along, axis=1, keepdims=True)
        keep = length[:, 0] > 1e-9
        a, b, along, length = a[keep], b[keep], along[keep], length[keep]
        side = np.stack([-along[:, 1], along[:, 0]], axis=1) / length * (self.style.path_width * self.scale / 2)
        offset = np.concatenate([side, np.zeros((len(side), 1))], axis=1)
        p, q, r, s = a - offset, a + offset, b + offset, b - offset
        triangles = np.concatenate([np.stack([p, q, r], axis=1), np.stack([p, r, s], axis=1)])
        kinds = np.where(held[1:][keep][:, None], _rgb("transfer"), _rgb("transit"))
        return triangles, np.concatenate([kinds, kinds])

    def grasp_axes(self, canvas: Canvas, object_pose: Array, grasps: Array, fingers: Array) -> None:
        """Each grasp (tcp poses in the object's frame) at ``object_pose`` (4x4): its approach and its fingers'
        closing axis (``fingers``, unit, in the tcp's frame), as :attr:`SpatialStyle.grasp_axis_m` long lines."""
        length = self.style.grasp_axis_m
        for grasp in np.asarray(grasps, dtype=np.float64).reshape(-1, 6):
            tcp = object_pose @ pose_matrix(grasp.tolist())
            at, approach, across = tcp[:3, 3], tcp[:3, 2], tcp[:3, :3] @ fingers
            for line, held in (
                (np.array([at - length * approach, at]), False),
                (np.array([at - length * across, at + length * across]), True),
            ):
                canvas.draw(*self._ribbons(line, np.full(2, held)))

    def solid(self, canvas: Canvas, pose: _Pose | None, things: Sequence[_Thing]) -> None:
        parts = [_arm(self.world, pose.joints, pose.held, self.style.mesh)] if pose is not None else []
        parts += [_object(self.world, thing, self.style.mesh) for thing in things]
        triangles = _Triangles.join(parts)
        if self.style.shadows:
            self._shadows(canvas, triangles)
        canvas.draw(self._project(triangles.corners), _shade(triangles, self.camera, self.style))

    def ghost(self, canvas: Canvas, pose: _Pose | None, things: Sequence[_Thing], alpha: float) -> None:
        parts = [_arm(self.world, pose.joints, pose.held, self.style.mesh)] if pose is not None else []
        parts += [_object(self.world, thing, self.style.mesh) for thing in things]
        triangles = _Triangles.join(parts)
        canvas.blend(self._project(triangles.corners), _shade(triangles, self.camera, self.style), alpha)

    def finish(self, canvas: Canvas, caption: str, status: str = "") -> Image.Image:
        """The canvas scaled down to the picture, with the caption band under it."""
        image = Image.fromarray(np.clip(canvas.colour + 0.5, 0, 255).astype(np.uint8), "RGB")
        if self.scale > 1:
            image = image.resize((self.view.width, self.view.height), Image.Resampling.BOX)
        if not self.style.caption:
            return image
        size = max(10, self.view.width // 60)
        band = round(size * 1.9)
        out = Image.new("RGB", (self.view.width, self.view.height + band), colour("background").rgb)
        out.paste(image, (0, 0))
        draw = ImageDraw.Draw(out)
        draw.line([(0, self.view.height), (self.view.width, self.view.height)], fill=colour("field_edge").rgb)
        middle = self.view.height + band / 2
        draw.text((size * 0.6, middle), caption, fill=colour("text").rgb, font=font(size), anchor="lm")
        right = f"{status}   {self.camera.describe()}".strip()
        draw.text((self.view.width - size * 0.6, middle), right, fill=colour("muted").rgb, font=font(size), anchor="rm")
        return out


def _fade(index: int, count: int, style: SpatialStyle) -> float:
    """Opacity of ghost ``index`` of ``count`` (the last pose, solid, is not counted): faint first."""
    first, last = style.ghost_alpha
    return first + (last - first) * (index / max(1, count - 1))


def _tcp_path(world: SpatialWorld, joints: Array) -> Array:
    return np.array([world.robot.tcp_pose(q.tolist())[:3, 3] for q in joints])


def _same_pose(a: Array, b: Array) -> bool:
    return bool(np.abs(a - b).max() < 1e-4)


def draw_spatial_frames(
    world: SpatialWorld,
    joints: Any,
    object_poses: Any = None,
    view: View3D | None = None,
    *,
    held: Any = None,
    style: SpatialStyle | None = None,
    title: str | None = None,
) -> Image.Image:
    """A still of frames: the arm at ``style.ghosts`` poses spread along ``joints`` (T, n), fading in, the
    last solid; the object where ``object_poses`` puts it (``None``: at rest at its initial pose; one pose,
    6 numbers or 4x4, at rest there; or one per frame), orange in the frames ``held`` (T,) flags; the tool
    centre point's path (transit blue, transfer orange); the goal placement ghosted in green."""
    style = style or SpatialStyle()
    view = view or View3D()
    q = _check_joints(world, joints)
    poses = _check_object_poses(world, object_poses, len(q))
    held_flags = _check_held(held, len(q))
    count = min(style.ghosts, len(q))
    rows = sorted({round(r) for r in np.linspace(0, len(q) - 1, count)})
    last = rows[-1]
    things: list[tuple[int, _Thing]] = []
    if poses is not None:
        for k, row in enumerate(rows):
            if row == last or not _same_pose(poses[row], poses[last]):
                key = "object_held" if held_flags[row] else "object_rest"
                alpha = 1.0 if row == last else _fade(k, len(rows) - 1, style)
                things.append((row, _Thing(poses[row], key, alpha)))
    goal = []
    if world.object is not None and poses is not None and not _same_pose(pose_matrix(world.object.goal), poses[last]):
        goal = [_Thing(pose_matrix(world.object.goal), "goal", style.goal_alpha)]
    path = _tcp_path(world, q) if len(q) > 1 else None
    sample = [_Pose(q[row], bool(held_flags[row])) for row in rows]
    painter = _Painter(world, view, style, sample=sample, things=[t for _, t in things] + goal, path=path)
    canvas = painter.background(path, held_flags)
    painter.solid(canvas, sample[-1], [t for row, t in things if row == last])
    for k, row in enumerate(rows[:-1]):
        mine = [t for r, t in things if r == row]
        painter.ghost(canvas, sample[k], mine, _fade(k, len(rows) - 1, style))
    if goal:
        painter.ghost(canvas, None, goal, style.goal_alpha)
    caption = title if title is not None else f"{world.name}: {len(q)} frames, {len(rows)} poses, the last solid"
    return painter.finish(canvas, caption)


def draw_spatial_world(
    world: SpatialWorld, view: View3D | None = None, *, style: SpatialStyle | None = None
) -> Image.Image:
    """The world alone: the arm at its start; the object at its start (blue) with its grasps' approach and
    finger axes (:attr:`SpatialStyle.grasp_axis_m`) and its goal placement ghosted (green), or, for a
    motion-only query, the arm at its goal configuration ghosted."""
    style = style or SpatialStyle()
    view = view or View3D()
    start = _Pose(world.initial, False)
    things = []
    if world.object is not None:
        things = [
            _Thing(pose_matrix(world.object.initial), "start", 1.0),
            _Thing(pose_matrix(world.object.goal), "goal", style.goal_alpha),
        ]
    goal_pose = _Pose(world.goal, False) if world.goal is not None else None
    sample = [start] + ([goal_pose] if goal_pose is not None else [])
    painter = _Painter(world, view, style, sample=sample, things=things, path=None)
    canvas = painter.background(None, None)
    painter.solid(canvas, start, things[:1])
    drawn = world.object is not None and style.grasp_axis_m > 0
    if drawn:
        from clew_ros.spatial.grasp_check import finger_axis

        assert world.object is not None
        painter.grasp_axes(canvas, pose_matrix(world.object.initial), world.object.grasps, finger_axis(world).axis)
    if goal_pose is not None:
        painter.ghost(canvas, goal_pose, [], style.goal_alpha)
    if len(things) > 1:
        painter.ghost(canvas, None, things[1:], style.goal_alpha)
    shown = "start solid, goal configuration faded" if goal_pose is not None else "start solid"
    if world.object is not None:
        shown += f"; object on {world.object.initial_on[0]}, goal on {world.object.goal_on[0]} (green)"
    if drawn:
        shown += "; grasp axes"
    return painter.finish(canvas, f"{world.name}: {shown}")


def spatial_gif_frames(
    world: SpatialWorld,
    joints: Any,
    object_poses: Any = None,
    view: View3D | None = None,
    *,
    held: Any = None,
    style: SpatialStyle | None = None,
    title: str | None = None,
) -> list[Image.Image]:
    """One picture per frame (T of them), the camera fixed for all: the arm and the object at that frame over
    the world, the path of the whole motion faint behind."""
    style = style or SpatialStyle()
    view = view or View3D()
    q = _check_joints(world, joints)
    poses = _check_object_poses(world, object_poses, len(q))
    held_flags = _check_held(held, len(q))
    spread = sorted({round(r) for r in np.linspace(0, len(q) - 1, min(len(q), 12))})
    sample = [_Pose(q[row], bool(held_flags[row])) for row in spread]
    things = [_Thing(poses[row], "object_rest", 1.0) for row in spread] if poses is not None else []
    path = _tcp_path(world, q) if len(q) > 1 else None
    painter = _Painter(world, view, style, sample=sample, things=things, path=path)
    base = painter.background(path, held_flags)
    caption = title if title is not None else world.name
    frames = []
    for row in range(len(q)):
        canvas = base.copy()
        objects = []
        if poses is not None:
            objects = [_Thing(poses[row], "object_held" if held_flags[row] else "object_rest", 1.0)]
        painter.solid(canvas, _Pose(q[row], bool(held_flags[row])), objects)
        status = f"frame {row + 1}/{len(q)}" + (", holding" if held_flags[row] else "")
        frames.append(painter.finish(canvas, caption, status))
    return frames


def write_spatial_gif(
    path: str | Path,
    world: SpatialWorld,
    joints: Any,
    object_poses: Any = None,
    view: View3D | None = None,
    *,
    held: Any = None,
    style: SpatialStyle | None = None,
    title: str | None = None,
) -> Path:
    """:func:`spatial_gif_frames` written as a looping GIF: ``frame_ms`` a frame, ``event_ms`` where the
    gripper closes or opens, ``end_ms`` on the last; one palette for all frames (no flicker)."""
    style = style or SpatialStyle()
    frames = spatial_gif_frames(world, joints, object_poses, view, held=held, style=style, title=title)
    flags = _check_held(held, len(frames))
    durations = [
        style.end_ms if k == len(frames) - 1 else style.event_ms if k and flags[k] != flags[k - 1] else style.frame_ms
        for k in range(len(frames))
    ]
    picks = [frames[i] for i in sorted({0, len(frames) // 3, 2 * len(frames) // 3, len(frames) - 1})]
    strip = Image.new("RGB", (sum(f.width for f in picks), max(f.height for f in picks)))
    x = 0
    for frame in picks:
        strip.paste(frame, (x, 0))
        x += frame.width
    palette = strip.quantize(colors=256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    quantized = [f.quantize(palette=palette, dither=Image.Dither.NONE) for f in frames]
    out = Path(path)
    quantized[0].save(
        out, format="GIF", save_all=True, append_images=quantized[1:], duration=durations, loop=0, disposal=1
    )
    return out
