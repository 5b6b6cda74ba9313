"""Security: the recorder itself (no ROS graph) makes private files, only directly inside its directory.

Whatever the umask, a run folder is 0700 and its files (the MCAP file,
``metadata.yaml``) 0600; a run id that is not a plain name is refused before
anything is created; a ``metadata.yaml`` is never written through a symbolic
link left in the run folder.
"""

from __future__ import annotations

import contextlib
import os
import stat
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest

pytest.importorskip("rclpy")
pytest.importorskip("mcap")

from clew_ros.recording import RecordingError, RunRecorder
from clew_ros.recording.recorder import write_bag_metadata


@contextlib.contextmanager
def umask(mask: int) -> Iterator[None]:
    previous = os.umask(mask)
    try:
        yield
    finally:
        os.umask(previous)


def mode(path: Path) -> int:
    return stat.S_IMODE(path.lstat().st_mode)


@pytest.mark.parametrize("mask", [0o000, 0o022], ids=["umask_000", "umask_022"])
def test_a_run_is_private_whatever_the_umask(tmp_path: Path, mask: int) -> None:
    run_id = uuid.uuid4().hex
    with umask(mask):
        recorder = RunRecorder(tmp_path, run_id)
        folder = recorder.close()
    assert folder == tmp_path / run_id
    assert mode(folder) == 0o700
    files = sorted(folder.iterdir())
    assert [p.name for p in files] == [f"{run_id}_0.mcap", "metadata.yaml"]
    assert [mode(p) for p in files] == [0o600, 0o600]


@pytest.mark.parametrize("run_id", ["../escape", "..", "a/b", "a\\b", "", "nul\0"])
def test_a_run_id_that_is_not_a_plain_name_is_refused(tmp_path: Path, run_id: str) -> None:
    inside = tmp_path / "runs"
    inside.mkdir()
    with pytest.raises(RecordingError, match="cannot name a directory"):
        RunRecorder(inside, run_id)
    assert list(tmp_path.rglob("*")) == [inside]


def test_metadata_is_never_written_through_a_link(tmp_path: Path) -> None:
    victim = tmp_path / "victim"
    victim.write_text("kept")
    folder = tmp_path / "run"
    folder.mkdir()
    (folder / "metadata.yaml.tmp").symlink_to(victim)  # a leftover, or planted
    write_bag_metadata(folder, {"version": 9})
    assert victim.read_text() == "kept"
    assert mode(folder / "metadata.yaml") == 0o600
    assert not (folder / "metadata.yaml").is_symlink()
