"""Collision-test throughput: batched ``is_valid`` against a per-configuration loop, and free intervals.

``python -m benchmarks.throughput WORLD [--configs N]`` prints one JSON object:

* ``batched``: :func:`clew_ros.planar.collision.is_valid` on chunks of random
  configurations (shapely 2 ufuncs on arrays), configurations per second;
* ``batch1``: the same function called once per configuration;
* ``valid_transfer``: ``is_valid`` on the valid configurations among them
  with the object held at grasp 0 (what validating a plan and the
  improvement's checks mostly see: every test passes, none ends early);
* ``loop``: :class:`PerStateChecker`, a plain Python loop with the same
  semantics (link LineStrings built per configuration, tested against the
  prepared union of the obstacles, the object shrunk by the grasp tolerance,
  the bounds and the non-adjacent links); ``agree`` counts configurations on
  which both answer the same (all of them, or the benchmark is wrong);
* ``intervals``: :func:`clew_ros.planar.manhattan.free_intervals`, the test the
  planner actually uses: intervals per second for batches of 24 (the GA
  population) and 1024 valid configurations, transit (object at rest) and
  transfer (object held at grasp 0).

Every kernel is called once before it is timed: numba loads it from its
on-disk cache at its first call, tens of milliseconds that the cold-start
benchmark reports and that are not a throughput. All figures are for one
process on one core (the libraries do not thread; the worker sets
``OMP_NUM_THREADS=1``), timed in process CPU time (``time.process_time``),
so that other load on the machine does not lower them.
"""

from __future__ import annotations

import argparse
import functools
import json
import math
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import shapely
import shapely.affinity

from benchmarks.worlds import all_worlds, select
from clew_ros.planar.collision import check_start_and_goal, is_valid
from clew_ros.planar.kinematics import compose, tip_poses, transform_points
from clew_ros.planar.manhattan import free_intervals, run_manhattan
from clew_ros.planar.world import World, world_from_parameters

__all__ = ["PerStateChecker", "measure", "random_configurations"]


class PerStateChecker:
    """Section 1's validity test for one configuration at a time, with prepared shapely geometry.

    The object rests at ``object_pose`` (transit), so its placement is tested
    and its shrunk outline prepared once. Same semantics as
    :func:`clew_ros.planar.collision.is_valid`: touching counts as collision,
    bounds are closed, links may touch the object but not enter it shrunk by
    ``grasp_tolerance``, non-adjacent links must not meet.
    """

    def __init__(self, world: World, object_pose: np.ndarray) -> None:
        self.world = world
        self.base = tuple(float(v) for v in world.robot.base)
        self.lengths = [float(v) for v in world.robot.link_lengths]
        self.low = [float(v) + world.robot.link_width / 2 for v in world.bounds[:2]]
        self.high = [float(v) - world.robot.link_width / 2 for v in world.bounds[2:]]
        self.radius = world.robot.link_width / 2
        obstacles = [shapely.Polygon(o.vertices) for o in world.obstacles]
        self.obstacles = shapely.union_all(obstacles) if obstacles else None
        if self.obstacles is not None:
            shapely.prepare(self.obstacles)
        # the object rests: its placement and shrunk outline are computed and prepared once
        pose = np.asarray(object_pose, dtype=float)
        vertices = transform_points(pose, world.object.polygon)
        self.object_ok = bool(np.all(vertices >= world.bounds[:2]) and np.all(vertices <= world.bounds[2:]))
        if self.obstacles is not None and self.obstacles.intersects(shapely.Polygon(vertices)):
            self.object_ok = False
        shrunk = shapely.Polygon(world.object.polygon).buffer(-world.grasp_tolerance, join_style="mitre")
        self.shrunk = shapely.affinity.affine_transform(
            shrunk, [math.cos(pose[2]), -math.sin(pose[2]), math.sin(pose[2]), math.cos(pose[2]), pose[0], pose[1]]
        )
        shapely.prepare(self.shrunk)
        n = world.robot.dof
        self.pairs = [(a, b) for a in range(n) for b in range(a + 2, n)] if world.robot.self_collision else []

    def __call__(self, q) -> bool:
        if not self.object_ok:
            return False
        x, y = self.base
        phi = 0.0
        points = [(x, y)]
        for angle, length in zip(q, self.lengths, strict=True):
            phi += angle
            x += length * math.cos(phi)
            y += length * math.sin(phi)
            if not (self.low[0] <= x <= self.high[0] and self.low[1] <= y <= self.high[1]):
                return False
            points.append((x, y))
        lines = [shapely.LineString(points[i : i + 2]) for i in range(len(self.lengths))]
        r = self.radius
        for line in lines:
            if self.obstacles is not None and (
                self.obstacles.dwithin(line, r) if r > 0 else self.obstacles.intersects(line)
            ):
                return False
            if self.shrunk.intersects(line):
                return False
        for a, b in self.pairs:
            if lines[a].dwithin(lines[b], 2 * r) if r > 0 else lines[a].intersects(lines[b]):
                return False
        return True


def random_configurations(world: World, count: int, rng: np.random.Generator) -> np.ndarray:
    """Uniform configurations ``(count, n)`` within the joint limits."""
    return rng.uniform(world.robot.joint_lower, world.robot.joint_upper, size=(count, world.robot.dof))


def _rate(count: int, seconds: float) -> float:
    return count / seconds if seconds > 0 else float("nan")


def _fastest(work: Callable[[], int], repeats: int) -> dict:
    """``work()`` (returning how many intervals it computed) timed ``repeats`` times in CPU time; the
    fastest repeat, as ``timeit`` advises: the slower ones measure the machine, not the code."""
    runs = []
    for _ in range(max(1, repeats)):
        started = time.process_time()
        total = work()
        runs.append((time.process_time() - started, total))
    seconds, total = min(runs, key=lambda run: run[0] / max(run[1], 1))
    return {
        "intervals": total,
        "seconds": seconds,
        "per_s": _rate(total, seconds),
        "repeats": len(runs),
        "per_s_all": [_rate(t, s) for s, t in runs],
    }


def _interval_figures(
    world: World,
    modes: list[tuple[str, np.ndarray, dict[str, Any]]],
    rng: np.random.Generator,
    interval_budget: int,
    repeats: int,
) -> dict:
    """Free intervals per second, per mode: one joint of batches of 24 and 1024, and a population of 24
    decoding its Manhattan paths."""
    figures = {}
    dof = world.robot.dof

    def free(sample: np.ndarray, batch: int, kwargs: dict[str, Any]) -> int:
        total, budget = 0, max(4 * batch, interval_budget // dof)
        for start in range(0, max(len(sample), 1), batch):
            rows = sample[start : start + batch]
            if not len(rows) or total >= budget:
                break
            for joint in range(dof):
                free_intervals(world, rows, joint, **kwargs)
                total += len(rows)
        return total

    def decoded(sample: np.ndarray, genes: np.ndarray, kwargs: dict[str, Any]) -> int:
        total = 0
        for start in range(0, max(len(sample), 1), 24):
            rows = sample[start : start + 24]
            if len(rows) < 24 or total >= 10 * interval_budget:
                break
            run_manhattan(world, rows, genes, threads=1, **kwargs)  # one core, as every figure here
            total += genes.size
        return total

    for mode, sample, kwargs in modes:
        for batch in (24, 1024):
            figures[f"{mode}_b{batch}"] = _fastest(functools.partial(free, sample, batch, kwargs), repeats)
        # as the planner computes them: a population of 24 decodes its Manhattan paths (order 2) in one call
        genes = rng.normal(0.0, 1.2, (24, 2, dof))
        figures[f"{mode}_decode24"] = _fastest(functools.partial(decoded, sample, genes, kwargs), repeats)
    return figures


def measure(
    world: World,
    configs: int,
    seed: int = 0,
    *,
    chunk: int = 10_000,
    interval_budget: int = 50_000,
    repeats: int = 3,
) -> dict:
    """The throughput figures of the module docstring for ``world``."""
    rng = np.random.default_rng(seed)
    q = random_configurations(world, configs, rng)
    pose = world.object.initial
    is_valid(world, q[:100], pose[None])  # warm-up: the scene is prepared once per world

    started = time.process_time()
    batched = np.concatenate([is_valid(world, q[i : i + chunk], pose[None]) for i in range(0, configs, chunk)])
    batched_s = time.process_time() - started

    single_count = min(configs, 2_000)
    started = time.process_time()
    for row in q[:single_count]:
        is_valid(world, row[None], pose[None])
    single_s = time.process_time() - started

    checker = PerStateChecker(world, pose)
    started = time.process_time()
    looped = np.fromiter((checker(row) for row in q.tolist()), dtype=bool, count=configs)
    loop_s = time.process_time() - started

    valid_q = q[batched]
    grasp_rel = np.array([-world.object.grasps[0][0], -world.object.grasps[0][1], 0.0])
    carried = compose(tip_poses(world.robot, q), grasp_rel)
    transfer_q = q[is_valid(world, q, carried)]
    modes: list[tuple[str, np.ndarray, dict[str, Any]]] = [
        ("transit", valid_q, {"object_poses": pose[None]}),
        ("transfer", transfer_q, {"grasp_rel": grasp_rel[None]}),
    ]
    held = compose(tip_poses(world.robot, transfer_q), grasp_rel)
    for _mode, sample, kwargs in modes:  # warm-up: the interval and decoding kernels load from numba's cache
        free_intervals(world, sample[:24], 0, **kwargs)
        run_manhattan(world, sample[:24], np.zeros((len(sample[:24]), 1, world.robot.dof)), threads=1, **kwargs)
    started = time.process_time()
    for i in range(0, len(transfer_q), chunk):
        is_valid(world, transfer_q[i : i + chunk], held[i : i + chunk])
    held_s = time.process_time() - started
    intervals = _interval_figures(world, modes, rng, interval_budget, repeats)
    return {
        "world": world.name,
        "configs": configs,
        "valid_fraction": float(batched.mean()),
        "batched": {"chunk": chunk, "seconds": batched_s, "per_s": _rate(configs, batched_s)},
        "batch1": {"count": single_count, "seconds": single_s, "per_s": _rate(single_count, single_s)},
        "loop": {"seconds": loop_s, "per_s": _rate(configs, loop_s)},
        "valid_transfer": {"count": len(transfer_q), "seconds": held_s, "per_s": _rate(len(transfer_q), held_s)},
        "agree": int(np.sum(batched == looped)),
        "ratio_batched_over_loop": loop_s / batched_s if batched_s > 0 else float("nan"),
        "ratio_batched_over_batch1": (single_s / single_count) / (batched_s / configs) if batched_s > 0 else None,
        "intervals": intervals,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.throughput", description=__doc__.split("\n\n")[0])
    parser.add_argument("world")
    parser.add_argument("--configs", type=int, default=100_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--interval-budget", type=int, default=50_000, help="free intervals per (mode, batch size) measurement, about"
    )
    parser.add_argument("--repeats", type=int, default=3, help="each free-interval figure is the fastest of these")
    args = parser.parse_args(argv)
    matches = select(all_worlds(), args.world)
    if len(matches) != 1:
        raise SystemExit(f"throughput: expected one world named {args.world!r}, found {len(matches)}")
    world = check_start_and_goal(world_from_parameters(matches[0].parameters))
    figures = measure(world, args.configs, args.seed, interval_budget=args.interval_budget, repeats=args.repeats)
    json.dump(figures, sys.stdout)
    print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
