"""Straight joint-space ways to a target, each move checked at the validator's 0.002 rad (:func:`way`): directly,
by way of the target's approach (the tcp backed off, the object lifted, or lifted a little and slid out of a
shelf), from the start's own retreat, or over the top; and the ways out from a configuration (:func:`way_out`:
a carried object out of a shelf; :func:`backed_off`: the tcp back along its own -z)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.space import Mode
from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.inverse import pose_rows
from clew_ros.spatial.space_parts import SpaceParts

__all__ = ["approach_poses", "backed_off", "offsets", "way", "way_out"]

Array = NDArray[np.float64]

#: a position: the pose error's x, y and z (the orientation free)
_POSITION_ROWS = pose_rows(("x", "y", "z"))


def way(parts: SpaceParts, mode: Mode, q: Array, targets: Array, *, far: bool = False) -> Array | None:
    """Waypoints (without ``q``) of straight joint-space moves from ``q`` to the first of ``targets``
    (nearest first) it reaches, each move checked at the validator's 0.002 rad in ``mode``: directly, or by
    way of the target's approach (:func:`offsets`: the tcp backed off, the object lifted), or from ``q``'s
    own retreat; ``None`` if none is clear. ``far``: a transit may also go through a drawn configuration
    (:func:`_over_the_top`; a search's last move, not each of its probes)."""
    checker = parts.checker_of(mode)
    targets = targets[: parts.tuning.straight_probes]
    count = len(targets)
    starts = np.broadcast_to(q, targets.shape)
    clear = parts.clear(checker, starts, targets)
    if clear.any():
        direct: Array = targets[int(np.argmax(clear))][None]
        return direct
    if parts.tuning.approach_m <= 0:
        return None
    vias = offsets(parts, mode, targets)
    retreat = offsets(parts, mode, q[None])[0]
    fine = [k for k in range(count) if not np.isnan(vias[k]).any()]
    ways = [[vias[k], targets[k]] for k in fine]
    if not np.isnan(retreat).any():
        ways += [[retreat, vias[k], targets[k]] for k in fine]
        ways += [[retreat, targets[k]] for k in range(count)]
    for path in ways:
        points = np.array([q, *path])
        if parts.clear(checker, points[:-1], points[1:]).all():
            via: Array = points[1:]
            return via
    return _other_ways(parts, mode, checker, q, targets, far=far)


def offsets(parts: SpaceParts, mode: Mode, qs: Array) -> Array:
    """Configurations (m, n) near ``qs`` (m, n) with the tcp moved :attr:`SpatialTuning.approach_m` away
    along its own -z (transit: backed off a grasp's approach) or up (transfer: the object lifted; where
    that is out of reach, lifted :attr:`SpatialTuning.slide_lift_m` and backed off along the tcp's -z, as
    a gripper slides an object out of a shelf); where no configuration near holds that whole pose, one
    with the tcp at its position (:attr:`SpatialTuning.position_approach`); a row is NaN where inverse
    kinematics seeded at it found none within its joint limits."""
    out = np.full(qs.shape, np.nan)
    for targets, _ in approach_poses(parts, mode, qs):
        missed = np.flatnonzero(np.isnan(out).any(axis=1))
        if not len(missed):
            break
        out[missed] = _approach_joints(parts, targets[missed], qs[missed])
    return out


def approach_poses(parts: SpaceParts, mode: Mode, qs: Array) -> list[tuple[Array, Array]]:
    """The tcp's approach poses (m, 4, 4) for configurations ``qs`` (m, n), first choice first (:func:`offsets`):
    backed off along its -z (transit); the object lifted, then lifted a little and slid out (transfer). Each
    with the move (m, 3) that takes it one approach further the same way (:func:`way_out`)."""
    here = parts.tcp(qs)
    tuning = parts.tuning
    shift = tuning.approach_m
    back = -shift * here[:, :3, 2]
    backed = here.copy()
    backed[:, :3, 3] += back
    if not mode.transfer:
        return [(backed, back)]
    up = np.broadcast_to([0.0, 0.0, shift], back.shape)
    lifted = here.copy()
    lifted[:, :3, 3] += up
    moves = [(lifted, up)]
    if tuning.slide_lift_m > 0:
        backed[:, 2, 3] += tuning.slide_lift_m
        moves.append((backed, back))
    return moves


def _approach_joints(parts: SpaceParts, targets: Array, qs: Array) -> Array:
    """Configurations (m, n) near ``qs`` (m, n) with the tcp at ``targets`` (m, 4, 4) (:func:`offsets`), NaN
    rows where none is found."""
    out = np.full(qs.shape, np.nan)
    found = parts.settle_ik.solve_many(list(targets), np.random.default_rng(0), seeds=[q[None] for q in qs])
    for k, solutions in enumerate(found):
        if len(solutions):
            out[k] = solutions[0]
    missed = np.flatnonzero(np.isnan(out).any(axis=1))
    if len(missed) and parts.tuning.position_approach:
        reached, ok = parts.settle_ik.solve_rows(targets[missed], qs[missed], _POSITION_ROWS)
        out[missed[ok]] = reached[ok]
    return out


def _other_ways(
    parts: SpaceParts, mode: Mode, checker: SpatialChecker, q: Array, targets: Array, *, far: bool
) -> Array | None:
    """:func:`way`'s moves by way of a carried object's other approach (:func:`approach_poses`: lifted
    :attr:`SpatialTuning.slide_lift_m` and slid out along the tcp's -z, where lifting it straight up is
    blocked by a shelf's lid or a cubby's ceiling), which :func:`offsets` passes over when the first is
    within reach; the lift and the slide as two moves (one straight joint move sags between them); between
    the retreat and the approach, directly or over the top (both raised :attr:`SpatialTuning.carry_raise_m`)."""
    kinds = approach_poses(parts, mode, np.vstack([q[None], targets]))
    if len(kinds) < 2:
        return _over_the_top(parts, checker, q, targets, kinds[0][0], far=far)
    rows = np.vstack([q[None], targets])
    slid = _approach_joints(parts, kinds[1][0], rows)
    raised = parts.tcp(rows)
    raised[:, 2, 3] += parts.tuning.slide_lift_m
    lifted = _approach_joints(parts, raised, rows)
    steps = _slide_steps(parts, raised, kinds[1][1], lifted)  # (steps, rows, n): the slide in short moves
    retreats = [[lifted[0], *steps[:, 0]], [lifted[0], slid[0]], [slid[0]], []]
    retreats = [r for r in retreats if _path_clear(parts, checker, [q, *r])]
    high: dict[bytes, Array] = {}
    for k in range(min(len(targets), parts.tuning.slide_targets)):
        comings = [[*steps[::-1, k + 1], lifted[k + 1]], [slid[k + 1], lifted[k + 1]], [slid[k + 1]], []]
        comings = [c for c in comings if _path_clear(parts, checker, [*c, targets[k]])]
        for retreat in retreats:
            for coming in comings:
                if not retreat and not coming:
                    continue  # way()'s direct move
                a, b = (retreat[-1] if retreat else q), (coming[0] if coming else targets[k])
                for middle in ([], [_raised(parts, a, high), _raised(parts, b, high)]):
                    if _path_clear(parts, checker, [a, *middle, b]):
                        found: Array = np.array([*retreat, *middle, *coming, targets[k]])
                        return found
    return None


def _over_the_top(
    parts: SpaceParts, checker: SpatialChecker, q: Array, targets: Array, backed: Array, *, far: bool
) -> Array | None:
    """A transit's way from ``q`` (or its retreat) to the approach of one of the first
    :attr:`SpatialTuning.slide_targets` ``targets`` (the tcp backed off, ``backed``: (m + 1, 4, 4), ``q``'s
    first) and in, straight or in :attr:`SpatialTuning.approach_steps` short moves (a straight joint move from
    the approach sags into a cubby's wall): directly, over the top (both ends raised
    :attr:`SpatialTuning.carry_raise_m`: a hand reaching into a cubby past the table it stands on), or through
    one of :attr:`SpatialTuning.carry_vias` valid configurations drawn from a generator of the call's own (a
    long swing that a straight move cannot make; ``far`` only)."""
    rows = np.vstack([q[None], targets])
    approaches = _approach_joints(parts, backed, rows)
    high: dict[bytes, Array] = {}
    starts: list[list[Array]] = [[]]
    if _path_clear(parts, checker, [q, approaches[0]]):
        starts.append([approaches[0]])
    comings: list[list[Array] | None] = [
        _coming(parts, checker, backed[k + 1], approaches[k + 1], targets[k])
        for k in range(min(len(targets), parts.tuning.slide_targets))
    ]
    ins = [c for c in comings if c is not None]
    for coming in ins:
        for start in starts:
            a = start[-1] if start else q
            for middle in ([], [_raised(parts, a, high), _raised(parts, coming[0], high)]):
                if _path_clear(parts, checker, [a, *middle, coming[0]]):
                    found: Array = np.array([*start, *middle, *coming])
                    return found
    if not far or not ins:
        return None
    robot = parts.world.robot
    vias = np.random.default_rng(0).uniform(robot.lower, robot.upper, size=(parts.tuning.carry_vias, robot.dof))
    vias = vias[checker.valid(vias)] if len(vias) else vias
    for coming in ins:
        for start in starts:
            a = start[-1] if start else q
            through = parts.clear(checker, np.broadcast_to(a, vias.shape), vias) & parts.clear(
                checker, vias, np.broadcast_to(coming[0], vias.shape)
            )
            if through.any():
                return np.array([*start, vias[int(np.argmax(through))], *coming])
    return None


def _coming(
    parts: SpaceParts, checker: SpatialChecker, backed: Array, approach: Array, target: Array
) -> list[Array] | None:
    """The moves in from a grasp's approach (the tcp at ``backed``, 4x4) to ``target``: straight from
    ``approach`` where it is clear, else in :attr:`SpatialTuning.approach_steps` short moves along the tcp's
    line, each configuration seeded at the next one in (``None``: neither is clear)."""
    if not np.isnan(approach).any() and _path_clear(parts, checker, [approach, target]):
        return [approach, target]
    count = parts.tuning.approach_steps
    here = parts.tcp(target[None])[0]
    path, last = [target], target
    for i in range(count, 0, -1):
        pose = here.copy()
        pose[:3, 3] += (backed[:3, 3] - here[:3, 3]) * (count - i + 1) / count
        step = _approach_joints(parts, pose[None], last[None])[0]
        if np.isnan(step).any():
            return None
        path.insert(0, step)
        last = step
    return path if _path_clear(parts, checker, path) else None


def _slide_steps(parts: SpaceParts, raised: Array, along: Array, lifted: Array) -> Array:
    """Configurations (steps, m, n) sliding the lifted tcps ``raised`` (m, 4, 4) out along ``along`` (m, 3), in
    :attr:`SpatialTuning.slide_steps` equal steps, each seeded at the one before (NaN: out of reach)."""
    count = parts.tuning.slide_steps
    out = np.full((count, *lifted.shape), np.nan)
    last = lifted
    for i in range(count):
        rows = np.flatnonzero(~np.isnan(last).any(axis=1))
        if not len(rows):
            break
        target = raised[rows].copy()
        target[:, :3, 3] += along[rows] * (i + 1) / count
        out[i, rows] = _approach_joints(parts, target, last[rows])
        last = out[i]
    return out


def _raised(parts: SpaceParts, q: Array, cache: dict[bytes, Array]) -> Array:
    """The configuration near ``q`` with the tcp :attr:`SpatialTuning.carry_raise_m` higher (NaN: none)."""
    key = q.tobytes()
    if key not in cache:
        target = parts.tcp(q[None])
        target[:, 2, 3] += parts.tuning.carry_raise_m
        cache[key] = _approach_joints(parts, target, q[None])[0]
    return cache[key]


def _path_clear(parts: SpaceParts, checker: SpatialChecker, path: Sequence[Array]) -> bool:
    """Whether every straight move of ``path`` (a list of configurations; NaN: none) is valid."""
    if any(np.isnan(p).any() for p in path):
        return False
    if len(path) < 2:
        return True
    points = np.asarray(path)
    return bool(parts.clear(checker, points[:-1], points[1:]).all())


def way_out(parts: SpaceParts, checker: SpatialChecker, mode: Mode, q: Array) -> Array | None:
    """The carried object's way out from ``q`` (k + 1, n), along the first of its approaches
    (:func:`approach_poses`: lifted, or lifted a little and slid back along the tcp's -z, the slide in
    :attr:`SpatialTuning.slide_steps` short moves) whose first step is clear, repeated step by step (each
    ``approach_m`` further, inverse kinematics seeded at the step before, each straight move clear) up to
    :attr:`SpatialTuning.transfer_way_out_m` while they stay clear: out of a shelf deeper than one approach;
    ``None`` if no first step is clear."""
    steps = max(1, math.ceil(parts.tuning.transfer_way_out_m / parts.tuning.approach_m - 1e-9))
    for kind, (first, along) in enumerate(approach_poses(parts, mode, q[None])):
        path, done = [q], 0
        if kind == 1:  # lifted a little, then slid out in short moves (one straight joint move sags)
            raised = parts.tcp(q[None])
            raised[:, 2, 3] += parts.tuning.slide_lift_m
            lifted = _approach_joints(parts, raised, q[None])
            for step in [lifted[0], *_slide_steps(parts, raised, along, lifted)[:, 0]]:
                if np.isnan(step).any() or not parts.clear(checker, path[-1][None], step[None])[0]:
                    break
                path.append(step)
            done = 1 if len(path) == parts.tuning.slide_steps + 2 else steps
        for k in range(done, steps):
            target = first[0].copy()
            target[:3, 3] += k * along[0]
            step = _approach_joints(parts, target[None], path[-1][None])
            if np.isnan(step).any() or not parts.clear(checker, path[-1][None], step)[0]:
                break
            path.append(step[0])
        if len(path) > 1:
            out: Array = np.array(path)
            return out
    return None


def backed_off(parts: SpaceParts, checker: SpatialChecker, q: Array) -> Array | None:
    """The tcp's way back from ``q`` along its own -z (k + 1, n): steps of
    :attr:`SpatialTuning.motion_way_out_step_m` up to :attr:`SpatialTuning.motion_way_out_m`, inverse
    kinematics seeded at the step before, while each straight move is clear (``checker``); ``None`` if
    the first step is not."""
    tuning = parts.tuning
    if tuning.motion_way_out_m <= 0 or tuning.motion_way_out_step_m <= 0:
        return None
    pose = parts.tcp(q[None])[0]
    path = [q]
    for k in range(1, math.ceil(tuning.motion_way_out_m / tuning.motion_way_out_step_m - 1e-9) + 1):
        target = pose.copy()
        target[:3, 3] -= k * tuning.motion_way_out_step_m * pose[:3, 2]
        step = _approach_joints(parts, target[None], path[-1][None])
        if np.isnan(step).any() or not parts.clear(checker, path[-1][None], step)[0]:
            break
        path.append(step[0])
    return np.array(path) if len(path) > 1 else None
