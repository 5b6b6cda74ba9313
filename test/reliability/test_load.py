"""Reliability under load (marked slow: ``make test PYTEST_ARGS='-m slow'``; the default run leaves it out).

On the quick ``rel_fast`` world (a plan in about 0.15 s):

- 500 sequential ``~/plan`` calls, with recording off and with recording on:
  every call succeeds, ``~/status`` and ``~/cancel`` keep answering, and the
  node's threads (``/proc/<pid>/task``), open files (``/proc/<pid>/fd``) and
  resident memory (``VmRSS``) do not grow (RSS within :data:`RSS_GROWTH_BOUND_KIB`
  after a warm-up);
- a burst of 100 ``~/goal_pose`` messages within one second: every goal is
  answered (a run, or a BUSY refusal), never two runs planning at once, and
  the node still answers ``~/status``, ``~/cancel`` and ``~/plan``.

Figures are printed (``-s``) and kept in docs/reliability.md.
"""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

rclpy = pytest.importorskip("rclpy")


from action_msgs.msg import GoalStatus  # noqa: E402
from helpers.node_harness import NodeProcess, Session, kv, run_id_of, wait_future  # noqa: E402
from helpers.rel_node import ProcessStats, goal_publisher, settled_stats, status_is  # noqa: E402
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402
from std_msgs.msg import String  # noqa: E402
from std_srvs.srv import Trigger  # noqa: E402

from clew_ros.node.main import EXECUTOR_THREADS  # noqa: E402
from clew_ros.ros import messages  # noqa: E402

pytestmark = [pytest.mark.ros, pytest.mark.slow]

WORLD = Path(__file__).parents[1] / "worlds" / "rel_fast.yaml"
FAST = {
    "trajectory.max_velocity": 20.0,
    "trajectory.max_acceleration": 400.0,
    "playback.rate": 50.0,
    "trajectory.grasp_dwell": 0.02,
}
PLANS = 500
WARM_UP = 50  # runs before the baseline sample: caches (scene per world, rclpy, numpy) fill up
#: Largest RSS growth (KiB) from the warmed-up baseline to the end of the 500 runs.
RSS_GROWTH_BOUND_KIB = 32 * 1024
#: ~/status and ~/cancel must answer within this (s) while the load runs (DDS included: its delivery
#: jitters by hundreds of ms on a busy machine, and a reliable message repaired after a loss takes longer):
#: the bound catches a node that stops answering, not a slow one (the printed figures say how fast).
RESPONSIVE_S = 5.0
BURST = 100
DEEP = QoSProfile(
    depth=2000,
    history=HistoryPolicy.KEEP_LAST,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)


def start(tmp_path: Path, record: bool) -> Session:
    node = NodeProcess(
        tmp_path / "node.log", WORLD, {"record.enabled": record, "record.directory": str(tmp_path / "runs"), **FAST}
    )
    session = Session(node)
    session.runs = tmp_path / "runs"
    session.recording = record
    session.deep_events = session.client.inbox(f"{node.name}/events", String, DEEP)
    return session


def stop(session: Session) -> None:
    code = session.close()
    assert code == 0, f"node exit code {code}; output:\n{session.node.output()[-4000:]}"


@pytest.fixture(params=[False, True], ids=["record_off", "record_on"])
def loaded(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[Session]:
    session = start(tmp_path, request.param)
    try:
        yield session
    finally:
        stop(session)


@pytest.fixture
def quick(tmp_path: Path) -> Iterator[Session]:
    session = start(tmp_path, False)
    try:
        yield session
    finally:
        stop(session)


def wait_idle(session: Session, timeout_s: float = 30.0) -> None:
    """Wait until the last accepted run has its outcome and, after a success, its playback has ended.

    (The harness's ``Session.wait_idle`` looks every run up in ``~/status``, which lists the last 100 only.)
    """
    events = [json.loads(m.data) for m in session.deep_events.messages]
    accepted = [e["run_id"] for e in events if e["event"] == "accepted"]
    if not accepted:
        return
    run_id = accepted[-1]
    outcome = session.deep_events.wait_for(
        lambda m: (
            json.loads(m.data)["run_id"] == run_id
            and json.loads(m.data)["event"] in ("succeeded", "aborted", "canceled")
        ),
        timeout_s,
    )
    if json.loads(outcome.data)["event"] == "succeeded":
        session.feedback.wait_for(
            lambda m: kv(m).get("run_id") == run_id and kv(m).get("phase", "").startswith("playback_"), timeout_s
        )


def responsive(session: Session, run_id: str) -> tuple[float, float]:
    """~/status shows the run's outcome and ~/cancel answers; returns both latencies (s)."""
    sent = time.monotonic()
    session.status.wait_for(status_is(run_id, GoalStatus.STATUS_SUCCEEDED), RESPONSIVE_S * 4)
    status_latency = time.monotonic() - sent
    sent = time.monotonic()
    session.client.call(session.srv("cancel"), Trigger, timeout_s=RESPONSIVE_S * 4)  # playback, or nothing
    return status_latency, time.monotonic() - sent


def test_500_sequential_plans(loaded: Session) -> None:
    pid = loaded.node.proc.pid
    latencies, cancels, durations = [], [], []
    baseline = middle = None
    started = time.monotonic()
    for k in range(PLANS):
        if k == WARM_UP:
            wait_idle(loaded)
            baseline = settled_stats(pid, ProcessStats(10**6, 10**6, 0))
        if k == (WARM_UP + PLANS) // 2:
            wait_idle(loaded)
            middle = settled_stats(pid, baseline)
        sent = time.monotonic()
        response = loaded.client.call(loaded.srv("plan"), Trigger, timeout_s=30.0)
        durations.append(time.monotonic() - sent)
        assert response.success, f"call {k}: {response.message}"
        if k % 25 == 24:
            status_latency, cancel_latency = responsive(loaded, run_id_of(response.message))
            latencies.append(status_latency)
            cancels.append(cancel_latency)
    total = time.monotonic() - started
    wait_idle(loaded)
    final = settled_stats(pid, baseline)
    figures = (
        f"{PLANS} plans (recording {'on' if loaded.recording else 'off'}) in {total:.0f} s, "
        f"call median {1000 * np.median(durations):.0f} ms / max {1000 * max(durations):.0f} ms; "
        f"status <= {1000 * max(latencies):.0f} ms, cancel <= {1000 * max(cancels):.0f} ms; "
        f"threads {baseline.threads} -> {final.threads}, fds {baseline.fds} -> {final.fds}, "
        f"RSS {baseline.rss_kib} -> {middle.rss_kib} (run {(WARM_UP + PLANS) // 2}) -> {final.rss_kib} KiB "
        f"({(final.rss_kib - baseline.rss_kib) / 1024:+.1f} MiB); "
        f"call p99 {1000 * np.percentile(durations[1:], 99):.0f} ms (the first call waits for discovery)"
    )
    print("\n" + figures)
    # the executor's pool starts its (at most EXECUTOR_THREADS) threads lazily; a leak would add one per run
    assert final.threads <= baseline.threads + EXECUTOR_THREADS, figures
    assert final.fds <= baseline.fds, figures
    assert final.rss_kib - baseline.rss_kib < RSS_GROWTH_BOUND_KIB, figures
    assert max(latencies) < RESPONSIVE_S, figures
    assert max(cancels) < RESPONSIVE_S, figures
    if loaded.recording:
        runs = [p for p in loaded.runs.iterdir() if p.is_dir()]
        assert len(runs) == PLANS
        assert all((p / "metadata.yaml").is_file() for p in runs)


def test_burst_of_goal_poses(quick: Session) -> None:
    loaded = quick
    pid = loaded.node.proc.pid
    warm = loaded.plan()  # warm up, then a baseline
    assert warm.success, warm.message
    loaded.wait_playback(run_id_of(warm.message), 30.0)
    baseline = settled_stats(pid, ProcessStats(10**6, 10**6, 0))
    publisher = goal_publisher(loaded, DEEP)  # probed: its messages reach the node
    goals = [np.array([1.8 + 0.05 * np.sin(k), 0.6 + 0.05 * np.cos(k), 0.0]) for k in range(BURST)]
    mark = len(loaded.deep_events.messages)
    started = time.monotonic()
    for k, goal in enumerate(goals):
        publisher.publish(messages.goal_pose_stamped(goal, 0))
        pause = started + (k + 1) / BURST - time.monotonic()  # spread over one second
        if pause > 0:
            time.sleep(pause)
    sent_in = time.monotonic() - started

    # during and right after the burst, the node answers ~/cancel and ~/status
    sent = time.monotonic()
    wait_future(loaded.client.call_async(loaded.srv("cancel"), Trigger), RESPONSIVE_S * 4, "~/cancel")
    cancel_latency = time.monotonic() - sent

    def answered() -> list[dict]:
        events = [json.loads(m.data) for m in loaded.deep_events.messages[mark:]]
        return [e for e in events if e.get("source") == "goal_pose" and e["event"] in ("accepted", "aborted")]

    deadline = time.monotonic() + 30.0
    while len(answered()) < BURST and time.monotonic() < deadline:
        time.sleep(0.05)
    events = [json.loads(m.data) for m in loaded.deep_events.messages[mark:]]
    got = answered()
    accepted = [e["run_id"] for e in got if e["event"] == "accepted"]
    busy = [e for e in got if e["event"] == "aborted"]
    # one run at a time: between a run's acceptance and its outcome no other run is accepted
    open_run = None
    for e in events:
        if e["event"] == "accepted":
            assert open_run is None, f"run {e['run_id']} accepted while {open_run} was planning"
            open_run = e["run_id"]
        elif e["event"] in ("succeeded", "aborted", "canceled") and e["run_id"] == open_run:
            open_run = None
    wait_idle(loaded)
    final = settled_stats(pid, baseline)
    figures = (
        f"burst: {BURST} goal poses sent in {sent_in:.2f} s; answered {len(got)} "
        f"({len(accepted)} runs, {len(busy)} BUSY); cancel answered in {1000 * cancel_latency:.0f} ms; "
        f"threads {baseline.threads} -> {final.threads}, fds {baseline.fds} -> {final.fds}"
    )
    print("\n" + figures)
    assert len(got) == BURST, figures
    assert all(e["code"] == "BUSY" for e in busy), figures
    assert cancel_latency < RESPONSIVE_S, figures
    assert final.threads <= baseline.threads + EXECUTOR_THREADS, figures
    assert final.fds <= baseline.fds, figures
    after = loaded.plan()  # and the next plan works
    assert after.success, after.message
