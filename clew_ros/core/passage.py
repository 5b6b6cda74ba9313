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
``polylabel`` finds (any inscribed disc keeps the proof sound; a larger one
proves more).
"""

from __future__ import annotations

import math

import numpy as np
import shapely
from shapely.ops import polylabel

from clew_ros.core.kinematics import transform_points
from clew_ros.core.reach import nearest_grasp_distance
from clew_ros.core.world import World

__all__ = ["PROOF_MAX_OBSTACLES", "inscribed_disc", "passage_refusal"]

#: How much less than the inscribed radius the obstacles are grown by (m): touching counts as collision,
#: so any smaller radius keeps the proof sound, and the margin absorbs rounding in GEOS.
_GROW_MARGIN_M = 1e-7
#: Distance (m) within which a part of the free region counts as containing a point.
_CONTAINS_SLACK_M = 1e-6
#: Discs smaller than this prove nothing worth the geometry (m).
_MIN_RADIUS_M = 1e-4
#: Worlds with more obstacles than this are not tried: the union of the grown obstacles costs about
#: 0.1 s per 500 obstacles here, and the answer must come at once.
PROOF_MAX_OBSTACLES = 200
#: Points of the polyline that stands for the arc of goal orientations.
_ARC_STEPS = 65
#: Segments per quarter circle of shapely's round buffers.
_QUAD_SEGS = 8


def inscribed_disc(polygon: np.ndarray) -> tuple[np.ndarray, float]:
    """A large disc inside ``polygon`` ``(V, 2)``: its centre ``(2,)`` and radius (m)."""
    shape = shapely.Polygon(polygon)
    extent = max(shape.bounds[2] - shape.bounds[0], shape.bounds[3] - shape.bounds[1])
    centre = polylabel(shape, tolerance=max(extent * 1e-3, 1e-9))
    radius = float(shape.exterior.distance(centre))
    return np.array([centre.x, centre.y]), radius


def _candidate_discs(polygon: np.ndarray) -> list[tuple[np.ndarray, float]]:
    """Discs inside the object to try: the largest found, and the one centred on the object's origin.

    The origin's disc is smaller, but its centre does not move when the object turns, so a goal
    orientation tolerance does not blur where it must end.
    """
    discs = [inscribed_disc(polygon)]
    shape = shapely.Polygon(polygon)
    origin = shapely.Point(0.0, 0.0)
    if shape.contains(origin):
        discs.append((np.zeros(2), float(shape.exterior.distance(origin))))
    return [(centre, radius) for centre, radius in discs if radius >= _MIN_RADIUS_M]


def _goal_region(world: World, goal: np.ndarray, centre: np.ndarray) -> shapely.Geometry:
    """Every place the disc's centre may take in a final pose within the goal tolerances.

    An arc of radius ``|centre|`` around the goal position (the orientation tolerance), thickened by
    ``goal_tolerance``, and by the arc's sagitta so that its polyline never cuts a corner: a superset of
    the true region, as the proof needs.
    """
    span = min(world.goal_angle_tolerance, math.pi)
    steps = _ARC_STEPS if span > 0 and np.any(centre) else 1
    angles = goal[2] + np.linspace(-span, span, steps) if steps > 1 else np.array([goal[2]])
    poses = np.column_stack([np.full(steps, goal[0]), np.full(steps, goal[1]), angles])
    points = transform_points(poses, centre[None])[:, 0]
    sagitta = float(np.linalg.norm(centre)) * (1 - math.cos(span / max(steps - 1, 1) / 2))
    path = shapely.LineString(points) if steps > 1 else shapely.Point(points[0])
    # shapely's round caps are polygons inscribed in the circle: grow by 1/cos of half a segment's angle
    # so that the polygon contains the true thickened arc.
    thickness = (world.goal_tolerance + sagitta + _CONTAINS_SLACK_M) / math.cos(math.pi / (4 * _QUAD_SEGS))
    return path.buffer(thickness, quad_segs=_QUAD_SEGS)


def passage_refusal(world: World, goal: np.ndarray) -> str | None:
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
    return _separated(world, goal)


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


def _separated(world: World, goal: np.ndarray) -> str | None:
    if not world.obstacles:
        return None  # the shrunk box is convex, so connected
    if len(world.obstacles) > PROOF_MAX_OBSTACLES:
        return None  # the union of the grown obstacles would cost more than a quick answer may
    for centre, radius in _candidate_discs(world.object.polygon):
        reason = _separated_for_disc(world, goal, centre, radius)
        if reason is not None:
            return reason
    return None


def _separated_for_disc(world: World, goal: np.ndarray, centre: np.ndarray, radius: float) -> str | None:
    xmin, ymin, xmax, ymax = (float(v) for v in world.bounds)
    if xmax - xmin <= 2 * radius or ymax - ymin <= 2 * radius:
        return None  # no room: the start would not be valid either; prove nothing
    box = shapely.box(xmin + radius, ymin + radius, xmax - radius, ymax - radius)
    obstacles = shapely.polygons([o.vertices for o in world.obstacles])
    grown: np.ndarray = np.asarray(shapely.buffer(obstacles, radius - _GROW_MARGIN_M, quad_segs=_QUAD_SEGS))
    free = box.difference(shapely.union_all(grown))
    start_centre = shapely.Point(transform_points(world.object.initial, centre[None])[0])
    parts = list(getattr(free, "geoms", [free]))
    reachable = [part for part in parts if part.distance(start_centre) <= _CONTAINS_SLACK_M]
    if not reachable:
        return None  # numerics: the start's own disc is not in F; prove nothing
    ends = _goal_region(world, goal, centre)
    if any(part.intersects(ends) for part in reachable):
        return None
    goal_side = shapely.union_all([part for part in parts if part.intersects(ends)])
    closing = [
        obstacle.name
        for obstacle, shape in zip(world.obstacles, grown, strict=True)
        if not goal_side.is_empty and shape.distance(goal_side) <= _CONTAINS_SLACK_M
    ]
    around = f" (the goal's side is closed off by {', '.join(repr(n) for n in closing)})" if closing else ""
    return (
        f"the object cannot pass from its start to the goal: a disc of radius {radius:.3f} m inside it "
        f"finds no way between the obstacles from where it starts to where it must end{around}"
    )
