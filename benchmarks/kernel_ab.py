"""The compiled kernel at a git revision against this one, interleaved in one process.

``python -m benchmarks compare --baseline REV collision_throughput [--worlds figure1,obstacles_32] [--configs N]``
prints one line per world and mode, then one JSON object.

On this machine the same loop runs up to 1.9x faster or slower from one
process to the next, so throughput measured in separate processes cannot
tell a 15 % change from noise. Here both kernels run in one process, taking
turns: ``REV:clew_ros/planar/kernel/`` is loaded as a package of its own
(the kernel imports only numpy and numba), the configurations are the same,
and each figure is the fastest of ``--repeats`` turns in CPU time. For each
world and mode (transit: object at rest; transfer: held at grasp 0):

* ``b24``: free intervals per second, one joint of 24 configurations per
  call (``kernel.intervals``), every joint in turn;
* ``decode24``: intervals per second as a population of 24 decodes its
  Manhattan paths of order 2 in one call (``kernel.decode``, one thread);
* ``valid24``: configurations per second through the validity test's first
  pass, 24 a call (``kernel.clearly_valid``);
* ``moves24``: straight moves per second, 24 a call, each from a configuration
  0.3 rad per joint towards zero, checked continuously (``kernel.moves_clear``, the
  improvement's margins);
* ``same``: whether both kernels gave the same numbers, bit for bit.
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import importlib.util
import json
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

import numpy as np

from benchmarks.throughput import random_configurations
from benchmarks.worlds import all_worlds, select
from clew_ros.planar import kernel
from clew_ros.planar.collision import check_start_and_goal, is_valid, packed_world
from clew_ros.planar.kinematics import compose, tip_poses
from clew_ros.planar.world import World, world_from_parameters

__all__ = ["baseline_kernel", "compare"]

ROOT = Path(__file__).resolve().parents[1]
#: ``moves24``: each move goes this far (rad) on every joint.
MOVE_RAD = 0.3


def baseline_kernel(revision: str, directory: Path) -> ModuleType:
    """``revision``'s kernel, loaded as module ``kernel_baseline`` from ``directory``: the package
    ``clew_ros/planar/kernel/`` (its imports of itself renamed), or the single ``kernel.py`` of older revisions."""
    listed = _git("ls-tree", "--name-only", revision, "clew_ros/planar/kernel/").split()
    files = [name for name in listed if name.endswith(".py")]
    if files:  # a package: its modules import each other by the package's name
        package = directory / "kernel_baseline"
        package.mkdir(exist_ok=True)
        for name in files:
            source = _git("show", f"{revision}:{name}").replace("clew_ros.planar.kernel", "kernel_baseline")
            (package / Path(name).name).write_text(source)
        path, search = package / "__init__.py", [str(package)]
    else:
        path, search = directory / "kernel_baseline.py", None
        path.write_text(_git("show", f"{revision}:clew_ros/planar/kernel.py"))
    spec = importlib.util.spec_from_file_location("kernel_baseline", path, submodule_search_locations=search)
    if spec is None or spec.loader is None:
        raise SystemExit(f"kernel_ab: cannot load {path}")
    module = importlib.util.module_from_spec(spec)
    sys.modules["kernel_baseline"] = module  # numba's cache locates a function by its module
    spec.loader.exec_module(module)
    return module


def _git(*arguments: str) -> str:
    """The output of ``git arguments`` in this repository."""
    return subprocess.run(["git", *arguments], cwd=ROOT, capture_output=True, text=True, check=True).stdout


def _timed(work: Callable[[], object], count: int, rates: list[float]) -> None:
    """Append ``count`` per CPU second of ``work()`` to ``rates``."""
    started = time.process_time()
    work()
    seconds = time.process_time() - started
    rates.append(count / seconds if seconds > 0 else float("nan"))


@dataclasses.dataclass(frozen=True)
class _Case:
    """One world and mode: the batches of 24 valid configurations, the object's pose, the genes."""

    n: int
    batches: list[np.ndarray]
    transfer: bool
    poses: np.ndarray  # (1, 3)
    genes: np.ndarray  # (24, 2, n)
    held_poses: list[np.ndarray]  # (24, 3) per batch: where the grasp holds the object (transfer)
    ends: list[np.ndarray]  # (24, n) per batch: each configuration MOVE_RAD per joint towards zero

    def intervals(self, module: ModuleType, packed: object) -> list[tuple[np.ndarray, np.ndarray]]:
        return [
            module.intervals(packed, b, j, self.transfer, self.poses, 1e-3) for b in self.batches for j in range(self.n)
        ]

    @property
    def decoded_batches(self) -> list[np.ndarray]:
        return self.batches[: max(1, len(self.batches) // 4)]

    def valid(self, module: ModuleType, packed: object) -> list[np.ndarray]:
        pose = self.poses[0]
        if self.transfer:  # the object where the grasp holds it: valid as the batches are
            return [module.clearly_valid(packed, b, self.held_poses[i]) for i, b in enumerate(self.batches)]
        return [module.clearly_valid(packed, b, pose) for b in self.batches]

    def moves(self, module: ModuleType, packed: object) -> list[tuple[np.ndarray, int]]:
        mode = (
            {"resting": None, "grasp_rel": self.poses[0]}
            if self.transfer
            else {"resting": self.poses[0], "grasp_rel": None}
        )
        return [
            module.moves_clear(packed, b, e, **mode, min_margin=5e-4, max_margin=0.05, coarse_stride=4)
            for b, e in zip(self.batches, self.ends, strict=True)
        ]

    def decoded(self, module: ModuleType, packed: object) -> list[np.ndarray]:
        out = []
        for b in self.decoded_batches:
            waypoints = np.empty((24, 2 * self.n + 1, self.n))
            waypoints[:, 0] = b
            poses = np.repeat(self.poses, 24, axis=0)
            module.decode(packed, waypoints, self.genes, 1, 2 * self.n + 1, self.transfer, poses, 1e-3, 1)
            out.append(waypoints)
        return out


def _same(case: _Case, base: ModuleType, theirs: object, ours: object) -> bool:
    """Both kernels give the same numbers, bit for bit (this also loads both, untimed)."""
    pairs = zip(case.intervals(base, theirs), case.intervals(kernel, ours), strict=True)
    if not all(np.array_equal(x[0], y[0]) and np.array_equal(x[1], y[1]) for x, y in pairs):
        return False
    if not all(np.array_equal(x, y) for x, y in zip(case.valid(base, theirs), case.valid(kernel, ours), strict=True)):
        return False
    moves = zip(case.moves(base, theirs), case.moves(kernel, ours), strict=True)
    if not all(np.array_equal(x[0], y[0]) and x[1] == y[1] for x, y in moves):
        return False
    return all(
        np.array_equal(x, y) for x, y in zip(case.decoded(base, theirs), case.decoded(kernel, ours), strict=True)
    )


def compare(world: World, base: ModuleType, configs: int, repeats: int, seed: int = 0) -> list[dict]:
    """The figures of the module docstring for ``world``: transit and transfer, baseline and this code."""
    rng = np.random.default_rng(seed)
    n = world.robot.dof
    q = random_configurations(world, configs, rng)
    pose = np.asarray(world.object.initial, dtype=float)
    grasp = world.object.grasps[0]
    grasp_rel = np.array([-grasp[0], -grasp[1], 0.0])
    ours = packed_world(world)
    theirs = base.PackedWorld(**{f.name: getattr(ours, f.name) for f in dataclasses.fields(base.PackedWorld)})
    genes = rng.normal(0.0, 1.2, (24, 2, n))
    rows = []
    for mode, transfer, poses in (("transit", False, pose[None]), ("transfer", True, grasp_rel[None])):
        placed = compose(tip_poses(world.robot, q), grasp_rel[None]) if transfer else poses
        sample = q[is_valid(world, q, placed)]
        batches = [np.ascontiguousarray(sample[i : i + 24]) for i in range(0, len(sample) - 23, 24)]
        held = [np.ascontiguousarray(compose(tip_poses(world.robot, b), grasp_rel[None])) for b in batches]
        ends = [np.ascontiguousarray(b - np.sign(b) * MOVE_RAD) for b in batches]
        case = _Case(n, batches, transfer, poses, genes, held, ends)
        same = _same(case, base, theirs, ours)
        counts = {
            "b24": len(batches) * 24 * n,
            "decode24": len(case.decoded_batches) * 24 * 2 * n,
            "valid24": len(batches) * 24,
            "moves24": len(batches) * 24,
        }
        works = {"b24": case.intervals, "decode24": case.decoded, "valid24": case.valid, "moves24": case.moves}
        rates: dict[str, dict[str, list[float]]] = {k: {"before": [], "after": []} for k in counts}
        for _turn in range(repeats):
            for label, module, packed in (("before", base, theirs), ("after", kernel, ours)):
                for name, work in works.items():
                    _timed(functools.partial(work, module, packed), counts[name], rates[name][label])
        row: dict = {"world": world.name, "mode": mode, "configurations": len(batches) * 24, "same": same}
        for name, runs in rates.items():
            before, after = max(runs["before"]), max(runs["after"])
            row[name] = {"before": before, "after": after, "after_over_before": after / before}
        rows.append(row)
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks compare --baseline REV collision_throughput", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("--baseline", required=True, help="git revision whose kernel is compared with this one")
    parser.add_argument("--worlds", default="figure1,obstacles_32,joints_10", help="comma-separated benchmark worlds")
    parser.add_argument("--configs", type=int, default=8000, help="random configurations drawn per world")
    parser.add_argument("--repeats", type=int, default=7, help="timed turns per kernel (the fastest counts)")
    args = parser.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory(prefix="kernel_ab_") as directory:
        base = baseline_kernel(args.baseline, Path(directory))
        for name in args.worlds.split(","):
            matches = select(all_worlds(), name)
            if len(matches) != 1:
                raise SystemExit(f"kernel_ab: expected one world named {name!r}, found {len(matches)}")
            world = check_start_and_goal(world_from_parameters(matches[0].parameters))
            for row in compare(world, base, args.configs, args.repeats):
                rows.append(row)
                print(
                    f"{row['world']:14s} {row['mode']:8s} same={row['same']!s:5s} "
                    + "  ".join(
                        f"{k} {row[k]['before']:,.0f} -> {row[k]['after']:,.0f} /s (x{row[k]['after_over_before']:.2f})"
                        for k in ("b24", "decode24", "valid24", "moves24")
                    ),
                    file=sys.stderr,
                )
    print(json.dumps({"baseline": args.baseline, "rows": rows}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
