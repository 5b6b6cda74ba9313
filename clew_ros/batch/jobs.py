"""The jobs of a batch: the world files given, their seeds, and where each job's plan goes.

A job is a (world, seed, planner settings) triple: the world file's
``world.*`` and ``planner.*`` parameters, ``planner.seed`` set to the job's
seed, and the batch's ``--time-limit`` / ``--improve-time`` overrides, exactly
as ``clew_plan WORLD --seed S [--time-limit T] [--improve-time I]`` would
plan it.

Worlds come from files, folders (every ``*.yaml`` in them, by name), list
files (``@FILE``: one file or folder per line, relative to the list file;
blank lines and ``#`` comments skipped) and generator specifications
(``--generate FAMILY:COUNT``: the worlds ``clew_world FAMILY --seed 0..COUNT-1``
writes, kept under the output folder's ``worlds/`` with their witnesses,
see :func:`generated_world_paths`). Seeds are ``0 .. N-1``, or with a
batch seed ``B`` derived from it (:func:`derived_seeds`). Every world uses the
same seeds. Job ``figure1/seed_0007`` writes ``plans/figure1/seed_0007.json``
under the output folder (the folder is the world file's name without
``.yaml``), and with ``--record`` its recording ``recordings/figure1/seed_0007/``.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from clew_ros.batch.errors import BatchInputError
from clew_ros.core.errors import ParameterError
from clew_ros.core.parameters import PLANNER_PARAMETERS, check_value
from clew_ros.core.settings import PlannerSettings
from clew_ros.kinds import AnyProblem, problem_from_parameters
from clew_ros.planar.world import read_parameter_file
from clew_ros.worlds import GenerationError, UnknownFamilyError, generate, write_world

__all__ = [
    "GENERATED_FOLDER",
    "PLANS_FOLDER",
    "RECORDINGS_FOLDER",
    "WORLD_SUFFIX",
    "BatchWorld",
    "Job",
    "collect_world_paths",
    "derived_seeds",
    "generated_world_paths",
    "load_worlds",
    "make_jobs",
]

#: The suffix of world files taken from a folder.
WORLD_SUFFIX = ".yaml"
#: The folder under the output folder that holds the plan files.
PLANS_FOLDER = "plans"
#: The folder under the output folder that holds the recordings (``--record``).
RECORDINGS_FOLDER = "recordings"
#: planner.seed's range is [0, 2**31 - 1]: derived seeds keep 31 bits.
_SEED_BITS = 31


@dataclass(frozen=True, eq=False)
class BatchWorld:
    """A world file of the batch: its resolved ``path``, the plan ``folder`` name, its ``parameters``
    (the ``ros__parameters`` tree) and the checked ``problem`` (world and file settings)."""

    path: Path
    folder: str
    parameters: Mapping[str, Any]
    problem: AnyProblem

    @property
    def name(self) -> str:
        """``world.name``, which the plan files carry."""
        return self.problem.world.name


@dataclass(frozen=True, eq=False)
class Job:
    """One plan to make: ``world`` planned with ``seed`` and the batch's overrides (s; ``None``: the
    world file's ``planner.time_limit`` / ``planner.improve_time``)."""

    world: BatchWorld
    seed: int
    time_limit_s: float | None = None
    improve_time_s: float | None = None

    @property
    def key(self) -> str:
        """The job's name in the index and the plan's path: ``<world folder>/seed_<seed>``."""
        return f"{self.world.folder}/seed_{self.seed:04d}"

    @property
    def plan_path(self) -> Path:
        """Where the job's plan file goes, relative to the output folder."""
        return Path(PLANS_FOLDER, f"{self.key}.json")

    @property
    def recording_path(self) -> Path:
        """Where the job's recording goes with ``--record`` (a rosbag2 folder), relative to the output folder."""
        return Path(RECORDINGS_FOLDER, self.key)

    @property
    def settings(self) -> PlannerSettings:
        """The planner settings of this job: the world file's, with the seed and the overrides."""
        return PlannerSettings.from_parameters(
            self.world.parameters, seed=self.seed, time_limit=self.time_limit_s, improve_time=self.improve_time_s
        )

    @property
    def problem(self) -> AnyProblem:
        """The world and the settings this job plans with."""
        return dataclasses.replace(self.world.problem, settings=self.settings)

    @property
    def fingerprint(self) -> str:
        """Hex digest of what decides the plan: the world's parameters and the job's planner settings
        (all but ``planner.threads``, which the plan does not depend on). A job whose fingerprint
        differs from the index's is planned again."""
        settings = asdict(self.settings)
        settings.pop("threads")
        content = {"world": self.world.parameters.get("world"), "planner": settings}
        text = json.dumps(content, sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def _list_file_entries(source: str) -> list[tuple[str, Path]]:
    """The entries of list file ``@FILE`` as (what to name in errors, path)."""
    list_path = Path(source[1:])
    try:
        lines = list_path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as error:
        reason = error.strerror if isinstance(error, OSError) else "not UTF-8 text"
        raise BatchInputError(source, f"expected a readable list file of world paths ({reason})") from None
    entries = []
    for number, line in enumerate(lines, start=1):
        text = line.split("#", 1)[0].strip()
        if text:
            entries.append((f"{list_path}:{number}", list_path.parent / text))
    if not entries:
        raise BatchInputError(source, "expected a list file naming at least one world file or folder, found none")
    return entries


def _world_files(what: str, path: Path) -> list[Path]:
    """``path`` itself (a file) or the ``*.yaml`` files in it (a folder), resolved."""
    if path.is_dir():
        files = sorted(p for p in path.iterdir() if p.suffix == WORLD_SUFFIX and p.is_file())
        if not files:
            raise BatchInputError(what, f"expected a folder holding {WORLD_SUFFIX} world files, found none in {path}")
        return [p.resolve() for p in files]
    if not path.is_file():
        raise BatchInputError(what, f"expected a world file or a folder of them, but {path} does not exist")
    return [path.resolve()]


def collect_world_paths(sources: Iterable[str]) -> list[Path]:
    """The world files named by ``sources`` (files, folders, ``@LIST`` files), resolved, each once, in
    the order given; :class:`BatchInputError` names the source at fault."""
    paths: dict[Path, None] = {}
    for source in sources:
        entries = _list_file_entries(source) if source.startswith("@") else [(source, Path(source))]
        for what, path in entries:
            paths.update(dict.fromkeys(_world_files(what, path)))
    if not paths:
        raise BatchInputError("WORLD", "expected at least one world file, folder or @list file")
    return list(paths)


def load_worlds(paths: Sequence[Path]) -> list[BatchWorld]:
    """Read and check every world file (start and goal included); :class:`BatchInputError` names the
    file and the parameter at fault, or two files whose plans would share a folder."""
    worlds: list[BatchWorld] = []
    folders: dict[str, Path] = {}
    for path in paths:
        folder = path.stem
        if folder in folders:
            raise BatchInputError(
                str(path),
                f"has the same file name as {folders[folder]}: their plans would share {PLANS_FOLDER}/{folder}/; "
                "rename one of them",
            )
        folders[folder] = path
        try:
            parameters = read_parameter_file(path)
            problem = problem_from_parameters(parameters, path.resolve().parent)
        except ParameterError as error:
            raise BatchInputError(str(path), str(error)) from None
        worlds.append(BatchWorld(path, folder, parameters, problem))
    return worlds


def derived_seeds(batch_seed: int, count: int) -> list[int]:
    """``count`` distinct planner seeds derived from ``batch_seed``.

    Seed ``i`` comes from child ``i`` of ``numpy.random.SeedSequence(batch_seed)`` (what
    ``SeedSequence(batch_seed).spawn(...)[i]`` is): the first 32-bit word of its
    ``generate_state``, shifted right by one to fit ``planner.seed`` (31 bits). A value already
    drawn is skipped and the next child is taken, so the list has no repeats; the first ``k``
    seeds of a longer list are the seeds of a shorter one.
    """
    if batch_seed < 0:
        raise BatchInputError("--batch-seed", f"expected an integer >= 0, got {batch_seed}")
    seeds: dict[int, None] = {}
    child = 0
    while len(seeds) < count:
        state = np.random.SeedSequence(batch_seed, spawn_key=(child,)).generate_state(1, dtype=np.uint32)
        seeds.setdefault(int(state[0]) >> (32 - _SEED_BITS))
        child += 1
    return list(seeds)


def make_jobs(
    worlds: Sequence[BatchWorld],
    seeds: Sequence[int],
    *,
    time_limit_s: float | None = None,
    improve_time_s: float | None = None,
) -> list[Job]:
    """Every world with every seed, world by world; the overrides (s) are checked once here
    (:class:`BatchInputError` naming ``--time-limit`` or ``--improve-time``)."""
    for option, name, value in (
        ("--time-limit", "time_limit", time_limit_s),
        ("--improve-time", "improve_time", improve_time_s),
    ):
        if value is not None:
            try:
                check_value(PLANNER_PARAMETERS[name], value)
            except ParameterError as error:
                raise BatchInputError(option, error.expected) from None
    return [Job(world, seed, time_limit_s, improve_time_s) for world in worlds for seed in seeds]


#: Where the generated worlds of ``--generate`` go, under the output folder.
GENERATED_FOLDER = "worlds"


def generated_world_paths(specs: Sequence[str], out: Path) -> list[Path]:
    """The world files of generator specifications ``FAMILY:COUNT`` (seeds ``0..COUNT-1``), written
    under ``out/worlds/`` as ``FAMILY_SSSS.yaml`` with the witness plan next to each; a file that is
    already there is kept (generation is deterministic, so a rerun finds the same worlds).
    :class:`BatchInputError` names the specification at fault."""
    paths: list[Path] = []
    for spec in specs:
        family, _, count_text = spec.partition(":")
        try:
            count = int(count_text)
        except ValueError:
            count = 0
        if count < 1:
            raise BatchInputError("--generate", f"expected FAMILY:COUNT with COUNT an integer >= 1, got {spec!r}")
        for seed in range(count):
            path = out / GENERATED_FOLDER / f"{family}_{seed:04d}{WORLD_SUFFIX}"
            if not path.is_file():
                try:
                    write_world(generate(family, seed), path)
                except UnknownFamilyError as error:
                    raise BatchInputError("--generate", str(error)) from None
                except GenerationError as error:
                    raise BatchInputError("--generate", f"{spec}: seed {seed}: {error}") from None
            paths.append(path)
    return paths
