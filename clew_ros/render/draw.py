"""A scene drawn once, into shapes: the one place that knows how a picture lays out the scene.

What is drawn, and in which colour, is the scene description's
(:mod:`clew_ros.scene`: the items in metres, the palette's keys); this
module places them in pixels and sizes them.

:func:`draw_still` makes the filmstrip that the PNG and the SVG both write
(the world, the landmark tree, the tip's path, the arm at poses fading in along
the plan, a caption with a legend); :func:`draw_animation` makes the GIF's
frames (the arm moving, holding at each grasp and ungrasp). The back ends
only paint these shapes (:mod:`clew_ros.render.raster`, :mod:`clew_ros.render.svg`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from clew_ros.planar.world import World
from clew_ros.render.scene import Motion, Scene
from clew_ros.render.shapes import Animation, Circle, Drawing, Frame, Paint, Point, Polygon, Polyline, Rect, Shape, Text
from clew_ros.render.text import font_height, text_width
from clew_ros.render.view import View
from clew_ros.scene.items import (
    ArmItems,
    TreeItems,
    arm_points,
    gripper_key,
    object_key,
    object_outline,
    world_items,
)

__all__ = [
    "END_MS",
    "EVENT_MS",
    "FILMSTRIP_POSES",
    "FRAME_MS",
    "GIF_FRAMES",
    "LEGEND",
    "Layout",
    "draw_animation",
    "draw_still",
    "fade",
    "summary",
]

#: Poses overlaid in the filmstrip (plus the grasp and ungrasp poses).
FILMSTRIP_POSES = 12
#: Frames of motion in an animation (plus held frames at grasps, ungrasps and the end).
GIF_FRAMES = 80
#: How long an animation shows a frame of motion, a grasp or ungrasp, and its last frame (ms).
FRAME_MS, EVENT_MS, END_MS = 50, 700, 1500

#: Legend entries: (label, colour key, style); style one of box, dashed, fill, dot, line.
LEGEND = (
    ("start", "start", "box"),
    ("goal", "goal", "dashed"),
    ("obstacle", "obstacle", "fill"),
    ("grasps", "grasp", "dot"),
    ("landmark tree", "tree_node", "dot"),
    ("transit", "transit", "line"),
    ("transfer", "transfer", "line"),
    ("gripper open", "open", "dot"),
    ("holding", "closed", "dot"),
)


def fade(index: int, count: int) -> int:
    """Opacity (0-255) of pose ``index`` of the ``count`` poses of a filmstrip: faint first, the last opaque."""
    if index >= count - 1:
        return 255
    return int(35 + 150 * ((index + 1) / count) ** 1.5)


def summary(scene: Scene) -> str:
    """The caption's title: the scene's title, the plan's size, the landmarks, notes."""
    parts = [scene.title]
    if scene.plan is not None:
        parts.append(f"{len(scene.plan.segments)} segments, {scene.grasp_count} grasp(s)")
    if scene.landmarks is not None:
        parts.append(f"{len(scene.landmarks.nodes)} landmarks")
    parts += scene.notes
    return " | ".join(p for p in parts if p)


def _text(
    position: Point, text: str, paint: Paint, size: int, anchor: str = "la", *, layer: str = "caption", title: str = ""
) -> Text:
    """A :class:`Text` with its measured width."""
    return Text(position, text, paint, size, anchor, text_width(text, size), layer=layer, title=title)


def _points(pixels: np.ndarray) -> tuple[Point, ...]:
    return tuple((float(x), float(y)) for x, y in pixels)


@dataclass(frozen=True)
class Layout:
    """Sizes of one picture of ``size`` pixels across: the map (``view``) on top, the caption band below."""

    view: View
    line: int  # px, the width of most lines
    title_size: int  # px
    small_size: int  # px
    caption_height: int  # px

    @classmethod
    def fit(cls, world: World, size: int) -> Layout:
        return cls(
            View.fit(world, size),
            max(2, round(size / 320)),
            max(10, size // 55),
            max(9, size // 70),
            max(48, round(size * 0.10)),
        )

    @property
    def width(self) -> int:
        return self.view.width

    @property
    def height(self) -> int:
        return self.view.height + self.caption_height


class _Painter:
    """Shapes of one scene at one layout; each method returns the shapes of one part of the picture."""

    def __init__(self, scene: Scene, layout: Layout, motion: Motion | None) -> None:
        self.scene = scene
        self.world = scene.world
        self.layout = layout
        self.view = layout.view
        self.line = layout.line
        self.motion = motion
        self.tips: tuple[Point, ...] = ()
        if motion is not None:  # the tip's path in pixels, once
            self.tips = _points(self.view.px(motion.tips(self.world)))

    # ------------------------------------------------------------------ what does not move

    def world_shapes(self) -> list[Shape]:
        """Bounds, obstacles, the object's start (outline) and goal (dashed), its grasp points (numbered)."""
        v, lw, items = self.view, self.line, world_items(self.world)
        (x0, y0), (x1, y1) = v.px(np.array([items.bounds[3], items.bounds[1]]))  # top-left, bottom-right
        shapes: list[Shape] = [
            Rect(
                float(x0),
                float(y0),
                float(x1),
                float(y1),
                Paint(items.field_key),
                Paint(items.bounds_key),
                lw,
                layer="bounds",
            )
        ]
        shapes += [
            Polygon(
                _points(v.px(obstacle.vertices)),
                Paint(obstacle.key),
                Paint(obstacle.edge_key),
                lw,
                layer="obstacles",
                title=obstacle.name,
            )
            for obstacle in items.obstacles
        ]
        shapes.append(
            Polygon(
                _points(v.px(items.goal)),
                Paint(items.goal_key, 40),
                Paint(items.goal_key),
                lw,
                dash=max(4.0, 3.0 * lw),
                layer="goal",
            )
        )
        shapes.append(
            Polygon(
                _points(v.px(items.start)),
                Paint(items.start_key, 35),
                Paint(items.start_key),
                lw,
                layer="start",
            )
        )
        radius = max(3, 1.3 * lw)
        centre = v.px(self.world.object.initial[:2])
        for index, point in enumerate(v.px(items.grasps)):
            shapes.append(
                Circle(
                    (float(point[0]), float(point[1])),
                    radius,
                    Paint(items.grasp_key),
                    layer="grasps",
                    title=f"grasp {index}",
                )
            )
            away = point - centre
            away = away / (np.hypot(*away) or 1.0)
            label = point + away * (radius + 8)
            shapes.append(
                _text(
                    (float(label[0]), float(label[1])),
                    str(index),
                    Paint(items.grasp_key),
                    self.layout.small_size,
                    "mm",
                    layer="grasps",
                )
            )
        return shapes

    def tree_shapes(self, tree: TreeItems | None) -> list[Shape]:
        """The landmark tree: parent -> child edges, a dot per landmark (the root larger)."""
        if tree is None:
            return []
        v = self.view
        shapes: list[Shape] = [
            Polyline(_points(edge), Paint(tree.edge_key, 230), self.line, layer="landmarks")
            for edge in v.px(tree.edges)
        ]
        radius = max(2.5, 1.1 * self.line)
        for index, (x, y) in enumerate(v.px(tree.nodes)):
            shapes.append(
                Circle(
                    (float(x), float(y)),
                    radius * (1.6 if index == tree.root else 1.0),
                    Paint(tree.node_key, 230),
                    layer="landmarks",
                    title=f"landmark {index}",
                )
            )
        return shapes

    def tip_path(self, upto: int | None = None, alpha: int = 255, width: int | None = None) -> list[Shape]:
        """The tip's path up to row ``upto`` (all of it: ``None``), by segment kind (transit, transfer)."""
        if self.motion is None:
            return []
        width = width or max(1, self.line - 1)
        return [
            Polyline(self.tips[p.first : p.stop], Paint(p.kind, alpha), width, rounded=True, layer="tip-path")
            for p in self.motion.tip_pieces(upto)
        ]

    # ------------------------------------------------------------------ what moves

    def object_at(self, pose: np.ndarray, held: bool, alpha: int = 255, layer: str = "poses") -> Shape:
        return Polygon(
            _points(self.view.px(object_outline(self.world, pose))),
            Paint(object_key(held), int(alpha * 0.75)),
            Paint(ArmItems.arm_key, int(alpha * 0.6)),
            max(1, self.line - 1),
            layer=layer,
        )

    def arm_at(self, q: np.ndarray, held: bool, alpha: int = 255) -> list[Shape]:
        """The links (one line), the base (a square), the joints (white dots), the gripper (green open, red holding)."""
        v, lw = self.view, self.line
        points = v.px(arm_points(self.world, q))
        width = max(2 * lw, round(v.length(self.world.robot.link_width)))
        ink = Paint(ArmItems.arm_key, alpha)
        shapes: list[Shape] = [Polyline(_points(points), ink, width, rounded=True, layer="poses")]
        r = max(2.5, 1.2 * lw)
        bx, by = (float(c) for c in points[0])
        base = 2.2 * r
        shapes.append(Rect(bx - base, by - base, bx + base, by + base, ink, layer="poses"))
        shapes += [
            Circle((float(x), float(y)), r, Paint(ArmItems.joint_key, alpha), ink, layer="poses")
            for x, y in points[1:-1]
        ]
        x, y = points[-1]
        shapes.append(Circle((float(x), float(y)), 1.9 * r, Paint(gripper_key(held), alpha), ink, layer="poses"))
        return shapes

    # ------------------------------------------------------------------ caption

    def caption(self, title: str, status: str = "", progress: float | None = None) -> list[Shape]:
        """Title (left), status (right) and a legend of what the picture holds; a progress bar for animations."""
        layout = self.layout
        top, width, height = self.view.height, layout.width, layout.height
        pad = max(4, self.view.margin)
        small = layout.small_size
        shapes: list[Shape] = [
            Rect(0, top, width, height, Paint("background"), layer="caption"),
            Polyline(((0, top), (width, top)), Paint("field_edge"), 1, layer="caption"),
            _text((pad, top + pad), title, Paint("text"), layout.title_size),
        ]
        if status:
            shapes.append(
                _text(
                    (width - pad, top + pad),
                    status,
                    Paint("closed" if "grasp" in status else "text"),
                    layout.title_size,
                    "ra",
                )
            )
        title_height = font_height(layout.title_size)
        small_height = font_height(small)
        y = top + pad + title_height + pad if title_height is not None else top + 2 * pad + 12
        s = max(6, small_height // 2 if small_height is not None else 5)
        x = pad
        for label, key, style in self.legend():
            cy = y + s
            text = _text((x + 2 * s + 4, cy), label, Paint("muted"), small, "lm")
            shapes += [_legend_mark(style, key, x, cy, s), text]
            x += 2 * s + 10 + int(text.length)
            if x > width - 60:
                x, y = pad, y + 2 * s + 4
        if progress is not None:
            shapes.append(
                Rect(0, height - 4, width * max(0.0, min(1.0, progress)), height, Paint("transfer"), layer="caption")
            )
        return shapes

    def legend(self) -> list[tuple[str, str, str]]:
        """The legend entries of what this scene shows."""
        planned = self.scene.plan is not None
        shown = {
            "landmark tree": self.scene.landmarks is not None,
            "transit": planned,
            "transfer": planned,
            "holding": planned,
            "obstacle": bool(self.world.obstacles),
        }
        return [entry for entry in LEGEND if shown.get(entry[0], True)]


def _legend_mark(style: str, key: str, x: float, cy: float, s: int) -> Shape:
    """The sample drawn before a legend label: ``2 s`` pixels wide, centred on ``cy``."""
    if style == "box":
        return Rect(x, cy - s, x + 2 * s, cy + s, outline=Paint(key), width=2, layer="caption")
    if style == "dashed":
        corners = ((x, cy - s), (x + 2 * s, cy - s), (x + 2 * s, cy + s), (x, cy + s))
        return Polygon(corners, outline=Paint(key), width=2, dash=3.0, layer="caption")
    if style == "fill":
        return Rect(x, cy - s, x + 2 * s, cy + s, Paint(key), layer="caption")
    if style == "dot":
        return Circle((x + s + 1, cy), s / 2 + 1, Paint(key), layer="caption")
    return Polyline(((x, cy), (x + 2 * s, cy)), Paint(key), 3, layer="caption")


def draw_still(scene: Scene, size: int = 800) -> Drawing:
    """The filmstrip: the world, the landmark tree, the tip's path and the arm at poses fading in along the plan
    (the arm at its start without a plan), with a caption; ``size`` pixels across."""
    motion = scene.motion()
    painter = _Painter(scene, Layout.fit(scene.world, size), motion)
    shapes = painter.world_shapes() + painter.tree_shapes(scene.landmarks)
    if motion is not None:
        shapes += painter.tip_path(alpha=230)
        shapes += [painter.object_at(pose, held=False, alpha=110, layer="rest-poses") for pose in motion.rest_poses()]
        rows = motion.sample(FILMSTRIP_POSES, before_events=False)
        for k, row in enumerate(rows):
            alpha = fade(k, len(rows))
            held = bool(motion.held[row] >= 0)
            if held or k == len(rows) - 1:
                shapes.append(painter.object_at(motion.object_poses[row], held, alpha))
            shapes += painter.arm_at(motion.configurations[row], held, alpha)
    else:
        shapes += painter.arm_at(scene.world.robot.initial, held=False)
    shapes += painter.caption(summary(scene))
    return Drawing(painter.layout.width, painter.layout.height, tuple(shapes), title=scene.title)


def _status(motion: Motion, row: int, event: tuple[str, int] | None) -> str:
    if event is not None:
        kind, grasp = event
        return f"{kind} {grasp}: gripper {'closes' if kind == 'grasp' else 'opens'}"
    if row == len(motion) - 1:
        return "done"
    grasp = int(motion.held[row])
    return f"transfer holding grasp {grasp}" if grasp >= 0 else "transit"


def draw_animation(scene: Scene, size: int = 600) -> Animation:
    """The plan animated: a frame per sampled row, held at each grasp and ungrasp (where the gripper changes colour)
    and at the end; a single frame of the arm at its start without a plan."""
    motion = scene.motion()
    painter = _Painter(scene, Layout.fit(scene.world, size), motion)
    base = painter.world_shapes() + painter.tree_shapes(scene.landmarks) + painter.tip_path(alpha=90)
    title = summary(scene)
    frames: list[Frame] = []
    if motion is None:
        shapes = painter.arm_at(scene.world.robot.initial, held=False) + painter.caption(title, "no plan")
        frames.append(Frame(tuple(shapes), END_MS))
    else:
        events = {row: (kind, grasp) for row, kind, grasp in motion.events}
        rows = motion.sample(GIF_FRAMES)
        for row in rows:
            event = events.get(row)
            held = bool(motion.held[row] >= 0)
            shapes = painter.tip_path(upto=row, alpha=255, width=painter.line)
            shapes.append(painter.object_at(motion.object_poses[row], held))
            shapes += painter.arm_at(motion.configurations[row], held)
            shapes += painter.caption(title, _status(motion, row, event), progress=row / max(1, len(motion) - 1))
            frames.append(Frame(tuple(shapes), END_MS if row == rows[-1] else EVENT_MS if event else FRAME_MS))
    layout = painter.layout
    return Animation(Drawing(layout.width, layout.height, tuple(base), title=scene.title), tuple(frames))
