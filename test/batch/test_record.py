"""``clew_batch --record``: one recording per job, read back with :class:`clew_ros.recording.Recording`; resume
redoes a job whose recording is gone; the plan files are those of a batch without ``--record``; without ROS,
``--record`` exits 2 at once."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers.batch_cli import CONFIG, ROOT, index_lines, run_batch_cli, without_wall_time

pytest.importorskip("rclpy", reason="--record needs rclpy (the ros extra)")
pytest.importorskip("mcap_ros2", reason="reading recordings back needs mcap-ros2-support")

from clew_ros.core.plan import Plan
from clew_ros.planar.world import load_world
from clew_ros.recording import Recording, trajectory_to_plan

SINGLE = CONFIG / "single_transfer.yaml"
#: Topics of interface.md §3 a recorded job holds (the node's names).
TOPICS = {
    "/clew_planner/status",
    "/clew_planner/world_markers",
    "/clew_planner/robot_description",
    "/clew_planner/trajectory",
    "/clew_planner/joint_states",
    "/clew_planner/object_pose",
    "/clew_planner/scene",
    "/clew_planner/landmarks",
    "/clew_planner/events",
    "/tf",
    "/tf_static",
}


def _args(out: Path, *more: object) -> list[object]:
    return [SINGLE, "--seeds", 2, "--out", out, "--jobs", 2, "--time-limit", 10, "--quiet", *more]


def _check_recording(out: Path, record: dict[str, object]) -> None:
    """The job's recording holds its run: the topics, its plan as the trajectory, TF, the grasp events."""
    folder = out / str(record["recording"])
    assert (folder / "metadata.yaml").is_file()
    recording = Recording(folder)
    assert recording.complete
    assert recording.bag_metadata is not None
    assert set(recording.topics) >= TOPICS
    assert all(recording.topics[topic].message_count > 0 for topic in TOPICS)

    world = load_world(SINGLE)
    plan = Plan.read(out / str(record["plan"]))
    events = [json.loads(m.data) for m in recording.decoded("/clew_planner/events")]
    grasps = [e["grasp"] for e in events if e["event"] == "grasp"]
    assert grasps == [s.grasp for s in plan.segments if s.kind == "transfer"]
    assert next(e["event"] for e in events if e["event"] in ("grasp", "ungrasp", "succeeded")) == "succeeded"
    assert {e["run_id"] for e in events} == {recording.bag_metadata["custom_data"]["run_id"]}

    trajectory = recording.last("/clew_planner/trajectory")
    rebuilt = trajectory_to_plan(world, trajectory, grasps=grasps, strict=True)
    assert [(s.kind, s.grasp) for s in rebuilt.segments] == [(s.kind, s.grasp) for s in plan.segments]
    for mine, theirs in zip(rebuilt.segments, plan.segments, strict=True):
        np.testing.assert_array_equal(mine.waypoints, theirs.waypoints)
    assert plan.final_object_pose is not None
    assert rebuilt.final_object_pose is not None
    np.testing.assert_allclose(rebuilt.final_object_pose, plan.final_object_pose, atol=1e-9)

    tf = recording.decoded("/tf")
    assert all(message.transforms for message in tf)
    children = {t.child_frame_id for message in tf for t in message.transforms}
    assert {"link_1", "link_2", "object"} <= children
    static = {t.child_frame_id for t in recording.last("/tf_static").transforms}
    assert {"base_link", "tool"} <= static
    # the playback ends where the plan ends, with the object at its final pose
    last_joints = recording.last("/clew_planner/joint_states")
    np.testing.assert_allclose(last_joints.position[:2], plan.segments[-1].waypoints[-1], atol=1e-9)
    last_pose = recording.last("/clew_planner/object_pose").pose.position
    np.testing.assert_allclose([last_pose.x, last_pose.y], plan.final_object_pose[:2], atol=1e-6)


def test_record_writes_one_recording_per_job_and_resume_redoes_a_lost_one(tmp_path: Path) -> None:
    out = tmp_path / "recorded"
    done = run_batch_cli(*_args(out, "--record"))
    assert done.returncode == 0, done.stderr
    records = {r["job"]: r for r in index_lines(out)}
    assert sorted(records) == ["single_transfer/seed_0000", "single_transfer/seed_0001"]
    for key, record in records.items():
        assert record["success"] is True
        assert record["recording"] == f"recordings/{key}"
        _check_recording(out, record)
    assert sorted(p.name for p in (out / "recordings" / "single_transfer").iterdir()) == ["seed_0000", "seed_0001"]

    # a lost recording: that job runs again; the other is left alone
    kept = out / "recordings" / "single_transfer" / "seed_0000"
    kept_files = {p.name: p.stat().st_mtime_ns for p in kept.iterdir()}
    lost = out / "recordings" / "single_transfer" / "seed_0001"
    for path in lost.iterdir():
        path.unlink()
    lost.rmdir()
    again = run_batch_cli(*_args(out, "--record"))
    assert again.returncode == 0, again.stderr
    assert "1 by an earlier run, 1 now" in again.stderr
    lines = index_lines(out)
    assert len(lines) == 3
    assert lines[-1]["job"] == "single_transfer/seed_0001"
    _check_recording(out, lines[-1])
    assert {p.name: p.stat().st_mtime_ns for p in kept.iterdir()} == kept_files

    # without --record the recordings are not asked for: nothing to do
    plain = run_batch_cli(*_args(out))
    assert plain.returncode == 0, plain.stderr
    assert "2 by an earlier run, 0 now" in plain.stderr

    # the same jobs without --record make the same plan files (all but the planner's wall time)
    unrecorded = tmp_path / "unrecorded"
    assert run_batch_cli(*_args(unrecorded)).returncode == 0
    assert not (unrecorded / "recordings").exists()
    assert all(r["recording"] is None for r in index_lines(unrecorded))
    for key in records:
        recorded_text = (out / "plans" / f"{key}.json").read_text()
        assert without_wall_time(recorded_text) == without_wall_time((unrecorded / "plans" / f"{key}.json").read_text())

    # a batch done without --record is not done for --record: the jobs run again, now recorded
    upgraded = run_batch_cli(*_args(unrecorded, "--record"))
    assert upgraded.returncode == 0, upgraded.stderr
    assert "0 by an earlier run, 2 now" in upgraded.stderr
    assert all(r["recording"] for r in index_lines(unrecorded)[-2:])


def test_record_without_ros_exits_2_naming_the_option(tmp_path: Path) -> None:
    # rclpy made unimportable in a fresh interpreter, as on a machine without the ros extra
    code = (
        "import sys; sys.modules['rclpy'] = None; from clew_ros.cli.batch import main; "
        f"raise SystemExit(main([{str(SINGLE)!r}, '--seeds', '1', '--out', {str(tmp_path / 'out')!r}, '--record']))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert done.returncode == 2, done.stderr
    assert "--record" in done.stderr
    assert "pip install 'clew_ros[ros]'" in done.stderr
    assert "Traceback" not in done.stderr
    assert not (tmp_path / "out").exists()  # at once: nothing planned, nothing written


def test_record_with_a_bad_playback_parameter_exits_2_naming_it(tmp_path: Path) -> None:
    """A world file whose node parameters cannot time a playback is refused before any job runs (without
    ``--record`` they are not used, and the same file plans)."""
    import yaml

    tree = yaml.safe_load(SINGLE.read_text())
    tree["clew_planner"]["ros__parameters"].setdefault("playback", {})["rate"] = -2.0
    world = tmp_path / "bad_rate.yaml"
    world.write_text(yaml.safe_dump(tree))
    out = tmp_path / "out"
    done = run_batch_cli(world, "--seeds", 1, "--out", out, "--record", "--quiet")
    assert done.returncode == 2, done.stderr
    assert "playback.rate" in done.stderr
    assert str(world) in done.stderr
    assert "Traceback" not in done.stderr
    assert not index_lines(out)  # nothing planned
    plain = run_batch_cli(world, "--seeds", 1, "--out", out, "--quiet", "--time-limit", 10)
    assert plain.returncode == 0, plain.stderr
    assert len(index_lines(out)) == 1


def test_a_recording_that_fails_in_the_worker_keeps_the_plan(tmp_path: Path) -> None:
    """The worker's recording raises: the plan found is kept (not retried, not INTERNAL_ERROR) and the
    driver records the run from it."""
    from helpers.batch_faults import unrecordable_job

    from clew_ros.batch.executors import LocalPool
    from clew_ros.batch.jobs import load_worlds, make_jobs
    from clew_ros.batch.runner import run_batch

    jobs = make_jobs(load_worlds([SINGLE.resolve()]), [0], time_limit_s=10)
    out = tmp_path / "out"
    report = run_batch(jobs, out, LocalPool(1, job_function=unrecordable_job), record=True)
    assert report.complete
    [record] = index_lines(out)
    assert record["code"] == "SUCCEEDED"
    assert record["attempts"] == 1
    _check_recording(out, record)


SPATIAL = CONFIG / "spatial" / "panda_table_to_table.yaml"
#: Topics a recorded spatial pick-and-place job holds (interface.md section 3's spatial paragraph).
SPATIAL_TOPICS = TOPICS | {"/clew_planner/world_yaml", "/clew_planner/goal_pose"}


def test_record_a_spatial_world_as_the_node_records_it(tmp_path: Path) -> None:
    """A spatial job's recording holds its world (with absolute file paths), every URDF joint's states, and the
    ``succeeded`` event's segments from which ``~/trajectory`` gives back the plan file's plan; ``clew_render``'s
    reader draws it as a recorded spatial run."""
    from clew_ros.recording import spatial_trajectory_plan
    from clew_ros.render.spatial.recording import spatial_recording

    out = tmp_path / "spatial"
    done = run_batch_cli(SPATIAL, "--seeds", 1, "--out", out, "--jobs", 1, "--time-limit", 20, "--quiet", "--record")
    assert done.returncode == 0, done.stderr
    (record,) = index_lines(out)
    assert record["success"] is True, record
    folder = out / str(record["recording"])
    recording = Recording(folder)
    assert recording.complete
    assert set(recording.topics) >= SPATIAL_TOPICS
    assert all(recording.topics[topic].message_count > 0 for topic in SPATIAL_TOPICS)

    plan = Plan.read(out / str(record["plan"]))
    events = [json.loads(m.data) for m in recording.decoded("/clew_planner/events")]
    succeeded = next(e for e in events if e["event"] == "succeeded")
    rebuilt = spatial_trajectory_plan(
        recording.last("/clew_planner/trajectory"), succeeded, succeeded["message"], plan.world
    )
    assert [(s.kind, s.grasp) for s in rebuilt.segments] == [(s.kind, s.grasp) for s in plan.segments]
    for mine, theirs in zip(rebuilt.segments, plan.segments, strict=True):
        # the track holds the plan's waypoints and the timed samples between them
        np.testing.assert_allclose(mine.waypoints[[0, -1]], theirs.waypoints[[0, -1]], atol=1e-9)
    assert plan.final_object_pose is not None
    assert rebuilt.final_object_pose is not None
    # the track's object pose is the tool's forward kinematics times the grasp (as the node's): within 1e-6
    np.testing.assert_allclose(rebuilt.final_object_pose, plan.final_object_pose, atol=1e-6)
    grasps = [e["grasp"] for e in events if e["event"] == "grasp"]
    assert grasps == [s.grasp for s in plan.segments if s.kind == "transfer"]

    # every movable joint of the URDF (the fingers too) on ~/joint_states; the world's files named absolute
    names = set(recording.last("/clew_planner/joint_states").name)
    assert {f"panda_joint{i}" for i in range(1, 8)} <= names
    world_yaml = recording.last("/clew_planner/world_yaml").data
    assert str((CONFIG / "robots" / "panda" / "panda.urdf").resolve()) in world_yaml

    run = spatial_recording(folder)
    assert run is not None
    assert "succeeded" in run.frames.title
    np.testing.assert_allclose(run.frames.joints[-1], plan.segments[-1].waypoints[-1], atol=1e-9)


def test_record_a_spatial_motion_only_query(tmp_path: Path) -> None:
    """A motion-only query's recording has no object: no ``~/goal_pose`` or ``~/object_pose``; its trajectory
    and the ``succeeded`` event give back the plan, ending at ``world.robot.goal``."""
    from clew_ros.recording import spatial_trajectory_plan

    out = tmp_path / "motion"
    world_file = CONFIG / "spatial" / "panda_scene_motion.yaml"
    done = run_batch_cli(world_file, "--seeds", 1, "--out", out, "--jobs", 1, "--time-limit", 20, "--quiet", "--record")
    assert done.returncode == 0, done.stderr
    (record,) = index_lines(out)
    assert record["success"] is True, record
    recording = Recording(out / str(record["recording"]))
    assert not {"/clew_planner/goal_pose", "/clew_planner/object_pose"} & set(recording.topics)
    plan = Plan.read(out / str(record["plan"]))
    succeeded = next(
        e
        for e in map(json.loads, (m.data for m in recording.decoded("/clew_planner/events")))
        if e["event"] == "succeeded"
    )
    rebuilt = spatial_trajectory_plan(recording.last("/clew_planner/trajectory"), succeeded, "", plan.world)
    assert rebuilt.final_object_pose is None
    assert [s.kind for s in rebuilt.segments] == [s.kind for s in plan.segments] == ["transit"]
    np.testing.assert_allclose(rebuilt.segments[-1].waypoints[-1], plan.segments[-1].waypoints[-1], atol=1e-9)
