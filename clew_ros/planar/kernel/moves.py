"""Straight moves in joint space, compiled: whether each move stays clear
(:func:`clew_ros.planar.continuous.straight_move_clear`, whose docstring says why it is sound), and the proposals'
screen of routes (straight, or one joint after the other)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from clew_ros.planar.kernel.jit import _jit, _leaf
from clew_ros.planar.kernel.kinematics import _forward
from clew_ros.planar.kernel.packed import Chain, Mode, Model, MoveCheck, PackedWorld, _arg, _named, plain
from clew_ros.planar.kernel.validity import _placed, _valid_beyond


@_leaf
def _at(
    a: np.ndarray, b: np.ndarray, t: float, q: np.ndarray, mode: Mode, chain: Chain, links: np.ndarray
) -> tuple[float, float, float]:
    """``q = a + t (b - a)`` and the object's pose there: at ``mode.resting``, or held as ``mode.grasp_rel`` by the
    tip (the tip's frame composed with it, as :func:`clew_ros.planar.kinematics.compose` does)."""
    for j in range(q.shape[0]):
        q[j] = a[j] + t * (b[j] - a[j])
    if not mode.transfer:
        return mode.resting[0], mode.resting[1], mode.resting[2]
    grasp_rel = mode.grasp_rel
    return _held(q, grasp_rel[0], grasp_rel[1], grasp_rel[2], chain.base, chain.lengths, links)


@_leaf
def _held(
    q: np.ndarray, gx: float, gy: float, gt: float, base: np.ndarray, lengths: np.ndarray, links: np.ndarray
) -> tuple[float, float, float]:
    """The pose of the object held as ``(gx, gy, gt)`` (``grasp_rel``) by the tip at configuration ``q`` (the
    tip's frame composed with it, as :func:`clew_ros.planar.kinematics.compose` does); ``links`` filled."""
    x, y, phi = _forward(q, base, lengths, links)
    c, s = math.cos(phi), math.sin(phi)
    return x + c * gx - s * gy, y + s * gx + c * gy, phi + gt


@_jit
def _move_clear(  # noqa: C901, PLR0911, PLR0912 - the levels of one move, commented step by step
    a: np.ndarray, b: np.ndarray, mode: Mode, check: MoveCheck, checked: np.ndarray, model: Model
) -> bool:
    """:func:`clew_ros.planar.continuous.straight_move_clear` of one move ``a -> b`` (its docstring says why it
    is sound); adds the configurations it checks to ``checked[0]``."""
    chain, object_edges, rounding = model.chain, model.shape.edges, model.rounding
    lengths, lower, upper = chain.lengths, chain.lower, chain.upper
    transfer, grasp_rel = mode.transfer, mode.grasp_rel
    min_margin, max_margin, coarse_stride = check
    n = lengths.shape[0]
    q = np.empty(n)
    placed = _placed(model)
    for j in range(n):  # both ends within the joint limits
        if a[j] < lower[j] or a[j] > upper[j] or b[j] < lower[j] or b[j] > upper[j]:
            return False
    # V: how far any point of the arm (and of the object held) moves; R_j sums links j..n-1 and the object
    held = 0.0
    if transfer:
        c, s = math.cos(grasp_rel[2]), math.sin(grasp_rel[2])
        for e in range(object_edges.shape[0]):
            vx, vy = object_edges[e, 0, 0], object_edges[e, 0, 1]
            held = max(held, math.hypot(grasp_rel[0] + c * vx - s * vy, grasp_rel[1] + s * vx + c * vy))
    motion = 0.0
    reach = 0.0
    for j in range(n - 1, -1, -1):
        reach += lengths[j]
        motion += abs(b[j] - a[j]) * (reach + held)
    motion = motion * (1.0 + 1e-9) + 1e-12
    # in a transfer the last link and the object it holds keep their distance: it is checked once, at a
    tested = n - 1 if transfer else n
    if transfer:
        px, py, pt = _at(a, b, 0.0, q, mode, chain, placed.links)
        checked[0] += 1
        if not _valid_beyond(q, px, py, pt, min_margin, n, placed, model):
            return False
    # level k: 2**k pieces, each cleared by its midpoint with margin motion / 2**(k + 1)
    level = max(0, math.ceil(math.log2(max(motion / (2.0 * max_margin), 1.0))))
    count = 2**level
    if count >= 2 * coarse_stride:  # a long move: every coarse_stride-th midpoint first, valid at all?
        for piece in range(coarse_stride // 2, count, coarse_stride):
            px, py, pt = _at(a, b, (piece + 0.5) / count, q, mode, chain, placed.links)
            checked[0] += 1
            if not _valid_beyond(q, px, py, pt, rounding, n, placed, model):
                return False  # most blocked moves end here, for a fraction of the first level's checks
    pending = np.arange(count)  # piece indices at this level
    while pending.shape[0]:
        pieces = float(count)
        margin = max(motion / (2.0 * pieces), min_margin)  # the last level: a short piece needs only the least
        failed = np.empty(pending.shape[0], np.int64)
        nfailed = 0
        for k in range(pending.shape[0]):
            t = (pending[k] + 0.5) / pieces
            px, py, pt = _at(a, b, t, q, mode, chain, placed.links)
            checked[0] += 1
            if _valid_beyond(q, px, py, pt, margin, tested, placed, model):
                continue
            if margin <= min_margin:
                return False
            # a midpoint that is not valid at all rejects the move at once (halving would only find it later)
            checked[0] += 1
            if not _valid_beyond(q, px, py, pt, rounding, n, placed, model):
                return False
            failed[nfailed] = pending[k]
            nfailed += 1
        if nfailed == 0:
            return True
        pending = np.empty(2 * nfailed, np.int64)
        for k in range(nfailed):
            pending[2 * k], pending[2 * k + 1] = 2 * failed[k], 2 * failed[k] + 1
        count *= 2
    return True


@_jit
def _moves_clear(
    starts: np.ndarray,
    ends: np.ndarray,
    every: bool,
    mode: tuple[Any, ...],
    check: tuple[Any, ...],
    out: np.ndarray,
    world: tuple[Any, ...],
) -> int:
    """``out[k]``: :func:`_move_clear` of ``starts[k] -> ends[k]``; when ``every``, the moves after the first
    that is not clear are left unchecked (False). Returns how many configurations were checked. ``mode``,
    ``check``: a :class:`~.packed.Mode` and :class:`~.packed.MoveCheck` as plain tuples; ``world``:
    :attr:`~.packed.PackedWorld.plain`."""
    model = _named(world)
    named_mode, named_check = Mode(*mode), MoveCheck(*check)
    out[:] = False
    checked = np.zeros(1, np.int64)
    for k in range(starts.shape[0]):
        out[k] = _move_clear(starts[k], ends[k], named_mode, named_check, checked, model)
        if every and not out[k]:
            break
    return int(checked[0])


def _mode(resting: np.ndarray | None, grasp_rel: np.ndarray | None) -> Mode:
    """A mode as the move kernels take it: whether the object is held, its pose held, its pose at rest."""
    if (resting is None) == (grasp_rel is None):
        raise ValueError("give the object's pose at rest (a transit) or the grasp_rel it is held by (a transfer)")
    if grasp_rel is None:
        return Mode(False, _NOWHERE, _arg(resting))  # type: ignore[arg-type]  # not None: tested above
    return Mode(True, _arg(grasp_rel), _NOWHERE)


_NOWHERE = np.zeros(3)  # the pose a mode does not use


def moves_clear(
    world: PackedWorld,
    starts: np.ndarray,
    ends: np.ndarray,
    *,
    resting: np.ndarray | None,
    grasp_rel: np.ndarray | None,
    min_margin: float,
    max_margin: float,
    coarse_stride: int,
    every: bool = False,
) -> tuple[np.ndarray, int]:
    """Compiled :func:`clew_ros.planar.continuous.straight_move_clear` of moves ``starts[k] -> ends[k]``
    ``(K, n)``, the object at ``resting`` (a transit) or held as ``grasp_rel`` (a transfer; give one): which
    are clear, and how many configurations were checked. With ``every``, the moves after the first that is
    not clear are not checked (and not clear)."""
    # called for every move the improvement tries: the Python here is kept to what the call needs
    starts, ends = _arg(starts), _arg(ends)
    if starts.ndim != 2 or starts.shape != ends.shape or starts.shape[1] != len(world.lengths):
        raise ValueError(
            f"starts, ends: expected two (K, {len(world.lengths)}) arrays, got {starts.shape}, {ends.shape}"
        )
    out = np.empty(len(starts), dtype=np.bool_)
    check = (float(min_margin), float(max_margin), int(coarse_stride))
    checked = _moves_clear(starts, ends, bool(every), plain(_mode(resting, grasp_rel)), check, out, world.plain)
    return out, int(checked)


@_jit
def _screen(
    a: np.ndarray, b: np.ndarray, samples: np.ndarray, mode: tuple[Any, ...], route: np.ndarray, world: tuple[Any, ...]
) -> int:
    """:func:`screen_routes` into ``route``; returns how many configurations were checked. ``mode``: a
    :class:`~.packed.Mode` (poses ``(M, 3)``) as a plain tuple; ``world``: :attr:`~.packed.PackedWorld.plain`."""
    model = _named(world)
    transfer, held, at_rest = mode
    base, lengths = model.chain.base, model.chain.lengths
    m, n = a.shape
    placed = _placed(model)
    links = placed.links
    q, moved, start = np.empty(n), np.empty(n), np.empty(n)
    checked = 0
    for k in range(m):
        route[k] = -1
        total = 0.0
        for j in range(n):
            moved[j] = abs(b[k, j] - a[k, j])
            total += moved[j]
        for way in range(3):
            sofar = 0.0
            for step in range(n):  # where each joint starts moving along the way (one joint after the other)
                j = step if way == 1 else n - 1 - step
                sofar += moved[j]
                start[j] = sofar - moved[j]
            clear = True
            for sample in range(2 * samples[k]):  # every fourth sample first: most blocked moves stop there
                coarse = sample < samples[k]
                index = sample if coarse else sample - samples[k]
                if (index % 4 == 0) != coarse:
                    continue
                share = _end_share(index, samples[k])
                _way_point(a, b, k, way, share * total, share, moved, start, q)
                px, py, pt = at_rest[k, 0], at_rest[k, 1], at_rest[k, 2]
                if transfer:
                    px, py, pt = _held(q, held[k, 0], held[k, 1], held[k, 2], base, lengths, links)
                checked += 1
                if not _valid_beyond(q, px, py, pt, model.rounding, n, placed, model):
                    clear = False
                    break
            if clear:
                route[k] = way
                break
    return checked


@_leaf
def _end_share(sample: int, count: int) -> float:
    """Sample ``sample`` of ``count`` along a move, as a share of it, closer together near both ends (cosine
    spacing, as ``0.5 - 0.5 cos(linspace(0, pi, count))``)."""
    angle = math.pi if sample == count - 1 else sample * (math.pi / (count - 1))
    return 0.5 - 0.5 * math.cos(angle)


@_leaf
def _way_point(
    a: np.ndarray,
    b: np.ndarray,
    k: int,
    way: int,
    travel: float,
    share: float,
    moved: np.ndarray,
    start: np.ndarray,
    q: np.ndarray,
) -> None:
    """``q`` = the point of way ``way`` (straight, or one joint after the other from ``start``) from ``a[k]``
    to ``b[k]`` at ``share`` of it, ``travel`` rad of joint travel along it."""
    for j in range(q.shape[0]):
        if way == 0:
            q[j] = a[k, j] + share * (b[k, j] - a[k, j])
        else:
            done = min(max((travel - start[j]) / max(moved[j], 1e-300), 0.0), 1.0)
            q[j] = a[k, j] + done * (b[k, j] - a[k, j])


def screen_routes(
    world: PackedWorld,
    starts: np.ndarray,
    ends: np.ndarray,
    samples: np.ndarray,
    *,
    resting: np.ndarray | None,
    grasp_rel: np.ndarray | None,
) -> tuple[np.ndarray, int]:
    """The proposals' screen (:meth:`clew_ros.planar.regrasp_keys.Kinematics.routes`), compiled: per move
    ``starts[k] -> ends[k]`` ``(M, n)``, the first way (0 straight, 1 one joint after the other from the
    first, 2 from the last) whose ``samples[k]`` configurations (cosine-spaced along the way's joint travel,
    every fourth first) pass :func:`~.validity.clearly_valid` with the world's rounding as the margin, the object
    resting at ``resting[k]`` or held as ``grasp_rel[k]`` (``(M, 3)``; give one); -1 when none does. Returns the ways
    and how many configurations were checked (a way stops at its first sample that does not pass)."""
    starts, ends = _arg(starts), _arg(ends)
    count = np.ascontiguousarray(samples, dtype=np.int64)
    n = len(world.lengths)
    if starts.shape != (len(starts), n) or ends.shape != starts.shape or count.shape != (len(starts),):
        raise ValueError(
            f"starts, ends, samples: expected (M, {n}), (M, {n}) and (M,), got {starts.shape}, {ends.shape}, "
            f"{count.shape}"
        )
    if np.any(count < 2):
        raise ValueError(f"samples: expected at least 2 per move, got {count.min()}")
    transfer, held, at_rest = _mode(resting, grasp_rel)
    held, at_rest = held.reshape(-1, 3), at_rest.reshape(-1, 3)
    if len(held if transfer else at_rest) != len(starts):
        raise ValueError(
            f"resting, grasp_rel: expected ({len(starts)}, 3), got {(held if transfer else at_rest).shape}"
        )
    route = np.empty(len(starts), dtype=np.int64)
    checked = _screen(starts, ends, count, (transfer, held, at_rest), route, world.plain)
    return route, int(checked)
