"""``python -m benchmarks.spatial_checker [--robots panda ur5] [--batch 1024] [--seconds S] [--agreement-seconds S]``:
the spatial checker's speed and its agreement with an exact reference (issue 43).

For each shipped robot (config/robots) in a 30-box scene (a table just under the base and 29 boxes seeded
around the arm): the sphere model (spheres, build time, over-approximation mean and max); validity checks
per CPU second on a batch of ``--batch`` random configurations (``all``: as drawn, most stop at their first
contact; ``valid``: only valid ones, every test run to the end); free intervals per CPU second (every
joint of valid configurations); inverse kinematics of reachable tcp poses (solved, distinct solutions,
time); and, when pinocchio and coal are installed (the ``spatial-ref`` extra), the exact reference
(pinocchio + coal on the URDF's own geometry, meshes as triangle BVHs): its CPU time per configuration,
and its agreement over as many random configurations as ``--agreement-seconds`` allows. A configuration
the checker calls valid that the reference finds colliding is a violation: there must be none.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.inverse import IKSettings, InverseKinematics
from clew_ros.spatial.robot import LinkModel, RobotModel, robot_from_parameters
from clew_ros.spatial.scene import Obstacle, make_obstacle
from clew_ros.spatial.spheres import SphereModel, over_approximation, sphere_model
from clew_ros.spatial.tier import coal_shape
from clew_ros.spatial.transforms import pose_matrix

CONFIG = Path(__file__).resolve().parents[1] / "config"
ROBOTS: dict[str, dict[str, Any]] = {
    "panda": {
        "urdf": "robots/panda/panda.urdf",
        "srdf": "robots/panda/panda.srdf",
        "base_link": "panda_link0",
        "tip_link": "panda_hand_tcp",
    },
    "ur5": {
        "urdf": "robots/ur5/ur5.urdf",
        "srdf": "robots/ur5/ur5.srdf",
        "base_link": "base_link",
        "tip_link": "tool0",
    },
}


def scene(robot: RobotModel, spheres: SphereModel, seed: int = 0, boxes: int = 30) -> list[Obstacle]:
    """A table 5 mm under the lowest sphere of the base, and ``boxes - 1`` boxes (4-20 cm) seeded around the
    arm (0.3-0.9 m from the base's axis, 0-1 m up), none touching the base."""
    static = spheres.frames == 0
    table_top = float(np.min(spheres.centers[static, 2] - spheres.radii[static])) - 0.005 if static.any() else 0.0
    out = [make_obstacle("table", "box", [1.6, 1.6, 0.04], pose_matrix([0, 0, table_top - 0.02, 0, 0, 0]), "table")]
    rng = np.random.default_rng(seed)
    while len(out) < boxes:
        radius, angle = rng.uniform(0.3, 0.9), rng.uniform(-math.pi, math.pi)
        pose = [radius * math.cos(angle), radius * math.sin(angle), table_top + rng.uniform(0.0, 1.0)]
        size = rng.uniform(0.04, 0.2, 3)
        out.append(make_obstacle(f"box{len(out)}", "box", size, pose_matrix([*pose, 0, 0, rng.uniform(-3, 3)]), "box"))
    return out


def cpu_rate(call: Any, count: int, seconds: float) -> float:
    """Items per CPU second of ``call()`` (which handles ``count`` items), repeated for about ``seconds``."""
    call()  # compiled already; this one warms caches
    start, calls = time.process_time(), 0
    while time.process_time() - start < seconds or calls < 3:
        call()
        calls += 1
    return count * calls / (time.process_time() - start)


class Reference:
    """The exact check: pinocchio's forward kinematics and coal's collision tests on the URDF's geometry
    (the same pairs: every moving link against every obstacle, the self pairs the checker tests)."""

    def __init__(self, robot: RobotModel, urdf: Path, obstacles: list[Obstacle], pairs: np.ndarray) -> None:
        # imported by name: the spatial-ref extra is optional, and its packages carry no type information
        self.pin = importlib.import_module("pinocchio")
        self.coal = importlib.import_module("coal")
        self.model = self.pin.buildModelFromUrdf(str(urdf))
        self.data = self.model.createData()
        self.geometry = self.pin.GeometryModel()
        owned = [self._add_link(link) for link in robot.links]
        static = [
            self.geometry.addGeometryObject(
                self.pin.GeometryObject(o.name, 0, self.pin.SE3(o.pose), _coal_shape(self.coal, o))
            )
            for o in obstacles
        ]
        moving = [i for i, link in enumerate(robot.links) if link.frame != 0]
        checked = [(g, o) for i in moving for g in owned[i] for o in static]
        checked += [(g, h) for a, b in pairs for g in owned[a] for h in owned[b]]
        for first, second in checked:
            self.geometry.addCollisionPair(self.pin.CollisionPair(first, second))
        self.geometry_data = self.pin.GeometryData(self.geometry)
        self.neutral = self.pin.neutral(self.model)
        for name, value in robot.fixed_positions.items():
            if self.model.existJointName(name):
                self.neutral[self.model.joints[self.model.getJointId(name)].idx_q] = value
        self.index = [self.model.joints[self.model.getJointId(name)].idx_q for name in robot.joint_names]

    def _add_link(self, link: LinkModel) -> list[int]:
        """The link's collision geometries added on its pinocchio frame; their indices."""
        frame = self.model.frames[self.model.getFrameId(link.name)]
        out = []
        for k, geometry in enumerate(link.geometries):
            placement = frame.placement * self.pin.SE3(geometry.origin)
            shape = _coal_shape(self.coal, geometry)
            obj = self.pin.GeometryObject(f"{link.name}_{k}", frame.parentJoint, placement, shape)
            out.append(self.geometry.addGeometryObject(obj))
        return out

    def collides(self, q: np.ndarray) -> bool:
        full = self.neutral.copy()
        full[self.index] = q
        return bool(self.pin.computeCollisions(self.model, self.data, self.geometry, self.geometry_data, full, True))


def _coal_shape(coal: Any, item: Any) -> Any:
    """A coal shape of a URDF geometry or an obstacle (:func:`clew_ros.spatial.tier.coal_shape`)."""
    kind = getattr(item, "kind", None) or item.shape
    return coal_shape(coal, kind, item.size, item if kind == "mesh" else None)


def inverse_kinematics(robot: RobotModel, rng: np.random.Generator, count: int) -> None:
    """A table row: the inverse kinematics of ``count`` reachable tcp poses (those of random configurations)."""
    poses = rng.uniform(robot.lower, robot.upper, size=(count, robot.dof))
    solver = InverseKinematics(robot)
    solver.solve(robot.tcp_pose(poses[0]), rng)  # compiled or loaded
    start_cpu = time.process_time()
    counts = [len(solver.solve(robot.tcp_pose(q), rng)) for q in poses]
    ik_ms = (time.process_time() - start_cpu) / len(poses) * 1e3
    solved = np.mean(np.array(counts) > 0)
    print(
        f"| inverse kinematics of reachable tcp poses ({IKSettings().seeds} seeds): solved / distinct solutions / "
        f"CPU ms a pose | {solved:.2f} / {np.mean(counts):.1f} / {ik_ms:.2f} |"
    )


def run_robot(name: str, args: argparse.Namespace) -> None:
    tree = ROBOTS[name]
    robot = robot_from_parameters(tree, CONFIG)
    start = time.perf_counter()
    spheres = sphere_model(robot)
    build_s = time.perf_counter() - start
    rng = np.random.default_rng(1)
    over = np.concatenate(
        [
            over_approximation(
                [(g, link.offset @ g.origin) for g in link.geometries],
                spheres.centers[spheres.starts[i] : spheres.starts[i + 1]],
                spheres.radii[spheres.starts[i] : spheres.starts[i + 1]],
                rng,
            )
            for i, link in enumerate(robot.links)
        ]
    )
    print(
        f"\n## {name}: {robot.dof} joints, {len(robot.links)} links, {spheres.count} spheres (built in {build_s:.2f} s)"
    )
    print(f"sphere model over the URDF's geometry: mean {over.mean() * 1e3:.1f} mm, max {over.max() * 1e3:.1f} mm")
    obstacles = scene(robot, spheres)
    checker = SpatialChecker(robot, spheres, obstacles)
    assert not checker.static_collision
    qs = rng.uniform(robot.lower, robot.upper, size=(args.batch, robot.dof))
    start = time.perf_counter()
    valid = checker.valid(qs)
    print(
        f"scene: {len(obstacles)} boxes; first call (compiling or loading the kernel) "
        f"{time.perf_counter() - start:.2f} s"
    )
    pool = rng.uniform(robot.lower, robot.upper, size=(20 * args.batch, robot.dof))
    good = pool[checker.valid(pool)]
    valid_batch = good[np.arange(args.batch) % len(good)]
    rate_all = cpu_rate(lambda: checker.valid(qs), len(qs), args.seconds)
    rate_valid = cpu_rate(lambda: checker.valid(valid_batch), len(valid_batch), args.seconds)
    intervals = good[: args.intervals]
    checker.free_intervals(intervals[:2], 0)
    start_cpu = time.process_time()
    widths = []
    for joint in range(robot.dof):
        lo, hi, _ok = checker.free_intervals(intervals, joint)
        widths.append(hi - lo)
    interval_rate = robot.dof * len(intervals) / (time.process_time() - start_cpu)
    print("| measure | value |")
    print("|---|--:|")
    print(f"| valid fraction of {len(qs)} random configurations | {valid.mean():.3f} |")
    print(f"| validity checks per CPU second, batch of {len(qs)} as drawn | {rate_all:,.0f} |")
    print(f"| validity checks per CPU second, batch of {len(qs)} valid ones | {rate_valid:,.0f} |")
    print(
        f"| free intervals per CPU second ({len(intervals)} valid configurations x {robot.dof} joints) | "
        f"{interval_rate:,.0f} |"
    )
    print(f"| mean free interval width (rad) | {np.mean(widths):.3f} |")
    inverse_kinematics(robot, rng, args.ik_poses)
    if importlib.util.find_spec("pinocchio") is None or importlib.util.find_spec("coal") is None:
        print("| exact reference (pinocchio + coal) | not installed (pip install 'clew_ros[spatial-ref]') |")
        return
    reference = Reference(robot, CONFIG / tree["urdf"], obstacles, checker.pairs)
    start_cpu = time.process_time()
    for q in qs:
        reference.collides(q)
    per_config = (time.process_time() - start_cpu) / len(qs)
    print(f"| exact reference CPU time per configuration, same batch (us) | {per_config * 1e6:.1f} |")
    print(
        f"| checker speed-up over the reference (as drawn / valid only) | "
        f"{rate_all * per_config:.0f}x / {rate_valid * per_config:.0f}x |"
    )
    agreement(checker, reference, robot, args.agreement_seconds, args.agreement_max)


def agreement(checker: SpatialChecker, reference: Reference, robot: RobotModel, seconds: float, most: int) -> None:
    rng = np.random.default_rng(2)
    counts = {"configurations": 0, "checker valid": 0, "reference free": 0, "violations": 0}
    deadline = time.perf_counter() + seconds
    while time.perf_counter() < deadline and counts["configurations"] < most:
        qs = rng.uniform(robot.lower, robot.upper, size=(1000, robot.dof))
        valid = checker.valid(qs)
        free = np.array([not reference.collides(q) for q in qs])
        counts["configurations"] += len(qs)
        counts["checker valid"] += int(valid.sum())
        counts["reference free"] += int(free.sum())
        counts["violations"] += int((valid & ~free).sum())
    print(
        f"| agreement: configurations / checker valid / reference free / valid but colliding | "
        f"{counts['configurations']:,} / {counts['checker valid']:,} / {counts['reference free']:,} / "
        f"{counts['violations']} |"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n", maxsplit=1)[0])
    parser.add_argument("--robots", nargs="+", default=list(ROBOTS), choices=list(ROBOTS))
    parser.add_argument("--batch", type=int, default=1024, help="configurations a validity call (default 1024)")
    parser.add_argument("--seconds", type=float, default=2.0, help="CPU seconds each speed is timed for (default 2)")
    parser.add_argument("--intervals", type=int, default=256, help="valid configurations whose intervals are timed")
    parser.add_argument("--ik-poses", type=int, default=50, help="reachable tcp poses solved by the inverse kinematics")
    parser.add_argument("--agreement-seconds", type=float, default=60.0, help="time for the agreement count (s)")
    parser.add_argument("--agreement-max", type=int, default=100_000, help="at most this many configurations")
    args = parser.parse_args(argv)
    for name in args.robots:
        run_robot(name, args)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
