"""Continuous joints (interface.md section 1b): an angle without limits, equal modulo 2 pi, a move between two
values taking the short way round.

A plan's straight piece from ``a`` to ``b`` turns each continuous joint by ``remainder(b - a, 2 pi)`` (the
short way; :func:`short_way`), every other joint by ``b - a``. The planner's own pieces are straight in the
joint values it checked; :func:`split_turns` cuts any piece that turns a continuous joint by more than
:attr:`TurnSettings.largest_turn_rad` into equal straight parts, so that the short way and the straight line
are one motion and a plan reads the same to the validator and to a controller. :func:`unwrapped` writes a path so that
consecutive points differ by less than pi on the continuous joints (what a ``joint_trajectory_controller``,
which interpolates the values it is given, needs); :func:`joint_gaps` is the distance modulo 2 pi;
:func:`goal_turns` lists a goal's values modulo 2 pi that lie within the joint limits (each a goal the
search may reach); :func:`joint_features` turns joints into points whose distances are taken modulo 2 pi
(EXPLORE's landmark distances).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "TURNS",
    "TurnSettings",
    "goal_turns",
    "joint_features",
    "joint_gaps",
    "nearest_turns",
    "short_way",
    "split_turns",
    "turnable",
    "unwrapped",
    "wrapped",
]

Array = NDArray[np.float64]
TURN = 2.0 * math.pi


@dataclass(frozen=True)
class TurnSettings:
    """How a plan's continuous joints turn."""

    #: The largest turn of a continuous joint between two waypoints of a plan (rad): below pi, so that the
    #: short way is the straight line.
    largest_turn_rad: float = 3.0


#: The settings :func:`split_turns` cuts with by default.
TURNS = TurnSettings()


def _mask(continuous: NDArray[np.bool_] | None, n: int) -> NDArray[np.bool_]:
    return np.zeros(n, dtype=bool) if continuous is None or len(continuous) == 0 else np.asarray(continuous, bool)


def short_way(starts: Array, ends: Array, continuous: NDArray[np.bool_] | None) -> Array:
    """``ends`` (broadcast with ``starts``) with each continuous joint moved by a whole number of turns to
    within pi of its start: the straight piece from a start to its end is then the short way round."""
    ends = np.asarray(ends, dtype=np.float64)
    mask = _mask(continuous, ends.shape[-1])
    if not mask.any():
        return ends
    starts = np.asarray(starts, dtype=np.float64)
    shape = np.broadcast_shapes(starts.shape, ends.shape)
    out = np.broadcast_to(ends, shape).copy()
    begin = np.broadcast_to(starts, shape)
    out[..., mask] = begin[..., mask] + np.remainder(out[..., mask] - begin[..., mask] + math.pi, TURN) - math.pi
    return out


def joint_gaps(a: Array, b: Array, continuous: NDArray[np.bool_] | None) -> Array:
    """``|b - a|`` per joint, modulo 2 pi (in [0, pi]) on the continuous joints (``a`` and ``b`` broadcast)."""
    out: Array = np.abs(short_way(a, b, continuous) - np.asarray(a, dtype=np.float64))
    return out


def wrapped(q: Array, continuous: NDArray[np.bool_] | None, lower: Array | None = None) -> Array:
    """``q`` with each continuous joint's value moved by whole turns into ``[lower, lower + 2 pi)`` (default
    ``lower`` -pi): the same configuration, within limits a full turn wide."""
    q = np.asarray(q, dtype=np.float64)
    mask = _mask(continuous, q.shape[-1])
    if not mask.any():
        return q
    base = np.full(q.shape[-1], -math.pi) if lower is None else np.asarray(lower, dtype=np.float64)
    out = q.copy()
    out[..., mask] = base[mask] + np.remainder(q[..., mask] - base[mask], TURN)
    return out


def unwrapped(path: Array, continuous: NDArray[np.bool_] | None) -> Array:
    """The path (k, n) from its first point on, each continuous joint's next value moved by whole turns to
    within pi of the one before: the short way round between consecutive points is the straight line."""
    out = np.array(path, dtype=np.float64)
    mask = _mask(continuous, out.shape[-1])
    if not mask.any() or len(out) < 2:
        return out
    steps = np.remainder(np.diff(out[:, mask], axis=0) + math.pi, TURN) - math.pi
    out[1:, mask] = out[0, mask] + np.cumsum(steps, axis=0)
    return out


def split_turns(
    path: Array,
    continuous: NDArray[np.bool_] | None,
    largest: float = TURNS.largest_turn_rad,
    steps: Array | None = None,
) -> Array:
    """``path`` (k, n) with equal straight parts inserted in each piece that turns a continuous joint by more
    than ``largest`` (rad, below pi): the same motion, on which the short way is the straight line. ``steps``
    (rad or m per joint: the validator's): the cuts fall on the piece's own validator samples, so the parts
    are checked at the very configurations the whole was (a part of a piece is otherwise sampled elsewhere)."""
    path = np.asarray(path, dtype=np.float64)
    mask = _mask(continuous, path.shape[-1] if path.ndim == 2 else 0)
    if not mask.any() or len(path) < 2:
        return path
    turns = np.max(np.abs(np.diff(path[:, mask], axis=0)), axis=1)
    if np.all(turns <= largest):
        return path
    rows = [path[:1]]
    for i, turn in enumerate(turns):
        parts = max(1, math.ceil(turn / largest))
        t = np.arange(1, parts + 1)[:, None] / parts
        if steps is not None:  # on the piece's samples: count of them, evenly spaced (validation_samples)
            count = max(1, math.ceil(float(np.max(np.abs(path[i + 1] - path[i]) / steps))))
            t = np.unique(np.floor(t[:, 0] * count + 0.5))[:, None] / count
            t = t[t[:, 0] > 0]
        piece = path[i] + t * (path[i + 1] - path[i])
        piece[-1] = path[i + 1]
        rows.append(piece)
    return np.concatenate(rows)


def nearest_turns(q0: Array, qs: Array, lower: Array, upper: Array, continuous: NDArray[np.bool_] | None) -> Array:
    """``qs`` (m, n) with each continuous joint moved by whole turns to within pi of ``q0`` where that stays
    within ``[lower, upper]`` (else left): the same configurations, each the short way from ``q0``."""
    qs = np.asarray(qs, dtype=np.float64)
    mask = _mask(continuous, qs.shape[-1])
    if not mask.any() or not len(qs):
        return qs
    near = short_way(q0, qs, continuous)
    inside = (near >= lower) & (near <= upper)
    return np.where(inside, near, qs)


def turnable(prismatic: NDArray[np.bool_], lower: Array, upper: Array) -> NDArray[np.bool_]:
    """The revolute joints whose limits span a full turn or more (a UR5's, +-2 pi; continuous joints): their
    values a turn apart are one posture, so an inverse kinematics solution may be moved by whole turns within
    the limits (:func:`nearest_turns`)."""
    out: NDArray[np.bool_] = ~np.asarray(prismatic, dtype=bool) & (np.asarray(upper) - np.asarray(lower) >= TURN - 1e-9)
    return out


def joint_features(joints: Array, continuous: NDArray[np.bool_] | None) -> Array:
    """Points (B, n + c) whose distances are joint distances modulo 2 pi: the other joints as they are, each
    of the c continuous joints as its (cos, sin) on the unit circle (the chord, 2 sin(d / 2): the angle d for
    small d, the same for values a turn apart). ``joints`` itself when there is no continuous joint."""
    joints = np.asarray(joints, dtype=np.float64)
    mask = _mask(continuous, joints.shape[-1])
    if not mask.any():
        return joints
    out: Array = np.concatenate([joints[..., ~mask], np.cos(joints[..., mask]), np.sin(joints[..., mask])], axis=-1)
    return out


def goal_turns(goal: Array, lower: Array, upper: Array, continuous: NDArray[np.bool_] | None) -> Array:
    """Every configuration (m, n) equal to ``goal`` modulo 2 pi on the continuous joints that lies within
    ``[lower, upper]``: ``goal`` itself first."""
    goal = np.asarray(goal, dtype=np.float64)
    mask = _mask(continuous, len(goal))
    options: list[list[float]] = []
    for j, value in enumerate(goal):
        if not mask[j]:
            options.append([float(value)])
            continue
        turns = range(math.ceil((lower[j] - value) / TURN - 1e-12), math.floor((upper[j] - value) / TURN + 1e-12) + 1)
        values = [float(value + k * TURN) for k in turns if k != 0 and lower[j] <= value + k * TURN <= upper[j]]
        options.append([float(value), *values])
    return np.array(list(itertools.product(*options)), dtype=np.float64)
