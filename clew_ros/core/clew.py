"""ARIADNE'S CLEW for manipulation (paper 1.2): EXPLORE, then SEARCH from each new landmark."""

from __future__ import annotations

import dataclasses
import traceback
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from clew_ros.core.explore import Candidate, Explorer
from clew_ros.core.settings import ManyJoints, Outcome, PlannerSettings, SearchSettings, Termination
from clew_ros.core.space import Improvement, PlanningContext, PlanningSpace, RegraspAims
from clew_ros.core.tree import Landmark, LandmarkTree, Segment, append_step

__all__ = ["PlanResult", "Progress", "plan"]

#: The improvement's generator is seeded with (planner.seed, this): its own stream of the same seed.
IMPROVE_STREAM = 14


@dataclass(frozen=True)
class Progress:
    """Reported after every landmark: how far the run has come."""

    landmarks: int
    best_distance: float  # m, smallest goal distance reached by SEARCH_TRANSFER so far (inf before any)
    elapsed: float  # s
    tree: LandmarkTree


@dataclass
class PlanResult:
    """What a run produced. ``segments`` is empty unless it succeeded."""

    outcome: Outcome
    message: str
    segments: list[Segment]
    final_object_pose: np.ndarray | None
    tree: LandmarkTree
    stats: dict[str, Any] = field(default_factory=dict)
    #: When the first plan was found (s since the start), before ``planner.improve_time``'s improvement;
    #: ``None`` without a plan. Not in ``stats``: the plan file holds no second clock reading.
    first_plan_s: float | None = None

    @property
    def success(self) -> bool:
        return self.outcome.succeeded


def plan(
    space: PlanningSpace,
    settings: PlannerSettings | None = None,
    *,
    goal: np.ndarray | None = None,
    termination: Termination | None = None,
    progress: Callable[[Progress], None] | None = None,
    search: SearchSettings | None = None,
    many: ManyJoints | None = None,
) -> PlanResult:
    """Plan a manipulation path in ``space`` from its start to ``goal`` (default ``space.goal``).

    Never raises for planning failures: the outcome says what happened. The
    run stops on success, when EXPLORE's new landmark is closer than
    ``settings.resolution`` to the others, or when ``termination`` says so.
    ``settings`` defaults to :class:`PlannerSettings` (), ``search`` (SEARCH's
    own tuning) to :class:`SearchSettings` (), ``many`` (arms of many joints)
    to :class:`ManyJoints` ().
    """
    settings = settings or PlannerSettings()
    search = search or SearchSettings()
    many = many or ManyJoints()
    settings = _adapted(settings, space.dof, many)
    goal = np.asarray(space.goal if goal is None else goal, dtype=float)
    termination = termination or Termination(settings.time_limit)
    rng = np.random.default_rng(settings.seed)
    ctx = PlanningContext(space, settings, rng, termination, hold_samples=search.hold_samples, many=many, search=search)
    tree = LandmarkTree(space.initial_joints, space.initial_object_pose)

    def finish(
        outcome: Outcome, message: str, segments: list[Segment] | None = None, final_pose: np.ndarray | None = None
    ) -> PlanResult:
        stats = {
            "time_s": round(termination.elapsed, 4),
            "landmarks": len(tree),
            "collision_checks": ctx.counters.clearance_checks,
            "evaluations": ctx.counters.evaluations,
            "seed": settings.seed,
        }
        return PlanResult(outcome, message, segments or [], final_pose, tree, stats)

    def succeed(landmark: Landmark, found: _Found, searched_s: float) -> PlanResult:
        """The plan through ``landmark`` and SEARCH's path from it, improved; ``searched_s``: when SEARCH
        found it (the first plan's time)."""
        segments = tree.history_of(landmark.id)
        append_step(segments, found.grasp, found.transit, found.transfer)
        assert found.object_pose is not None  # a successful SEARCH_TRANSFER says where the object ends
        better = _improved(space, ctx, segments, found.object_pose, goal)
        result = finish(
            Outcome.SUCCEEDED,
            _found_message(len(tree), better, settings.improve_time),
            better.segments,
            better.final_object_pose,
        )
        result.stats.update(_quality(better))
        result.first_plan_s = round(searched_s, 4)
        return result

    quick = space.quick_refusal(goal)
    if quick is not None:
        return finish(*quick)
    report = progress or _no_report
    best = np.inf
    try:
        explorer = Explorer(ctx, tree)
        aims = space.regrasp_aims(goal)
        tried = _Tried()
        if search.search_from_start:
            landmark, found, closest = _search_start(ctx, explorer, tree, goal, aims=aims, tried=tried)
            best = min(best, closest)
            if found.success:
                return succeed(landmark, found, termination.elapsed)
        while True:
            reason = termination.reason()
            if reason is not None:
                return finish(reason, _stopped_message(reason, settings, len(tree), tried.summary(explorer, best)))
            exploration = explorer.explore()
            if exploration is None:
                _retry_harder(ctx, explorer, tried)
                continue
            ctx.transit_joins = False  # transits found: joins only while EXPLORE finds none (elsewhere they cost more)
            new = tree.add(**exploration.fields)
            landmark, found, closest = _search_chain(ctx, explorer, tree, new, goal, aims=aims, tried=tried)
            searched_s = termination.elapsed  # when SEARCH ended: the first plan's time if it found one
            best = min(best, closest)
            report(Progress(len(tree), best, termination.elapsed, tree))
            if found.success:
                return succeed(landmark, found, searched_s)
            if (
                search.resolution_proves
                and exploration.distance < settings.resolution
                and exploration.covered
                and exploration.moved
            ):
                # the paper's criterion, once EXPLORE has searched every (landmark, grasp) pair's transit:
                # its farthest new landmark lies within the resolution of the others (and it moved the
                # object: a step that could not move it at all has explored nothing)
                return finish(
                    Outcome.NO_PATH_AT_RESOLUTION,
                    f"no path at resolution {settings.resolution}: the new landmark lies "
                    f"{exploration.distance:.4g} from the others after {len(tree)} landmarks; "
                    f"best goal distance {best:.4g} m",
                )
    except Exception as error:  # noqa: BLE001 - a bug: reported as an outcome so a node keeps running
        return finish(Outcome.INTERNAL_ERROR, f"internal error: {error!r}\n{traceback.format_exc(limit=4)}")


def _adapted(settings: PlannerSettings, dof: int, many: ManyJoints) -> PlannerSettings:
    """``settings`` with Manhattan paths of ``many.manhattan_order`` on arms of many joints (:class:`ManyJoints`)."""
    if dof >= many.straight_probe_joints and settings.manhattan_order > many.manhattan_order:
        return dataclasses.replace(settings, manhattan_order=many.manhattan_order)
    return settings


def _no_report(_progress: Progress) -> None:
    """No progress callback."""


def _retry_harder(ctx: PlanningContext, explorer: Explorer, tried: _Tried) -> None:
    """After an EXPLORE round with no transit from any landmark. That proves nothing (the transit search is
    local and stochastic, and the holding configurations a sample), so never NO_PATH_AT_RESOLUTION: the
    failed pairs are tried again, with twice the holding configurations (their inverse kinematics is not
    interruptible: at most ``SearchSettings.hold_sample_joints`` samples x joints, a few tens of milliseconds)
    and stalled transits joined to them, until the time limit."""
    tried.idle_rounds += 1
    explorer.forget_failures()
    most = ctx.search.hold_sample_joints // ctx.space.dof
    ctx.hold_samples = max(ctx.hold_samples, min(2 * ctx.hold_samples, most))
    ctx.transit_joins = True


@dataclass
class _Found:
    """SEARCH's answer from one landmark: the reaching path, or on failure the attempt that came closest."""

    success: bool
    distance: float
    grasp: int | None = None
    transit: np.ndarray | None = None
    transfer: np.ndarray | None = None
    object_pose: np.ndarray | None = None
    grasp_rel: np.ndarray | None = None


def _search_chain(
    ctx: PlanningContext,
    explorer: Explorer,
    tree: LandmarkTree,
    landmark: Landmark,
    goal: np.ndarray,
    *,
    aims: RegraspAims,
    tried: _Tried,
) -> tuple[Landmark, _Found, float]:
    """SEARCH from a new landmark; while its closest attempt gets nearer the goal, that attempt becomes a
    landmark and SEARCH goes on from it (at most ``SearchSettings.search_chain`` times); then, if none
    reached the goal, by way of intermediate placements from the new landmark (:func:`_search_via`).

    Returns the last landmark, SEARCH's answer from it and the closest goal distance reached (m).
    """
    first = landmark
    found = _search(ctx, explorer, landmark, goal, aims=aims)
    closest = found.distance
    for _ in range(ctx.search.search_chain):
        if found.success or not _worth_chaining(ctx, landmark, found, goal) or ctx.termination():
            break
        landmark = _chained(tree, landmark, found)
        found = _search(ctx, explorer, landmark, goal, aims=aims)
        closest = min(closest, found.distance)
    if not found.success and ctx.search.via_placements > 0 and first.grasp is not None:
        candidate = explorer.candidate(first.id, first.grasp)
        via = _search_via(
            ctx,
            explorer,
            tree,
            landmark=first,
            candidates=[] if candidate is None else [candidate],
            goal=goal,
            aims=aims,
            tried=tried,
        )
        if via is not None:
            return via[0], via[1], 0.0
    return landmark, found, closest


def _search_start(
    ctx: PlanningContext,
    explorer: Explorer,
    tree: LandmarkTree,
    goal: np.ndarray,
    *,
    aims: RegraspAims,
    tried: _Tried,
) -> tuple[Landmark, _Found, float]:
    """SEARCH from the start (``SearchSettings.search_from_start``): SEARCH_TRANSFER from each grasp a transit
    reaches at the object's initial placement (:meth:`Explorer.start_candidates`), by grasp, until one reaches
    the goal; where none does and the closest attempt got nearer the goal, that attempt becomes a landmark and
    SEARCH goes on from it, as :func:`_search_chain` does.

    Returns the landmark the answer starts from (the root, or that attempt's), the answer and the closest
    goal distance reached (m)."""
    root = tree[0]
    found = _Found(False, np.inf)
    candidates = explorer.start_candidates()
    for candidate in candidates:
        if ctx.termination():
            break
        found = _closer(ctx, candidate, goal, found)
        if found.success:
            break
    if not found.success and ctx.search.via_placements > 0 and not ctx.termination():
        via = _search_via(ctx, explorer, tree, landmark=root, candidates=candidates, goal=goal, aims=aims, tried=tried)
        if via is not None:
            return via[0], via[1], 0.0
    if found.success or not _worth_chaining(ctx, root, found, goal) or ctx.termination():
        return root, found, found.distance
    new = _chained(tree, root, found)
    landmark, chained, closest = _search_chain(ctx, explorer, tree, new, goal, aims=aims, tried=tried)
    return landmark, chained, min(found.distance, closest)


def _search_via(
    ctx: PlanningContext,
    explorer: Explorer,
    tree: LandmarkTree,
    *,
    landmark: Landmark,
    candidates: list[Candidate],
    goal: np.ndarray,
    aims: RegraspAims,
    tried: _Tried,
) -> tuple[Landmark, _Found] | None:
    """SEARCH by way of an intermediate placement (``SearchSettings.via_placements``, the paper's closing
    suggestion of searching for placements inside the optimisation): for ``candidates`` (grasps held at
    ``landmark``'s placement), SEARCH_TRANSFER to the placements the space proposes for each
    (:meth:`~clew_ros.core.space.RegraspAims.placements`: where a grasp serving the goal can take the object),
    every candidate's best placement first, then every one's second, and so on; each one reached becomes a
    landmark, and SEARCH (its regrasps in place) goes on from it. Returns that landmark and SEARCH's
    successful answer from it, or ``None``."""
    proposed = [(c, aims.placements(landmark, c.grasp, c.start)[: ctx.search.via_placements]) for c in candidates]
    rounds = max((len(poses) for _, poses in proposed), default=0)
    tries = [(c, poses[r]) for r in range(rounds) for c, poses in proposed if r < len(poses)]  # breadth first
    for candidate, pose in tries:
        if ctx.termination():
            return None
        tried.via_placements += 1
        result = ctx.space.search_transfer(ctx, candidate.start, candidate.grasp_rel, pose)
        if not result.success:
            continue
        tried.via_reached += 1
        reached = _Found(
            True, 0.0, candidate.grasp, candidate.transit, result.waypoints, result.object_pose, candidate.grasp_rel
        )
        middle = _chained(tree, landmark, reached)
        found = _search(ctx, explorer, middle, goal, aims=aims)
        if found.success:
            return middle, found
    return None


def _search(
    ctx: PlanningContext,
    explorer: Explorer,
    landmark: Landmark,
    goal: np.ndarray,
    *,
    aims: RegraspAims,
) -> _Found:
    """SEARCH from a new landmark: SEARCH_TRANSFER with its grasp; then, if the space says so
    (:meth:`~clew_ros.core.space.RegraspAims.retake`: planar, the grasp is held outside the goal's approach
    core), with the same grasp taken again in place; then with every other grasp reachable by a transit at
    its placement (a regrasp in place, aimed as :meth:`~clew_ros.core.space.RegraspAims.aim` says, in the
    order :meth:`~clew_ros.core.space.RegraspAims.ranked` gives), until one reaches the goal."""
    closest = _Found(False, np.inf)
    own = landmark.grasp
    assert own is not None  # SEARCH starts from landmarks holding a grasp
    own_rel = landmark.grasp_rel
    assert own_rel is not None
    others = aims.ranked(landmark, [g for g in ctx.rng.permutation(ctx.space.grasp_count).tolist() if g != own])

    def tries() -> Iterator[tuple[int, bool]]:  # (grasp, regrasped in place), asked for while SEARCH fails
        yield own, False
        if aims.retake(own, own_rel):
            yield own, True  # the same grasp taken again, aimed
        for other in others:
            yield other, True

    for grasp, regrasp in tries():
        if ctx.termination():
            break
        approach = None
        if regrasp:
            approach = aims.aim(landmark, grasp)
            if approach is None:
                continue
        candidate = explorer.candidate(landmark.id, grasp, approach)
        if candidate is None:
            continue
        closest = _closer(ctx, candidate, goal, closest)
        if closest.success:
            break
    return closest


def _closer(ctx: PlanningContext, candidate: Candidate, goal: np.ndarray, closest: _Found) -> _Found:
    """SEARCH_TRANSFER from ``candidate`` (a transit's end, holding its grasp): its answer where it reached the
    goal or came closer than ``closest``, else ``closest``."""
    result = ctx.space.search_transfer(ctx, candidate.start, candidate.grasp_rel, goal)
    if not result.success and result.distance >= closest.distance:
        return closest
    return _Found(
        result.success,
        result.distance,
        candidate.grasp,
        candidate.transit,
        result.waypoints,
        result.object_pose,
        candidate.grasp_rel,
    )


def _chained(tree: LandmarkTree, parent: Landmark, found: _Found) -> Landmark:
    """SEARCH's attempt from ``parent`` (one that moved the object) as a new landmark: its closest (SEARCH's
    chain), or one that reached an intermediate placement (:func:`_search_via`)."""
    assert found.transfer is not None  # worth chaining: the closest attempt moved the object
    return tree.add(
        parent=parent.id,
        joints=found.transfer[-1].copy(),
        object_pose=found.object_pose,
        grasp=found.grasp,
        grasp_rel=found.grasp_rel,
        transit=found.transit,
        transfer=found.transfer,
    )


def _worth_chaining(ctx: PlanningContext, landmark: Landmark, found: _Found, goal: np.ndarray) -> bool:
    """Whether SEARCH's closest attempt ended nearer the goal than ``landmark`` by more than the resolution."""
    if found.transfer is None or len(found.transfer) < 2 or not np.isfinite(found.distance):
        return False
    here = float(ctx.space.goal_distance(landmark.object_pose[None], goal)[0])
    return found.distance < here - ctx.settings.resolution


def _improved(
    space: PlanningSpace, ctx: PlanningContext, segments: list[Segment], object_pose: np.ndarray, goal: np.ndarray
) -> Improvement:
    """The first plan improved within ``planner.improve_time`` (:meth:`~clew_ros.core.space.PlanningSpace.improve`),
    drawing from its own generator, seeded from ``planner.seed``."""
    rng = np.random.default_rng([ctx.settings.seed, IMPROVE_STREAM])
    own = dataclasses.replace(ctx, rng=rng, hold_samples=ctx.search.hold_samples, transit_joins=False)
    return space.improve(own, segments, object_pose, goal)


def _found_message(landmarks: int, better: Improvement, improve_time: float) -> str:
    if improve_time <= 0:  # the first plan's message, as before improvement existed
        return f"plan found with {landmarks} landmarks, {better.transfers} grasp(s)"
    message = (
        f"plan found with {landmarks} landmarks, {better.transfers} grasp(s), joint travel {better.travel:.2f} rad"
    )
    if better.travel < better.first_travel or better.transfers < better.first_transfers:
        message += f" (first plan: {better.first_transfers} grasp(s), {better.first_travel:.2f} rad)"
    if better.refused:
        message += f"; the improved plan was refused ({better.refused}), the first plan is returned"
    return message


def _quality(better: Improvement) -> dict[str, Any]:
    """The plan's quality for its stats: joint travel (rad, sum over joints of the absolute motion) and
    transfers, of the returned plan and of the first one, and the improvement's work (deterministic); when the
    final checks refused a better plan (a fault of the space's improvement), what they found."""
    quality: dict[str, Any] = {
        "joint_travel_rad": round(better.travel, 6),
        "transfers": better.transfers,
        "first_joint_travel_rad": round(better.first_travel, 6),
        "first_transfers": better.first_transfers,
        "improve_work": better.work,
    }
    if better.refused:
        quality["improve_refused"] = better.refused
    return quality


@dataclass
class _Tried:
    """What a run tried, for the message of a run stopped without a plan."""

    idle_rounds: int = 0  # EXPLORE rounds that found no transit from any landmark
    via_placements: int = 0  # intermediate placements SEARCH_TRANSFER was sent to
    via_reached: int = 0  # ... and reached

    def summary(self, explorer: Explorer, best: float) -> str:
        found = sum(candidate is not None for candidate in explorer.transits.values())
        text = f"{explorer.transit_searches} transit searches ({found} (landmark, grasp) pairs reached)"
        if self.idle_rounds:
            text += f", {self.idle_rounds} EXPLORE rounds without any transit"
        if self.via_placements:
            text += f", {self.via_placements} intermediate placements aimed at ({self.via_reached} reached)"
        if np.isfinite(best):
            text += f", best goal distance {best:.4g} m"
        return text


def _stopped_message(reason: Outcome, settings: PlannerSettings, landmarks: int, tried: str) -> str:
    if reason is Outcome.CANCELED:
        return f"canceled after {landmarks} landmarks; tried: {tried}"
    return f"time limit of {settings.time_limit} s reached after {landmarks} landmarks; no plan found; tried: {tried}"
