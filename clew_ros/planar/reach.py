"""Necessary conditions that spare hopeless searches.

Each function answers "could this possibly succeed?" from geometry alone,
ignoring joint limits and everything it cannot bound: ``False`` means a search
would fail whatever it tried, ``True`` means nothing. (:func:`two_link_grasps`
is the exception: it samples, and uses the limits and the validity test.) SEARCH_TRANSIT and
SEARCH_TRANSFER ask them first, because a search that cannot succeed costs as
much as a successful one (it runs every generation before giving up).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from clew_ros.core.settings import SearchSettings
from clew_ros.core.space import PlanningContext
from clew_ros.planar.collision import is_valid, packed_world
from clew_ros.planar.inverse import solve_point
from clew_ros.planar.kernel import clearly_valid
from clew_ros.planar.kinematics import compose, relative, tip_poses, transform_points, wrap_angle
from clew_ros.planar.world import World

__all__ = [
    "REACH",
    "ReachSettings",
    "approach_cell",
    "approach_cells",
    "approach_excess",
    "carry_cells",
    "goal_approach_core",
    "goal_within_reach",
    "holding_configurations",
    "holding_configurations_aimed",
    "holding_configurations_near",
    "nearest_grasp_distance",
    "reach_of",
    "two_link_grasps",
    "within_reach",
]


def within_reach(world: World, point: np.ndarray, slack: float = 0.0, lengths: np.ndarray | None = None) -> bool:
    """Whether the chain's end could be at ``point``: inside the annulus its links ``lengths``
    (default the robot's) sweep about the base."""
    lengths = world.robot.link_lengths if lengths is None else lengths
    distance = float(np.hypot(*(np.asarray(point) - world.robot.base)))
    inner = max(0.0, 2.0 * float(lengths.max()) - float(lengths.sum()))
    return inner - slack <= distance <= float(lengths.sum()) + slack


def nearest_grasp_distance(world: World, object_pose: np.ndarray) -> float:
    """Distance (m) from the base to the nearest grasp point of the object resting at ``object_pose``: beyond
    the arm's reach plus ``grasp_tolerance``, no grasp can be held there."""
    grasp_points = transform_points(np.asarray(object_pose, float), world.object.grasps)
    return float(np.min(np.linalg.norm(grasp_points - world.robot.base, axis=1)))


def goal_within_reach(world: World, grasp_rel: np.ndarray, goal: np.ndarray) -> bool:
    """Whether the object, held as ``grasp_rel``, could be at the goal.

    Held rigidly, the object's origin is a point of the last link's frame, so
    it sweeps the annulus of the chain whose last link ends there instead of at
    the tip. Also some goal orientation within tolerance must put the tip in
    reach.
    """
    grasp_rel = np.asarray(grasp_rel, float)
    lengths = np.array(world.robot.link_lengths, dtype=float)
    lengths[-1] = np.hypot(lengths[-1] + grasp_rel[0], grasp_rel[1])
    if not within_reach(world, goal[:2], world.goal_tolerance, lengths):
        return False
    span = min(world.goal_angle_tolerance, np.pi)
    thetas = goal[2] + np.linspace(-span, span, 65)
    poses = np.stack([np.full_like(thetas, goal[0]), np.full_like(thetas, goal[1]), thetas], axis=1)
    tips = compose(poses, relative(grasp_rel, np.zeros(3)))[:, :2]  # end effector in the object frame
    slack = world.goal_tolerance + world.grasp_tolerance
    return any(within_reach(world, tip, slack) for tip in tips)


@dataclass(frozen=True)
class ReachSettings:
    """Tuning of the reach pre-checks, the holding configurations and the goal's approach core."""

    #: cells (count) of the approach angle, the last link's direction in the object's frame
    #: (:func:`approach_cells`): 0.5 degree each, finer than any grasp tolerance a world gives
    approach_cells: int = 720
    #: damped-least-squares iterations (count) of :func:`holding_configurations`' solver: enough to converge
    #: from a random start on the config worlds' arms; more cost time on every hopeless-transit test
    hold_iterations: int = 30
    #: goal orientations (count) sampled by :func:`goal_approach_core` within the goal's angle tolerance
    goal_core_angles: int = 24
    #: half-width (rad) of the window that smooths :func:`goal_approach_core`'s histogram (15 degrees)
    goal_core_window_rad: float = float(np.radians(15.0))
    #: cells kept by :func:`goal_approach_core`: smoothed count at least this fraction (1) of the
    #: :attr:`goal_core_percentile` th percentile of the cells counting any (the largest counts are noisy)
    goal_core_fraction: float = 0.5
    goal_core_percentile: float = 90.0
    #: points (count) on each of the two rings around the grasp point that :func:`two_link_grasps` solves (a
    #: quarter and half the grasp tolerance out): 2-joint arms hold a grasp in at most two ways, the rings
    #: give a transit targets that still count as holding it
    two_link_probes: int = 12


#: The defaults, which the functions below take unless given other settings.
REACH = ReachSettings()


def reach_of(ctx: PlanningContext) -> ReachSettings:
    """The reach tuning of a planning run's planar space (``PlanarSpace.reach_settings``, a
    ``PlanarTuning.reach`` copy when a benchmark varies it)."""
    settings = getattr(ctx.space, "reach_settings", None)
    if not isinstance(settings, ReachSettings):
        raise TypeError(f"expected a planning context over a planar space, got {type(ctx.space).__name__}")
    return settings


#: Random starts of the holding configurations' solver unless told otherwise (the run's are
#: ``PlanningContext.hold_samples``).
_HOLD_SAMPLES = SearchSettings().hold_samples


def _cell_centres(cells: int = REACH.approach_cells) -> np.ndarray:
    """Approach angle at the centre of each cell: cell ``i`` is centred on ``(i + 0.5) 2 pi / cells``."""
    return (np.arange(cells) + 0.5) * 2.0 * np.pi / cells


def approach_cell(psi: np.ndarray | float, cells: int = REACH.approach_cells) -> np.ndarray:
    """Index of the cell holding approach angle ``psi`` (rad, any turn)."""
    return (np.mod(psi, 2.0 * np.pi) / (2.0 * np.pi) * cells).astype(int) % cells


def approach_cells(
    world: World, object_pose: np.ndarray, grasp: int, *, angle_spread: float = 0.0, position_slack: float = 0.0
) -> np.ndarray:
    """Which approach angles could hold grasp ``grasp`` of the object at ``object_pose``.

    Held rigidly, the last link keeps one direction ``psi`` in the object's
    frame. For each of :attr:`ReachSettings.approach_cells` cells of ``psi`` (cell ``i``
    centred on ``(i + 0.5) 2 pi / cells``), ``False`` means that no direction
    in the cell puts the last joint inside the annulus the other links sweep,
    for any object orientation within ``angle_spread`` of ``object_pose`` and
    any position within ``position_slack`` (plus the grasp tolerance):
    the grasp cannot be held that way there. Obstacles and joint limits are
    ignored, so ``True`` promises nothing.
    """
    robot = world.robot
    cells = REACH.approach_cells
    if robot.dof < 2:
        return np.ones(cells, bool)
    last = float(robot.link_lengths[-1])
    rest = robot.link_lengths[:-1]
    inner = max(0.0, 2.0 * float(rest.max()) - float(rest.sum()))
    outer = float(rest.sum())
    grasp_point = np.asarray(world.object.grasps[grasp], float)
    theta = float(object_pose[2])
    v = transform_points(np.asarray(object_pose, float), grasp_point[None])[0] - robot.base
    distance = float(np.hypot(*v))
    spread = min(float(angle_spread), np.pi)
    half = np.pi / cells + spread  # half-width of the absolute directions a cell stands for
    psi = _cell_centres(cells)
    # the last joint is at point - last * u, u = dir(theta + psi): |joint - base|^2 =
    # distance^2 + last^2 - 2 last distance cos(angle(u, v)), extreme at the cell's extreme angles
    delta = np.abs((theta + psi - np.arctan2(v[1], v[0]) + np.pi) % (2.0 * np.pi) - np.pi)
    squared = distance**2 + last**2
    near = np.sqrt(np.maximum(squared - 2.0 * last * distance * np.cos(np.maximum(0.0, delta - half)), 0.0))
    far = np.sqrt(np.maximum(squared - 2.0 * last * distance * np.cos(np.minimum(np.pi, delta + half)), 0.0))
    # the grasp point itself moves with the orientation spread (chord <= arc) and the slack
    slack = float(np.hypot(*grasp_point)) * spread + position_slack + world.grasp_tolerance + 1e-9
    holdable: np.ndarray = (far >= inner - slack) & (near <= outer + slack)
    return holdable


def approach_excess(cells: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """``psi -> angle (rad)`` from approach angles ``psi`` to the nearest allowed cell of ``cells``:
    piecewise linear between cell centres so that it has a slope to follow, 0 between the centres
    of allowed cells and at most half a cell's width inside the edge cells of an allowed run."""
    count = len(cells)
    centres = _cell_centres(count)
    allowed = centres[cells]
    gap = np.abs((centres[:, None] - allowed[None] + np.pi) % (2.0 * np.pi) - np.pi)
    distance = np.min(gap, axis=1) if len(allowed) else np.full(count, np.pi)
    distance = np.maximum(distance - np.pi / count, 0.0)  # a cell counts from its edge
    xp = np.concatenate([centres[-1:] - 2.0 * np.pi, centres, centres[:1] + 2.0 * np.pi])
    fp = np.concatenate([distance[-1:], distance, distance[:1]])

    def excess(psi: np.ndarray) -> np.ndarray:
        angle: np.ndarray = np.interp(np.mod(psi, 2.0 * np.pi), xp, fp)
        return angle

    return excess


def two_link_grasps(
    world: World, object_pose: np.ndarray, grasp: int, probes: int = REACH.two_link_probes
) -> np.ndarray:
    """Two-joint arms: the configurations ``(m, 2)`` that hold grasp ``grasp`` of the object resting
    at ``object_pose``, valid and within the joint limits.

    A two-link arm reaches a point with at most two configurations (elbow one
    way or the other), so SEARCH_TRANSIT can only end near one of them. The
    grasp point and two rings of ``probes`` points around it, at a quarter
    and half the grasp tolerance (how close a transit must end), are solved.
    Unlike the other functions here this is a sampled test, not a bound: an
    empty answer means no transit can end at those points, so a transit that
    could only end between them (a sliver of free space thinner than the
    probes' spacing, or an elbow limit met just there) is given up.
    """
    robot = world.robot
    l1, l2 = (float(v) for v in robot.link_lengths)
    centre = transform_points(np.asarray(object_pose, float), np.asarray(world.object.grasps[grasp], float)[None])[0]
    ring = np.linspace(0.0, 2.0 * np.pi, probes, endpoint=False)
    circle = np.column_stack([np.cos(ring), np.sin(ring)])
    tolerance = world.grasp_tolerance
    points = np.vstack([centre, centre + 0.25 * tolerance * circle, centre + 0.5 * tolerance * circle])
    v = points - robot.base
    cos_elbow = (np.sum(v * v, axis=1) - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)
    reachable = np.abs(cos_elbow) <= 1.0
    v, cos_elbow = v[reachable], cos_elbow[reachable]
    elbow = np.arccos(np.clip(cos_elbow, -1.0, 1.0))
    q2 = np.concatenate([elbow, -elbow])
    q1 = np.tile(np.arctan2(v[:, 1], v[:, 0]), 2) - np.arctan2(l2 * np.sin(q2), l1 + l2 * np.cos(q2))
    q: np.ndarray = np.column_stack([q1, q2])
    # each joint to its representative within the limits, if any (limits may span more than a turn)
    lower, upper = robot.joint_lower, robot.joint_upper
    q = lower + np.mod(q - lower, 2.0 * np.pi)
    q = q[np.all(q <= upper, axis=1)]
    if not len(q):
        return q
    valid: np.ndarray = q[is_valid(world, q, np.asarray(object_pose, float)[None])]
    return valid


def carry_cells(world: World, goal: np.ndarray, grasp: int) -> np.ndarray:
    """Which approach angles could carry the object, held by ``grasp``, to the goal position.

    Held with approach ``psi`` the object's origin is a fixed point of the last
    link's frame, ``last * x - R(-psi) grasp``: the chain ending there must
    reach the goal position (within ``goal_tolerance``), whatever the goal
    orientation. Per cell of :attr:`ReachSettings.approach_cells`, loosened by what the
    origin moves within the cell; obstacles and joint limits ignored.
    """
    robot = world.robot
    cells = REACH.approach_cells
    grasp_point = np.asarray(world.object.grasps[grasp], float)
    psi = _cell_centres(cells)
    c, s = np.cos(-psi), np.sin(-psi)
    last = float(robot.link_lengths[-1])
    virtual = np.hypot(last - (c * grasp_point[0] - s * grasp_point[1]), -(s * grasp_point[0] + c * grasp_point[1]))
    rest = np.asarray(robot.link_lengths[:-1], float)
    longest_rest = float(rest.max()) if len(rest) else 0.0
    total = float(rest.sum()) + virtual
    inner = np.maximum(0.0, 2.0 * np.maximum(longest_rest, virtual) - total)
    distance = float(np.hypot(*(np.asarray(goal[:2], float) - robot.base)))
    slack = float(np.hypot(*grasp_point)) * np.pi / cells + world.goal_tolerance + world.grasp_tolerance + 1e-9
    carriable: np.ndarray = (distance >= inner - slack) & (distance <= total + slack)
    return carriable


def holding_configurations(
    world: World,
    object_pose: np.ndarray,
    grasp: int,
    samples: int = _HOLD_SAMPLES,
    iterations: int = REACH.hold_iterations,
) -> np.ndarray:
    """Arms of any number of joints: valid configurations ``(m, n)`` within the joint limits that
    hold grasp ``grasp`` of the object resting at ``object_pose`` (tip within half the grasp tolerance).

    Sampled, like :func:`two_link_grasps`: damped least squares on the tip position
    (:func:`clew_ros.planar.inverse.solve_point`, compiled), from ``samples`` random configurations
    within the limits, all solved at once and clamped to the limits at every step; the converged ones
    that pass the validity test are returned. An empty answer means none was found, not that none
    exists. The random starts come from a generator seeded by the request itself, so the answer is the
    same whenever it is asked and the planner's own random stream is untouched.
    """
    pose = np.asarray(object_pose, float)
    target = transform_points(pose, np.asarray(world.object.grasps[grasp], float)[None])[0]
    seed = np.frombuffer(np.round(np.r_[pose, target], 9).tobytes(), dtype=np.uint32)
    rng = np.random.default_rng([grasp, *seed.tolist()])
    q, _, holding = _solve_holds(world, np.broadcast_to(target, (samples, 2)), rng, iterations)
    held: np.ndarray = q[holding]
    if not len(held):
        return held
    valid: np.ndarray = held[is_valid(world, held, pose[None])]
    return valid


def holding_configurations_aimed(
    world: World, object_pose: np.ndarray, grasp: int, approach: np.ndarray, samples: int = _HOLD_SAMPLES
) -> np.ndarray:
    """:func:`holding_configurations` whose last link comes in within an allowed ``approach`` cell (of
    :func:`approach_cells`): the solver is given the tip's angle too, the centre of an allowed cell drawn
    for each start (uniformly among the allowed cells), within half a cell. For arms of many joints,
    where few unaimed samples fall in a narrow set of cells. Seeded by the request as the other."""
    allowed = np.flatnonzero(approach)
    if not len(allowed):
        return np.zeros((0, world.robot.dof))
    pose = np.asarray(object_pose, float)
    target = transform_points(pose, np.asarray(world.object.grasps[grasp], float)[None])[0]
    seed = np.frombuffer(np.round(np.r_[pose, target], 9).tobytes(), dtype=np.uint32)
    rng = np.random.default_rng([grasp, len(allowed), *seed.tolist()])
    robot = world.robot
    cells = allowed[rng.integers(0, len(allowed), samples)]
    angles = pose[2] + _cell_centres(len(approach))[cells]
    start = rng.uniform(robot.joint_lower, robot.joint_upper, size=(samples, robot.dof))
    return _aimed_holds(
        world, start, target, pose, angles=angles, approach=approach, angle_tolerance=np.pi / len(approach)
    )


def holding_configurations_near(
    world: World,
    q0: np.ndarray,
    object_pose: np.ndarray,
    grasp: int,
    approach: np.ndarray | None,
    *,
    starts: int,
    spread_rad: float,
) -> np.ndarray:
    """:func:`holding_configurations` solved from the arm's own configuration ``q0`` and ``starts`` - 1
    configurations drawn around it (``spread_rad`` per joint, within the limits): damped least squares
    moves the joints little, so these holds are near ``q0`` in joint space and a straight move to them
    travels little (arms of many joints, whose random holds lie far from any posture). With ``approach``
    (cells of :func:`approach_cells`), the tip's angle is aimed at the allowed cell nearest the start's.
    Seeded by the request, as the others."""
    robot = world.robot
    q0 = np.asarray(q0, float)
    pose = np.asarray(object_pose, float)
    target = transform_points(pose, np.asarray(world.object.grasps[grasp], float)[None])[0]
    seed = np.frombuffer(np.round(np.r_[q0, pose, target], 9).tobytes(), dtype=np.uint32)
    rng = np.random.default_rng([grasp, starts, *seed.tolist()])
    drawn = q0 + rng.normal(0.0, spread_rad, size=(max(0, starts - 1), robot.dof))
    start = np.clip(np.vstack([q0[None], drawn]), robot.joint_lower, robot.joint_upper)
    angles = None
    tolerance = np.pi
    if approach is not None:
        allowed = np.flatnonzero(approach)
        if not len(allowed):
            return np.zeros((0, robot.dof))
        centres = _cell_centres(len(approach))[allowed]
        psi = tip_poses(robot, start)[:, 2] - pose[2]
        nearest = np.argmin(np.abs(wrap_angle(psi[:, None] - centres[None])), axis=1)
        angles = pose[2] + centres[nearest]
        tolerance = np.pi / len(approach)
    return _aimed_holds(world, start, target, pose, angles=angles, approach=approach, angle_tolerance=tolerance)


def _aimed_holds(
    world: World,
    start: np.ndarray,
    target: np.ndarray,
    pose: np.ndarray,
    *,
    angles: np.ndarray | None,
    approach: np.ndarray | None,
    angle_tolerance: float,
) -> np.ndarray:
    """The valid configurations, solved from ``start`` with the tip at ``target`` (and at ``angles`` within
    ``angle_tolerance`` when given), that hold the grasp within half the grasp tolerance and, with
    ``approach``, come in within an allowed cell: what the aimed and the near holds share."""
    robot = world.robot
    solved = solve_point(
        robot,
        start,
        np.broadcast_to(target, (len(start), 2)),
        angles=angles,
        angle_tolerance=angle_tolerance,
        iterations=REACH.hold_iterations * 2,
        tolerance_m=0.25 * world.grasp_tolerance,
    )
    tips = tip_poses(robot, solved.q)
    holding = np.linalg.norm(tips[:, :2] - target, axis=1) <= 0.5 * world.grasp_tolerance
    if approach is not None:
        holding &= approach[approach_cell(tips[:, 2] - pose[2], len(approach))]
    held: np.ndarray = solved.q[holding]
    if not len(held):
        return held
    valid: np.ndarray = held[is_valid(world, held, pose[None])]
    return valid


def _solve_holds(
    world: World, targets: np.ndarray, rng: np.random.Generator, iterations: int = REACH.hold_iterations
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Inverse kinematics of the tip onto ``targets`` ``(B, 2)`` from one random start within the joint limits
    each (drawn from ``rng``): the configurations ``(B, n)``, their tip frames ``(B, 3)`` and which of them
    hold the target (tip within half the grasp tolerance) ``(B,)``."""
    robot = world.robot
    start = rng.uniform(robot.joint_lower, robot.joint_upper, size=(len(targets), robot.dof))
    q = solve_point(robot, start, targets, iterations=iterations, tolerance_m=0.25 * world.grasp_tolerance).q
    tips = tip_poses(robot, q)
    return q, tips, np.linalg.norm(tips[:, :2] - targets, axis=1) <= 0.5 * world.grasp_tolerance


def goal_approach_core(
    world: World, goal: np.ndarray, grasp: int, samples: int = _HOLD_SAMPLES, settings: ReachSettings = REACH
) -> np.ndarray | None:
    """The approach cells (of :attr:`ReachSettings.approach_cells`) where most of the valid configurations holding
    ``grasp`` with the object on ``goal`` lie; ``None`` when the sample found none.

    Configurations holding the grasp at ``settings.goal_core_angles`` orientations within the goal's angle
    tolerance are sampled like :func:`holding_configurations` (``samples`` random starts each, all solved
    in one batch, kept when the compiled first pass finds them valid beyond doubt); their approach angles
    are counted per cell and smoothed over ``settings.goal_core_window_rad``; cells counting at least
    ``settings.goal_core_fraction`` of a high count (``settings.goal_core_percentile``) are kept. Where few
    configurations hold the goal (an arm at full stretch, an approach between obstacles) a transfer must
    end in a sliver of joint space; a grasp taken in the core has room. The random starts come from a
    generator seeded by the request: the same answer whenever it is asked.
    """
    goal = np.asarray(goal, float)
    span = min(float(world.goal_angle_tolerance), np.pi)
    thetas = goal[2] + np.linspace(-span, span, settings.goal_core_angles, endpoint=span < np.pi)
    poses = np.repeat(np.column_stack([np.broadcast_to(goal[:2], (len(thetas), 2)), thetas]), samples, axis=0)
    targets = compose(poses, np.r_[world.object.grasps[grasp], 0.0])[:, :2]
    seed = np.frombuffer((np.round(goal, 9) + 0.0).tobytes(), dtype=np.uint32)  # + 0.0: -0.0 is 0.0
    q, tips, held = _solve_holds(world, targets, np.random.default_rng([grasp, *seed.tolist()]))
    held[held] = clearly_valid(packed_world(world), np.ascontiguousarray(q[held]), poses[held])
    if not held.any():
        return None
    cells = settings.approach_cells
    counts = np.bincount(approach_cell(tips[held, 2] - poses[held, 2], cells), minlength=cells).astype(float)
    width = round(settings.goal_core_window_rad / (2.0 * np.pi) * cells)
    smoothed = np.convolve(np.pad(counts, width, mode="wrap"), np.ones(2 * width + 1), "valid")  # cells wrap around
    high = np.percentile(smoothed[smoothed > 0], settings.goal_core_percentile)
    core: np.ndarray = smoothed >= settings.goal_core_fraction * high
    return core
