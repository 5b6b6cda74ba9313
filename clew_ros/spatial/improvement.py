"""The spatial plan's improvement within ``planner.improve_time`` (:func:`improve`).

First the pruning that needs no checking (:func:`clew_ros.core.improve.pruned_path`: repeats, loops and
collinear waypoints; :func:`clew_ros.core.improve.joined_regrasps`: a transfer put down and taken again by the
same grasp without the arm moving made one), then shortcuts between waypoints of a segment, each straight move
checked at 0.002 rad, taken only when shorter (:func:`clew_ros.core.improve.shortcut_path`); then the plan of
one transfer made of straight moves (:func:`straight_plan`), and a plan of several transfers tried as one. What
comes out has its dragging transfers mended (:func:`clew_ros.spatial.lift.lifted_segments`) and is kept only if
the plan validator's checks pass it."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import partial

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.improve import WorkBudget, WorkCosts, joined_regrasps, joint_travel, pruned_path, shortcut_path
from clew_ros.core.space import Improvement, Mode, PlanningContext, TransitRequest
from clew_ros.core.tree import Segment
from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.lift import drag_free, lifted_segments
from clew_ros.spatial.plan import make_plan, path_problems
from clew_ros.spatial.search import SearchSpace
from clew_ros.spatial.space_parts import SpaceParts
from clew_ros.spatial.targets import goal_configurations, holds
from clew_ros.spatial.ways import way

__all__ = ["checked", "improved", "shortcut_segments", "straight_plan"]

Array = NDArray[np.float64]


def checked(space: SearchSpace, segments: list[Segment], object_pose: Array, better: Improvement) -> Improvement:
    """The improvement ``better`` of the first plan ``segments`` (:func:`improved`), its dragging transfers
    mended, returned only if the plan validator's checks of every segment
    (:func:`clew_ros.spatial.plan.path_problems`, the grasps and placements included) pass it; else the
    first plan, with what was refused (the planner's own checks sample the moves where the validator's
    samples may fall elsewhere: an improved move grazing a support within its tolerance is not kept)."""
    parts = space.parts
    mended = lifted_segments(parts, better.segments, parts.tuning.lift)
    if not _same_waypoints(mended, better.segments):
        better = replace(better, segments=mended, travel=joint_travel(mended))
    if _same_waypoints(better.segments, segments):
        return better  # nothing changed: the first plan, checked by the planner as it was found
    built = [(s.kind, s.grasp, np.asarray(s.waypoints, dtype=float)) for s in better.segments]
    problems = path_problems(parts.world, make_plan(parts.world, built))
    if not problems:
        return better
    return Improvement(
        segments,
        object_pose,
        better.first_travel,
        better.first_transfers,
        better.first_travel,
        better.first_transfers,
        0,
        better.work,
        better.stopped,
        refused="; ".join(problems[:2]),
    )


def improved(
    space: SearchSpace, ctx: PlanningContext, segments: list[Segment], object_pose: Array, goal: Array
) -> Improvement:
    """Shortcuts (:func:`shortcut_segments`); then the straight plan (:func:`straight_plan`) where it is
    shorter; then a plan still of several transfers is tried as one, from the start: each grasp's transit
    at the initial placement, then SEARCH_TRANSFER to the goal, shortcut; the one-transfer plan replaces it
    where it is no longer."""
    parts = space.parts
    better = shortcut_segments(parts, ctx, segments, object_pose)
    if ctx.settings.improve_time <= 0 or better.stopped:
        return better
    straight = straight_plan(parts, ctx, goal)
    if straight is not None:
        single, pose = straight
        direct = shortcut_segments(parts, ctx, single, pose)
        if direct.travel < better.travel:
            better = _replaced(better, direct, pose)
    if better.transfers <= 1 or better.stopped:
        return better
    world = parts.world
    assert world.object is not None
    start, resting = world.initial, np.asarray(world.object.initial, dtype=float)
    for grasp in range(space.grasp_count):
        if ctx.termination():
            break
        if not len(goal_configurations(parts, ctx, start, parts.grasp_rel(grasp), goal)):
            continue  # no configuration holds the object at the goal with this grasp: spare its searches
        transit = space.search_transits(ctx, [TransitRequest(start, resting, grasp, None)])[0]
        if not transit.success or transit.grasp_rel is None:
            continue
        carried = space.search_transfer(ctx, transit.waypoints[-1], transit.grasp_rel, goal)
        if not carried.success or carried.object_pose is None:
            continue
        single = [
            Segment("transit", None, list(transit.waypoints)),
            Segment("transfer", grasp, list(carried.waypoints)),
        ]
        direct = shortcut_segments(parts, ctx, single, carried.object_pose)
        if direct.travel <= better.travel:
            return _replaced(better, direct, direct.final_object_pose)
    return better


def _replaced(better: Improvement, direct: Improvement, pose: Array) -> Improvement:
    """``direct`` (a plan of one transfer, shortcut) in place of ``better``, ending with the object at ``pose``:
    the first plan's figures kept, the work of both counted."""
    return Improvement(
        direct.segments,
        pose,
        better.first_travel,
        better.first_transfers,
        direct.travel,
        direct.transfers,
        better.shortcuts + direct.shortcuts,
        better.work + direct.work + 1,
        direct.stopped,
    )


def straight_plan(parts: SpaceParts, ctx: PlanningContext, goal: Array) -> tuple[list[Segment], Array] | None:
    """The shortest plan of one transfer made of straight moves (:func:`~clew_ros.spatial.ways.way`: direct or
    by way of the approaches) from the start to a hold and from it to a goal configuration, over every grasp:
    for each, the :attr:`SpatialTuning.straight_pairs` (hold, goal configuration) pairs of least joint travel in
    straight lines, the first whose moves are clear; ``None`` if none is."""
    world = parts.world
    assert world.object is not None
    start, pose = world.initial, np.asarray(world.object.initial, dtype=float)
    best: tuple[float, list[Segment], Array] | None = None
    for grasp in range(len(parts.grasps)):
        if ctx.termination():
            break
        rel = parts.grasp_rel(grasp)
        goals = goal_configurations(parts, ctx, start, rel, goal)
        held = holds(parts, ctx, start, pose, grasp) if len(goals) else goals
        if not len(held):
            continue
        cost = np.abs(held - start).sum(axis=1)[:, None] + np.abs(held[:, None] - goals[None]).sum(axis=2)
        for flat in np.argsort(cost, axis=None, kind="stable")[: parts.tuning.straight_pairs]:
            i, j = np.unravel_index(flat, cost.shape)
            if best is not None and cost[i, j] >= best[0]:
                break
            reach = way(parts, Mode.resting(pose[None]), start, held[i][None])
            carry = None if reach is None else way(parts, Mode.held(rel[None]), held[i], goals[j][None])
            if reach is None or carry is None:
                continue
            segments = [
                Segment("transit", None, [start, *reach]),
                Segment("transfer", grasp, [held[i], *carry]),
            ]
            travel = joint_travel(segments)
            if best is None or travel < best[0]:
                best = (travel, segments, parts.held_object_poses(goals[j][None], rel)[0])
            break
    return None if best is None else (best[1], best[2])


def _same_waypoints(a: Sequence[Segment], b: Sequence[Segment]) -> bool:
    """Whether two plans are the same segments through the same waypoints."""
    return len(a) == len(b) and all(
        x.kind == y.kind and x.grasp == y.grasp and np.array_equal(np.asarray(x.waypoints), np.asarray(y.waypoints))
        for x, y in zip(a, b, strict=True)
    )


@dataclass
class _Piece:
    """A segment as the pruning sees it (:class:`clew_ros.core.improve.JoinablePiece`): a spatial transfer's held
    pose is its grasp's nominal one, so kind, grasp and waypoints are all there is."""

    kind: str
    grasp: int | None
    waypoints: Array

    def with_waypoints(self, waypoints: Array) -> _Piece:
        return _Piece(self.kind, self.grasp, waypoints)


def _pruned(segments: list[Segment], same_rad: float) -> list[_Piece]:
    """The plan's segments pruned without checking (the module's docstring): each path's repeats, loops and
    collinear waypoints dropped, then each transfer put down and taken again in place joined to the one before."""
    pieces = [_Piece(s.kind, s.grasp, pruned_path(np.array(s.waypoints, dtype=float))) for s in segments]
    return joined_regrasps(pieces, same_rad)


def _clear_lifted(
    parts: SpaceParts, checker: SpatialChecker, rel: Array, starts: Array, ends: Array
) -> NDArray[np.bool_]:
    """A transfer's shortcuts: clear, and not dragging the object over a support (:func:`lift.drag_free`)."""
    clear = parts.clear(checker, starts, ends)
    if clear.any():
        clear[clear] = drag_free(parts, starts[clear], ends[clear], rel, parts.tuning.lift.drag)
    return clear


def shortcut_segments(
    parts: SpaceParts, ctx: PlanningContext, segments: list[Segment], object_pose: Array
) -> Improvement:
    """The plan's segments pruned and shortcut (the module's docstring); ``object_pose``: where the object
    ends. The work is the shortcuts' tries (a fixed number per segment), counted by a
    :class:`~clew_ros.core.improve.WorkBudget` without a total: only the clock, and the exact contacts they cost
    (:attr:`SpatialTuning.shortcut_exact_rate`), stop it early."""
    first_travel = joint_travel(segments)
    first_transfers = sum(s.kind == "transfer" for s in segments)
    if ctx.settings.improve_time <= 0:
        return Improvement(
            segments, object_pose, first_travel, first_transfers, first_travel, first_transfers, 0, 0, False
        )
    tuning = parts.tuning
    budget = WorkBudget(math.inf, WorkCosts(), ctx.termination)
    exact_limit = parts.exact_checks + tuning.shortcut_exact_rate * ctx.settings.improve_time

    def stop() -> bool:
        return budget.stop() or parts.exact_checks >= exact_limit

    pieces = _pruned(segments, tuning.same_rad)
    transfers = sum(p.kind == "transfer" for p in pieces)
    thing = parts.world.object
    assert thing is not None
    resting = np.asarray(thing.initial, dtype=float)
    out: list[Segment] = []
    shortcuts = 0
    for segment in pieces:
        path = segment.waypoints
        if segment.kind == "transfer":
            assert segment.grasp is not None
            rel = parts.grasp_rel(segment.grasp)
            checker = parts.transfer_checker(rel)
        else:
            rel = None
            checker = parts.transit_checker(resting)
        if not budget.stopped:
            clear = partial(parts.clear, checker) if rel is None else partial(_clear_lifted, parts, checker, rel)
            path, taken, spent, _ = shortcut_path(
                clear,
                path,
                tries=tuning.shortcut_tries,
                rng=ctx.rng,
                stop=stop,
                steps=parts.validation_steps,
            )
            shortcuts += taken
            budget.spend(spent)
        out.append(Segment(segment.kind, segment.grasp, list(path)))
        if rel is not None:
            resting = parts.held_object_poses(path[-1:], rel)[0]
    travel = joint_travel(out)
    if travel > first_travel:  # (never: pruning and shortcuts only shorten)
        return Improvement(
            segments,
            object_pose,
            first_travel,
            first_transfers,
            first_travel,
            first_transfers,
            0,
            budget.spent,
            budget.stopped,
        )
    return Improvement(
        out, object_pose, first_travel, first_transfers, travel, transfers, shortcuts, budget.spent, budget.stopped
    )
