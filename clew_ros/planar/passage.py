"""Whether the object can pass from its start to its goal at all: a proof of infeasibility.

Not an idea of the paper (docs/algorithm.md lists it among the departures):
the planner itself never proves that no plan exists, it stops at
``planner.resolution`` or at its time limit. Some worlds can be refused at
once, with a proof that holds whatever the arm does:

* **The object never moves.** It moves only while held, and it is first taken
  at its start placement. When no grasp point of the object at its start lies
  within the arm's reach (plus ``grasp_tolerance``) of the base, it stays where
  it is, so a goal it does not already satisfy is never reached.
* **The free workspace separates start and goal.** Take any disc inside the
  object polygon (centre ``c`` in the object frame, radius ``r``). Wherever
  the object is, carried or resting, it lies inside ``bounds`` and meets no
  obstacle, so that disc does too, whatever the orientation: the disc's centre
  stays in ``F``, the box shrunk by ``r`` minus every obstacle grown by ``r``.
  The centre moves continuously, so it stays in the connected part of ``F``
  where it starts. A final pose within the goal tolerances puts the centre
  within ``goal_tolerance + |c| * goal_angle_tolerance`` of its place at the
  goal pose; when that part of ``F`` stays farther than this, no plan exists.

Soundness: shapely draws the grown obstacles as polygons whose vertices lie on
the true offset curve, so they lie inside the true grown obstacles; the
obstacles are grown by slightly less than ``r``; and the start's part of
``F`` is taken generously (any part within a micrometre of the start centre).
Each approximation makes ``F`` larger, so it can only fail to refuse, never
refuse a world that has a plan. The disc is the largest one shapely's
``maximum_inscribed_circle`` finds, shrunk a little (any inscribed disc keeps
the proof sound; a larger one proves more).

Two callers: the planner's quick answers (:func:`passage_refusal`: both
proofs, every disc of :func:`_candidate_discs`, the goal a client asked for)
and the ``unsolvable`` family of generated worlds (:func:`separation`: the
second proof with the largest disc, the world's own goal), which keeps a ring
around the goal only when this proves it closed. The numbers the geometry
uses are the fields of :class:`ProofSettings`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely

from clew_ros.planar.kinematics import transform_points
from clew_ros.planar.reach import nearest_grasp_distance
from clew_ros.planar.world import World

__all__ = ["ProofSettings", "Separation", "inscribed_disc", "passage_refusal", "separating_disc", "separation"]


@dataclass(frozen=True)
class ProofSettings:
    """The numbers of the proof's geometry; the defaults are what the planner and the generated worlds use."""

    #: How much less than the inscribed radius the obstacles are grown by (m): touching counts as collision,
    #: so any smaller radius keeps the proof sound, and the margin absorbs rounding in GEOS.
    grow_margin_m: float = 1e-7
    #: Distance (m) within which a part of the free region counts as containing a point.
    contains_slack_m: float = 1e-6
    #: Discs smaller than this (m) prove nothing worth the geometry.
    min_radius_m: float = 1e-4
    #: Worlds with more obstacles than this are not tried (count): the union of the grown obstacles costs
    #: about 0.1 s per 500 obstacles, and the planner's answer must come at once.
    max_obstacles: int = 200
    #: Points of the polyline that stands for the arc of goal orientations (count).
    arc_steps: int = 65
    #: Segments per quarter circle of shapely's round buffers (count): more hug the true circle closer.
    quad_segs: int = 8
    #: Tolerance (m) of shapely's search for the largest inscribed circle.
    disc_tolerance_m: float = 1e-5
    #: The inscribed disc's radius is the found one times this (ratio): the search's tolerance works both
    #: ways, so a slightly smaller disc is surely inside the object.
    disc_shrink: float = 0.999


_DEFAULT = ProofSettings()


@dataclass(frozen=True)
class Separation:
    """A disc inside the object (centre in the object frame, radius in m) whose free space keeps the goal
    from the start, and the obstacles that close off the goal's side (names, world order)."""

    centre: np.ndarray
    radius: float
    closing: tuple[str, ...]


def inscribed_disc(polygon: np.ndarray, settings: ProofSettings = _DEFAULT) -> tuple[np.ndarray, float]:
    """A large disc inside ``polygon`` ``(V, 2)``: its centre ``(2,)`` and radius (m)."""
    circle = shapely.maximum_inscribed_circle(shapely.Polygon(polygon), settings.disc_tolerance_m)
    return np.asarray(circle.coords[0], dtype=float), float(circle.length) * settings.disc_shrink


def _candidate_discs(polygon: np.ndarray, settings: ProofSettings) -> list[tuple[np.ndarray, float]]:
    """Discs inside the object to try: the largest found, and the one centred on the object's origin.

    The origin's disc is smaller, but its centre does not move when the object turns, so a goal
    orientation tolerance does not blur where it must end.
    """
    discs = [inscribed_disc(polygon, settings)]
    shape = shapely.Polygon(polygon)
    origin = shapely.Point(0.0, 0.0)
    if shape.contains(origin):
        discs.append((np.zeros(2), float(shape.exterior.distance(origin))))
    return [(centre, radius) for centre, radius in discs if radius >= settings.min_radius_m]


def _goal_region(world: World, goal: np.ndarray, centre: np.ndarray, settings: ProofSettings) -> shapely.Geometry:
    """Every place the disc's centre may take in a final pose within the goal tolerances.

    An arc of radius ``|centre|`` around the goal position (the orientation tolerance), thickened by
    ``goal_tolerance``, and by the arc's sagitta so that its polyline never cuts a corner: a superset of
    the true region, as the proof needs.
    """
    span = min(world.goal_angle_tolerance, math.pi)
    steps = settings.arc_steps if span > 0 and np.any(centre) else 1
    angles = goal[2] + np.linspace(-span, span, steps) if steps > 1 else np.array([goal[2]])
    poses = np.column_stack([np.full(steps, goal[0]), np.full(steps, goal[1]), angles])
    points = transform_points(poses, centre[None])[:, 0]
    sagitta = float(np.linalg.norm(centre)) * (1 - math.cos(span / max(steps - 1, 1) / 2))
    path = shapely.LineString(points) if steps > 1 else shapely.Point(points[0])
    # shapely's round caps are polygons inscribed in the circle: grow by 1/cos of half a segment's angle
    # so that the polygon contains the true thickened arc.
    slack = world.goal_tolerance + sagitta + settings.contains_slack_m
    thickness = slack / math.cos(math.pi / (4 * settings.quad_segs))
    return path.buffer(thickness, quad_segs=settings.quad_segs)


def passage_refusal(world: World, goal: np.ndarray, settings: ProofSettings = _DEFAULT) -> str | None:
    """Why no plan can take the object from its start to ``goal``, or ``None`` when none is proven.

    ``goal`` is the goal placement ``(x, y, theta)`` (the world's or a client's).
    The answer is a sentence for the outcome message; see the module docstring
    for the proof behind it.
    """
    goal = np.asarray(goal, dtype=float)
    start = world.object.initial
    if _within_goal(world, start, goal):
        return None
    reason = _never_grasped(world)
    if reason is not None:
        return reason
    if len(world.obstacles) > settings.max_obstacles:
        return None  # the union of the grown obstacles would cost more than a quick answer may
    found = separating_disc(world, goal, _candidate_discs(world.object.polygon, settings), settings)
    if found is None:
        return None
    around = f" (the goal's side is closed off by {', '.join(repr(n) for n in found.closing)})" if found.closing else ""
    return (
        f"the object cannot pass from its start to the goal: a disc of radius {found.radius:.3f} m inside it "
        f"finds no way between the obstacles from where it starts to where it must end{around}"
    )


def separation(world: World, settings: ProofSettings = _DEFAULT) -> str | None:
    """Why the object cannot pass from ``world.object.initial`` to ``world.object.goal`` (a sentence), or
    ``None`` when the free space eroded by its largest inscribed disc proves nothing.

    The second proof of the module docstring alone, with one disc: what the ``unsolvable`` family of
    generated worlds writes into its files.
    """
    disc = inscribed_disc(world.object.polygon, settings)
    found = separating_disc(world, world.object.goal, [disc], settings)
    if found is None:
        return None
    return (
        f"the object cannot pass from its start to its goal: the free space eroded by its inscribed disc "
        f"(radius {found.radius:.4f} m) puts them in different components"
    )


def _within_goal(world: World, pose: np.ndarray, goal: np.ndarray) -> bool:
    distance = math.hypot(pose[0] - goal[0], pose[1] - goal[1])
    angle = abs(math.remainder(pose[2] - goal[2], 2 * math.pi))
    return distance <= world.goal_tolerance and angle <= world.goal_angle_tolerance + 1e-9


def _never_grasped(world: World) -> str | None:
    nearest = nearest_grasp_distance(world, world.object.initial)
    if nearest <= world.robot.reach + world.grasp_tolerance:
        return None
    return (
        f"the object never moves: at its start its nearest grasp is {nearest:.3f} m from the base, "
        f"the arm reaches {world.robot.reach:.3f} m"
    )


def separating_disc(
    world: World, goal: np.ndarray, discs: list[tuple[np.ndarray, float]], settings: ProofSettings = _DEFAULT
) -> Separation | None:
    """The first of ``discs`` (centre in the object frame, radius in m, each inside the object) whose eroded
    free space keeps the start from ``goal`` within the goal tolerances, or ``None``."""
    if not world.obstacles:
        return None  # the shrunk box is convex, so connected
    goal = np.asarray(goal, dtype=float)
    for centre, radius in discs:
        found = _separated_for_disc(world, goal, centre, radius, settings)
        if found is not None:
            return found
    return None


def _separated_for_disc(
    world: World, goal: np.ndarray, centre: np.ndarray, radius: float, settings: ProofSettings
) -> Separation | None:
    xmin, ymin, xmax, ymax = (float(v) for v in world.bounds)
    if xmax - xmin <= 2 * radius or ymax - ymin <= 2 * radius:
        return None  # no room: the start would not be valid either; prove nothing
    box = shapely.box(xmin + radius, ymin + radius, xmax - radius, ymax - radius)
    obstacles = shapely.polygons([o.vertices for o in world.obstacles])
    grown: np.ndarray = np.asarray(
        shapely.buffer(obstacles, radius - settings.grow_margin_m, quad_segs=settings.quad_segs)
    )
    free = box.difference(shapely.union_all(grown))
    start_centre = shapely.Point(transform_points(world.object.initial, centre[None])[0])
    parts = list(getattr(free, "geoms", [free]))
    reachable = [part for part in parts if part.distance(start_centre) <= settings.contains_slack_m]
    if not reachable:
        return None  # numerics: the start's own disc is not in F; prove nothing
    ends = _goal_region(world, goal, centre, settings)
    if any(part.intersects(ends) for part in reachable):
        return None
    goal_side = shapely.union_all([part for part in parts if part.intersects(ends)])
    closing = tuple(
        obstacle.name
        for obstacle, shape in zip(world.obstacles, grown, strict=True)
        if not goal_side.is_empty and shape.distance(goal_side) <= settings.contains_slack_m
    )
    return Separation(centre, radius, closing)
