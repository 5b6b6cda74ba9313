"""The one entry of the benchmarks: ``python -m benchmarks COMMAND [ARGS]``; ``python -m benchmarks`` lists them.

Each command runs one module's ``main(ARGS)`` (``python -m benchmarks COMMAND --help`` for its options);
``python -m benchmarks compare --baseline REV COMMAND [ARGS]`` runs any of them on revision REV and on this
checkout and prints the ratios (:mod:`benchmarks.compare`): the one way to compare two revisions. Run from
the repository root.
"""

from __future__ import annotations

import importlib
import sys
from typing import NamedTuple

__all__ = ["COMMANDS", "Command", "main"]


class Command(NamedTuple):
    """A benchmark command: the module whose ``main(argv)`` runs it and what it measures (one line)."""

    module: str
    what: str


#: Every command, in the order ``python -m benchmarks`` lists them.
COMMANDS: dict[str, Command] = {
    "suite": Command("run", "the suite: planner runs on every benchmark world, throughput, cold start, OMPL, profile"),
    "planner_runs": Command("worker", "one world's planner runs in a process of its own: time, CPU, work, peak RSS"),
    "collision_throughput": Command(
        "throughput", "batched is_valid against a per-configuration loop; free intervals per s"
    ),
    "ompl_peer": Command("peer", "OMPL RRTConnect against the project's planner on transit sub-problems"),
    "profile": Command("profile", "cProfile of one planner run: top functions by own and cumulative time"),
    "cold_start": Command("cold_start", "compiling and loading the kernel, import, first plan against second"),
    "generated_families": Command("families_run", "the planner on clew_world's generated families, figure1 beside"),
    "compare": Command(
        "compare", "any command on a git revision and on this checkout (suite, generated_families: run by run)"
    ),
    "setting_variants": Command("variants", "planner settings compared on the same worlds: time to the first plan"),
    "improvement_gain": Command("improvement", "what the anytime improvement gains: first and improved plans' travel"),
    "improvement_stages": Command("improvement_stages", "wall time and work charged per stage of the improvement"),
    "check_cost": Command("check_cost", "what a batched check costs against what the improvement's budget charges"),
    "grid_reference": Command("reference", "2-joint plans against a brute-force grid planner's least joint travel"),
    "one_transfer_bound": Command("one_transfer_bound", "3-joint plans against the shortest one-transfer lattice plan"),
    "batch_throughput": Command("batch", "clew_batch in sequence, on the local pool and on a local Ray; resume"),
    "spatial_checker": Command("spatial_checker", "the spatial checker's speed and agreement with an exact reference"),
    "spatial_ik": Command("spatial_ik", "the spatial tcp inverse kinematics' success rate and speed"),
    "spatial_motion": Command(
        "spatial_motion", "motion-only problems (table, shelf, cage, bookshelf): OMPL, roboplan and others by name"
    ),
    "spatial_families": Command(
        "spatial_families", "the planner on clew_world's spatial families (Panda, UR5, random arms): witness beside"
    ),
    "spatial_regrasp": Command(
        "spatial_regrasp", "the planner on spatial worlds that need a regrasp (bin to cubby and back): witness beside"
    ),
    "spatial_render": Command("spatial_render", "how fast the 3-D renderer draws a spatial world, a still, a frame"),
    "point_clouds": Command("point_clouds", "a 300k-point cloud read and voxelised with the self-filter (~/points)"),
}


def listing() -> str:
    """The commands, one line each: name and what it measures."""
    width = max(len(name) for name in COMMANDS)
    lines = ["usage: python -m benchmarks COMMAND [ARGS]  (COMMAND --help for its options)", "", "commands:"]
    lines += [f"  {name:<{width}}  {command.what}" for name, command in COMMANDS.items()]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Run ``argv[0]``'s module with the rest of ``argv``; no command: list them (exit 0); an unknown one: exit 2."""
    args = sys.argv[1:] if argv is None else argv
    if not args or args[0] in ("-h", "--help"):
        print(listing())
        return 0
    name, rest = args[0], args[1:]
    if name not in COMMANDS:
        print(
            f"python -m benchmarks: unknown command {name!r}; expected one of: {', '.join(COMMANDS)}", file=sys.stderr
        )
        return 2
    module = importlib.import_module(f"benchmarks.{COMMANDS[name].module}")
    result = module.main(rest)
    return int(result or 0)


if __name__ == "__main__":
    sys.exit(main())
