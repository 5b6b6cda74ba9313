"""Security: a goal flood cannot fill the disk (``record.max_runs``, ``record.max_bytes``).

Unit tests of :mod:`clew_ros.recording.retention` (no ROS): only complete
run folders (a run id's name, a real directory holding ``metadata.yaml`` and
only regular files) are counted or deleted, oldest first, never the current
run. Then a real node started with ``record.max_runs: 5`` and a flood of
goals on ``~/goal_pose``: 5 runs are left, the newest, and each deletion is
logged.
"""

from __future__ import annotations

import os
import uuid
from pathlib import Path

import pytest

from clew_ros.recording.retention import RetentionPolicy, is_run_folder, prune_runs, run_folders


def make_run(directory: Path, closed_s: int, size: int = 100, *, complete: bool = True) -> Path:
    folder = directory / uuid.uuid4().hex
    folder.mkdir()
    (folder / f"{folder.name}_0.mcap").write_bytes(b"x" * size)
    if complete:
        metadata = folder / "metadata.yaml"
        metadata.write_text("rosbag2_bagfile_information: {}\n")
        os.utime(metadata, (closed_s, closed_s))
    return folder


def test_only_complete_run_folders_are_pruned_oldest_first(tmp_path: Path) -> None:
    runs = [make_run(tmp_path, 1000 + i) for i in range(6)]
    open_run = make_run(tmp_path, 0, complete=False)  # another writer's run in progress
    current = make_run(tmp_path, 0, complete=False)
    decoys = [tmp_path / "notes", tmp_path / ("a" * 31 + "z"), tmp_path / ("b" * 32)]
    for decoy in decoys:
        decoy.mkdir()
        (decoy / "metadata.yaml").write_text("x")
    (decoys[2] / "nested").mkdir()  # a run id's name with metadata.yaml, but a folder inside: not a run
    link = tmp_path / ("c" * 32)
    link.symlink_to(runs[0])  # a link to a run: never a run itself
    outside = tmp_path.parent / f"{tmp_path.name}_outside"
    outside.mkdir()
    (outside / "keep").write_text("x")

    assert [is_run_folder(p) for p in (runs[0], open_run, *decoys, link)] == [True] + [False] * 5
    deleted = prune_runs(tmp_path, RetentionPolicy(max_runs=3), current=current.name)
    assert [d.path for d in deleted] == runs[:4]  # 2 complete runs + the current one make 3
    assert all("record.max_runs 3" in d.reason for d in deleted)
    assert run_folders(tmp_path) == runs[4:]
    for kept in (open_run, current, *decoys, link, outside / "keep"):
        assert kept.exists() or kept.is_symlink(), kept
    assert runs[0].exists() is False
    assert link.is_symlink()


def test_bytes_are_capped_and_the_current_run_is_never_deleted(tmp_path: Path) -> None:
    runs = [make_run(tmp_path, 1000 + i, size=1000) for i in range(4)]
    current = make_run(tmp_path, 0, size=10_000, complete=False)
    deleted = prune_runs(tmp_path, RetentionPolicy(max_bytes=2500), current=current.name)
    assert [d.path for d in deleted] == runs[:2]
    assert "record.max_bytes 2500" in deleted[0].reason
    assert current.exists()
    # a complete current run (the recorder closed it) is never deleted either
    current_closed = runs[3].name
    assert [d.path for d in prune_runs(tmp_path, RetentionPolicy(max_runs=1), current=current_closed)] == [runs[2]]
    assert runs[3].exists()
    assert prune_runs(tmp_path, RetentionPolicy()) == []


@pytest.mark.ros
def test_a_goal_flood_leaves_max_runs(tmp_path: Path) -> None:
    pytest.importorskip("rclpy")
    pytest.importorskip("mcap")
    from geometry_msgs.msg import PoseStamped
    from helpers.node_harness import wait_until
    from helpers.rel_node import goal_publisher, new_events, wait_event
    from helpers.security_node import quick_session

    runs = tmp_path / "runs"
    runs.mkdir()
    earlier = [make_run(runs, 1000 + i) for i in range(3)]  # left by an earlier node: the oldest go first
    unrelated = runs / "notes"
    unrelated.mkdir()
    accepted: list[str] = []
    goals = 9
    with quick_session(tmp_path / "node.log", {"record.directory": str(runs), "record.max_runs": 5}) as session:
        publisher = goal_publisher(session)
        goal = PoseStamped()
        goal.header.frame_id = "world"
        goal.pose.position.x, goal.pose.position.y = 1.8, 0.6  # rel_fast's goal
        goal.pose.orientation.w = 1.0
        for _ in range(goals):
            mark = len(session.events.messages)
            publisher.publish(goal)
            event, _ = wait_event(session, mark, lambda e: e["event"] == "accepted", 20.0)
            accepted.append(event["run_id"])
            # flood: the next goal as soon as this one is out (it stops this one's playback, never its plan)
            wait_event(session, mark, lambda e, r=event["run_id"]: e["run_id"] == r and e["event"] == "succeeded", 30.0)
            names = {p.name for p in runs.iterdir()}
            assert len(names - {"notes"}) <= 5, sorted(names)
            assert accepted[-1] in names, "the current run was deleted"
        # then a burst: most are refused (busy), those accepted each replace the oldest run
        mark = len(session.events.messages)
        for _ in range(3 * goals):
            publisher.publish(goal)

        def answered() -> int:  # each goal is accepted or refused (BUSY) with an event of its own
            return sum(e["event"] == "accepted" or e.get("code") == "BUSY" for e in new_events(session, mark))

        wait_until(lambda: answered() == 3 * goals, 30.0, "an answer to every goal")
        session.wait_idle()
        burst = [json_event["run_id"] for json_event in new_events(session, mark) if json_event["event"] == "accepted"]
        accepted += burst
    kept = sorted(p.name for p in runs.iterdir() if p.name != "notes")
    assert kept == sorted(accepted[-5:])
    assert all(is_run_folder(runs / name) for name in kept)
    assert unrelated.is_dir()
    log = session.node.output()
    deleted_lines = [line for line in log.splitlines() if "deleted the recording" in line]
    assert len(deleted_lines) == len(accepted) + len(earlier) - 5, deleted_lines
    assert str(earlier[0]) in deleted_lines[0]
    assert "record.max_runs 5" in deleted_lines[0]
    print(
        f"\n{goals} goals one after the other then {3 * goals} at once ({len(burst)} accepted) with "
        f"record.max_runs 5 and 3 runs left before: {len(deleted_lines)} oldest deleted, 5 kept"
    )
