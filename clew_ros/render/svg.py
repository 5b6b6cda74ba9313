"""SVG output: the same filmstrip as the PNG, written as text."""

from __future__ import annotations

from pathlib import Path
from xml.sax.saxutils import escape

import numpy as np

from clew_ros.core.kinematics import transform_points
from clew_ros.render.raster import FILMSTRIP_POSES, _summary
from clew_ros.render.scene import Scene
from clew_ros.render.view import COLORS, View, arm_points, object_outline, rest_poses

__all__ = ["render_svg"]


def _rgb(key: str) -> str:
    r, g, b = COLORS[key]
    return f"#{r:02x}{g:02x}{b:02x}"


def _points(points: np.ndarray) -> str:
    return " ".join(f"{x:.1f},{y:.1f}" for x, y in points)


def render_svg(scene: Scene, path: str | Path, size: int = 800) -> Path:
    """Write the scene as an SVG filmstrip (world, landmark tree, tip path, fading poses)."""
    world = scene.world
    view = View.fit(world, size)
    line = max(2, round(size / 320))
    caption = max(36, round(size * 0.06))
    width, height = view.width, view.height + caption
    out: list[str] = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
        f'viewBox="0 0 {width} {height}" font-family="sans-serif">',
        f"<title>{escape(scene.title)}</title>",
        f'<rect width="{width}" height="{height}" fill="{_rgb("background")}"/>',
    ]
    xmin, ymin, xmax, ymax = (float(b) for b in world.bounds)
    (x0, y0), (x1, y1) = view.px(np.array([[xmin, ymax], [xmax, ymin]]))
    out.append(f'<rect id="bounds" x="{x0:.1f}" y="{y0:.1f}" width="{x1 - x0:.1f}" height="{y1 - y0:.1f}" '
               f'fill="{_rgb("field")}" stroke="{_rgb("field_edge")}" stroke-width="{line}"/>')
    out.append('<g id="obstacles">')
    for obstacle in world.obstacles:
        out.append(f'<polygon points="{_points(view.px(obstacle.vertices))}" fill="{_rgb("obstacle")}" '
                   f'stroke="{_rgb("obstacle_edge")}" stroke-width="{line}"><title>{escape(obstacle.name)}</title>'
                   "</polygon>")
    out.append("</g>")
    out.append(f'<polygon id="goal" points="{_points(view.px(object_outline(world, world.object.goal)))}" '
               f'fill="{_rgb("goal")}" fill-opacity="0.16" stroke="{_rgb("goal")}" stroke-width="{line}" '
               f'stroke-dasharray="{3 * line} {3 * line}"/>')
    out.append(f'<polygon id="start" points="{_points(view.px(object_outline(world, world.object.initial)))}" '
               f'fill="{_rgb("start")}" fill-opacity="0.14" stroke="{_rgb("start")}" stroke-width="{line}"/>')
    out.append('<g id="grasps">')
    radius = max(3, 1.3 * line)
    for index, (x, y) in enumerate(view.px(transform_points(world.object.initial, world.object.grasps))):
        out.append(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="{radius:.1f}" fill="{_rgb("grasp")}">'
                   f"<title>grasp {index}</title></circle>")
    out.append("</g>")
    if scene.landmarks is not None:
        out.append('<g id="landmarks">')
        for a, b in view.px(scene.landmarks.edges):
            out.append(f'<line x1="{a[0]:.1f}" y1="{a[1]:.1f}" x2="{b[0]:.1f}" y2="{b[1]:.1f}" '
                       f'stroke="{_rgb("tree_edge")}" stroke-width="{line}"/>')
        for index, (x, y) in enumerate(view.px(scene.landmarks.nodes)):
            r = max(2.5, 1.1 * line) * (1.6 if index == scene.landmarks.root else 1.0)
            out.append(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="{r:.1f}" fill="{_rgb("tree_node")}"/>')
        out.append("</g>")
    motion = scene.motion()
    poses: list[tuple[np.ndarray, np.ndarray, bool, float]] = []
    if motion is not None:
        tips = view.px(np.array([arm_points(world, q)[-1] for q in motion.configurations]))
        held = motion.held >= 0
        out.append('<g id="tip-path" fill="none">')
        start = 0
        for i in range(1, len(motion) + 1):
            if i == len(motion) or held[i] != held[start]:
                piece = tips[start:min(i + 1, len(motion))]
                if len(piece) > 1:
                    out.append(f'<polyline points="{_points(piece)}" stroke="{_rgb("transfer" if held[start] else "transit")}" '
                               f'stroke-width="{max(1, line - 1)}"/>')
                start = i
        out.append("</g>")
        for pose in rest_poses(motion):
            out.append(f'<polygon points="{_points(view.px(object_outline(world, pose)))}" fill="{_rgb("object_rest")}" '
                       'fill-opacity="0.35"/>')
        rows = motion.sample(FILMSTRIP_POSES, before_events=False)
        for k, row in enumerate(rows):
            opacity = 1.0 if row == rows[-1] else 0.14 + 0.6 * ((k + 1) / len(rows)) ** 1.5
            poses.append((motion.configurations[row], motion.object_poses[row], bool(held[row]) or row == rows[-1],
                          opacity))
        final_held = [bool(held[row]) for row in rows]
    else:
        poses.append((world.robot.initial, world.object.initial, False, 1.0))
        final_held = [False]
    out.append('<g id="poses">')
    for (q, pose, draw_object, opacity), is_held in zip(poses, final_held):
        out.append(f'<g opacity="{opacity:.2f}">')
        if draw_object and motion is not None:
            out.append(f'<polygon points="{_points(view.px(object_outline(world, pose)))}" '
                       f'fill="{_rgb("object_held" if is_held else "object_rest")}" fill-opacity="0.75" '
                       f'stroke="{_rgb("arm")}" stroke-width="1"/>')
        points = view.px(arm_points(world, q))
        link = max(2 * line, view.length(world.robot.link_width))
        out.append(f'<polyline points="{_points(points)}" fill="none" stroke="{_rgb("arm")}" stroke-width="{link:.1f}" '
                   'stroke-linecap="round" stroke-linejoin="round"/>')
        r = max(2.5, 1.2 * line)
        out.append(f'<rect x="{points[0][0] - 2.2 * r:.1f}" y="{points[0][1] - 2.2 * r:.1f}" width="{4.4 * r:.1f}" '
                   f'height="{4.4 * r:.1f}" fill="{_rgb("arm")}"/>')
        for x, y in points[1:-1]:
            out.append(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="{r:.1f}" fill="{_rgb("joint")}" stroke="{_rgb("arm")}"/>')
        x, y = points[-1]
        out.append(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="{1.9 * r:.1f}" fill="{_rgb("closed" if is_held else "open")}" '
                   f'stroke="{_rgb("arm")}"/>')
        out.append("</g>")
    out.append("</g>")
    font = max(10, size // 55)
    out.append(f'<line x1="0" y1="{view.height}" x2="{width}" y2="{view.height}" stroke="{_rgb("field_edge")}"/>')
    out.append(f'<text x="{view.margin}" y="{view.height + caption / 2 + font / 3:.1f}" font-size="{font}" '
               f'fill="{_rgb("text")}">{escape(_summary(scene))}</text>')
    out.append("</svg>")
    path = Path(path)
    path.write_text("\n".join(out) + "\n")
    return path
