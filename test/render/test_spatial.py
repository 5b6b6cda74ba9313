"""Pictures of spatial worlds: the 3-D renderer (clew_ros/render/spatial) and clew_render on a spatial world.

The world is test/data/spatial/panda_table.yaml (a Panda beside two tables, a box to move); its plan
panda_table.plan.json is made by hand from inverse kinematics solutions (drawn, not validated).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image, ImageSequence

pytest.importorskip("trimesh")
pytest.importorskip("urdf_parser_py")

from clew_ros.cli.render import main as clew_render
from clew_ros.render.errors import RenderError
from clew_ros.render.spatial import (
    SpatialStyle,
    View3D,
    draw_spatial_frames,
    draw_spatial_world,
    parse_view,
    write_spatial_gif,
)
from clew_ros.render.spatial.frames import frames_from_plan, load_spatial_world, read_frames
from clew_ros.render.spatial.meshes import box_mesh, cylinder_mesh, simplify, sphere_mesh
from clew_ros.render.spatial.zbuffer import Canvas, RasterSettings
from clew_ros.scene.palette import colour
from clew_ros.spatial.transforms import pose_matrix

DATA = Path(__file__).resolve().parents[1] / "data" / "spatial"
WORLD = DATA / "panda_table.yaml"
PLAN = DATA / "panda_table.plan.json"
#: Small pictures, no caption: what is asserted is where things are drawn, not how finely.
STYLE = SpatialStyle(caption=False)
VIEW = View3D(width=320, height=240)


@pytest.fixture(scope="module")
def world():
    return load_spatial_world(WORLD)


def obstacle_pixels(image: Image.Image) -> int:
    """Pixels of the grey obstacles and tables: grey, between the dark arm and the light ground."""
    rgb = np.asarray(image.convert("RGB")).astype(int)
    grey = (rgb.max(axis=2) - rgb.min(axis=2)) < 12
    return int((grey & (rgb.max(axis=2) > 95) & (rgb.max(axis=2) < 185)).sum())


def arm_mask(image: Image.Image) -> np.ndarray:
    """Pixels of the arm's links: the palette's near-black "arm", shaded (grey, darker than anything else)."""
    rgb = np.asarray(image.convert("RGB")).astype(int)
    grey = (rgb.max(axis=2) - rgb.min(axis=2)) < 20
    return grey & (rgb.max(axis=2) < 90)


def near(image: Image.Image, key: str) -> int:
    """How many pixels have the hue of palette colour ``key``: shading scales a colour and lifts it towards
    white, which keeps the direction of its deviation from grey (cosine > 0.95, at least 40 % as strong)."""
    rgb = np.asarray(image.convert("RGB")).astype(float)
    chroma = rgb - rgb.mean(axis=2, keepdims=True)
    target = np.asarray(colour(key).rgb, dtype=float)
    target -= target.mean()
    strength = np.linalg.norm(chroma, axis=2)
    cosine = (chroma @ target) / (np.maximum(strength, 1e-9) * np.linalg.norm(target))
    return int(((cosine > 0.95) & (strength > 0.4 * np.linalg.norm(target))).sum())


# ----------------------------------------------------------------------------------------- clew_render


def test_clew_render_draws_a_panda_world(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "world.png"
    assert clew_render([str(WORLD), "-o", str(out), "--size", "320"]) == 0
    assert "wrote" in capsys.readouterr().out
    image = Image.open(out)
    assert image.format == "PNG"
    assert image.width == 320
    assert image.height > 240
    pixels = np.asarray(image.convert("RGB")).reshape(-1, 3)
    assert len(np.unique(pixels, axis=0)) > 50  # shaded faces, not a blank or flat picture
    assert arm_mask(image).sum() > 1500  # the arm is there, large enough to read
    assert near(image, "start") > 20  # the box at its start, blue
    assert near(image, "open") > 20  # the gripper, open


def test_clew_render_view_changes_the_picture(tmp_path: Path) -> None:
    pictures = []
    for view in ("-50,28", "130,28", "-50,70"):
        out = tmp_path / f"{view}.png"
        assert clew_render([str(WORLD), "-o", str(out), "--size", "320", f"--view={view}"]) == 0
        pictures.append(np.asarray(Image.open(out).convert("RGB")).astype(int))
    for a in range(3):
        for b in range(a + 1, 3):
            changed = np.any(np.abs(pictures[a] - pictures[b]) > 30, axis=2).mean()
            assert changed > 0.1, (a, b, changed)


@pytest.mark.parametrize(
    ("view", "expected"),
    [
        ("10", "expected az,el[,dist]"),
        ("a,b", "expected az,el[,dist]"),
        ("0,10,2,3", "expected az,el[,dist]"),
        ("0,95", "elevation 95"),
        ("0,10,-1", "distance -1"),
        ("nan,10", "expected az,el[,dist]"),
    ],
)
def test_a_bad_view_is_refused_naming_it(
    view: str, expected: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "x.png"
    assert clew_render([str(WORLD), "-o", str(out), f"--view={view}"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("clew_render: --view:")
    assert expected in err
    assert len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_a_negative_azimuth_needs_no_equals_sign(tmp_path: Path) -> None:
    joined, spaced = tmp_path / "joined.png", tmp_path / "spaced.png"
    assert clew_render([str(WORLD), "-o", str(joined), "--size", "200", "--view=-120,30"]) == 0
    assert clew_render([str(WORLD), "-o", str(spaced), "--size", "200", "--view", "-120,30"]) == 0
    assert np.array_equal(np.asarray(Image.open(joined)), np.asarray(Image.open(spaced)))


def test_parse_view_keeps_the_size() -> None:
    view = parse_view("30,20,2.5", View3D(width=200, height=150))
    assert (view.azimuth_deg, view.elevation_deg, view.distance_m, view.width, view.height) == (30, 20, 2.5, 200, 150)
    assert parse_view("30,20").distance_m is None


def test_clew_render_refuses_what_it_cannot_draw(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    figure1 = Path(__file__).resolve().parents[2] / "config" / "figure1.yaml"
    assert clew_render([str(WORLD), "-o", str(tmp_path / "x.svg")]) == 2
    assert "--output: a spatial world is drawn as .png or .gif" in capsys.readouterr().err
    assert clew_render([str(figure1), "-o", str(tmp_path / "x.png"), "--view", "0,10"]) == 2
    assert "--view: only for spatial worlds" in capsys.readouterr().err
    assert clew_render([str(WORLD), "-o", str(tmp_path / "x.png"), "--frames", str(tmp_path / "none.json")]) == 2
    assert "--frames:" in capsys.readouterr().err
    other = json.loads(PLAN.read_text())
    other["world"] = "elsewhere"
    (tmp_path / "other.json").write_text(json.dumps(other))
    assert clew_render([str(tmp_path / "other.json"), "--world", str(WORLD), "-o", str(tmp_path / "x.png")]) == 2
    assert "world: the plan is for world 'elsewhere'" in capsys.readouterr().err
    other = json.loads(PLAN.read_text())
    other["segments"][1]["waypoints"][1] = [0.0, 1.0]
    (tmp_path / "short.json").write_text(json.dumps(other))
    assert clew_render([str(tmp_path / "short.json"), "--world", str(WORLD), "-o", str(tmp_path / "x.png")]) == 2
    assert "segments[1].waypoints: expected 7 numbers each" in capsys.readouterr().err
    broken = WORLD.read_text().replace("tip_link: panda_hand_tcp", "tip_link: no_such_link")
    (tmp_path / "broken.yaml").write_text(broken.replace("../../../config", str(WORLD.parents[3] / "config")))
    assert clew_render([str(tmp_path / "broken.yaml"), "-o", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert "world.robot.tip_link" in err
    assert "no_such_link" in err
    assert not (tmp_path / "x.png").exists()


def test_clew_render_gif_of_a_plan(tmp_path: Path, world) -> None:
    out = tmp_path / "plan.gif"
    assert clew_render([str(PLAN), "--world", str(WORLD), "-o", str(out), "--size", "240"]) == 0
    frames = read_frames(PLAN, world)
    gif = Image.open(out)
    assert gif.n_frames == len(frames.joints)
    assert frames.held.any()
    assert not frames.held.all()


def test_clew_render_png_of_frames(tmp_path: Path, world) -> None:
    q = np.linspace(world.initial, world.initial + np.array([1.0, 0.3, 0.0, 0.4, 0.0, 0.0, 0.0]), 4)
    path = tmp_path / "frames.json"
    path.write_text(json.dumps({"joints": q.tolist()}))
    out = tmp_path / "frames.png"
    assert clew_render([str(WORLD), "--frames", str(path), "-o", str(out), "--size", "240"]) == 0
    assert arm_mask(Image.open(out)).sum() > 200
    path.write_text(json.dumps({"joints": q[:, :6].tolist()}))
    assert clew_render([str(WORLD), "--frames", str(path), "-o", str(out)]) == 2


# ----------------------------------------------------------------------------------------- the pictures


def test_the_arm_moves_when_the_joints_change(world) -> None:
    """The arm reaching out turned about its first joint from -2.4 to +0.7 rad, from pointing to the left of
    the view (from the front right, azimuth -50 degrees) to its right: its pixels move to the right; the
    tables stay put."""
    fixed = View3D(width=320, height=240, distance_m=2.6, target=(0.3, 0.0, 0.35))
    reach = np.array([-2.4, 0.3, 0.0, -1.5, 0.0, 1.8, 0.785])
    before = draw_spatial_frames(world, reach, None, fixed, style=STYLE)
    turned = reach + np.array([3.1, 0, 0, 0, 0, 0, 0])
    after = draw_spatial_frames(world, turned, None, fixed, style=STYLE)
    a, b = arm_mask(before), arm_mask(after)
    assert a.sum() > 500
    assert b.sum() > 500
    assert (a ^ b).sum() > 0.3 * a.sum()
    assert np.nonzero(b)[1].mean() > np.nonzero(a)[1].mean() + 20
    table_before, table_after = obstacle_pixels(before), obstacle_pixels(after)
    assert table_before > 0
    assert abs(table_before - table_after) < 0.2 * table_before


def test_distance_and_azimuth_change_the_picture(world) -> None:
    close = draw_spatial_world(world, View3D(width=320, height=240, distance_m=2.0), style=STYLE)
    far = draw_spatial_world(world, View3D(width=320, height=240, distance_m=4.0), style=STYLE)
    assert arm_mask(close).sum() > 2.5 * arm_mask(far).sum()  # twice as far: about a quarter of the pixels
    behind = draw_spatial_world(world, View3D(azimuth_deg=130, width=320, height=240), style=STYLE)
    front = draw_spatial_world(world, View3D(width=320, height=240), style=STYLE)
    diff = np.abs(np.asarray(behind).astype(int) - np.asarray(front).astype(int))
    assert np.any(diff > 30, axis=2).mean() > 0.1


def test_default_view_frames_the_scene(world) -> None:
    """Everything shown lies inside the picture, and fills most of it along one side."""
    image = draw_spatial_world(world, VIEW, style=SpatialStyle(caption=False, shadows=False))
    rgb = np.asarray(image).astype(int)
    drawn = np.any(np.abs(rgb - colour("background").rgb) > 60, axis=2)  # not the background nor the grid
    rows, cols = np.nonzero(drawn)
    assert rows.min() > 0
    assert cols.min() > 0
    assert rows.max() < 239
    assert cols.max() < 319
    assert (rows.max() - rows.min()) > 0.75 * 240 or (cols.max() - cols.min()) > 0.75 * 320


def test_goal_placement_and_held_object_colours(world) -> None:
    picture = draw_spatial_world(world, VIEW, style=STYLE)
    assert near(picture, "start") > 20
    rgb = np.asarray(picture).astype(int)
    greenish = (rgb[:, :, 1] > rgb[:, :, 0] + 15) & (rgb[:, :, 1] > rgb[:, :, 2] + 5)
    assert greenish.sum() > 20  # the goal placement (and the open gripper) in green
    frames = read_frames(PLAN, world)
    carrying = int(np.flatnonzero(frames.held)[len(np.flatnonzero(frames.held)) // 2])
    held = draw_spatial_frames(
        world, frames.joints[carrying], frames.object_poses[carrying], VIEW, held=[True], style=STYLE
    )
    assert near(held, "object_held") > 20
    assert near(held, "closed") > 20


def test_a_motion_only_query_shows_its_goal_configuration(tmp_path: Path) -> None:
    """No object, a goal configuration: the arm at its start solid, at its goal ghosted (light grey where
    the start is not)."""
    import yaml

    tree = yaml.safe_load(WORLD.read_text())
    world_tree = tree["clew_planner"]["ros__parameters"]["world"]
    del world_tree["object"]
    world_tree["robot"]["goal"] = [1.2, 0.3, 0.0, -1.5, 0.0, 1.8, 0.785]
    for key in ("urdf", "srdf"):
        world_tree["robot"][key] = str((WORLD.parent / world_tree["robot"][key]).resolve())
    path = tmp_path / "motion_only.yaml"
    path.write_text(yaml.safe_dump(tree))
    motion_only = load_spatial_world(path)
    fixed = View3D(width=320, height=240, distance_m=2.6, target=(0.3, 0.0, 0.35))
    both = np.asarray(draw_spatial_world(motion_only, fixed, style=STYLE)).astype(int)
    start = np.asarray(draw_spatial_frames(motion_only, motion_only.initial, None, fixed, style=STYLE)).astype(int)
    ghost = np.any(np.abs(both - start) > 20, axis=2)
    assert ghost.sum() > 300
    assert (both[ghost].max(axis=1) - both[ghost].min(axis=1) < 25).mean() > 0.8  # grey: the faded arm
    with pytest.raises(RenderError, match=r"^object_poses: the world has no object"):
        draw_spatial_frames(motion_only, motion_only.initial, [0, 0, 0, 0, 0, 0])


def test_a_camera_pose_is_the_same_view_as_its_angles(world) -> None:
    """``eye`` and ``target`` (a camera pose) draw what azimuth, elevation and distance around that target do."""
    target = (0.3, 0.0, 0.35)
    angles = View3D(azimuth_deg=40.0, elevation_deg=20.0, distance_m=2.5, target=target, width=240, height=180)
    eye = tuple(float(v) for v in np.asarray(target) + 2.5 * angles.direction())
    posed = View3D(eye=eye, target=target, width=240, height=180)
    a = np.asarray(draw_spatial_world(world, angles, style=STYLE)).astype(int)
    b = np.asarray(draw_spatial_world(world, posed, style=STYLE)).astype(int)
    assert np.abs(a - b).max() <= 1
    with pytest.raises(RenderError, match=r"^view eye: expected a point away from the target"):
        draw_spatial_world(world, View3D(eye=target, target=target))


def test_link_meshes_are_simplified_once_and_cached(world) -> None:
    from clew_ros.render.spatial.meshes import MeshSettings, geometry_mesh, robot_mesh
    from clew_ros.spatial.robot import Geometry

    assert robot_mesh(world.robot) is robot_mesh(world.robot)
    coarse = MeshSettings(max_mesh_faces=80)
    assert robot_mesh(world.robot, coarse) is robot_mesh(world.robot, coarse)
    assert len(robot_mesh(world.robot, coarse).faces) < len(robot_mesh(world.robot).faces)
    vertices, faces = sphere_mesh(0.1, 4)
    big = Geometry("link", "mesh", (), pose_matrix([0.0, 0.0, 0.5, 0.0, 0.0, 0.0]), vertices, faces)
    small_v, small_f = geometry_mesh(big, MeshSettings(max_mesh_faces=500))
    assert len(small_f) <= 500
    assert small_v[:, 2].mean() == pytest.approx(0.5, abs=0.01)  # the geometry's origin applied


def test_a_still_shows_ghosts_along_the_frames(world) -> None:
    q = np.linspace(world.initial, world.initial + np.array([1.2, 0.4, 0.0, 0.5, 0.0, 0.0, 0.0]), 12)
    fixed = View3D(width=320, height=240, distance_m=2.6, target=(0.3, 0.0, 0.35))
    one = np.asarray(draw_spatial_frames(world, q[-1], None, fixed, style=STYLE)).astype(int)
    many = np.asarray(draw_spatial_frames(world, q, None, fixed, style=STYLE)).astype(int)
    changed = np.any(np.abs(one - many) > 12, axis=2)
    assert changed.sum() > 1000  # the faded earlier poses (and the path) drawn where the last pose is not
    assert (
        arm_mask(Image.fromarray(many.astype(np.uint8))) == arm_mask(Image.fromarray(one.astype(np.uint8)))
    ).mean() > 0.97


def test_gif_has_one_frame_per_configuration(tmp_path: Path, world) -> None:
    q = np.linspace(world.initial, world.initial + np.array([1.0, 0.3, 0.0, 0.4, 0.0, 0.0, 0.0]), 5)
    held = [False, False, True, True, False]
    style = SpatialStyle(frame_ms=60, event_ms=300, end_ms=900)
    out = write_spatial_gif(tmp_path / "f.gif", world, q, None, View3D(width=200, height=150), held=held, style=style)
    gif = Image.open(out)
    assert gif.n_frames == 5
    durations = [frame.info["duration"] for frame in ImageSequence.Iterator(gif)]
    assert durations == [60, 60, 300, 60, 900]  # the gripper closes at frame 2; the last frame lasts


def test_bad_frames_are_refused_naming_the_argument(world) -> None:
    with pytest.raises(RenderError, match=r"^joints: expected finite values of shape \(T, 7\)"):
        draw_spatial_frames(world, np.zeros((3, 6)))
    with pytest.raises(RenderError, match=r"^joints:"):
        draw_spatial_frames(world, [[np.nan] * 7])
    with pytest.raises(RenderError, match=r"^object_poses: .* got 2 poses for 3 frames"):
        draw_spatial_frames(world, np.zeros((3, 7)), np.zeros((2, 6)))
    with pytest.raises(RenderError, match=r"^held: expected one flag per frame"):
        draw_spatial_frames(world, np.zeros((3, 7)), held=[True])
    with pytest.raises(RenderError, match=r"^view elevation_deg"):
        View3D(elevation_deg=90.0)


# ----------------------------------------------------------------------------------------- plan replay


def test_a_plan_replayed_carries_the_object_to_its_goal(world) -> None:
    plan = json.loads(PLAN.read_text())
    frames = frames_from_plan(world, plan)
    assert np.allclose(frames.joints[0], world.initial)
    assert frames.object_poses is not None
    first_held = int(np.argmax(frames.held))
    # the first frame holding: the object still where it rests (the grasp's configuration holds it there)
    assert np.allclose(frames.object_poses[first_held], pose_matrix(world.object.initial), atol=1e-4)
    assert np.allclose(frames.object_poses[-1], pose_matrix(plan["final_object_pose"]), atol=1e-4)
    assert np.allclose(frames.object_poses[0], pose_matrix(world.object.initial))
    steps = np.abs(np.diff(frames.joints, axis=0)).max(axis=1)
    assert steps.max() <= 0.04 + 1e-9
    failed = {**plan, "success": False, "segments": [], "message": "nothing"}
    alone = frames_from_plan(world, failed)
    assert len(alone.joints) == 1
    assert "no plan: nothing" in alone.title


# ----------------------------------------------------------------------------------------- meshes, z-buffer


@pytest.mark.parametrize(
    ("mesh", "volume", "tolerance"),
    [
        (box_mesh([0.2, 0.3, 0.5]), 0.03, 1e-12),
        (cylinder_mesh(0.5, 0.1, 24), np.pi * 0.01 * 0.5, 0.012),
        (sphere_mesh(0.3, 2), 4 / 3 * np.pi * 0.027, 0.05),
    ],
)
def test_primitive_meshes_are_closed_and_wound_outward(mesh, volume: float, tolerance: float) -> None:
    """The signed volume (divergence theorem) is the solid's: closed, every face wound outward."""
    vertices, faces = mesh
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    signed = float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6)
    assert signed == pytest.approx(volume, rel=tolerance)


def test_simplify_keeps_the_shape_with_fewer_triangles() -> None:
    vertices, faces = sphere_mesh(0.2, 4)  # 5120 triangles
    small_v, small_f = simplify(vertices, faces, 600)
    assert 50 < len(small_f) <= 600
    assert np.allclose(small_v.min(axis=0), vertices.min(axis=0), atol=0.03)
    assert np.allclose(small_v.max(axis=0), vertices.max(axis=0), atol=0.03)
    assert simplify(vertices, faces, 10_000)[1] is faces


def test_zbuffer_nearest_wins_whatever_the_order() -> None:
    square = np.array([[[0, 0, 0], [40, 0, 0], [40, 40, 0]], [[0, 0, 0], [40, 40, 0], [0, 40, 0]]], dtype=float)
    near_, far_ = square.copy(), square.copy()
    near_[:, :, 2], far_[:, :, 2] = 1.0, 2.0
    red, blue = np.array([[255.0, 0, 0]] * 2), np.array([[0, 0, 255.0]] * 2)
    for order in ((near_, red, far_, blue), (far_, blue, near_, red)):
        canvas = Canvas.blank(40, 40, (255, 255, 255), RasterSettings())
        canvas.draw(order[0], order[1])
        canvas.draw(order[2], order[3])
        assert np.all(canvas.colour == [255, 0, 0])  # every pixel covered once by the square, red in front
        assert np.allclose(canvas.inverse_depth, 1.0)


def test_zbuffer_covers_a_triangles_area_and_blends_in_front_only() -> None:
    triangle = np.array([[[10, 10, 1.0], [90, 10, 1.0], [10, 70, 1.0]]])
    canvas = Canvas.blank(100, 100, (255, 255, 255), RasterSettings())
    canvas.draw(triangle, np.array([[0.0, 0.0, 0.0]]))
    covered = int((canvas.colour[:, :, 0] == 0).sum())
    assert abs(covered - 0.5 * 80 * 60) < 80 + 60 + 100  # the area, give or take the edges' pixels
    behind = np.array([[[0, 0, 3.0], [100, 0, 3.0], [0, 100, 3.0]]])
    before = canvas.colour.copy()
    canvas.blend(behind, np.array([[0.0, 255.0, 0.0]]), 0.5)
    inside = before[:, :, 0] == 0
    assert np.all(canvas.colour[inside] == before[inside])  # hidden behind the black triangle
    outside = (~inside) & (np.arange(100)[:, None] + np.arange(100)[None, :] < 95)
    assert np.allclose(canvas.colour[outside], [127.5, 255.0, 127.5])  # half green over white
