"""``clew_world FAMILY --seed N -o WORLD.yaml [--robot panda|ur5|random] [--no-witness]``: generate a world of
a family, solvable by construction; ``clew_world --list`` lists the families; ``clew_world check WORLD.yaml``
checks a spatial world's grasps (:mod:`clew_ros.spatial.grasp_check`). The ``spatial_*`` families
(:mod:`clew_ros.worlds.spatial`) build spatial worlds on the robot ``--robot`` names (default panda); the
others are planar and take no ``--robot``.

Writes the ROS 2 parameter file WORLD.yaml (``clew_plan`` and the node read it as any world) and,
unless ``--no-witness``, the witness plan WORLD.witness.json next to it (``clew-plan/1``: the
manipulation the world was built around; for the ``unsolvable`` family a failed plan saying why no
plan exists). Same family and seed, same bytes. Exit 0: written; 1: no world could be built for this
seed; 2: invalid arguments (an unknown family, a negative seed, an output that cannot be written).

``check`` prints one line per grasp (the face approached, the faces the fingers close on) and a warning per
doubt (fingers that close on no pair of faces, faces wider apart than the fingers open, a hand that comes
through or closes on the face the object rests on). Exit 0: no warning; 1: warnings; 2: an invalid world.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from clew_ros.worlds import FAMILIES, GenerationError, UnknownFamilyError, generate, write_world
from clew_ros.worlds.spatial import SPATIAL_FAMILIES, SPATIAL_ROBOTS, generate_spatial, write_spatial_world

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_INVALID = 2


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="clew_world", description=__doc__.split("\n\n")[0])
    parser.add_argument("family", nargs="?", help="the family of worlds (--list shows them), or check")
    parser.add_argument("world", nargs="?", type=Path, help="with check: the spatial world file to check")
    parser.add_argument("--seed", type=int, default=0, help="the world's seed, an integer >= 0 (default 0)")
    parser.add_argument("--output", "-o", type=Path, help="parameter file to write (WORLD.yaml)")
    parser.add_argument("--robot", help=f"the arm of a spatial_* family: {', '.join(SPATIAL_ROBOTS)} (default panda)")
    parser.add_argument("--no-witness", action="store_true", help="do not write WORLD.witness.json")
    parser.add_argument("--list", action="store_true", help="list the families, one line each, and exit")
    return parser


def _invalid(message: str) -> int:
    print(f"clew_world: invalid arguments: {message}", file=sys.stderr)
    return EXIT_INVALID


def _argument_problem(args: argparse.Namespace) -> str | None:
    """What is wrong with the arguments of a generation (the argument named first), or ``None``."""
    if args.family is None:
        return f"FAMILY: expected one of {', '.join([*FAMILIES, *SPATIAL_FAMILIES])} (or --list)"
    if args.family not in FAMILIES and args.family not in SPATIAL_FAMILIES:
        return f"FAMILY: {UnknownFamilyError(args.family, [*FAMILIES, *SPATIAL_FAMILIES])}"
    robot = _robot_problem(args)
    if robot:
        return robot
    if args.output is None:
        return "--output: expected the parameter file to write (WORLD.yaml)"
    if args.seed < 0:
        return f"--seed: expected an integer >= 0, got {args.seed}"
    return None


def _robot_problem(args: argparse.Namespace) -> str | None:
    if args.world is not None:
        return f"{args.world}: unexpected argument (only check takes a world file)"
    if args.robot is not None and args.family not in SPATIAL_FAMILIES:
        return f"--robot: only the spatial_* families take a robot, not {args.family}"
    if args.robot is not None and args.robot not in SPATIAL_ROBOTS:
        return f"--robot: expected one of {', '.join(SPATIAL_ROBOTS)}, got {args.robot}"
    return None


def _list() -> int:
    summaries = {name: family.summary for name, family in FAMILIES.items()}
    summaries.update({name: family.summary for name, family in SPATIAL_FAMILIES.items()})
    width = max(len(name) for name in summaries)
    for name, summary in summaries.items():
        print(f"{name:<{width}}  {summary}")
    return EXIT_OK


def _spatial(args: argparse.Namespace) -> int:
    robots = SPATIAL_FAMILIES[args.family].robots
    if (args.robot or "panda") not in robots:
        return _invalid(f"--robot: family {args.family} is generated on {', '.join(robots)}, got {args.robot!r}")
    try:
        generated = generate_spatial(args.family, args.seed, args.robot or "panda")
        written = write_spatial_world(generated, args.output, witness=not args.no_witness)
    except GenerationError as error:
        print(f"clew_world: no world: {error}", file=sys.stderr)
        return EXIT_FAILED
    except OSError as error:
        return _invalid(f"--output: cannot write {args.output} ({error.strerror})")
    what = f"{'solvable' if generated.solvable else 'unsolvable'}, "
    what += f"{len(generated.parameters['world'].get('obstacle_names', []))} obstacles"
    print(f"clew_world: {generated.name} ({what}) -> {', '.join(str(p) for p in written)}", file=sys.stderr)
    return EXIT_OK


def _check(world_file: Path | None) -> int:
    """``clew_world check WORLD.yaml``: each grasp in words, and the warnings (the module docstring)."""
    from clew_ros.core.errors import ClewError
    from clew_ros.planar.world import read_parameter_file
    from clew_ros.spatial.grasp_check import check_grasps
    from clew_ros.spatial.world import spatial_world_from_parameters

    if world_file is None:
        return _invalid("WORLD: expected the world file to check (clew_world check WORLD.yaml)")
    try:
        parameters = read_parameter_file(world_file)
        world = spatial_world_from_parameters(parameters, world_file.resolve().parent)
    except ClewError as error:
        print(f"clew_world: invalid world {world_file}: {error}", file=sys.stderr)
        return EXIT_INVALID
    if world.object is None:
        print(f"clew_world: {world_file}: a motion-only query (no world.object): no grasps to check")
        return EXIT_OK
    reports = check_grasps(world)
    for report in reports:
        print(report.summary)
    warnings = [warning for report in reports for warning in report.warnings]
    for warning in warnings:
        print(f"clew_world: warning: {warning}", file=sys.stderr)
    return EXIT_FAILED if warnings else EXIT_OK


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    return _check(args.world) if args.family == "check" else _generate(args)


def _generate(args: argparse.Namespace) -> int:
    problem = None if args.list else _argument_problem(args)
    if args.list or problem:
        return _list() if args.list else _invalid(str(problem))
    if args.family in SPATIAL_FAMILIES:
        return _spatial(args)
    try:
        generated = generate(args.family, args.seed)
        written = write_world(generated, args.output, witness=not args.no_witness)
    except UnknownFamilyError as error:
        return _invalid(f"FAMILY: {error}")
    except GenerationError as error:
        print(f"clew_world: no world: {error}", file=sys.stderr)
        return EXIT_FAILED
    except OSError as error:
        return _invalid(f"--output: cannot write {args.output} ({error.strerror})")
    what = f"{'solvable' if generated.solvable else 'unsolvable'}, "
    what += f"{len(generated.parameters['world'].get('obstacle_names', []))} obstacles"
    if generated.solvable:
        what += f", witness with {generated.stats['transfers']} transfer(s)"
    print(f"clew_world: {generated.name} ({what}) -> {', '.join(str(p) for p in written)}", file=sys.stderr)
    return EXIT_OK


if __name__ == "__main__":
    raise SystemExit(main())
