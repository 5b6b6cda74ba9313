"""Aimed regrasps in a spatial world: where to put the object down so that a grasp serving the goal can take it.

The paper's closing section proposes searching for intermediate placements inside the optimisation. SEARCH
from a landmark whose grasps all fail to reach the goal asks :meth:`SpatialAims.placements` for stable
placements (on any support: tables, boards, the floor of a bin) where

- the landmark's grasp holds the object in a valid configuration (it can put the object there), and
- another grasp that holds the object at the goal in a valid configuration (a *goal grasp*) holds it there
  too (it can take the object on from there);

SEARCH_TRANSFER then carries the object to one of them, and SEARCH goes on from that new landmark with its
regrasps in place (:func:`clew_ros.core.clew._search_via`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.tree import Landmark
from clew_ros.spatial.inverse import pose_rows
from clew_ros.spatial.placements import Support, placement_pose, sample_placements
from clew_ros.spatial.transforms import matrix_pose, rpy_matrix, turned_about_z
from clew_ros.spatial.views import HeldObjectView

__all__ = ["RegraspSettings", "SpatialAims"]

Array = NDArray[np.float64]

#: a placement solved for: the object's centre at a point of the support and level (its yaw free)
_LEVEL_AT = pose_rows(("x", "y", "z", "rx", "ry"))


class SpatialSpace(HeldObjectView, Protocol):
    """What the aims ask of :class:`clew_ros.spatial.space.SpatialSpace` beyond :class:`HeldObjectView`."""

    @property
    def dof(self) -> int: ...

    @property
    def grasp_count(self) -> int: ...

    @property
    def initial_joints(self) -> np.ndarray: ...

    def nearest_turns(self, q0: Array, found: Array) -> Array: ...

    def tcp(self, q: Array) -> Array: ...


def _matrix(pose: Array) -> Array:
    """A pose's 4x4 matrix (6 numbers, URDF rpy)."""
    out = np.eye(4)
    out[:3, :3] = rpy_matrix(*(float(v) for v in pose[3:]))
    out[:3, 3] = pose[:3]
    return out


@dataclass(frozen=True)
class RegraspSettings:
    """How intermediate placements are drawn and kept."""

    #: placements drawn per support and face (count) once per run; each costs one inverse kinematics per grasp
    per_support_face: int = 32
    #: random starts (count) of the inverse kinematics that decides whether a grasp holds the object at a
    #: placement ...
    ik_seeds: int = 16
    #: ... or at the goal (as many as SEARCH_TRANSFER's goal configurations: a grasp refused here is one that
    #: SEARCH_TRANSFER would give up at once)
    goal_seeds: int = 48
    #: the goal turned about z by these (rad, within ``world.goal_angle_tolerance``) when deciding goal grasps
    goal_yaws: tuple[float, ...] = (0.0, math.pi / 2, -math.pi / 2, math.pi)
    #: a placement nearer than this (m) to the landmark's or to the goal's is not an intermediate one
    min_move_m: float = 0.05
    #: where no drawn placement is held by both a landmark's grasp and a goal grasp (an arm that holds the
    #: object on few of them), placements are drawn again near those held by either, once per grasp: this
    #: many (count) near each of at most ``refine_sources`` of each grasp's, within ``refine_m`` (m) and
    #: ``refine_rad`` (rad of yaw)
    refine_draws: int = 8
    refine_sources: int = 8
    refine_m: float = 0.05
    refine_rad: float = 0.7
    #: where that finds none either, placements are solved for: per grasp (the landmark's and the goal
    #: grasps), support and face, inverse kinematics from this many random configurations (count) per point
    #: (the top's centre and half-way to each corner) sets the object down level there (its yaw free); at
    #: most ``solve_keep`` kept per grasp (count; 0: no solving), then refined as above
    solve_seeds: int = 4
    solve_keep: int = 8


def _spots(support: Support) -> list[tuple[float, float]]:
    """Points (x, y) of ``support``'s top a placement is solved at: its centre, then half-way to each corner."""
    cos, sin = math.cos(support.yaw), math.sin(support.yaw)
    out = [(float(support.center[0]), float(support.center[1]))]
    for u, v in ((0.5, 0.5), (-0.5, 0.5), (-0.5, -0.5), (0.5, -0.5)):
        du, dv = u * support.half[0], v * support.half[1]
        out.append((float(support.center[0] + cos * du - sin * dv), float(support.center[1] + sin * du + cos * dv)))
    return out


class SpatialAims:
    """The regrasp aims of one run towards ``goal`` (6 numbers): every approach allowed in place, and
    intermediate placements where a goal grasp can take the object (computed lazily, once per run)."""

    def __init__(self, space: SpatialSpace, goal: Array, settings: RegraspSettings | None = None) -> None:
        self.space, self.goal = space, np.asarray(goal, dtype=float)
        self.settings = settings or RegraspSettings()
        self._goal_grasps: list[int] | None = None
        self._drawn: Array | None = None  # (m, 4, 4) candidate placements
        self._where: list[tuple[int, str]] = []  # per candidate: its support (index) and face
        self._refined: set[int] = set()  # the grasps whose placements were refined (_refine)
        self._holds: dict[int, list[Array]] = {}  # grasp -> per candidate, the configurations holding it
        self._goal_solutions: dict[int, Array] = {}  # goal grasp -> configurations holding the object at the goal
        self._take_costs: dict[tuple[int, bytes], float] = {}  # (grasp, placement) -> take_cost
        self._rng = np.random.default_rng([int(v * 1e6) & 0xFFFFFFFF for v in self.goal])

    # -- the core's RegraspAims
    def retake(self, grasp: int, grasp_rel: np.ndarray) -> bool:
        return False

    def aim(self, landmark: Landmark, grasp: int) -> Any | None:
        """Every approach of a goal grasp (:meth:`goal_grasps`; of every grasp where none was found); ``None``:
        a regrasp in place with a grasp that holds the object at the goal in no configuration is not worth
        its transit."""
        goal_grasps = self.goal_grasps()
        return np.ones(1, dtype=bool) if grasp in goal_grasps or not goal_grasps else None

    def ranked(self, landmark: Landmark, grasps: list[int]) -> list[int]:
        """The goal grasps among ``grasps`` first, nearest first: the joint distance (rad, L1) from a
        configuration holding the object by it at ``landmark``'s placement to one holding it at the goal (the
        transfer after the regrasp); then the others, as they were."""
        goal_grasps = set(self.goal_grasps())
        serving = [g for g in grasps if g in goal_grasps]
        if len(serving) < 2:
            return serving + [g for g in grasps if g not in goal_grasps]
        cost = {g: self.take_cost(g, landmark.object_pose) for g in serving}
        return sorted(serving, key=lambda g: cost[g]) + [g for g in grasps if g not in goal_grasps]

    def take_cost(self, grasp: int, object_pose: Array) -> float:
        """The least joint distance (rad, L1, by whole turns) from a configuration holding the object by
        ``grasp`` at ``object_pose`` (6 numbers) to one holding it at the goal (inf: either is not found)."""
        if grasp not in self.goal_grasps():
            return math.inf
        key = (grasp, np.asarray(object_pose, dtype=float).tobytes())
        if key not in self._take_costs:
            here = _matrix(np.asarray(object_pose, dtype=float))[None]
            found = self._solve(grasp, here, self.settings.ik_seeds)[0]
            self._take_costs[key] = self._nearest(found, self._goal_solutions[grasp])
        return self._take_costs[key]

    def placements(self, landmark: Landmark, grasp: int, start: np.ndarray) -> list[np.ndarray]:
        """Intermediate placements (6 numbers each), best first: ``grasp`` holds the object there and so does
        a goal grasp other than it. The best are nearest in the joints: ``grasp``'s configuration there to
        ``start`` (holding it at ``landmark``'s placement), plus the goal grasp's there to its configuration
        at the goal (rad, L1; the nearest of the solutions found): the transfers on either side of the regrasp
        stay in one posture family."""
        goal_grasps = [g for g in self.goal_grasps() if g != grasp]
        if not goal_grasps:
            return []
        if not len(self._candidates()):
            return []
        found = self._placements(landmark, grasp, goal_grasps, start)
        if not found and grasp not in self._refined:
            self._refined.add(grasp)
            self._refine([grasp, *goal_grasps])
            found = self._placements(landmark, grasp, goal_grasps, start)
            if not found and self.settings.solve_keep > 0:
                since = len(self._candidates())
                self._solve_for([grasp, *goal_grasps])
                self._refine([grasp, *goal_grasps], since)
                found = self._placements(landmark, grasp, goal_grasps, start)
        return found

    def _placements(
        self, landmark: Landmark, grasp: int, goal_grasps: list[int], start: np.ndarray
    ) -> list[np.ndarray]:
        """:meth:`placements` among the candidates drawn so far."""
        drawn = self._candidates()
        here = _matrix(np.asarray(landmark.object_pose, dtype=float))[:3, 3]
        there = _matrix(self.goal)[:3, 3]
        centres = drawn[:, :3, 3]
        apart = (np.linalg.norm(centres - here, axis=1) > self.settings.min_move_m) & (
            np.linalg.norm(centres - there, axis=1) > self.settings.min_move_m
        )
        joints = np.asarray(start, dtype=float)
        cost = np.full(len(drawn), np.inf)
        mine = self._solutions(grasp)
        for k in np.flatnonzero(apart).tolist():
            if not len(mine[k]):
                continue
            put = float(np.min(np.abs(self.space.nearest_turns(joints, mine[k]) - joints).sum(axis=1)))
            take = min(
                (self._nearest(self._solutions(g)[k], self._goal_solutions[g]) for g in goal_grasps),
                default=math.inf,
            )
            cost[k] = put + take
        order = np.flatnonzero(np.isfinite(cost))
        order = order[np.argsort(cost[order], kind="stable")]
        return [np.asarray(matrix_pose(drawn[k])) for k in order]

    # -- what the placements rest on
    def goal_grasps(self) -> list[int]:
        """The grasps that hold the object at the goal (any yaw of :attr:`RegraspSettings.goal_yaws` within the
        goal's tolerance) in a valid configuration inverse kinematics finds."""
        if self._goal_grasps is None:
            space = self.space
            tolerance = space.world.tolerances["goal_angle_tolerance"]
            poses = turned_about_z(_matrix(self.goal), self.settings.goal_yaws, tolerance)
            self._goal_grasps = [g for g in range(space.grasp_count) if self._holds_any(g, np.array(poses))]
        return self._goal_grasps

    def _holds_any(self, grasp: int, poses: Array) -> bool:
        found = self._solve(grasp, poses, self.settings.goal_seeds)
        self._goal_solutions[grasp] = np.vstack([f for f in found if len(f)] or [np.zeros((0, self.space.dof))])
        return bool(len(self._goal_solutions[grasp]))

    def _solve(self, grasp: int, poses: Array, starts: int) -> list[Array]:
        """Valid configurations holding the object by ``grasp`` at each of ``poses`` (k, 4, 4): an (m, n) array
        each (m = 0: none found)."""
        space = self.space
        rel = space.grasp_rel(grasp)
        grasp_pose = np.asarray(np.linalg.inv(_matrix(np.asarray(rel, dtype=float))), dtype=np.float64)
        tcps = list(poses @ grasp_pose)
        seeds = [space.initial_joints[None]] * len(tcps)
        found: list[Array] = space.ik(starts).solve_many(
            tcps, self._rng, seeds=seeds, checker=space.transfer_checker(rel)
        )
        return found

    def _nearest(self, a: Array, b: Array) -> float:
        """The least L1 distance (rad) between a row of ``a`` and a row of ``b``, each of ``b`` taken by whole
        turns nearest the row of ``a`` (inf: either is empty)."""
        if not len(a) or not len(b):
            return math.inf
        return min(float(np.abs(self.space.nearest_turns(row, b) - row).sum(axis=1).min()) for row in a)

    def _candidates(self) -> Array:
        if self._drawn is None:
            world = self.space.world
            thing = world.object
            assert thing is not None
            drawn, where = [], []
            for s, support in enumerate(world.supports):
                for face in thing.shape.faces:
                    poses = sample_placements(
                        thing.shape, support, face, world.obstacles, count=self.settings.per_support_face, rng=self._rng
                    )
                    drawn.append(poses)
                    where += [(s, face)] * len(poses)
            self._drawn = np.concatenate(drawn) if drawn else np.zeros((0, 4, 4))
            self._where = where
        return self._drawn

    def _refine(self, grasps: list[int], since: int = 0) -> None:
        """New candidates near those ``grasps`` hold (:attr:`RegraspSettings.refine_draws`) among the candidates
        from index ``since`` on, solved for every grasp asked so far."""
        world, settings = self.space.world, self.settings
        thing = world.object
        assert thing is not None
        drawn = self._candidates()
        sources = sorted(
            {
                k
                for g in grasps
                for k in [k for k, q in enumerate(self._solutions(g)) if len(q) and k >= since][
                    : settings.refine_sources
                ]
            }
        )
        near = [
            sample_placements(
                thing.shape,
                world.supports[self._where[k][0]],
                self._where[k][1],
                world.obstacles,
                count=settings.refine_draws,
                rng=self._rng,
                around=(drawn[k], settings.refine_m, settings.refine_rad),
            )
            for k in sources
        ]
        self._add([n for n in near if len(n)], [self._where[k] for k, n in zip(sources, near, strict=True) if len(n)])

    def _add(self, poses: list[Array], where: list[tuple[int, str]]) -> None:
        """Candidates ``poses`` (each (k, 4, 4), on the support and face of ``where``'s entry), solved for every
        grasp asked so far."""
        if not poses:
            return
        added = np.concatenate(poses)
        self._drawn = np.concatenate([self._candidates(), added])
        self._where += [w for w, p in zip(where, poses, strict=True) for _ in range(len(p))]
        for g in self._holds:
            self._holds[g] = self._holds[g] + self._solve(g, added, self.settings.ik_seeds)

    def _solve_for(self, grasps: list[int]) -> None:
        """Candidates solved for where each of ``grasps`` holds the object (none drawn is held by both the
        landmark's grasp and a goal grasp: an arm that holds it on a sliver of a table): per support and face,
        from :attr:`RegraspSettings.solve_seeds` random configurations, the object set down level at the
        support's height (its x, y and yaw free), kept where it rests inside the top touching nothing else, at
        most :attr:`RegraspSettings.solve_keep` per grasp."""
        world, settings = self.space.world, self.settings
        thing = world.object
        assert thing is not None
        robot = world.robot
        ik = self.space.ik(1)
        for grasp in grasps:
            frame = _matrix(np.asarray(self.space.grasp_rel(grasp), dtype=float))
            kept: list[Array] = []
            where: list[tuple[int, str]] = []
            for s, support in enumerate(world.supports):
                for face in thing.shape.faces:
                    if len(kept) >= settings.solve_keep:
                        break
                    targets = np.array(
                        [placement_pose(thing.shape, support, face, x=x, y=y, yaw=0.0) for x, y in _spots(support)]
                    )
                    targets = np.repeat(targets, settings.solve_seeds, axis=0)
                    seeds = self._rng.uniform(robot.lower, robot.upper, size=(len(targets), robot.dof))
                    reached, ok = ik.solve_rows(targets, seeds, _LEVEL_AT, frame=frame)
                    for q in reached[ok]:
                        if len(kept) >= settings.solve_keep:
                            break
                        pose = self.space.tcp(q[None])[0] @ frame
                        placed = sample_placements(
                            thing.shape, support, face, world.obstacles, count=1, rng=self._rng, tries=1,
                            around=(pose, 0.0, 0.0),
                        )  # fmt: skip
                        if len(placed):
                            kept.append(placed)
                            where.append((s, face))
            self._add(kept, where)

    def _solutions(self, grasp: int) -> list[Array]:
        """Per candidate placement, the valid configurations found holding it by ``grasp``."""
        if grasp not in self._holds:
            self._holds[grasp] = self._solve(grasp, self._candidates(), self.settings.ik_seeds)
        return self._holds[grasp]
