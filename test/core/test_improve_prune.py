"""Pruning that needs no checking (:mod:`clew_ros.core.improve.prune`): a pruned path keeps its ends, visits
only waypoints of the old one and is never longer; regrasps in place are joined only when the arm did not move
and the grasp is the same, whatever else a piece carries."""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import pytest
from helpers.paths import random_path

from clew_ros.core.improve import joined_regrasps, joint_travel, plan_score, pruned_path, without_repeats


def _pruned_in_python(waypoints: np.ndarray) -> np.ndarray:
    """The pruning as it was written in Python before it was compiled (pruned_path): the reference."""
    points = np.empty_like(waypoints)
    size = 0
    for w in waypoints:
        back = np.flatnonzero(np.max(np.abs(points[:size] - w), axis=1) <= 1e-12)
        if len(back):
            size = int(back[0]) + 1
        else:
            points[size] = w
            size += 1
        while size >= 3:
            u, v = points[size - 2] - points[size - 3], points[size - 1] - points[size - 2]
            scale = max(float(np.max(np.abs(u))), float(np.max(np.abs(v))))
            if scale > 0 and float(np.max(np.abs(u * np.linalg.norm(v) ** 2 - v * (u @ v)))) > 1e-12 * scale**3:
                break
            points[size - 2] = points[size - 1]
            size -= 1
    return points[:size].copy()


@pytest.mark.parametrize("joints", [2, 3, 7])
def test_the_compiled_pruning_gives_the_paths_the_python_one_gave(joints: int) -> None:
    rng = np.random.default_rng(100 + joints)
    for _ in range(300):
        w = random_path(rng, joints)
        assert np.array_equal(pruned_path(w), _pruned_in_python(w))


@pytest.mark.parametrize("joints", [2, 3, 7])
def test_pruned_paths_keep_their_ends_visit_only_old_waypoints_and_turn_at_every_waypoint(joints: int) -> None:
    rng = np.random.default_rng(joints)
    for _ in range(200):
        w = random_path(rng, joints)
        pruned = pruned_path(w)
        assert np.array_equal(pruned[0], w[0])
        assert np.max(np.abs(pruned[-1] - w[-1])) <= 1e-12  # a loop back ends on the earlier waypoint
        assert all(np.any(np.all(w == p, axis=1)) for p in pruned)  # a waypoint of the old path, not near one
        assert joint_travel([pruned]) <= joint_travel([w]) + 1e-12
        steps = np.diff(pruned, axis=0)
        assert np.all(np.max(np.abs(steps), axis=1) > 1e-12)
        for u, v in itertools.pairwise(steps):  # no two pieces in a row along one line
            assert np.max(np.abs(u * (v @ v) - v * (u @ v))) > 1e-12 * max(np.max(np.abs(u)), np.max(np.abs(v))) ** 3


def test_pruning_drops_back_and_forth_and_loops_only() -> None:
    w = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, 0.0], [0.5, 1.0], [0.5, 2.0], [0.5, 1.5], [1.0, 1.5], [0.5, 1.5]])
    pruned = pruned_path(w)
    # 0->1->0.5 along joint 1 is one move to 0.5; 1.0->2.0->1.5 along joint 2 is one move; the loop closes
    assert pruned.tolist() == [[0.0, 0.0], [0.5, 0.0], [0.5, 1.5]]
    assert joint_travel([pruned]) < joint_travel([w])


def test_pruning_keeps_a_path_with_nothing_to_drop_and_refuses_a_flat_array() -> None:
    w = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    assert np.array_equal(pruned_path(w), w)
    assert np.array_equal(pruned_path(w.tolist()), w)  # a list is taken as an array
    with pytest.raises(ValueError, match="waypoints: expected an \\(m, n\\) array"):
        pruned_path(np.zeros(3))


def test_without_repeats_drops_only_waypoints_within_1e_12_of_the_one_before() -> None:
    w = np.array([[0.0, 0.0], [0.0, 5e-13], [1.0, 0.0], [1.0, 0.0], [0.0, 0.0]])
    assert without_repeats(w).tolist() == [[0.0, 0.0], [1.0, 0.0], [0.0, 0.0]]


@dataclass
class _Piece:
    """A piece as a space keeps it: kind, grasp, waypoints and a payload the pruning must not look at."""

    kind: str
    grasp: int | None
    waypoints: np.ndarray
    payload: object

    def with_waypoints(self, waypoints: np.ndarray) -> _Piece:
        return _Piece(self.kind, self.grasp, waypoints, self.payload)


def _regrasped(rng: np.random.Generator, joints: int = 3) -> list[_Piece]:
    """A transit to a grasp, a transfer, a transit of no motion (put down, taken again), a transfer by the same
    grasp, another still transit and a third transfer by it."""
    a, b, c, d = (rng.uniform(-2.0, 2.0, joints) for _ in range(4))
    return [
        _Piece("transit", None, np.array([a, b]), "rest 0"),
        _Piece("transfer", 1, np.array([b, (b + c) / 2, c]), "held 1"),
        _Piece("transit", None, np.array([c, c]), "rest 1"),
        _Piece("transfer", 1, np.array([c, d]), "held 2"),
        _Piece("transit", None, np.array([d]), "rest 2"),
        _Piece("transfer", 1, np.array([d, a]), "held 3"),
    ]


def test_transfers_put_down_and_taken_again_in_place_become_one_keeping_the_first_ones_payload() -> None:
    rng = np.random.default_rng(3)
    for _ in range(20):
        pieces = _regrasped(rng)
        joined = joined_regrasps(pieces, 1e-12)
        assert [(p.kind, p.grasp, p.payload) for p in joined] == [
            ("transit", None, "rest 0"),
            ("transfer", 1, "held 1"),
        ]
        expected = np.vstack([pieces[1].waypoints, pieces[3].waypoints[1:], pieces[5].waypoints[1:]])
        assert np.array_equal(joined[1].waypoints, expected)  # the arm moves exactly as before
        assert joint_travel([p.waypoints for p in joined]) == pytest.approx(joint_travel([p.waypoints for p in pieces]))
        assert plan_score(joined)[0] == plan_score(pieces)[0] - 2


def test_transfers_stay_apart_when_the_arm_moves_between_them_the_grasp_differs_or_the_next_starts_elsewhere() -> None:
    pieces = _regrasped(np.random.default_rng(4))[:4]
    c = pieces[2].waypoints[0]
    moved = _Piece("transit", None, np.array([c, c + 0.01]), "rest 1")
    other = _Piece("transfer", 2, pieces[3].waypoints, "held 2")
    elsewhere = _Piece("transfer", 1, pieces[3].waypoints + 0.01, "held 2")
    for changed in ([*pieces[:2], moved, pieces[3]], [*pieces[:3], other], [*pieces[:3], elsewhere]):
        assert joined_regrasps(changed, 1e-12) == changed
    nearly = _Piece("transit", None, np.array([c, c + 1e-13]), "rest 1")  # within same_rad: the same place
    assert len(joined_regrasps([*pieces[:2], nearly, pieces[3]], 1e-12)) == 2
