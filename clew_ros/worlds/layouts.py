"""Obstacle layouts built around a witness: shelves, pockets, walls with windows, clutter, blocks beside a
placement, and the closed rings of the unsolvable family.

Every solvable layout is made of straight walls cut into cells of about :data:`CELL_M`; a cell is
kept only when :meth:`~clew_ros.worlds.sweep.Sweep.clear` says it keeps the margin from the arm and
the object along the whole witness, and the kept cells of a wall are merged back into rectangles.
So a wall built tight around a placement opens exactly where the witness came in or went out: a
pocket opens towards the side the arm entered from, a wall across the object's way gets the windows
the witness passed through. Each layout scores its candidates (how much of the intended walls
survives) and raises :class:`LayoutError` when none is good enough; the generator then starts over.
Vertices are rounded to 0.1 mm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely

from clew_ros.planar.kinematics import joint_positions, transform_points
from clew_ros.planar.world import World
from clew_ros.worlds.sweep import Sweep

__all__ = [
    "CELL_M",
    "Layout",
    "LayoutError",
    "blocks_near",
    "clutter",
    "pocket",
    "ring",
    "shelves",
    "window",
]

#: Length (m) of the cells walls are cut into before the witness carves them.
CELL_M = 0.04
#: Least share of the two boards beside the object that a shelf rack keeps.
SHELF_COVERAGE = 0.55
#: Farthest (m) a rack's further boards stand from the boards beside the object.
RACK_REACH_M = 0.6
#: Obstacle vertices are rounded to this grid (m).
GRID_M = 1e-4


class LayoutError(Exception):
    """No candidate layout was good enough around this witness."""


@dataclass
class Layout:
    """Obstacles by name (vertices (V, 2), counter-clockwise) and lines that describe them."""

    obstacles: dict[str, np.ndarray]
    notes: list[str]

    def add(self, prefix: str, polygons: list[np.ndarray]) -> None:
        for polygon in polygons:
            self.obstacles[f"{prefix}_{sum(k.startswith(prefix + '_') for k in self.obstacles):02d}"] = polygon


def _rounded(vertices: np.ndarray) -> np.ndarray:
    rounded: np.ndarray = np.round(np.round(vertices / GRID_M) * GRID_M, 4)
    return rounded


def polygons(vertices: list[np.ndarray] | np.ndarray) -> np.ndarray:
    """Shapely polygons ``(K,)`` of vertex arrays ``(K, V, 2)``."""
    return np.asarray(shapely.polygons(np.asarray(vertices)), dtype=object)


def rectangle(a: np.ndarray, b: np.ndarray, thickness: float) -> np.ndarray:
    """The rectangle (4, 2) of ``thickness`` m centred on the segment ``a -> b``, counter-clockwise."""
    u = (b - a) / np.linalg.norm(b - a)
    v = np.array([-u[1], u[0]]) * thickness / 2
    return _rounded(np.array([a - v, b - v, b + v, a + v]))


def _carved_wall(sweep: Sweep, a: np.ndarray, b: np.ndarray, thickness: float) -> tuple[list[np.ndarray], np.ndarray]:
    """The wall ``a -> b`` of ``thickness`` cut into cells, the cells that keep clear merged back into
    rectangles (runs of at least two cells), and the clear flag of each cell."""
    length = float(np.linalg.norm(b - a))
    count = max(1, round(length / CELL_M))
    ends = a + np.linspace(0.0, 1.0, count + 1)[:, None] * (b - a)
    cells = polygons([rectangle(ends[i], ends[i + 1], thickness) for i in range(count)])
    ok = sweep.clear(cells)
    pieces = []
    start = None
    for index, flag in enumerate([*ok.tolist(), False]):
        if flag and start is None:
            start = index
        elif not flag and start is not None:
            if index - start >= 2:
                pieces.append(rectangle(ends[start], ends[index], thickness))
            start = None
    return pieces, ok


@dataclass(frozen=True)
class _Frame:
    """A placement's minimum rotated rectangle: centre, unit axes ``u`` and ``v``, half sizes (m)."""

    centre: np.ndarray
    u: np.ndarray
    v: np.ndarray
    half_u: float
    half_v: float

    def point(self, along_u: float, along_v: float) -> np.ndarray:
        return self.centre + along_u * self.u + along_v * self.v

    def turned(self) -> _Frame:
        return _Frame(self.centre, self.v, -self.u, self.half_v, self.half_u)


def _frame(world: World, pose: np.ndarray) -> _Frame:
    polygon = shapely.Polygon(transform_points(np.asarray(pose, float), world.object.polygon))
    corners = shapely.get_coordinates(shapely.minimum_rotated_rectangle(polygon))[:4]
    edge_u, edge_v = corners[1] - corners[0], corners[2] - corners[1]
    centre = corners.mean(axis=0)
    return _Frame(
        centre,
        edge_u / np.linalg.norm(edge_u),
        edge_v / np.linalg.norm(edge_v),
        float(np.linalg.norm(edge_u)) / 2,
        float(np.linalg.norm(edge_v)) / 2,
    )


def _frame_along(world: World, pose: np.ndarray, direction: np.ndarray) -> _Frame:
    """The placement's bounding rectangle with its ``u`` axis along ``direction``."""
    vertices = transform_points(np.asarray(pose, float), world.object.polygon)
    u = direction / np.linalg.norm(direction)
    v = np.array([-u[1], u[0]])
    along_u, along_v = vertices @ u, vertices @ v
    centre = (along_u.max() + along_u.min()) / 2 * u + (along_v.max() + along_v.min()) / 2 * v
    return _Frame(centre, u, v, float(np.ptp(along_u)) / 2, float(np.ptp(along_v)) / 2)


def _approach_direction(world: World, sweep: Sweep, at_goal: bool) -> np.ndarray:
    """The last link's direction where the witness first takes the object (``at_goal`` false) or leaves
    it at the goal: the way the arm reaches in."""
    transfers = [s for s in sweep.plan.segments if s.kind == "transfer"]
    q = transfers[-1].waypoints[-1] if at_goal else transfers[0].waypoints[0]
    points = joint_positions(world.robot, np.asarray(q, float)[None])[0]
    direction: np.ndarray = points[-1] - points[-2]
    return direction


def _frame_walls(frame: _Frame, gap: float, thickness: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """The four walls (centre lines) of a closed frame ``gap`` m around the rectangle, corners included."""
    out_u, out_v = frame.half_u + gap + thickness / 2, frame.half_v + gap + thickness / 2
    long_u, long_v = frame.half_u + gap + thickness, frame.half_v + gap
    return [
        (frame.point(-long_u, out_v), frame.point(long_u, out_v)),
        (frame.point(-long_u, -out_v), frame.point(long_u, -out_v)),
        (frame.point(out_u, -long_v), frame.point(out_u, long_v)),
        (frame.point(-out_u, -long_v), frame.point(-out_u, long_v)),
    ]


def pocket(world: World, sweep: Sweep, rng: np.random.Generator, pose: np.ndarray) -> Layout:
    """A pocket around the placement ``pose``: a frame of walls close around the object, opened where the
    witness passes. Keeps the candidate (gap, thickness) with the most wall left, at least half of it."""
    frame = _frame(world, pose)
    best: tuple[float, list[np.ndarray]] = (0.0, [])
    for _ in range(6):
        gap = sweep.margin * float(rng.uniform(1.15, 2.0))
        thickness = float(rng.uniform(0.04, 0.08))
        pieces, kept = [], 0
        total = 0
        for a, b in _frame_walls(frame, gap, thickness):
            wall, ok = _carved_wall(sweep, a, b, thickness)
            pieces += wall
            kept += int(ok.sum())
            total += len(ok)
        if kept / total > best[0]:
            best = (kept / total, pieces)
    coverage, pieces = best
    if coverage < 0.5:
        raise LayoutError(f"the pocket keeps {coverage:.0%} of its walls")
    layout = Layout({}, [f"a pocket around the goal, {coverage:.0%} closed, open where the witness enters"])
    layout.add("pocket", pieces)
    return layout


def _rack(
    sweep: Sweep, frame: _Frame, *, gap: float, thickness: float, extra: int, overhang: float
) -> tuple[float, list[np.ndarray]]:
    """Boards along ``frame.u`` on both sides of the object (and ``extra`` more on each side, one shelf
    apart): the share of the two boards beside the object that stays, and the kept pieces."""
    pitch = 2 * (frame.half_v + gap) + thickness
    half = frame.half_u + overhang
    pieces: list[np.ndarray] = []
    beside = 0.0
    for side in (-1.0, 1.0):
        for level in range(extra + 1):
            if level * pitch > RACK_REACH_M:
                break
            offset = side * (frame.half_v + gap + thickness / 2 + level * pitch)
            wall, ok = _carved_wall(sweep, frame.point(-half, offset), frame.point(half, offset), thickness)
            pieces += wall
            if level == 0:
                centre = np.abs(np.linspace(-half, half, len(ok) + 1)[:-1] + half / len(ok)) <= frame.half_u + gap
                beside += float(ok[centre].mean()) / 2 if centre.any() else 0.0
    return beside, pieces


def shelves(world: World, sweep: Sweep, rng: np.random.Generator) -> Layout:
    """A rack of shelf boards at the start placement and one at the goal: the object sits between two
    boards, with more boards one shelf apart beside them. Each rack takes the orientation (along the last
    link where the arm reaches in, or either axis of the placement's rectangle) and gap that keep most of
    the two boards beside the object, at least :data:`SHELF_COVERAGE`."""
    layout = Layout({}, [])
    for name, pose in (("start", world.object.initial), ("goal", world.object.goal)):
        frame = _frame(world, pose)
        along = _frame_along(world, pose, _approach_direction(world, sweep, name == "goal"))
        best: tuple[float, list[np.ndarray]] = (0.0, [])
        for index in range(12):
            candidate = (along, frame, frame.turned())[index % 3]
            gap = sweep.margin * float(rng.uniform(1.15, 3.0))
            score, pieces = _rack(
                sweep,
                candidate,
                gap=gap,
                thickness=float(rng.uniform(0.03, 0.06)),
                extra=int(rng.integers(1, 3)),
                overhang=float(rng.uniform(0.15, 0.45)),
            )
            if score > best[0]:
                best = (score, pieces)
        if best[0] < SHELF_COVERAGE:
            raise LayoutError(f"the shelf at the {name} keeps {best[0]:.0%} of its boards")
        layout.add(f"shelf_{name}", best[1])
        layout.notes.append(f"a rack of shelves at the {name}, {best[0]:.0%} of the boards beside the object")
    return layout


def _clip_to_bounds(
    world: World, point: np.ndarray, direction: np.ndarray, inset: float
) -> tuple[np.ndarray, np.ndarray]:
    """The chord of the line through ``point`` along ``direction`` inside the bounds shrunk by ``inset``."""
    xmin, ymin, xmax, ymax = np.asarray(world.bounds) + np.array([inset, inset, -inset, -inset])
    far = 4.0 * float(max(xmax - xmin, ymax - ymin))
    line = shapely.LineString([point - far * direction, point + far * direction])
    chord = np.asarray(line.intersection(shapely.box(xmin, ymin, xmax, ymax)).coords)
    return chord[0], chord[-1]


def window(world: World, sweep: Sweep, rng: np.random.Generator) -> Layout:
    """A wall from bound to bound between the start and the goal placements, with the windows the witness
    passes through: the candidate line (across the way from start to goal) with the most wall left, at
    least 45%, 1 to 3 windows."""
    start, goal = np.asarray(world.object.initial[:2]), np.asarray(world.object.goal[:2])
    way = goal - start
    if np.linalg.norm(way) < 0.4:
        raise LayoutError("start and goal are too close for a wall between them")
    best: tuple[float, list[np.ndarray], int] = (0.0, [], 0)
    for _ in range(8):
        angle = math.atan2(way[1], way[0]) + math.pi / 2 + float(rng.uniform(-0.5, 0.5))
        point = start + float(rng.uniform(0.3, 0.7)) * way
        thickness = float(rng.uniform(0.04, 0.08))
        a, b = _clip_to_bounds(world, point, np.array([math.cos(angle), math.sin(angle)]), thickness / 2 + 1e-3)
        pieces, ok = _carved_wall(sweep, a, b, thickness)
        windows = int(np.sum(np.diff(np.r_[1, ok.astype(int), 1]) == -1))
        if 1 <= windows <= 3 and ok.mean() > best[0]:
            best = (float(ok.mean()), pieces, windows)
    if best[0] < 0.45:
        raise LayoutError(f"the wall keeps {best[0]:.0%} of its length")
    layout = Layout({}, [f"a wall between start and goal, {best[0]:.0%} of it standing, {best[2]} window(s)"])
    layout.add("wall", best[1])
    return layout


def _box(centre: np.ndarray, size: np.ndarray, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * size / 2
    return _rounded(centre + corners @ np.array([[c, s], [-s, c]]))


def _place_boxes(
    world: World,
    sweep: Sweep,
    rng: np.random.Generator,
    anchors: np.ndarray,
    *,
    count: int,
    reach: tuple[float, float],
    taken: list[np.ndarray],
) -> list[np.ndarray]:
    """Up to ``count`` boxes (5-14 cm) each ``reach`` m (beyond the margin) from a random anchor point,
    clear of the witness, inside the bounds and 3 cm from every box in ``taken`` and from each other."""
    boxes: list[np.ndarray] = []
    others = [shapely.Polygon(t) for t in taken]
    bounds = shapely.box(*world.bounds)
    for _ in range(60):
        if len(boxes) == count:
            break
        k = 32
        size = rng.uniform(0.05, 0.14, (k, 2))
        angle = rng.uniform(0.0, math.pi / 2, k)
        direction = rng.uniform(0.0, 2 * math.pi, k)
        distance = sweep.margin + np.linalg.norm(size, axis=1) / 2 + rng.uniform(*reach, k)
        centre = anchors[rng.integers(0, len(anchors), k)] + distance[:, None] * np.stack(
            [np.cos(direction), np.sin(direction)], axis=1
        )
        candidates = [_box(centre[i], size[i], float(angle[i])) for i in range(k)]
        shapes = polygons(candidates)
        ok = sweep.clear(shapes) & shapely.contains(bounds, shapes)
        for index in np.flatnonzero(ok):
            polygon = shapes[index]
            if all(polygon.distance(o) >= 0.03 for o in others):
                boxes.append(candidates[index])
                others.append(polygon)
                if len(boxes) == count:
                    break
    return boxes


def clutter(world: World, sweep: Sweep, rng: np.random.Generator, count: int) -> Layout:
    """``count`` boxes scattered along the witness (each 0-25 cm beyond the margin from a point the arm
    or the object passes); at least three quarters of them must find a place."""
    anchors = np.concatenate([sweep.object_vertices.reshape(-1, 2), sweep.arm_points[:, 1:].reshape(-1, 2)])
    boxes = _place_boxes(world, sweep, rng, anchors, count=count, reach=(0.0, 0.25), taken=[])
    if len(boxes) < 0.75 * count:
        raise LayoutError(f"only {len(boxes)} of {count} clutter boxes found a place")
    layout = Layout({}, [f"{len(boxes)} boxes scattered along the witness"])
    layout.add("box", boxes)
    return layout


def blocks_near(
    world: World,
    sweep: Sweep,
    rng: np.random.Generator,
    pose: np.ndarray,
    *,
    count: int,
    what: str,
    taken: list[np.ndarray],
) -> Layout:
    """Up to ``count`` boxes within 6 cm beyond the margin of the object placed at ``pose`` (``what``
    names the placement in the notes and the obstacle names)."""
    anchors = transform_points(np.asarray(pose, float), world.object.polygon)
    edges = np.roll(anchors, -1, axis=0) - anchors
    points = (anchors[:, None] + np.linspace(0.0, 1.0, 5)[None, :, None] * edges[:, None]).reshape(-1, 2)
    boxes = _place_boxes(world, sweep, rng, points, count=count, reach=(0.0, 0.06), taken=taken)
    layout = Layout({}, [f"{len(boxes)} block(s) close to the {what}"] if boxes else [])
    layout.add(f"near_{what}", boxes)
    return layout


def ring(world: World, start: Sweep, rng: np.random.Generator, *, opening: float | None) -> Layout:
    """A closed frame of walls around the goal placement (``opening`` None), or one with a gap of
    ``opening`` m in the middle of one wall; it must keep clear of the arm's start configuration and the
    object's start placement (``start``: the sweep of the start alone)."""
    frame = _frame(world, world.object.goal)
    for _ in range(8):
        gap = start.margin * float(rng.uniform(1.15, 2.5))
        thickness = float(rng.uniform(0.04, 0.08))
        walls = [rectangle(a, b, thickness) for a, b in _frame_walls(frame, gap, thickness)]
        if opening is not None:
            side = int(rng.integers(0, 4))
            a, b = _frame_walls(frame, gap, thickness)[side]
            middle, u = (a + b) / 2, (b - a) / np.linalg.norm(b - a)
            walls[side : side + 1] = [
                rectangle(a, middle - u * opening / 2, thickness),
                rectangle(middle + u * opening / 2, b, thickness),
            ]
        if start.clear(polygons(walls)).all():
            what = "closed ring" if opening is None else f"ring with a {opening:.3f} m opening"
            layout = Layout({}, [f"the goal inside a {what} the object cannot pass"])
            layout.add("ring", walls)
            return layout
    raise LayoutError("the ring around the goal meets the arm or the object at the start")
