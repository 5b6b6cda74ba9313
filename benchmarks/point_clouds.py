"""``python -m benchmarks.point_clouds [--points 300000] [--repeats 7]``: how fast the node turns a point
cloud into occupied cubes (interface.md section 3c, ``~/points``; issue 54).

On the shipped Panda between its two tables, two clouds of ``--points`` float32 points, each sent as a
``sensor_msgs/PointCloud2`` of 16-byte points: ``scene`` (what a depth camera over the tables sees: the two
table tops (on the tables: dropped), a 0.2 m box on the floor, the arm's own links (a quarter of the points:
the self-filter drops them) and 1 % noise) and ``uniform`` (points drawn uniformly over the workspace: every
voxel test at its worst). For each, the median and the fastest of ``--repeats`` runs of the two steps the
node takes: reading the message (``clew_ros.ros.state_messages.cloud_xyz``) and voxelising with the
self-filter (``clew_ros.spatial.voxels.occupied_cubes``: arm spheres grown by 0.02 m, the tables, cubes of
0.02 m), the points kept and the cubes. The first run compiles (or loads from numba's cache) and is left
out. Prints one JSON object.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
WORLD = ROOT / "config" / "spatial" / "panda_table_to_table.yaml"
VOXEL_M = 0.02
GROW_M = 0.02


def _scene(world: Any, count: int, rng: np.random.Generator) -> np.ndarray:
    """A depth camera's view over the tables: table tops, a box on the floor, the arm, noise."""
    box_n, arm_n, noise_n = count // 5, count // 4, count // 100
    table_n = (count - box_n - arm_n - noise_n) // len(world.supports)
    parts = []
    for support in world.supports:
        local = rng.uniform(-1.0, 1.0, size=(table_n, 2)) * np.asarray(support.half)
        parts.append(np.column_stack([local + np.asarray(support.center), np.full(table_n, support.top)]))
    face = rng.integers(0, 5, size=box_n)  # the box's four sides and its top
    box = rng.uniform(-0.1, 0.1, size=(box_n, 3))
    box[np.arange(box_n), np.where(face < 3, face, face - 3)] = np.where(face < 3, 0.1, -0.1)
    parts.append(box + np.array([-0.4, 0.4, 0.1]))
    spheres = world.checker.sphere_positions(world.initial.tolist())
    pick = rng.integers(0, len(spheres), size=arm_n)
    direction = rng.normal(size=(arm_n, 3))
    direction /= np.linalg.norm(direction, axis=1)[:, None]
    parts.append(spheres[pick] + direction * (world.spheres.radii[pick] * 0.9)[:, None])
    rest = count - sum(len(p) for p in parts)
    parts.append(rng.uniform(world.bounds[:3], world.bounds[3:], size=(rest, 3)))
    return np.concatenate(parts).astype(np.float32)


def _message(points: np.ndarray) -> Any:
    from sensor_msgs.msg import PointCloud2, PointField

    padded = np.zeros((len(points), 4), dtype=np.float32)
    padded[:, :3] = points
    fields = [PointField(name=n, offset=4 * k, datatype=PointField.FLOAT32, count=1) for k, n in enumerate("xyz")]
    return PointCloud2(
        height=1, width=len(points), fields=fields, is_bigendian=False, point_step=16, row_step=16 * len(points),
        data=padded.tobytes(), is_dense=True,
    )  # fmt: skip


def _measure(world: Any, points: np.ndarray, repeats: int) -> dict[str, Any]:
    from clew_ros.ros.state_messages import cloud_xyz
    from clew_ros.spatial.voxels import occupied_cubes

    msg = _message(points)
    spheres = world.checker.sphere_positions(world.initial.tolist())
    read_s, voxel_s = [], []
    cubes = np.zeros((0, 3))
    for k in range(repeats + 1):
        started = time.perf_counter()
        xyz = cloud_xyz(msg, 10**8)
        read = time.perf_counter() - started
        started = time.perf_counter()
        cubes = occupied_cubes(
            xyz, voxel_m=VOXEL_M, grow_m=GROW_M, sphere_centers=spheres, sphere_radii=world.spheres.radii,
            solids=world.obstacles, bounds=world.bounds,
        )  # fmt: skip
        voxel = time.perf_counter() - started
        if k:  # the first run compiles or loads the kernels
            read_s.append(read)
            voxel_s.append(voxel)
    return {
        "points": len(points),
        "cubes": len(cubes),
        "read_ms": {"median": 1000 * statistics.median(read_s), "min": 1000 * min(read_s)},
        "voxelise_ms": {"median": 1000 * statistics.median(voxel_s), "min": 1000 * min(voxel_s)},
        "total_ms_median": 1000 * statistics.median(r + v for r, v in zip(read_s, voxel_s, strict=True)),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.point_clouds", description=__doc__.split("\n\n")[0])
    parser.add_argument("--points", type=int, default=300_000, help="points a cloud (default 300000)")
    parser.add_argument("--repeats", type=int, default=7, help="timed runs a cloud (default 7)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    from clew_ros.ros.spatial import load_spatial, resolved_parameters

    parameters = resolved_parameters(WORLD)
    world, _ = load_spatial({"world": parameters["world"]}, WORLD.parent)
    rng = np.random.default_rng(args.seed)
    bounds = world.bounds
    assert bounds is not None  # the shipped world has bounds
    clouds = {
        "scene": _scene(world, args.points, rng),
        "uniform": rng.uniform(bounds[:3], bounds[3:], size=(args.points, 3)).astype(np.float32),
    }
    report = {name: _measure(world, points, args.repeats) for name, points in clouds.items()}
    json.dump(report, sys.stdout, indent=1)
    sys.stdout.write("\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
