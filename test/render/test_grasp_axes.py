"""A spatial world's picture draws each grasp's approach (blue) and finger axis (orange) at the object's start."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("trimesh")

from clew_ros.render.spatial import SpatialStyle, View3D, draw_spatial_world
from clew_ros.render.spatial.frames import load_spatial_world
from clew_ros.scene.palette import colour

WORLD = Path(__file__).resolve().parents[2] / "config" / "spatial" / "panda_table_to_table.yaml"


def _near(picture, name: str) -> int:  # type: ignore[no-untyped-def]
    pixels = np.asarray(picture.convert("RGB"), dtype=float)
    return int((np.abs(pixels - np.asarray(colour(name).rgb, dtype=float)).sum(axis=2) < 40).sum())


def test_the_grasps_axes_are_drawn_and_can_be_left_out() -> None:
    world = load_spatial_world(WORLD)
    view = View3D(azimuth_deg=-30.0, elevation_deg=35.0, distance_m=1.2, width=320, height=240)
    drawn = draw_spatial_world(world, view)
    plain = draw_spatial_world(world, view, style=SpatialStyle(grasp_axis_m=0.0))
    assert _near(drawn, "transfer") > _near(plain, "transfer") + 20  # the orange finger axes
    assert _near(drawn, "transit") > _near(plain, "transit")  # the blue approaches
