"""``python -m benchmarks.spatial_render [--world W.yaml] [--size 800] [--frames 30] [--repeats 3]``: how fast
the 3-D renderer draws a spatial world (issue 43).

Printed, in one core's CPU seconds (the best of ``--repeats``, after a first drawing that builds the
cached link meshes): the world alone (the arm at its start, the goal ghosted), a still of ``--frames``
frames (six poses, five of them ghosted, and the path), and a GIF frame (the arm and the object over the
static part drawn once), at ``--size`` pixels wide (3:4), and the triangles drawn a pose. Default world:
test/data/spatial/panda_table.yaml (a Panda's collision meshes, two tables, a post, a box).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from clew_ros.render.spatial import View3D, draw_spatial_frames, draw_spatial_world, spatial_gif_frames
from clew_ros.render.spatial.frames import load_spatial_world
from clew_ros.render.spatial.meshes import robot_mesh

WORLD = Path(__file__).resolve().parents[1] / "test" / "data" / "spatial" / "panda_table.yaml"


def _best(run: Callable[[], object], repeats: int) -> float:
    run()  # the link meshes built and cached
    times = []
    for _ in range(repeats):
        start = time.process_time()
        run()
        times.append(time.process_time() - start)
    return min(times)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.spatial_render", description=__doc__.split("\n\n")[0])
    parser.add_argument("--world", type=Path, default=WORLD, help="a spatial world parameter file")
    parser.add_argument("--size", type=int, default=800, help="picture width in pixels (height 3/4 of it)")
    parser.add_argument("--frames", type=int, default=30, help="frames of the still and of the GIF")
    parser.add_argument("--repeats", type=int, default=3, help="timed repeats (the best is printed)")
    args = parser.parse_args(argv)
    world = load_spatial_world(args.world)
    view = View3D(width=args.size, height=round(args.size * 0.75))
    rng = np.random.default_rng(0)
    end = np.clip(world.initial + rng.uniform(-0.6, 0.6, world.robot.dof), world.robot.lower, world.robot.upper)
    joints = np.linspace(world.initial, end, max(2, args.frames))
    triangles = len(robot_mesh(world.robot).faces)
    alone = _best(lambda: draw_spatial_world(world, view), args.repeats)
    still = _best(lambda: draw_spatial_frames(world, joints, None, view), args.repeats)
    gif = _best(lambda: spatial_gif_frames(world, joints, None, view), args.repeats) / len(joints)
    print(f"spatial render: {world.name}, {args.size}x{view.height} px, robot {triangles} triangles a pose")
    print(f"  world alone (start, goal ghosted)      {alone:7.3f} s CPU")
    print(f"  still of {len(joints)} frames (6 poses, path)  {still:7.3f} s CPU")
    print(f"  GIF, per frame                          {gif:7.3f} s CPU ({1 / gif:.1f} frames/s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
