"""The core runs without the planar and the spatial worlds: :mod:`toy_space` (a point gripper in the unit
square carrying a point object over a wall, numpy only) is planned by :func:`clew_ros.core.clew.plan`, in a
process of its own that imports neither :mod:`clew_ros.planar` nor :mod:`clew_ros.spatial`."""

from __future__ import annotations

import itertools
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(HERE))

from toy_space import GOAL_TOLERANCE_M, GRASPS, WALL, ToySpace  # noqa: E402


def _outside_wall(points: np.ndarray) -> bool:
    inside = np.all((points > WALL[:2]) & (points < WALL[2:]), axis=1)
    in_square = np.all((points >= -1e-12) & (points <= 1 + 1e-12), axis=1)
    return bool(np.all(~inside & in_square))


def _samples(path: np.ndarray) -> np.ndarray:
    """Every move of ``path`` (one joint at a time) sampled every 1 mm, ends included."""
    parts = [path[:1]]
    for a, b in itertools.pairwise(path):
        assert np.count_nonzero(np.abs(b - a) > 1e-12) <= 1, f"{a} -> {b} moves both joints"
        count = max(2, int(np.ceil(np.max(np.abs(b - a)) / 1e-3)) + 1)
        parts.append(a + np.linspace(0.0, 1.0, count)[:, None] * (b - a))
    return np.vstack(parts)


def test_the_core_plans_in_a_toy_space_without_importing_planar_or_spatial() -> None:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    done = subprocess.run(
        [sys.executable, str(HERE / "toy_space.py")], capture_output=True, text=True, env=env, cwd=ROOT, timeout=120
    )
    assert done.returncode == 0, done.stdout + done.stderr
    report = json.loads(done.stdout.strip().splitlines()[-1])
    assert report["outcome"] == "SUCCEEDED", report["message"]
    assert report["packages"] == ["core"]  # clew_ros.core only: no planar, no spatial, nothing above
    assert report["landmarks"] >= 2  # EXPLORE placed a landmark, SEARCH went on from it

    space = ToySpace()
    segments = report["segments"]
    assert [kind for kind, _, _ in segments][::2] == ["transit"] * ((len(segments) + 1) // 2)
    assert np.allclose(segments[0][2][0], space.initial_joints)
    resting = space.initial_object_pose
    for kind, grasp, waypoints in segments:
        path = np.array(waypoints)
        gripper = _samples(path)
        assert _outside_wall(gripper)
        if kind == "transit":
            continue
        assert np.allclose(path[0] + GRASPS[grasp], resting, atol=1e-6)  # it holds the grasp where it rests
        assert _outside_wall(gripper + GRASPS[grasp])  # and carries the object clear of the wall
        resting = path[-1] + GRASPS[grasp]
    assert np.linalg.norm(resting - space.goal) <= GOAL_TOLERANCE_M
    assert np.allclose(report["final_object_pose"], resting)
