"""``python -m benchmarks.check_cost [--worlds NAME|PATH ...] [--batch N]``: what a configuration checked in a
batched call of the compiled checks costs, against what the improvement's budget charges for it (issue 14).

The improvement (:mod:`clew_ros.planar.improve`) counts its budget in work units, not seconds, so that the same
seed gives the same plan on any machine: :attr:`~clew_ros.planar.improve.ImproveSettings.work_per_second` units per
second of ``planner.improve_time``. A configuration checked costs
:attr:`~clew_ros.planar.improve.ImproveSettings.batch_check_share` x :func:`~clew_ros.planar.improve.check_work` units.
This
times :func:`clew_ros.planar.continuous.straight_moves_clear` on ``N`` random configurations of each world
(``still``: each checked where it is, as the lattice checks its nodes; ``moves``: a straight move of 0.3 rad
per joint from each, checked continuously, as shortcuts and routings are), the best of five calls, and prints
the time per configuration and its ratio to the time the budget charges for it (``charged``: the charge at
:attr:`~clew_ros.planar.improve.ImproveSettings.batch_check_share` 1, ``now``: at its value). A ratio below 1: the
budget buys fewer checks than the time it stands for would; the improvement's whole wall time against its work is the
last column of :mod:`benchmarks.improvement`.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from benchmarks.improvement import load_worlds
from clew_ros.planar.continuous import straight_moves_clear
from clew_ros.planar.improve import ImproveSettings, check_work
from clew_ros.planar.kernel import warm_up

WORLDS = ("figure1", "single_transfer", "obstacles_8", "obstacles_32", "joints_7")
REPEATS = 5
MOVE_RAD = 0.3


class _Counter:
    """The budget :func:`straight_moves_clear` charges: the configurations it checked."""

    def __init__(self) -> None:
        self.configurations = 0

    def spend_move_checks(self, configurations: int) -> None:
        self.configurations += configurations

    def stop(self) -> bool:
        return False


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n", maxsplit=1)[0])
    parser.add_argument("--worlds", nargs="+", default=list(WORLDS), help="benchmark world names or YAML files")
    parser.add_argument("--batch", type=int, default=8000, help="configurations a call (default 8000)")
    args = parser.parse_args(argv)
    warm_up()
    unit_us = 1e6 / ImproveSettings().work_per_second
    print(f"one work unit stands for {unit_us:.2f} us; batch_check_share {ImproveSettings().batch_check_share}")
    print("| world | check_work | kind | configurations | us a configuration | ratio, charged 1 / now |")
    print("|---|--:|---|--:|--:|---|")
    for world, _parameters in load_worlds(args.worlds):
        rng = np.random.default_rng(0)
        lower, upper = np.asarray(world.robot.joint_lower), np.asarray(world.robot.joint_upper)
        starts = lower + (upper - lower) * rng.random((args.batch, world.robot.dof))
        moved = np.clip(starts + rng.choice([-MOVE_RAD, MOVE_RAD], starts.shape), lower, upper)
        pose = np.asarray(world.object.initial, dtype=float)
        work = check_work(world)
        for kind, ends in (("still", starts), ("moves", np.ascontiguousarray(moved))):
            best, counter = float("inf"), _Counter()
            for _ in range(REPEATS):
                counter = _Counter()
                began = time.perf_counter()
                straight_moves_clear(
                    world, starts, ends, object_pose=pose, grasp_rel=None, min_margin=0.01, budget=counter
                )
                best = min(best, time.perf_counter() - began)
            per_us = best * 1e6 / counter.configurations
            charged_us = work * unit_us
            print(
                f"| {world.name} | {work:.2f} | {kind} | {counter.configurations} | {per_us:.3f} "
                f"| {per_us / charged_us:.2f} / {per_us / (ImproveSettings().batch_check_share * charged_us):.2f} |",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
