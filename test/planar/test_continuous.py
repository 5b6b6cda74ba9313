"""The straight-move check (:mod:`clew_ros.planar.continuous`), compiled in :func:`clew_ros.planar.kernel.moves_clear`:
the same answers as the check written in Python with numpy (kept here as the reference), batches the same as
single moves, and ``every`` stops at the first move that is not clear."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from clew_ros.planar.collision import packed_carrying, packed_world
from clew_ros.planar.continuous import ContinuousSettings, straight_move_clear, straight_moves_clear
from clew_ros.planar.kernel import PackedWorld, clearly_valid
from clew_ros.planar.kinematics import compose, relative, tip_poses, transform_points
from clew_ros.planar.world import World, load_world

ROOT = Path(__file__).resolve().parents[2]


def _reach_radii(world: World, grasp_rel: np.ndarray | None) -> np.ndarray:
    lengths = np.asarray(world.robot.link_lengths, dtype=float)
    radii = np.cumsum(lengths[::-1])[::-1]
    if grasp_rel is not None:
        radii = radii + float(np.max(np.linalg.norm(transform_points(grasp_rel, world.object.polygon), axis=-1)))
    return radii


def _poses(world: World, q: np.ndarray, resting: np.ndarray, grasp_rel: np.ndarray | None) -> np.ndarray:
    if grasp_rel is None:
        return np.array(np.broadcast_to(resting, (len(q), 3)))
    return compose(tip_poses(world.robot, q), grasp_rel)


def _cleared(parts: list[tuple[PackedWorld, int]], q: np.ndarray, poses: np.ndarray, margin: float) -> np.ndarray:
    clear = np.ones(len(q), dtype=bool)
    for packed, joints in parts:
        rows = np.flatnonzero(clear)
        if len(rows):
            part = dataclasses.replace(packed, rounding=margin)
            clear[rows] = clearly_valid(part, np.ascontiguousarray(q[rows, :joints]), poses[rows])
    return clear


def _reference(
    world: World, a: np.ndarray, b: np.ndarray, resting: np.ndarray, grasp_rel: np.ndarray | None, min_margin: float
) -> bool:
    """The check as it was written in Python with numpy, before it was compiled."""
    ends = np.stack([a, b])
    if np.any(ends < world.robot.joint_lower) or np.any(ends > world.robot.joint_upper):
        return False
    packed = packed_world(world)
    if grasp_rel is None:
        parts = [(packed, world.robot.dof)]
    else:
        pose = compose(tip_poses(world.robot, a[None]), grasp_rel)
        if not clearly_valid(dataclasses.replace(packed, rounding=min_margin), a[None], pose)[0]:
            return False
        without_object, links_but_last = packed_carrying(world)
        parts = [(without_object, world.robot.dof), (links_but_last, world.robot.dof - 1)]
    tuning = ContinuousSettings()
    stride = tuning.coarse_stride
    motion = float(np.abs(b - a) @ _reach_radii(world, grasp_rel)) * (1.0 + 1e-9) + 1e-12
    level = max(0, math.ceil(math.log2(max(motion / (2.0 * tuning.max_margin_m), 1.0))))
    pending = np.arange(2**level, dtype=float)
    if len(pending) >= 2 * stride:
        t = (pending[stride // 2 :: stride] + 0.5) / 2.0**level
        q = a + t[:, None] * (b - a)
        if not clearly_valid(packed, q, _poses(world, q, resting, grasp_rel)).all():
            return False
    while len(pending):
        pieces = 2.0**level
        margin = max(motion / (2.0 * pieces), min_margin)
        t = (pending + 0.5) / pieces
        q = a + t[:, None] * (b - a)
        poses = _poses(world, q, resting, grasp_rel)
        clear = _cleared(parts, q, poses, margin)
        if clear.all():
            return True
        if margin <= min_margin or not clearly_valid(packed, q[~clear], poses[~clear]).all():
            return False
        pending = ((2.0 * pending[~clear])[:, None] + np.array([0.0, 1.0])).reshape(-1)
        level += 1
    return True


def _moves(world: World, rng: np.random.Generator, count: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """Moves from configurations near the world's start, of every length from 0.01 rad to across the limits;
    a few leave the joint limits."""
    lower, upper = world.robot.joint_lower, world.robot.joint_upper
    moves = []
    for _ in range(count):
        a = np.clip(world.robot.initial + rng.normal(0.0, 0.6, world.robot.dof), lower, upper)
        direction = rng.normal(size=world.robot.dof)
        b = a + 10.0 ** rng.uniform(-2.0, 0.8) * direction / np.abs(direction).max()
        moves.append((a, b if rng.uniform() < 0.1 else np.clip(b, lower, upper)))
    return moves


WORLDS = ["figure1", "arm3_regrasp", "arm5_regrasp"]


@pytest.mark.parametrize("name", WORLDS)
@pytest.mark.parametrize("carried", [False, True], ids=["transit", "transfer"])
def test_the_compiled_check_answers_as_the_python_one(name: str, carried: bool) -> None:
    world = load_world(ROOT / "config" / f"{name}.yaml")
    rng = np.random.default_rng(7)
    resting = np.asarray(world.object.initial, dtype=float)
    # held as the arm holds it at its start configuration (the object's start pose in the tip's frame)
    grasp_rel = relative(tip_poses(world.robot, world.robot.initial[None])[0], resting) if carried else None
    answers = {True: 0, False: 0}
    for a, b in _moves(world, rng, 300):
        for margin in (5e-4, 0.02):
            expected = _reference(world, a, b, resting, grasp_rel, margin)
            clear = straight_move_clear(
                world, a, b, object_pose=None if carried else resting, grasp_rel=grasp_rel, min_margin=margin
            )
            assert clear == expected, (a.tolist(), b.tolist(), margin)
            answers[expected] += 1
    assert min(answers.values()) >= 30  # both answers are common: the comparison means something


class _Counting:
    def __init__(self) -> None:
        self.calls = 0
        self.configurations = 0

    def spend_move_checks(self, configurations: int) -> None:
        self.calls += 1
        self.configurations += configurations

    def stop(self) -> bool:
        return False


def test_a_batch_answers_as_its_moves_one_by_one_and_every_stops_at_the_first_blocked() -> None:
    world = load_world(ROOT / "config" / "arm3_regrasp.yaml")
    moves = _moves(world, np.random.default_rng(3), 120)
    starts, ends = np.array([a for a, _ in moves]), np.array([b for _, b in moves])
    resting = world.object.initial
    alone, each = _Counting(), _Counting()
    singles = [straight_move_clear(world, a, b, object_pose=resting, min_margin=0.01, budget=each) for a, b in moves]
    batch = straight_moves_clear(world, starts, ends, object_pose=resting, min_margin=0.01, budget=alone)
    assert batch.tolist() == singles
    assert 0 < sum(singles) < len(singles)
    assert (alone.calls, each.calls) == (1, len(moves))  # one call of the compiled check for the batch
    assert alone.configurations == each.configurations > 0
    first_blocked = singles.index(False)
    counted = _Counting()
    every = straight_moves_clear(world, starts, ends, object_pose=resting, min_margin=0.01, budget=counted, every=True)
    assert every.tolist() == singles[:first_blocked] + [False] * (len(moves) - first_blocked)
    assert counted.configurations < alone.configurations  # the moves after it were not checked


def test_a_budget_that_says_stop_gets_no_move_checked() -> None:
    world = load_world(ROOT / "config" / "figure1.yaml")

    class Stopped(_Counting):
        def stop(self) -> bool:
            return True

    stopped = Stopped()
    a = world.robot.initial
    assert not straight_move_clear(world, a, a + 0.01, object_pose=world.object.initial, min_margin=0.0, budget=stopped)
    assert stopped.calls == 0
    assert straight_move_clear(world, a, a + 0.01, object_pose=world.object.initial, min_margin=0.0)


def test_moves_of_the_wrong_shape_or_without_a_mode_are_refused_by_name() -> None:
    world = load_world(ROOT / "config" / "figure1.yaml")
    rest = world.object.initial
    with pytest.raises(ValueError, match="starts, ends"):
        straight_moves_clear(world, np.zeros((2, 2)), np.zeros((3, 2)), object_pose=rest, min_margin=0.01)
    with pytest.raises(ValueError, match="starts, ends"):
        straight_moves_clear(world, np.zeros((2, 3)), np.zeros((2, 3)), object_pose=rest, min_margin=0.01)
    with pytest.raises(ValueError, match="grasp_rel"):
        straight_move_clear(world, np.zeros(2), np.zeros(2), min_margin=0.01)
