"""Fuzz of every file reader: a generated corpus of malformed plan files and recordings (mutated real ones and
crafted ones, :mod:`helpers.security_files`), plus hypothesis' own mutations; and of the spatial world's files
(planning scenes, URDFs, meshes, :mod:`helpers.security_spatial`) and recorded spatial runs.

Every case is either read or refused with the project's own error type (PlanFileError, RecordingError), and
the command-line tools given it (clew_render, clew_replay --dry-run; in-process, and a few real processes) exit
0 or 2, and on 2 print exactly one line on stderr, never a traceback. Run with ``-s`` to see the counts by kind.
"""

from __future__ import annotations

import collections
import contextlib
import functools
import io
import random
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import pytest
from helpers.security_files import (
    SEEDS,
    crafted_recordings,
    plan_bytes,
    plan_cases,
    recording_cases,
    world_path,
    write_recording,
)
from helpers.security_spatial import MESHES, SECRET, mesh_cases, scene_cases, urdf_cases, urdf_with_meshes
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

pytest.importorskip("rclpy")
pytest.importorskip("mcap")

from clew_ros.cli.render import main as clew_render
from clew_ros.cli.replay import main as clew_replay
from clew_ros.core.errors import PlanFileError
from clew_ros.core.plan import Plan
from clew_ros.recording import Recording, RecordingError

#: The recordings mutated: the first world's run with each chunk compression, the second's with zstd.
RECORDING_SEEDS = ((*SEEDS[0], "zstd"), (*SEEDS[0], "lz4"), (*SEEDS[0], "none"), (*SEEDS[1], "zstd"))
MIN_CASES = 500


@functools.cache
def seed_recordings() -> tuple[bytes, ...]:
    """The bytes of each recording of :data:`RECORDING_SEEDS`, written once per process."""
    with tempfile.TemporaryDirectory(prefix="clew_fuzz_") as folder:
        return tuple(
            write_recording(Path(folder) / f"{number}", world, plan, compression=compression).read_bytes()
            for number, (world, plan, compression) in enumerate(RECORDING_SEEDS)
        )


@pytest.fixture(scope="module")
def corpus(tmp_path_factory: pytest.TempPathFactory) -> dict[str, list[tuple[str, Path]]]:
    """The malformed files on disk: ``plans`` and ``recordings``, each ``(kind, path)``."""
    folder = tmp_path_factory.mktemp("corpus")
    mcaps = seed_recordings()
    files: dict[str, list[tuple[str, Path]]] = {"plans": [], "recordings": []}
    for name, cases, suffix in (
        ("plans", plan_cases(), ".json"),
        ("recordings", recording_cases(list(mcaps)), ".mcap"),
    ):
        for number, (kind, data) in enumerate(cases):
            path = folder / f"{name}_{number:04d}{suffix}"
            path.write_bytes(data)
            files[name].append((kind, path))
    return files


def _tally(title: str, counts: collections.Counter[tuple[str, str]]) -> None:
    kinds = sorted({kind for kind, _ in counts})
    print(f"\n{title}: {sum(counts.values())} cases")
    for kind in kinds:
        outcomes = ", ".join(f"{outcome} {counts[kind, outcome]}" for _, outcome in sorted(counts) if _ == kind)
        print(f"  {kind}: {outcomes}")


def test_every_malformed_plan_file_is_read_or_refused(corpus: dict[str, list[tuple[str, Path]]]) -> None:
    counts: collections.Counter[tuple[str, str]] = collections.Counter()
    for kind, path in corpus["plans"]:
        try:
            Plan.read(path)
        except PlanFileError as error:
            refusal = str(error)
        else:
            refusal = None
        assert refusal is None or refusal.startswith(str(path)), refusal
        counts[kind, "read" if refusal is None else "refused"] += 1
    _tally("Plan.read", counts)
    assert sum(n for (_, outcome), n in counts.items() if outcome == "refused") > 0.9 * len(corpus["plans"])


def _read_whole(path: Path) -> Recording:
    recording = Recording(path)
    for topic in recording.topics:
        recording.decoded(topic)
    return recording


def test_every_malformed_recording_is_read_or_refused(corpus: dict[str, list[tuple[str, Path]]]) -> None:
    total = len(corpus["plans"]) + len(corpus["recordings"])
    assert total >= MIN_CASES
    kinds = {kind for cases in corpus.values() for kind, _ in cases}
    for kind in ("truncated", "bit flips", "bytes inserted", "huge record length", "chunk over the size cap"):
        assert kind in kinds
    for kind in ("nested JSON", "NaN or Infinity", "wrong types", "crafted type name", "decompression bomb"):
        assert kind in kinds
    counts: collections.Counter[tuple[str, str]] = collections.Counter()
    for kind, path in corpus["recordings"]:
        try:
            recording = _read_whole(path)
        except RecordingError as error:
            refusal = str(error)
            assert str(path) in refusal, refusal
            counts[kind, "refused"] += 1
        else:
            counts[kind, "read whole" if recording.complete else "read up to a fault"] += 1
    _tally("Recording", counts)
    refused_kinds = {kind for (kind, outcome) in counts if outcome == "refused"}
    assert {"chunk over the size cap", "binary", "crafted profile"} <= refused_kinds
    assert not any(outcome == "read whole" for kind, outcome in counts if kind == "chunk over the size cap")


def _run(main: Callable[[list[str]], int], argv: list[str]) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = main(argv)
    return code, err.getvalue()


def _check_cli(name: str, code: int, err: str, counts: collections.Counter[tuple[str, str]], kind: str) -> None:
    assert code in (0, 2), (name, code, err)
    if code == 2:
        assert len(err.splitlines()) == 1, err
        assert err.startswith(f"{name}: "), err
    counts[kind, f"exit {code}"] += 1


def test_clew_render_reads_or_refuses_every_case(corpus: dict[str, list[tuple[str, Path]]], tmp_path: Path) -> None:
    counts: collections.Counter[tuple[str, str]] = collections.Counter()
    out = str(tmp_path / "out.svg")
    for number, (kind, path) in enumerate(corpus["plans"]):
        world = world_path(SEEDS[number * len(SEEDS) // len(corpus["plans"])][0])
        code, err = _run(clew_render, [str(path), "-o", out, "--world", str(world), "--size", "64"])
        _check_cli("clew_render", code, err, counts, kind)
    for kind, path in corpus["recordings"]:
        code, err = _run(clew_render, [str(path), "-o", out, "--size", "64"])
        _check_cli("clew_render", code, err, counts, kind)
    _tally("clew_render", counts)


def test_clew_replay_reads_or_refuses_every_recording(corpus: dict[str, list[tuple[str, Path]]]) -> None:
    counts: collections.Counter[tuple[str, str]] = collections.Counter()
    for kind, path in corpus["recordings"]:
        code, err = _run(clew_replay, [str(path), "--dry-run"])
        _check_cli("clew_replay", code, err, counts, kind)
    _tally("clew_replay --dry-run", counts)
    assert counts["crafted type name", "exit 2"] == sum(
        1 for kind, _ in corpus["recordings"] if kind == "crafted type name"
    )


def test_the_tools_in_their_own_processes(tmp_path: Path) -> None:
    """Real runs: exit 2, one line on stderr, no traceback."""
    bomb = tmp_path / "bomb.mcap"
    bomb.write_bytes(next(data for kind, data in crafted_recordings() if kind == "decompression bomb"))
    crafted = tmp_path / "crafted.mcap"
    crafted.write_bytes(next(data for kind, data in crafted_recordings() if kind == "crafted type name"))
    nested = tmp_path / "nested.json"
    nested.write_bytes(b"[" * 10**6 + b"]" * 10**6)
    runs = [
        ["clew_ros.cli.render", str(bomb), "-o", str(tmp_path / "a.png")],
        ["clew_ros.cli.render", str(nested), "-o", str(tmp_path / "b.png"), "--world", str(world_path("figure1"))],
        ["clew_ros.cli.replay", str(bomb)],
        ["clew_ros.cli.replay", str(crafted)],
    ]
    for run in runs:
        result = subprocess.run([sys.executable, "-m", *run], capture_output=True, text=True, timeout=120, check=False)
        assert result.returncode == 2, (run, result.stderr)
        assert len(result.stderr.splitlines()) == 1, result.stderr
        assert "Traceback" not in result.stderr


def _mutated(data: bytes, changes: list[tuple[int, int]], cut: int | None) -> bytes:
    mutated = bytearray(data)
    for at, value in changes:
        mutated[at % len(mutated)] = value
    return bytes(mutated[:cut] if cut is not None else mutated)


_MUTATIONS = st.tuples(
    st.lists(st.tuples(st.integers(0, 2**20), st.integers(0, 255)), min_size=1, max_size=12),
    st.none() | st.integers(0, 2**17),
)


@settings(max_examples=150, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(_MUTATIONS)
def test_hypothesis_mutations_of_a_recording(mutation: tuple[list[tuple[int, int]], int | None]) -> None:
    data = _mutated(seed_recordings()[0], *mutation)
    with tempfile.NamedTemporaryFile(suffix=".mcap") as file:
        file.write(data)
        file.flush()
        with contextlib.suppress(RecordingError):
            _read_whole(Path(file.name))


@settings(max_examples=150, deadline=None, derandomize=True)
@given(_MUTATIONS)
def test_hypothesis_mutations_of_a_plan_file(mutation: tuple[list[tuple[int, int]], int | None]) -> None:
    data = _mutated(plan_bytes(SEEDS[1][1]), *mutation)
    with contextlib.suppress(PlanFileError):
        Plan.from_json(data, source="mutated")


# --------------------------------------------------------------------------- spatial worlds and their files

#: The issue's bound on a refusal (s): a malformed spatial file is read or refused within it.
SPATIAL_CASE_S = 10.0


def _read_or_refuse(load: Callable[[], object], counts: collections.Counter[tuple[str, str]], kind: str) -> None:
    """``load()`` either reads or raises WorldError: one line, no file contents, within the bound."""
    from clew_ros.core.errors import WorldError

    start = time.monotonic()
    try:
        load()
    except WorldError as error:
        text = str(error)
        assert "\n" not in text, text
        assert SECRET not in text, text
        counts[kind, "refused"] += 1
    else:
        counts[kind, "read"] += 1
    assert time.monotonic() - start < SPATIAL_CASE_S, kind


def test_every_malformed_spatial_file_is_read_or_refused(tmp_path: Path) -> None:
    """Planning scenes, URDFs and meshes, each mutated: the world loader reads it or refuses it with a
    WorldError (never another exception), in one line and within the bound."""
    pytest.importorskip("trimesh")
    pytest.importorskip("urdf_parser_py")
    from clew_ros.spatial.robot import robot_from_parameters
    from clew_ros.spatial.scene import world_obstacles
    from clew_ros.spatial.spheres import sphere_model

    panda = {"base_link": "panda_link0", "tip_link": "panda_hand_tcp"}
    counts: collections.Counter[tuple[str, str]] = collections.Counter()
    for number, (kind, data) in enumerate(scene_cases()):
        path = tmp_path / f"scene_{number:03d}.yaml"
        path.write_bytes(data)
        _read_or_refuse(lambda path=path: world_obstacles({"scene_file": str(path)}, tmp_path), counts, f"scene {kind}")
    for number, (kind, data) in enumerate(urdf_cases()):
        path = tmp_path / f"robot_{number:03d}.urdf"
        path.write_bytes(data)
        _read_or_refuse(
            lambda path=path: robot_from_parameters({**panda, "urdf": str(path)}, tmp_path), counts, f"URDF {kind}"
        )
    urdf = urdf_with_meshes(tmp_path, lambda text: text.replace(f"{MESHES}/link3.stl", str(tmp_path / "mesh.stl")))
    for kind, data in mesh_cases():
        (tmp_path / "mesh.stl").write_bytes(data)

        def load() -> None:
            sphere_model(robot_from_parameters({**panda, "urdf": str(urdf)}, tmp_path))

        _read_or_refuse(load, counts, f"mesh {kind}")
    _tally("spatial files", counts)
    kinds = {kind for kind, _ in counts}
    assert len(kinds) >= 15
    for kind in ("scene aliases", "URDF entities", "URDF many links", "URDF files", "mesh huge triangle count"):
        assert (kind, "refused") in counts, kind
    assert sum(counts.values()) >= 140


@pytest.fixture(scope="module")
def spatial_recording_bytes(tmp_path_factory: pytest.TempPathFactory) -> bytes:
    pytest.importorskip("trimesh")
    from helpers.spatial_recording import record_witness

    run = record_witness(tmp_path_factory.mktemp("spatial_seed"))
    return next(run.glob("*.mcap")).read_bytes()


def test_clew_render_reads_or_refuses_every_mutated_spatial_recording(
    spatial_recording_bytes: bytes, tmp_path: Path
) -> None:
    """A recorded spatial run truncated, bit-flipped or with bytes inserted: clew_render draws it (from what
    is left) or exits 2 with one line, within the bound."""
    from helpers.security_files import bit_flips, insertions, truncations

    rng = random.Random(0)
    data = spatial_recording_bytes
    cases = [("unchanged", data), *truncations(data, rng, 5), *bit_flips(data, rng, 6), *insertions(data, rng, 4)]
    counts: collections.Counter[tuple[str, str]] = collections.Counter()
    for number, (kind, mutated) in enumerate(cases):
        path = tmp_path / f"run_{number:02d}.mcap"
        path.write_bytes(mutated)
        start = time.monotonic()
        code, err = _run(clew_render, [str(path), "-o", str(tmp_path / "out.png"), "--size", "64"])
        assert time.monotonic() - start < SPATIAL_CASE_S, kind
        _check_cli("clew_render", code, err, counts, kind)
    _tally("clew_render, spatial recordings", counts)
    assert counts["unchanged", "exit 0"] == 1
