"""PNG (a filmstrip of overlaid, fading poses) and GIF (an animation) with Pillow."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from clew_ros.core.kinematics import joint_positions, transform_points
from clew_ros.render.scene import Motion, Scene
from clew_ros.render.view import COLORS, LEGEND, View, arm_points, object_outline, rest_poses

__all__ = ["render_png", "render_gif", "FILMSTRIP_POSES", "GIF_FRAMES"]

#: Poses overlaid in the PNG filmstrip (plus the grasp and ungrasp poses).
FILMSTRIP_POSES = 12
#: Frames of motion in a GIF (plus held frames at grasps, ungrasps and the end).
GIF_FRAMES = 80
_FRAME_MS = 50
_EVENT_MS = 700
_END_MS = 1500


def _font(size: int) -> ImageFont.ImageFont:
    try:
        return ImageFont.load_default(size=size)
    except TypeError:  # Pillow < 10.1: fixed bitmap font
        return ImageFont.load_default()


def _rgba(key: str, alpha: int = 255) -> tuple[int, int, int, int]:
    return (*COLORS[key], int(alpha))


def _xy(points: np.ndarray) -> list[tuple[float, float]]:
    return [(float(x), float(y)) for x, y in points]


class Canvas:
    """One picture: the map area on top, a caption band with title and legend below."""

    def __init__(self, scene: Scene, size: int) -> None:
        self.scene = scene
        self.world = scene.world
        self.view = View.fit(scene.world, size)
        self.line = max(2, round(size / 320))
        self.font = _font(max(10, size // 55))
        self.small = _font(max(9, size // 70))
        self.caption_height = max(48, round(size * 0.10))
        self.image = Image.new("RGB", (self.view.width, self.view.height + self.caption_height), COLORS["background"])
        self.draw = ImageDraw.Draw(self.image, "RGBA")

    def copy(self) -> "Canvas":
        other = object.__new__(Canvas)
        other.__dict__.update(self.__dict__)
        other.image = self.image.copy()
        other.draw = ImageDraw.Draw(other.image, "RGBA")
        return other

    # ------------------------------------------------------------------ static layers

    def dashed(self, points: np.ndarray, color: tuple, width: int, dash: float, closed: bool = True) -> None:
        pts = np.asarray(points, dtype=float)
        if closed:
            pts = np.vstack([pts, pts[:1]])
        carry = 0.0  # keep the dash pattern running around corners
        for a, b in zip(pts[:-1], pts[1:]):
            length = float(np.hypot(*(b - a)))
            if length == 0:
                continue
            direction = (b - a) / length
            t = -carry
            while t < length:
                start, end = max(t, 0.0), min(t + dash, length)
                if end > start:
                    self.draw.line(_xy([a + direction * start, a + direction * end]), fill=color, width=width)
                t += 2 * dash
            carry = t - length

    def world_layer(self) -> None:
        """Bounds, obstacles, the object's start (outline) and goal (dashed), its grasp points."""
        v, w, lw = self.view, self.world, self.line
        xmin, ymin, xmax, ymax = (float(b) for b in w.bounds)
        box = v.px(np.array([[xmin, ymax], [xmax, ymin]]))
        self.draw.rectangle(_xy(box), fill=COLORS["field"], outline=COLORS["field_edge"], width=lw)
        for obstacle in w.obstacles:
            self.draw.polygon(_xy(v.px(obstacle.vertices)), fill=COLORS["obstacle"], outline=COLORS["obstacle_edge"],
                              width=lw)
        goal = v.px(object_outline(w, w.object.goal))
        self.draw.polygon(_xy(goal), fill=_rgba("goal", 40))
        self.dashed(goal, _rgba("goal"), lw, dash=max(4.0, 3.0 * lw))
        start = v.px(object_outline(w, w.object.initial))
        self.draw.polygon(_xy(start), fill=_rgba("start", 35), outline=_rgba("start"), width=lw)
        radius = max(3, 1.3 * lw)
        centre = v.px(w.object.initial[:2])
        for index, point in enumerate(v.px(transform_points(w.object.initial, w.object.grasps))):
            x, y = point
            self.draw.ellipse([x - radius, y - radius, x + radius, y + radius], fill=_rgba("grasp"))
            away = point - centre
            away = away / (np.hypot(*away) or 1.0)
            label = point + away * (radius + 8)
            self.draw.text((float(label[0]), float(label[1])), str(index), fill=_rgba("grasp"), font=self.small,
                           anchor="mm")

    def tree_layer(self) -> None:
        tree = self.scene.landmarks
        if tree is None:
            return
        v = self.view
        for a, b in v.px(tree.edges):
            self.draw.line(_xy([a, b]), fill=_rgba("tree_edge", 230), width=self.line)
        radius = max(2.5, 1.1 * self.line)
        for index, (x, y) in enumerate(v.px(tree.nodes)):
            r = radius * (1.6 if index == tree.root else 1.0)
            self.draw.ellipse([x - r, y - r, x + r, y + r], fill=_rgba("tree_node", 230))

    def tip_path(self, motion: Motion, upto: int | None = None, alpha: int = 255, width: int | None = None) -> None:
        """The tip's path, coloured by segment kind, up to row ``upto``."""
        end = len(motion) if upto is None else upto + 1
        if end < 2:
            return
        tips = self._tips(motion)[:end]
        held = motion.held[:end] >= 0
        width = width or max(1, self.line - 1)
        start = 0
        for i in range(1, end + 1):
            if i == end or held[i] != held[start]:
                piece = tips[start:min(i + 1, end)]
                if len(piece) > 1:
                    self.draw.line(_xy(piece), fill=_rgba("transfer" if held[start] else "transit", alpha),
                                   width=width, joint="curve")
                start = i

    def _tips(self, motion: Motion) -> np.ndarray:
        """Pixel positions of the tip along the whole motion (computed once per canvas family)."""
        cached = self.__dict__.get("_tip_cache")
        if cached is None or cached[0] is not motion:
            tips = joint_positions(self.world.robot, motion.configurations)[:, -1]
            cached = (motion, self.view.px(tips))
            self.__dict__["_tip_cache"] = cached
        return cached[1]

    # ------------------------------------------------------------------ poses

    def object_at(self, pose: np.ndarray, held: bool, alpha: int = 255) -> None:
        outline = self.view.px(object_outline(self.world, pose))
        key = "object_held" if held else "object_rest"
        self.draw.polygon(_xy(outline), fill=_rgba(key, int(alpha * 0.75)), outline=(*COLORS["arm"], int(alpha * 0.6)),
                          width=max(1, self.line - 1))

    def arm_at(self, q: np.ndarray, held: bool, alpha: int = 255) -> None:
        v, lw = self.view, self.line
        points = v.px(arm_points(self.world, q))
        width = max(2 * lw, int(round(v.length(self.world.robot.link_width))))
        self.draw.line(_xy(points), fill=_rgba("arm", alpha), width=width, joint="curve")
        r = max(2.5, 1.2 * lw)
        bx, by = points[0]
        base = 2.2 * r
        self.draw.rectangle([bx - base, by - base, bx + base, by + base], fill=_rgba("arm", alpha))
        for x, y in points[1:-1]:
            self.draw.ellipse([x - r, y - r, x + r, y + r], fill=_rgba("joint", alpha), outline=_rgba("arm", alpha))
        x, y = points[-1]
        g = 1.9 * r
        self.draw.ellipse([x - g, y - g, x + g, y + g], fill=_rgba("closed" if held else "open", alpha),
                          outline=_rgba("arm", alpha))

    # ------------------------------------------------------------------ caption

    def caption(self, title: str, status: str = "", progress: float | None = None) -> None:
        """Title (left), status (right) and a legend of what the picture holds; a progress bar for GIFs."""
        top = self.view.height
        pad = max(4, self.view.margin)
        self.draw.rectangle([0, top, self.image.width, self.image.height], fill=COLORS["background"])
        self.draw.line([(0, top), (self.image.width, top)], fill=COLORS["field_edge"], width=1)
        self.draw.text((pad, top + pad), title, fill=COLORS["text"], font=self.font)
        if status:
            self.draw.text((self.image.width - pad, top + pad), status, fill=COLORS["closed"] if "grasp" in status
                           else COLORS["text"], font=self.font, anchor="ra")
        y = top + pad + self.font.size + pad if hasattr(self.font, "size") else top + 2 * pad + 12
        x = pad
        s = max(6, self.small.size // 2 if hasattr(self.small, "size") else 5)
        shown = {"landmark tree": self.scene.landmarks is not None,
                 "transit": self.scene.plan is not None, "transfer": self.scene.plan is not None,
                 "holding": self.scene.plan is not None, "obstacle": bool(self.world.obstacles)}
        for label, key, style in LEGEND:
            if not shown.get(label, True):
                continue
            cy = y + s
            if style == "box":
                self.draw.rectangle([x, cy - s, x + 2 * s, cy + s], outline=COLORS[key], width=2)
            elif style == "dashed":
                self.dashed(np.array([[x, cy - s], [x + 2 * s, cy - s], [x + 2 * s, cy + s], [x, cy + s]]),
                            COLORS[key], 2, dash=3.0)
            elif style == "fill":
                self.draw.rectangle([x, cy - s, x + 2 * s, cy + s], fill=COLORS[key])
            elif style == "dot":
                self.draw.ellipse([x + s / 2, cy - s / 2 - 1, x + 1.5 * s + 2, cy + s / 2 + 1], fill=COLORS[key])
            else:
                self.draw.line([(x, cy), (x + 2 * s, cy)], fill=COLORS[key], width=3)
            self.draw.text((x + 2 * s + 4, cy), label, fill=COLORS["muted"], font=self.small, anchor="lm")
            x += 2 * s + 10 + int(self.draw.textlength(label, font=self.small))
            if x > self.image.width - 60:
                x, y = pad, y + 2 * s + 4
        if progress is not None:
            bar = self.image.height - 4
            self.draw.rectangle([0, bar, self.image.width * max(0.0, min(1.0, progress)), self.image.height],
                                fill=COLORS["transfer"])

    def background(self, motion: Motion | None) -> None:
        self.world_layer()
        self.tree_layer()
        if motion is not None:
            self.tip_path(motion, alpha=90)


def _summary(scene: Scene) -> str:
    parts = [scene.title]
    if scene.plan is not None:
        parts.append(f"{len(scene.plan.segments)} segments, {scene.grasp_count} grasp(s)")
    if scene.landmarks is not None:
        parts.append(f"{len(scene.landmarks.nodes)} landmarks")
    parts += scene.notes
    return " | ".join(p for p in parts if p)


def render_png(scene: Scene, path: str | Path, size: int = 800) -> Path:
    """A still: the world, the landmark tree, the tip path and the arm at fading poses along the plan."""
    canvas = Canvas(scene, size)
    motion = scene.motion()
    canvas.world_layer()
    canvas.tree_layer()
    if motion is not None:
        canvas.tip_path(motion, alpha=230)
        rows = motion.sample(FILMSTRIP_POSES, before_events=False)
        for pose in rest_poses(motion):
            canvas.object_at(pose, held=False, alpha=110)
        for k, row in enumerate(rows):
            fraction = (k + 1) / len(rows)
            alpha = 255 if row == rows[-1] else int(35 + 150 * fraction ** 1.5)
            held = bool(motion.held[row] >= 0)
            if held or row == rows[-1]:
                canvas.object_at(motion.object_poses[row], held, alpha)
            canvas.arm_at(motion.configurations[row], held, alpha)
    else:
        canvas.arm_at(scene.world.robot.initial, held=False)
    canvas.caption(_summary(scene))
    path = Path(path)
    canvas.image.save(path, format="PNG", optimize=True)
    return path


def _status(motion: Motion, row: int, event: tuple | None) -> str:
    if event is not None:
        kind, grasp = event
        return f"{kind} {grasp}: gripper {'closes' if kind == 'grasp' else 'opens'}"
    if row == len(motion) - 1:
        return "done"
    grasp = int(motion.held[row])
    return f"transfer holding grasp {grasp}" if grasp >= 0 else "transit"


def render_gif(scene: Scene, path: str | Path, size: int = 600) -> Path:
    """An animation of the plan; frames hold at each grasp and ungrasp, where the gripper changes colour."""
    base = Canvas(scene, size)
    motion = scene.motion()
    base.background(motion)
    frames: list[Image.Image] = []
    durations: list[int] = []
    if motion is None:
        canvas = base.copy()
        canvas.arm_at(scene.world.robot.initial, held=False)
        canvas.caption(_summary(scene), "no plan")
        frames.append(canvas.image)
        durations.append(_END_MS)
    else:
        events = {row: (kind, grasp) for row, kind, grasp in motion.events}
        rows = motion.sample(GIF_FRAMES)
        for row in rows:
            event = events.get(row)
            held = bool(motion.held[row] >= 0)
            canvas = base.copy()
            canvas.tip_path(motion, upto=row, alpha=255, width=base.line)
            canvas.object_at(motion.object_poses[row], held)
            canvas.arm_at(motion.configurations[row], held)
            canvas.caption(_summary(scene), _status(motion, row, event), progress=row / max(1, len(motion) - 1))
            frames.append(canvas.image)
            durations.append(_END_MS if row == rows[-1] else _EVENT_MS if event else _FRAME_MS)
    palette = _palette(frames)
    quantized = [f.quantize(palette=palette, dither=Image.Dither.NONE) for f in frames]
    path = Path(path)
    quantized[0].save(path, format="GIF", save_all=True, append_images=quantized[1:], duration=durations, loop=0,
                      optimize=False, disposal=1)
    return path


def _palette(frames: list[Image.Image]) -> Image.Image:
    """One palette for every frame (no flicker): quantised from a few frames side by side."""
    picks = [frames[i] for i in sorted({0, len(frames) // 3, 2 * len(frames) // 3, len(frames) - 1})]
    strip = Image.new("RGB", (sum(f.width for f in picks), max(f.height for f in picks)), COLORS["background"])
    x = 0
    for frame in picks:
        strip.paste(frame, (x, 0))
        x += frame.width
    return strip.quantize(colors=256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
