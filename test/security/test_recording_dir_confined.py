"""Security: recordings stay where the node was told at start (a real node in a subprocess).

``record.directory`` is resolved once at start: ``~`` is expanded, an
environment variable is not (a ``$`` is refused: the node does not start,
naming the parameter, and creates nothing); ``..`` and symbolic links are
resolved, so nothing is created on the way and the answers name the
resolved folder; a symbolic link changed later does not move the
recordings. Run folders get mode 0700 and their files 0600 whatever the
umask, as do the folders the node creates for the directory.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

rclpy = pytest.importorskip("rclpy")
pytest.importorskip("mcap")

from helpers.node_harness import Session, wait_until  # noqa: E402
from helpers.security_node import plan_and_wait, quick_session, start_quick  # noqa: E402

pytestmark = pytest.mark.ros

#: How long a node that refuses its parameters takes to exit (kernel warm-up from numba's cache included).
STARTUP_EXIT_S = 60.0


def files_under(path: Path) -> list[Path]:
    return sorted(p for p in path.rglob("*") if p.name != "node.log")


def mode(path: Path) -> int:
    return stat.S_IMODE(path.lstat().st_mode)


def test_an_environment_variable_is_not_expanded(tmp_path: Path) -> None:
    home = tmp_path / "home"
    secret = home / "secret"
    secret.mkdir(parents=True)
    node = start_quick(
        tmp_path / "node.log",
        {"record.directory": "$CLEW_SECRET/runs"},
        env={"HOME": str(home), "CLEW_SECRET": str(secret)},
    )
    try:
        code = node.proc.wait(timeout=STARTUP_EXIT_S)
    finally:
        node.stop()
    output = node.output()
    assert code == 2, output
    assert "record.directory: expected a path without '$'" in output, output
    assert str(secret) not in output  # the variable's value is never printed
    assert not any(secret.iterdir()), "the node created something where the variable points"
    assert not list(Path.cwd().glob("$*")), "the node created a folder named after the variable"


def test_dot_dot_and_links_are_resolved_once(tmp_path: Path) -> None:
    target, other = tmp_path / "target", tmp_path / "other"
    target.mkdir()
    other.mkdir()
    link = tmp_path / "link"
    link.symlink_to(target)
    given = tmp_path / "stray" / ".." / "link" / "runs"  # 'stray' does not exist
    with quick_session(tmp_path / "node.log", {"record.directory": str(given)}) as session:
        response, run_id = plan_and_wait(session)
        assert response.success, response.message
        resolved = target.resolve() / "runs"
        assert f"recording {resolved / run_id}" in response.message, response.message
        assert not (tmp_path / "stray").exists(), "a folder was created on the way"
        wait_until((resolved / run_id / "metadata.yaml").is_file, 10.0, "the closed recording")

        # the link now points elsewhere: the node recorded where it resolved at start
        link.unlink()
        link.symlink_to(other)
        response, run_id = plan_and_wait(session)
        assert response.success, response.message
        assert f"recording {resolved / run_id}" in response.message, response.message
        assert files_under(other) == [], files_under(other)

        # the resolved folder itself swapped for a link elsewhere: not followed, the run not recorded
        resolved.rename(target / "moved")
        resolved.symlink_to(other)
        response, run_id = plan_and_wait(session)
        assert response.success, response.message
        assert "not recorded" in response.message, response.message
        assert "a symbolic link changed" in response.message, response.message
        assert files_under(other) == [], files_under(other)
        check_events_name_the_folder(session, run_id, None)


def check_events_name_the_folder(session: Session, run_id: str, folder: Path | None) -> None:
    accepted = next(e for e in session.events_of(run_id) if e["event"] == "accepted")
    assert accepted["recording_path"] == (None if folder is None else str(folder)), accepted


def test_modes_are_private_whatever_the_umask(tmp_path: Path) -> None:
    runs = tmp_path / "made" / "by" / "node"
    with quick_session(tmp_path / "node.log", {"record.directory": str(runs)}, umask=0o002) as session:
        response, run_id = plan_and_wait(session)
        assert response.success, response.message
        folder = runs.resolve() / run_id
        wait_until((folder / "metadata.yaml").is_file, 10.0, "the closed recording")
        check_events_name_the_folder(session, run_id, folder)
    made = [tmp_path / "made", tmp_path / "made" / "by", runs]
    assert {str(p): oct(mode(p)) for p in [*made, folder]} == {str(p): "0o700" for p in [*made, folder]}
    files = list(folder.iterdir())
    assert {p.name.rsplit("_", 1)[-1] for p in files} == {"metadata.yaml", "0.mcap"}
    assert {p.name: oct(mode(p)) for p in files} == {p.name: "0o600" for p in files}
    assert os.access(folder / "metadata.yaml", os.R_OK)
