"""The recording reader refuses bad files with a RecordingError naming the file: a chunk whose declared size is
over the cap is not decompressed, lengths past the end of the file do not allocate, a type name from the file
imports nothing but an installed interface package, and a trajectory with NaN is not a plan."""

from __future__ import annotations

import struct
import subprocess
import sys
import tracemalloc
from pathlib import Path
from types import SimpleNamespace

import pytest
from helpers.security_files import crafted_recordings, records, write_recording

pytest.importorskip("rclpy")
pytest.importorskip("mcap")

from clew_ros.planar.world import load_world
from clew_ros.recording import Recording, RecordingError, RecordingLimits, TrajectoryError, trajectory_to_plan
from clew_ros.recording.msgdefs import message_class

CHUNK = 0x06


@pytest.fixture(scope="module")
def mcap_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_recording(tmp_path_factory.mktemp("seed"), "figure1", "figure1_seed0")


def _crafted(kind: str) -> list[bytes]:
    return [data for name, data in crafted_recordings() if name == kind]


def _with(data: bytes, at: int, fmt: str, value: int) -> bytes:
    mutated = bytearray(data)
    struct.pack_into(fmt, mutated, at, value)
    return bytes(mutated)


def test_a_real_recording_reads(mcap_file: Path) -> None:
    recording = Recording(mcap_file)
    assert recording.complete
    assert recording.problem is None
    assert len(recording.decoded("/clew_planner/trajectory")) == 1


def test_a_chunk_declared_over_the_cap_is_refused_before_it_is_decompressed(tmp_path: Path) -> None:
    bomb = tmp_path / "bomb.mcap"
    bomb.write_bytes(_crafted("decompression bomb")[0])  # 80 MiB of zeros in about 2.6 kB of zstd
    tracemalloc.start()
    try:
        with pytest.raises(RecordingError, match="declares 83886080 bytes uncompressed, over the limit") as raised:
            Recording(bomb)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert str(raised.value).startswith(str(bomb))
    assert peak < 8 * 2**20


def test_a_chunk_that_holds_more_than_it_declares_is_not_decompressed_whole(tmp_path: Path) -> None:
    bomb = tmp_path / "bomb.mcap"
    bomb.write_bytes(_crafted("decompression bomb")[1])  # declares 1000 bytes, holds 80 MiB
    tracemalloc.start()
    try:
        recording = Recording(bomb)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert not recording.complete
    assert "more bytes than the 1000 it declares" in str(recording.problem)
    assert peak < 8 * 2**20


def test_a_smaller_chunk_cap_refuses_a_real_recording(mcap_file: Path) -> None:
    with pytest.raises(RecordingError, match="over the limit of 100"):
        Recording(mcap_file, limits=RecordingLimits(max_chunk_bytes=100))
    with pytest.raises(RecordingError, match="larger than 1000 bytes"):
        Recording(mcap_file, limits=RecordingLimits(max_file_bytes=1000))


@pytest.mark.parametrize("length", [2**40, 2**63 - 1, 2**64 - 1])
def test_huge_lengths_neither_allocate_nor_crash(mcap_file: Path, tmp_path: Path, length: int) -> None:
    data = mcap_file.read_bytes()
    chunk = next(at for at, opcode, _ in records(data) if opcode == CHUNK)
    compression_length = struct.unpack_from("<I", data, chunk + 9 + 28)[0]
    crafted = {
        "header record": _with(data, 9, "<Q", length),
        "chunk record": _with(data, chunk + 1, "<Q", length),
        "chunk data": _with(data, chunk + 9 + 32 + compression_length, "<Q", length),
    }
    path = tmp_path / "crafted.mcap"
    for where, mutated in crafted.items():
        path.write_bytes(mutated)
        tracemalloc.start()
        try:
            recording = Recording(path)
        except RecordingError as error:
            refusal = str(error)
        else:
            refusal = None
            assert not recording.complete, where
        finally:
            _, peak = tracemalloc.get_traced_memory()
            tracemalloc.stop()
        assert refusal is None or refusal.startswith(str(path)), where
        assert peak < 4 * len(data) + 2**20, where


def test_a_flipped_bit_in_a_chunk_fails_its_crc(mcap_file: Path, tmp_path: Path) -> None:
    data = bytearray(mcap_file.read_bytes())
    chunks = [(at, length) for at, opcode, length in records(bytes(data)) if opcode == CHUNK]
    at, length = chunks[1]
    data[at + 9 + length - 10] ^= 0x10  # inside the second chunk's compressed data
    path = tmp_path / "flipped.mcap"
    path.write_bytes(bytes(data))
    recording = Recording(path)
    assert not recording.complete
    assert "chunk" in str(recording.problem)


def test_message_class_imports_only_installed_interface_packages() -> None:
    """``this`` prints the Zen of Python when imported, ``antigravity`` opens a browser: neither may be."""
    script = """
import sys
from clew_ros.recording import RecordingError
from clew_ros.recording.msgdefs import message_class
refused = 0
for name in ("this/msg/String", "antigravity/msg/X", "this/String", "os.path/msg/X", "this/msg/../X", "This/msg/X"):
    try:
        message_class(name)
    except RecordingError:
        refused += 1
print(refused, "this" in sys.modules, "antigravity" in sys.modules)
"""
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120, check=False)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "6 False False", result.stdout
    assert message_class("std_msgs/msg/String").__name__ == "String"
    assert message_class("std_srvs/srv/Trigger_Request").__name__ == "Trigger_Request"


def test_a_message_that_is_not_its_type_is_a_recording_error(tmp_path: Path) -> None:
    path = tmp_path / "bad.mcap"
    for data in _crafted("message not its type")[:3]:
        path.write_bytes(data)
        with pytest.raises(RecordingError, match=r"message 0 on /clew_planner/events is not a 'std_msgs/msg/String'"):
            Recording(path).decoded("/clew_planner/events")


def test_a_schema_that_does_not_parse_is_a_recording_error(tmp_path: Path) -> None:
    path = tmp_path / "bad.mcap"
    for data in _crafted("crafted schema"):
        path.write_bytes(data)
        with pytest.raises(RecordingError, match=r"(cannot decode|message 0 on) /clew_planner/events"):
            Recording(path).decoded("/clew_planner/events")


def _trajectory(names: list, rows: list[list[float]]) -> SimpleNamespace:
    return SimpleNamespace(joint_names=names, points=[SimpleNamespace(positions=row) for row in rows])


@pytest.mark.parametrize(
    ("names", "rows", "reason"),
    [
        (["joint_1", "joint_2", "gripper"], [[0.0, float("nan"), 0.0]], "point 0 has a position that is not a finite"),
        (["joint_1", "joint_2", "gripper"], [[0.0, 0.0, 0.0], [0.0, float("inf"), 1.0]], "point 1 has a position"),
        (["joint_1", "joint_2", "gripper"], [[0.0, 0.0, 0.0], [0.0]], "point 1 has 1 positions, expected 3"),
        (["joint_1", 7, "gripper"], [[0.0, 0.0, 0.0]], "joint_names: expected names"),
    ],
)
def test_trajectory_to_plan_refuses_what_is_not_a_plan(names: list, rows: list, reason: str) -> None:
    world = load_world(Path(__file__).resolve().parents[2] / "config" / "figure1.yaml")
    with pytest.raises(TrajectoryError, match=reason) as raised:
        trajectory_to_plan(world, _trajectory(names, rows), source="run.mcap (/clew_planner/trajectory)")
    assert str(raised.value).startswith("run.mcap (/clew_planner/trajectory): ")
    assert isinstance(raised.value, ValueError)


def test_trajectory_to_plan_refuses_grasps_the_object_does_not_have() -> None:
    world = load_world(Path(__file__).resolve().parents[2] / "config" / "figure1.yaml")
    rows = [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.1, 0.0, 1.0]]
    trajectory = _trajectory(["joint_1", "joint_2", "gripper"], rows)
    with pytest.raises(TrajectoryError, match="grasps: expected indices in"):
        trajectory_to_plan(world, trajectory, grasps=[99])


def test_metadata_yaml_cannot_point_outside_the_run_folder_or_crash_it(mcap_file: Path, tmp_path: Path) -> None:
    outside = tmp_path / "outside.mcap"
    outside.write_bytes(mcap_file.read_bytes())
    run = tmp_path / "run"
    run.mkdir()
    (run / "own.mcap").write_bytes(mcap_file.read_bytes())
    for name in (str(outside), "../outside.mcap"):
        (run / "metadata.yaml").write_text(f"rosbag2_bagfile_information:\n  relative_file_paths: ['{name}']\n")
        assert Recording(run).mcap_path == run / "own.mcap"
    for text in ("[" * 10_000 + "]" * 10_000, "rosbag2_bagfile_information: [1, 2]", "\udcff"):
        (run / "metadata.yaml").write_bytes(text.encode("utf-8", "surrogateescape"))
        with pytest.raises(RecordingError, match=r"metadata.yaml is not rosbag2 metadata"):
            Recording(run)
