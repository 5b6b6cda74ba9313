"""clew_render's default 3-D camera: from the side from which the robot and its goal are seen."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

pytest.importorskip("trimesh")

from clew_ros.render.spatial import View3D
from clew_ros.render.spatial.frames import load_spatial_world
from clew_ros.render.spatial.open_side import OpenSideSettings, _boxes, _hidden, _places, open_side_view

CONFIG = Path(__file__).resolve().parents[2] / "config" / "spatial"


def _hidden_from(world, view: View3D) -> int:  # type: ignore[no-untyped-def]
    return _hidden(_places(world, OpenSideSettings().lift_m), view.direction(), _boxes(world))


def test_a_world_with_nothing_in_the_way_keeps_the_default_view() -> None:
    world = load_spatial_world(CONFIG / "panda_table_to_table.yaml")
    assert _hidden_from(world, View3D()) == 0
    assert open_side_view(world, View3D()) == View3D()


def test_a_shelf_whose_side_hides_the_goal_is_seen_from_its_open_side() -> None:
    world = load_spatial_world(CONFIG / "panda_table_to_shelf.yaml")
    default = View3D()
    assert _hidden_from(world, default) > 0  # the shelf's wall hides the object or its goal from -50 deg
    chosen = open_side_view(world, default)
    assert chosen.azimuth_deg != default.azimuth_deg
    assert _hidden_from(world, chosen) == 0
    assert dataclasses.replace(chosen, azimuth_deg=default.azimuth_deg) == default  # only the azimuth turns


def test_a_camera_pose_given_is_kept() -> None:
    world = load_spatial_world(CONFIG / "panda_table_to_shelf.yaml")
    fixed = View3D(eye=(2.0, 0.0, 1.0))
    assert open_side_view(world, fixed) is fixed
