"""Helpers of the security tests that start a ``clew_planner`` (test/security/test_node_*, test_recording_dir_*).

Built on :mod:`node_harness`: :func:`start_quick` starts the node in a
subprocess on the reliability tests' quick world (a plan in about 0.1 s, a
short playback) with a recording directory and any other start values;
:func:`plan_and_wait` asks ``~/plan`` and waits for the playback's end, so
that the next request starts a new run at once.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from helpers.node_harness import NodeProcess, Session, run_id_of

__all__ = ["FAST", "QUICK_WORLD", "plan_and_wait", "quick_session", "start_quick"]

ROOT = Path(__file__).resolve().parents[2]
QUICK_WORLD = ROOT / "test" / "worlds" / "rel_fast.yaml"
#: A quick playback, so that runs follow each other fast.
FAST = {
    "trajectory.max_velocity": 20.0,
    "trajectory.max_acceleration": 400.0,
    "playback.rate": 50.0,
    "trajectory.grasp_dwell": 0.02,
}


def start_quick(log: Path, parameters: dict[str, Any], *, env: dict[str, str] | None = None) -> NodeProcess:
    """``clew_planner`` on the quick world with :data:`FAST` and ``parameters`` (they win)."""
    return NodeProcess(log, QUICK_WORLD, {**FAST, **parameters}, env=env)


@contextlib.contextmanager
def quick_session(log: Path, parameters: dict[str, Any], *, umask: int | None = None) -> Iterator[Session]:
    """A :class:`Session` on :func:`start_quick`'s node, closed (and its exit code checked) at the end.

    ``umask``: the node process starts with it (the test process's is restored at once).
    """
    previous = os.umask(umask) if umask is not None else None
    try:
        node = start_quick(log, parameters)
    finally:
        if previous is not None:
            os.umask(previous)
    session = Session(node)
    try:
        yield session
    finally:
        code = session.close()
        assert code == 0, f"node exit code {code}; output:\n{session.node.output()}"


def plan_and_wait(session: Session, timeout_s: float = 30.0) -> tuple[Any, str]:
    """``~/plan``'s answer and its run id, once the run's playback (if it succeeded) is over."""
    response = session.plan(timeout_s=timeout_s)
    run_id = run_id_of(response.message)
    if response.success:
        session.wait_playback(run_id)
    return response, run_id
