"""One drawing: a scene is drawn once into shapes (render/draw.py); the PNG/GIF and SVG back ends paint those shapes.

These tests fail if a back end draws anything of its own (its own arms, path or
fade), if the two back ends stop receiving the same shapes, or if the landmark
tree stops coming from the recorded ``landmark`` events.
"""

from __future__ import annotations

import ast
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from helpers.rec_plan import quick_plan, quick_world
from PIL import Image

from clew_ros.core.plan import Plan
from clew_ros.render import (
    LandmarkGraph,
    draw_animation,
    draw_still,
    landmarks_from_events,
    scene_from_plan,
    scene_from_world,
)
from clew_ros.render.draw import END_MS, EVENT_MS, FILMSTRIP_POSES, FRAME_MS, GIF_FRAMES, fade
from clew_ros.render.raster import rasterize, render_png
from clew_ros.render.shapes import Circle, Paint, Polygon, Polyline, Rect, Text
from clew_ros.render.svg import render_svg, svg_text

SIZE = 400
RENDER = Path(__file__).resolve().parents[2] / "clew_ros" / "render"
SVG = "{http://www.w3.org/2000/svg}"
TAGS = {Polygon: "polygon", Polyline: "polyline", Rect: "rect", Circle: "circle", Text: "text"}


@pytest.fixture(scope="module")
def scene():
    return scene_from_plan(quick_world(), Plan.from_dict(quick_plan()))


@pytest.fixture(scope="module")
def still(scene):
    return draw_still(scene, SIZE)


def arms(shapes) -> list[Polyline]:
    """The arm's links: one rounded line per pose drawn."""
    return [s for s in shapes if isinstance(s, Polyline) and s.layer == "poses"]


def grippers(shapes) -> list[Circle]:
    return [s for s in shapes if isinstance(s, Circle) and s.layer == "poses" and s.fill.key in ("open", "closed")]


def test_fade_rises_to_opaque() -> None:
    alphas = [fade(k, 9) for k in range(9)]
    assert alphas == sorted(alphas)
    assert len(set(alphas)) == 9
    assert alphas[0] < 80
    assert alphas[-2] < 255
    assert alphas[-1] == 255


def test_still_overlays_fading_poses_along_the_plan(scene, still) -> None:
    motion = scene.motion()
    rows = motion.sample(FILMSTRIP_POSES, before_events=False)
    drawn = arms(still.shapes)
    assert len(drawn) == len(rows) > FILMSTRIP_POSES // 2
    assert [arm.stroke.alpha for arm in drawn] == [fade(k, len(rows)) for k in range(len(rows))]
    assert [g.fill.key for g in grippers(still.shapes)] == ["closed" if motion.held[r] >= 0 else "open" for r in rows]
    path = [s for s in still.shapes if s.layer == "tip-path"]
    assert {s.stroke.key for s in path} == {"transit", "transfer"}
    nodes = [s for s in still.shapes if isinstance(s, Circle) and s.layer == "landmarks"]
    assert len(nodes) == len(quick_plan()["landmarks"])
    legend = {s.text for s in still.shapes if isinstance(s, Text) and s.layer == "caption"}
    assert {"landmark tree", "transit", "transfer", "holding"} <= legend


def test_world_alone_is_the_arm_at_its_start() -> None:
    world = quick_world()
    drawing = draw_still(scene_from_world(world), SIZE)
    (arm,) = arms(drawing.shapes)
    assert arm.stroke.alpha == 255
    assert [g.fill.key for g in grippers(drawing.shapes)] == ["open"]
    assert not any(s.layer in ("tip-path", "landmarks", "rest-poses") for s in drawing.shapes)
    legend = {s.text for s in drawing.shapes if isinstance(s, Text) and s.layer == "caption"}
    assert "start" in legend
    assert not {"landmark tree", "transit", "transfer", "holding"} & legend


def test_png_is_the_drawing_painted(scene, still, tmp_path: Path) -> None:
    out = render_png(scene, tmp_path / "still.png", SIZE)
    assert np.array_equal(np.asarray(Image.open(out).convert("RGB")), np.asarray(rasterize(still)))


def test_svg_has_one_element_per_shape_of_the_same_drawing(scene, still, tmp_path: Path) -> None:
    out = render_svg(scene, tmp_path / "still.svg", SIZE)
    text = out.read_text()
    assert text == svg_text(still)
    root = ET.fromstring(text)
    assert (root.get("width"), root.get("height")) == (str(still.width), str(still.height))
    elements = [e for e in root.iter() if e.tag not in (SVG + "svg", SVG + "g", SVG + "title")][1:]  # 0: background
    assert [e.tag.removeprefix(SVG) for e in elements] == [TAGS[type(s)] for s in still.shapes]
    poses = next(g for g in root.iter(SVG + "g") if g.get("id") == "poses")
    links = poses.findall(SVG + "polyline")
    assert len(links) == len(arms(still.shapes))
    opacities = [float(e.get("stroke-opacity", 1.0)) for e in links]
    assert opacities == pytest.approx([arm.stroke.alpha / 255 for arm in arms(still.shapes)], abs=1e-3)


def test_animation_moves_one_arm_and_holds_at_grasps(scene) -> None:
    motion = scene.motion()
    animation = draw_animation(scene, 320)
    rows = motion.sample(GIF_FRAMES)
    assert len(animation.frames) == len(rows)
    assert all(len(arms(frame.shapes)) == 1 for frame in animation.frames)
    durations = [frame.duration_ms for frame in animation.frames]
    assert durations[-1] == END_MS
    assert durations.count(EVENT_MS) == len(motion.events)
    assert set(durations[:-1]) <= {FRAME_MS, EVENT_MS}
    assert {s.stroke.alpha for s in animation.base.shapes if s.layer == "tip-path"} == {90}
    assert not arms(animation.base.shapes)
    held = [g.fill.key for frame in animation.frames for g in grippers(frame.shapes)]
    assert held == ["closed" if motion.held[r] >= 0 else "open" for r in rows]


def test_paint_and_text_refuse_what_no_back_end_knows() -> None:
    with pytest.raises(ValueError, match="'teal' is not a colour"):
        Paint("teal")
    with pytest.raises(ValueError, match="alpha"):
        Paint("arm", 300)
    with pytest.raises(ValueError, match="anchor"):
        Text((0, 0), "x", Paint("text"), 10, "ls")


def _imports(path: Path) -> list[tuple[str, list[str]]]:
    """``(module, names)`` of every ``from module import names`` of a source file."""
    tree = ast.parse(path.read_text())
    return [
        (node.module or "", [alias.name for alias in node.names])
        for node in ast.walk(tree)
        if isinstance(node, ast.ImportFrom)
    ]


@pytest.mark.parametrize("back_end", ["raster.py", "svg.py"])
def test_back_ends_hold_no_scene_logic(back_end: str) -> None:
    """A back end takes shapes from draw.py; it reaches neither the core (arms, paths) nor the world geometry."""
    modules = {module for module, _names in _imports(RENDER / back_end) if module.startswith("clew_ros")}
    assert modules <= {
        "clew_ros.render.draw",
        "clew_ros.render.scene",
        "clew_ros.render.shapes",
        "clew_ros.render.text",
    }
    drawn = {
        name for module, names in _imports(RENDER / back_end) if module == "clew_ros.render.draw" for name in names
    }
    assert drawn <= {"draw_still", "draw_animation"}
    scene = {
        name for module, names in _imports(RENDER / back_end) if module == "clew_ros.render.scene" for name in names
    }
    assert scene <= {"Scene"}


def test_no_private_names_cross_modules() -> None:
    paths = [*RENDER.glob("*.py"), RENDER.parent / "cli" / "render.py"]
    crossing = [
        (path.name, module, name)
        for path in paths
        for module, names in _imports(path)
        for name in names
        if module.startswith("clew_ros") and name.startswith("_")
    ]
    assert crossing == []


@pytest.mark.parametrize("root", ["announced", "from the world"])
def test_landmark_tree_from_events(root: str) -> None:
    """The tree of the events is the plan's; the node does not announce the root: then it comes from the world."""
    plan, world = quick_plan(), quick_world()
    events = [
        {"run_id": "f" * 32, "event": "landmark", "time": 1.0 + i, **landmark}
        for i, landmark in enumerate(plan["landmarks"])
        if root == "announced" or landmark["parent"] is not None
    ]
    noise = [{"event": "accepted"}, {"event": "landmark", "landmark": 0}, {"event": "landmark", "id": 99}]
    landmarks = landmarks_from_events(noise + events, world)
    assert [lm.id for lm in landmarks] == [lm["id"] for lm in plan["landmarks"]]
    assert landmarks[0].object_pose.tolist() == list(world.object.initial)
    from_events = LandmarkGraph.from_landmarks(landmarks)
    from_plan = scene_from_plan(world, Plan.from_dict(plan)).landmarks
    np.testing.assert_array_equal(from_events.nodes, from_plan.nodes)
    np.testing.assert_array_equal(from_events.edges, from_plan.edges)
    assert from_events.root == from_plan.root
    moved = {**events[-1], "object_pose": [9.0, 9.0, 0.0]}  # a later event for the same id replaces it
    assert landmarks_from_events([*events, moved], world)[-1].object_pose.tolist() == [9.0, 9.0, 0.0]
    assert landmarks_from_events(noise, world) == ()
