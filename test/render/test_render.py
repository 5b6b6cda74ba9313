"""clew_render: PNG, GIF and SVG from a plan, a world alone and a recording (its landmark tree from its events)."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from helpers.rec_plan import WORLD_PATH, quick_plan, quick_world
from PIL import Image, ImageSequence

from clew_ros.cli.render import main as clew_render
from clew_ros.render import draw_still, scene_from_recording
from clew_ros.render.shapes import COLORS
from clew_ros.render.view import View

SIZE = 480


@pytest.fixture(scope="module")
def plan_file(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("render") / "plan.json"
    path.write_text(json.dumps(quick_plan()))
    return path


def _record(directory: Path, triples) -> Path:
    from clew_ros.recording import RunRecorder

    recorder = RunRecorder(directory, "f" * 32)
    for topic, msg, time_ns in triples:
        recorder.write(topic, msg, time_ns)
    return recorder.close()


@pytest.fixture(scope="module")
def recording(tmp_path_factory) -> Path:
    """A successful run whose ``landmark`` events carry the landmarks as the node sends them."""
    pytest.importorskip("rclpy")
    from helpers import rec_messages
    from helpers.rec_landmark_events import with_landmark_events

    triples = rec_messages.sample_run(quick_world(), WORLD_PATH.read_text(), quick_plan())
    return _record(tmp_path_factory.mktemp("records"), with_landmark_events(triples, quick_plan()["landmarks"]))


def colours(image: Image.Image) -> np.ndarray:
    return np.asarray(image.convert("RGB")).reshape(-1, 3)


def near(pixels: np.ndarray, rgb: tuple[int, int, int], tolerance: int = 24) -> int:
    """How many pixels are within ``tolerance`` of ``rgb`` on every channel."""
    return int(np.all(np.abs(pixels.astype(int) - rgb) <= tolerance, axis=1).sum())


def test_png_of_a_plan(plan_file: Path, tmp_path: Path, capsys) -> None:
    out = tmp_path / "plan.png"
    assert clew_render([str(plan_file), "--world", str(WORLD_PATH), "-o", str(out), "--size", str(SIZE)]) == 0
    assert f"wrote {out}" in capsys.readouterr().out
    image = Image.open(out)
    assert image.format == "PNG"
    assert image.width == SIZE
    assert image.height > SIZE
    pixels = colours(image)
    assert len(np.unique(pixels, axis=0)) > 50  # fading poses, paths, legend: many colours
    not_background = np.any(pixels != COLORS["background"], axis=1).mean()
    assert not_background > 0.5  # the field fills most of the map
    for key in ("start", "goal", "transfer", "closed", "arm", "tree_node"):
        assert near(pixels, COLORS[key]) > 10, f"no {key} pixels"


def test_gif_animates_the_plan(plan_file: Path, tmp_path: Path) -> None:
    out = tmp_path / "plan.gif"
    assert clew_render([str(plan_file), "--world", str(WORLD_PATH), "-o", str(out), "--size", "320"]) == 0
    gif = Image.open(out)
    frames = [frame.convert("RGB") for frame in ImageSequence.Iterator(gif)]
    durations = [frame.info.get("duration") for frame in ImageSequence.Iterator(Image.open(out))]
    assert len(frames) > 10
    assert max(durations) > 3 * min(durations)  # held frames at the grasp and at the end
    map_height = View.fit(quick_world(), 320).height  # above the caption and its legend
    first, last = (colours(frame.crop((0, 0, frame.width, map_height))) for frame in (frames[0], frames[-1]))
    assert near(first, COLORS["open"]) > 5  # transit: open gripper
    assert near(first, COLORS["closed"], 12) == 0
    holding_at_end = quick_plan()["segments"][-1]["kind"] == "transfer"
    assert near(last, COLORS["closed" if holding_at_end else "open"]) > 5
    assert not np.array_equal(first, last)


def test_svg_is_xml(plan_file: Path, tmp_path: Path) -> None:
    out = tmp_path / "plan.svg"
    assert clew_render([str(plan_file), "--world", str(WORLD_PATH), "-o", str(out), "--size", str(SIZE)]) == 0
    root = ET.parse(out).getroot()
    assert root.tag == "{http://www.w3.org/2000/svg}svg"
    assert root.get("width") == str(SIZE)
    ids = {element.get("id") for element in root.iter()}
    assert {"bounds", "goal", "start", "grasps", "landmarks", "tip-path", "poses"} <= ids
    poses = next(e for e in root.iter() if e.get("id") == "poses")
    assert len(list(poses)) > 5


def test_world_alone(tmp_path: Path) -> None:
    out = tmp_path / "world.png"
    assert clew_render([str(WORLD_PATH), "-o", str(out), "--size", "200"]) == 0
    assert Image.open(out).width == 200


def test_recording(recording: Path, tmp_path: Path) -> None:
    scene = scene_from_recording(recording)
    plan = quick_plan()
    assert [(s.kind, s.grasp) for s in scene.plan.segments] == [(s["kind"], s["grasp"]) for s in plan["segments"]]
    assert "succeeded" in scene.title
    landmarks = plan["landmarks"]  # the events announce all but the root, which comes from the world
    np.testing.assert_allclose(scene.landmarks.nodes, [lm["object_pose"][:2] for lm in landmarks])
    assert len(scene.landmarks.edges) == sum(lm["parent"] is not None for lm in landmarks)
    assert scene.landmarks.root == next(i for i, lm in enumerate(landmarks) if lm["parent"] is None)
    for suffix in ("png", "svg", "gif"):
        out = tmp_path / f"run.{suffix}"
        assert clew_render([str(recording), "-o", str(out), "--size", "240"]) == 0
        assert out.stat().st_size > 1000


@pytest.mark.parametrize("events", ["bare", "none"])
def test_recording_without_landmark_events(tmp_path: Path, events: str) -> None:
    """Landmark events without the landmark (``bare``) or none at all: no tree, though ``~/landmarks`` markers are
    recorded (they are not decoded), and the rest is drawn."""
    pytest.importorskip("rclpy")
    from helpers import rec_messages
    from helpers.rec_landmark_events import without_landmark_events

    triples = rec_messages.sample_run(quick_world(), WORLD_PATH.read_text(), quick_plan())
    assert any(topic.endswith("/landmarks") for topic, _msg, _t in triples)
    recording = _record(tmp_path, triples if events == "bare" else without_landmark_events(triples))
    scene = scene_from_recording(recording)
    assert scene.landmarks is None
    assert scene.plan is not None
    drawing = draw_still(scene, 240)
    assert not any(shape.layer == "landmarks" for shape in drawing.shapes)
    assert "landmark tree" not in {getattr(shape, "text", None) for shape in drawing.shapes}
    out = tmp_path / "run.png"
    assert clew_render([str(recording), "-o", str(out), "--size", "240"]) == 0
    pixels = colours(Image.open(out).crop((0, 0, 240, View.fit(quick_world(), 240).height)))
    assert near(pixels, COLORS["tree_node"], 10) == 0


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["{plan}", "-o", "{tmp}/x.png"], "pass its world with --world"),
        (["{plan}", "--world", "{world}", "-o", "{tmp}/x.jpg"], "expected a file ending in .png, .gif, .svg"),
        (["{tmp}/nothing", "-o", "{tmp}/x.png"], "does not exist"),
        (["{world}", "--world", "{world}", "-o", "{tmp}/x.png"], "either as INPUT or with --world"),
        (["{tmp}", "-o", "{tmp}/x.png"], "expected a recording directory"),
    ],
)
def test_invalid_input(plan_file: Path, tmp_path: Path, capsys, args: list[str], message: str) -> None:
    argv = [a.format(plan=plan_file, world=WORLD_PATH, tmp=tmp_path) for a in args]
    assert clew_render(argv) == 2
    assert message in capsys.readouterr().err
