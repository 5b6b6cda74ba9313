"""The generated families as benchmark worlds: ``clew_world``'s worlds written into a directory.

Each world of :mod:`clew_ros.worlds` (family, world seed 0..N-1) is generated and written as
``DIR/<family>_<seed>.yaml`` with its witness next to it, exactly as ``clew_world FAMILY --seed S``
would write it; :class:`GeneratedBenchWorld` keeps what the benchmark table needs: whether the
world is solvable (the success rate's denominator counts only those) and the witness's transfers
and joint travel (the plan-quality reference). :func:`reference_world` adds figure1 from
``config/`` in the same form, so that the table shows it next to the families. Worlds are never
written into ``config/``.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

from benchmarks.worlds import CONFIG_DIR
from clew_ros.worlds import FAMILIES, generate, write_world

__all__ = ["GeneratedBenchWorld", "build_world", "reference_world", "solvable_families"]


@dataclass(frozen=True)
class GeneratedBenchWorld:
    """One benchmark world: its file, family, world seed, and the witness's figures (solvable worlds)."""

    family: str
    seed: int
    path: str
    solvable: bool
    joints: int
    obstacles: int
    witness_transfers: int | None
    witness_travel_rad: float | None


#: The first world seed no session has measured or tuned on (docs/benchmarks.md, "Held-out worlds").
HELD_OUT_FROM = 70


def add_first_world(parser: argparse.ArgumentParser) -> None:
    """``--first-world K``: the family benchmarks generate worlds K..K+W-1 (default 0)."""
    parser.add_argument(
        "--first-world",
        type=int,
        default=0,
        metavar="K",
        help=f"the first world seed (default 0; {HELD_OUT_FROM} and on: held out, docs/benchmarks.md)",
    )


def world_seeds(args: argparse.Namespace, count: int) -> range:
    """The world seeds ``--first-world`` and a count of worlds give."""
    return range(args.first_world, args.first_world + count)


def solvable_families() -> list[str]:
    """The families whose worlds are solvable by construction, in :data:`clew_ros.worlds.FAMILIES`' order."""
    return [name for name, family in FAMILIES.items() if family.solvable]


def build_world(family: str, seed: int, directory: str | Path) -> GeneratedBenchWorld:
    """Generate world ``seed`` of ``family`` and write it (and its witness) into ``directory``."""
    directory = Path(directory).resolve()
    if directory == CONFIG_DIR.resolve():
        raise ValueError("benchmark worlds are never written into config/")
    generated = generate(family, seed)
    path = directory / f"{generated.name}.yaml"
    write_world(generated, path)
    tree = generated.parameters["world"]
    return GeneratedBenchWorld(
        family,
        seed,
        str(path),
        generated.solvable,
        len(tree["robot"]["link_lengths"]),
        len(tree.get("obstacle_names", [])),
        generated.stats.get("transfers"),
        generated.stats.get("joint_travel_rad"),
    )


#: The planar worlds of ``config/`` that no plan solves (their files say why): a failed run there is the answer.
UNSOLVABLE_CONFIG_WORLDS = frozenset({"unreachable"})


def reference_world(name: str = "figure1") -> GeneratedBenchWorld:
    """A world of ``config/`` (default figure1) as a family of one world, for the table's reference row;
    solvable unless it is one of :data:`UNSOLVABLE_CONFIG_WORLDS`."""
    from clew_ros.planar.world import load_world

    path = CONFIG_DIR / f"{name}.yaml"
    world = load_world(path)
    solvable = name not in UNSOLVABLE_CONFIG_WORLDS
    return GeneratedBenchWorld(name, 0, str(path), solvable, world.robot.dof, len(world.obstacles), None, None)
