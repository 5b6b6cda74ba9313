"""Random shortcuts of one path with a ``clear`` callable (:func:`clew_ros.core.improve.shortcut_path`): the ends
stay, the path never gets longer, every move it adds was found clear, and the same generator gives the same path."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from helpers.paths import random_path

from clew_ros.core.improve import joint_travel, shortcut_path


def _blocked_by_ball(center: np.ndarray, radius: float, checked: list[tuple[np.ndarray, np.ndarray]]):
    """``clear(starts, ends)``: a straight move is clear when no point of it (sampled at 0.01 rad) lies within
    ``radius`` (largest joint difference) of ``center``; every move asked about is kept in ``checked``."""

    def clear(starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
        out = []
        for a, b in zip(starts, ends, strict=True):
            checked.append((a.copy(), b.copy()))
            count = max(2, int(np.ceil(np.abs(b - a).max() / 0.01)) + 1)
            points = a + np.linspace(0.0, 1.0, count)[:, None] * (b - a)
            out.append(bool(np.all(np.abs(points - center).max(axis=1) > radius)))
        return np.array(out)

    return clear


def _within(a: np.ndarray, b: np.ndarray, moves: list[tuple[np.ndarray, np.ndarray]]) -> bool:
    """Whether the move ``a -> b`` lies on one of ``moves`` (a part of it: a later shortcut may start inside)."""
    return any(_on_segment(a, u, v) and _on_segment(b, u, v) for u, v in moves)


@pytest.mark.parametrize("joints", [2, 3, 7])
def test_shortcuts_keep_the_ends_never_lengthen_and_add_only_moves_found_clear(joints: int) -> None:
    rng = np.random.default_rng(joints)
    shortened = 0
    for _ in range(40):
        path = random_path(rng, joints)
        if len(path) < 3:
            continue
        checked: list[tuple[np.ndarray, np.ndarray]] = []
        center = path[len(path) // 2] + rng.normal(0.0, 0.2, joints)
        clear = _blocked_by_ball(center, 0.15, checked)
        answers: list[bool] = []

        def recorded(starts: np.ndarray, ends: np.ndarray, clear=clear, answers=answers) -> np.ndarray:
            found = clear(starts, ends)
            answers.extend(found.tolist())
            return found

        out, taken, spent, stopped = shortcut_path(recorded, path, tries=30, rng=np.random.default_rng(1))
        assert not stopped
        assert np.array_equal(out[0], path[0])
        assert np.array_equal(out[-1], path[-1])
        assert joint_travel([out]) <= joint_travel([path]) + 1e-9
        assert taken <= spent <= 30
        clear_moves = [m for m, ok in zip(checked, answers, strict=True) if ok]
        for a, b in itertools.pairwise(out):  # every move: on one of the old path's, or on one found clear
            assert _within(a, b, list(itertools.pairwise(path))) or _within(a, b, clear_moves)
        shortened += joint_travel([out]) < joint_travel([path]) - 1e-9
    assert shortened >= 10


def _on_segment(point: np.ndarray, a: np.ndarray, b: np.ndarray) -> bool:
    span = b - a
    t = float(span @ (point - a) / (span @ span)) if span @ span > 0 else 0.0
    return bool(np.allclose(a + t * span, point, atol=1e-9) and -1e-9 <= t <= 1 + 1e-9)


def test_the_same_generator_gives_the_same_path() -> None:
    rng = np.random.default_rng(7)
    for _ in range(10):
        path = random_path(rng, 4)
        clear = _blocked_by_ball(path[len(path) // 2], 0.1, [])
        one = shortcut_path(clear, path, tries=25, rng=np.random.default_rng(5))
        two = shortcut_path(clear, path, tries=25, rng=np.random.default_rng(5))
        assert np.array_equal(one[0], two[0])
        assert one[1:] == two[1:]


def test_a_clear_straight_line_is_taken_at_once_and_a_stop_ends_the_tries() -> None:
    path = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [2.0, 1.0]])
    out, taken, spent, stopped = shortcut_path(
        lambda a, b: np.ones(len(a), bool), path, tries=10, rng=np.random.default_rng(0)
    )
    assert out.tolist() == [[0.0, 0.0], [2.0, 1.0]]
    assert (taken, spent, stopped) == (1, 1, False)
    calls = []

    def stop() -> bool:
        calls.append(1)
        return len(calls) > 3

    blocked = shortcut_path(
        lambda a, b: np.zeros(len(a), bool), path, tries=10, rng=np.random.default_rng(0), stop=stop
    )
    assert np.array_equal(blocked[0], path)  # nothing clear: the path as it was
    assert blocked[1:] == (0, 3, True)
