"""The compiled validity checker of a spatial world, batched over configurations.

:class:`SpatialChecker` packs a robot's sphere model, the obstacles and the bounds once into arrays and
answers for whole batches (``(N, n)`` arrays of planned-joint values): :meth:`~SpatialChecker.valid`
(joint limits, spheres vs obstacles and bounds, self-collision over the pairs not exempted) and
:meth:`~SpatialChecker.free_intervals` (the interval of one joint, the others fixed, that is free for
the sphere model, found by conservative steps). The sphere model covers the URDF's geometry, so what the
checker calls free is free for the URDF's geometry. Touching counts as colliding.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.kernels import collide
from clew_ros.spatial.placements import MovableObject, Support
from clew_ros.spatial.robot import RobotModel
from clew_ros.spatial.scene import Obstacle, obstacle_arrays
from clew_ros.spatial.spheres import SphereModel, SphereSettings, cover

__all__ = ["Held", "IntervalSettings", "SpatialChecker"]


@dataclass(frozen=True)
class IntervalSettings:
    """How :meth:`SpatialChecker.free_intervals` steps."""

    #: Clearance (m) every step keeps from contact: room for the rounding of the distance computations.
    margin_m: float = 1e-7
    #: A step shorter than this (rad, or m for a prismatic joint) ends the interval on that side: near a
    #: contact the certified steps shrink geometrically, and the last few buy almost nothing.
    min_step: float = 1e-3
    #: At most this many steps each way (each one costs a forward kinematics and a clearance pass).
    max_steps: int = 64


@dataclass(frozen=True, eq=False)
class Held:
    """The object the robot holds (transfer): its shape, ``grasp`` (the tcp's 4x4 pose in the object's
    frame), and the ``supports`` it may touch from above (within ``tolerance_m``; it leaves one and is put
    down on one)."""

    shape: MovableObject
    grasp: NDArray[np.float64]
    supports: tuple[Support, ...] = ()
    tolerance_m: float = 0.001


def _bounding(centers: NDArray[np.float64], radii: NDArray[np.float64]) -> tuple[NDArray[np.float64], float]:
    middle = (centers.min(axis=0) + centers.max(axis=0)) / 2
    return middle, float(np.max(np.linalg.norm(centers - middle, axis=1) + radii))


def _held_arrays(robot: RobotModel, held: Held | None, obstacles: Sequence[Obstacle], n_links: int) -> dict[str, Any]:
    """The held object packed for the kernels: its piece's index (-1: none), its corners (a box) or cap
    centres (a cylinder) and its axis in the tcp's frame, its radius (0 for a box), and the supports it may
    touch from above: their obstacle indices and tops."""
    if held is None:
        return {
            "held_link": -1, "held_points": np.zeros((0, 3)), "held_disc": 0.0, "held_axis": np.zeros(3),
            "sup_index": np.zeros(0, dtype=np.int64), "sup_top": np.zeros(0), "sup_tol": 0.0,
        }  # fmt: skip
    placed = robot.tcp @ np.linalg.inv(held.grasp)
    if held.shape.shape == "box":
        half = np.asarray(held.shape.size) / 2
        points = np.array(np.meshgrid(*[[-h, h] for h in half], indexing="ij")).reshape(3, -1).T
        disc = 0.0
    else:
        points = np.array([[0.0, 0.0, -held.shape.size[0] / 2], [0.0, 0.0, held.shape.size[0] / 2]])
        disc = held.shape.size[1]
    names = [o.name for o in obstacles]
    missing = [s.name for s in held.supports if s.name not in names]
    if missing:
        raise ValueError(f"held.supports: {missing} are not among the obstacles")
    return {
        "held_link": n_links,
        "held_points": np.ascontiguousarray(points @ placed[:3, :3].T + placed[:3, 3]),
        "held_disc": disc,
        "held_axis": np.ascontiguousarray(placed[:3, 2]),
        "sup_index": np.array([names.index(s.name) for s in held.supports], dtype=np.int64),
        "sup_top": np.array([s.top for s in held.supports], dtype=np.float64),
        "sup_tol": float(held.tolerance_m),
    }


class SpatialChecker:
    """Validity and free intervals of one robot (its sphere model) among obstacles, inside bounds."""

    def __init__(
        self,
        robot: RobotModel,
        spheres: SphereModel,
        obstacles: Sequence[Obstacle] = (),
        bounds: NDArray[np.float64] | None = None,
        *,
        self_collision: bool = True,
        resting_object: Obstacle | None = None,
        held: Held | None = None,
    ) -> None:
        """``bounds``: ``[xmin, ymin, zmin, xmax, ymax, zmax]`` (m) or ``None`` (unbounded);
        ``self_collision`` false leaves every pair of links unchecked. ``resting_object``: the object where it
        rests (in transit), an obstacle to every link but the robot's ``gripper_links``. ``held``: the object
        in the hand (in transfer), its conservative spheres riding on the tcp's frame, checked against the
        obstacles (its supports only from below their top), the bounds and every link but the
        ``gripper_links``."""
        if resting_object is not None and held is not None:
            raise ValueError("resting_object and held: the object either rests or is held, not both")
        self.robot = robot
        self.spheres = spheres
        #: The scene's obstacles (without the resting object), the bounds, the held and the resting object, as
        #: given: what :func:`~clew_ros.spatial.validate.explain_invalid` tries one at a time.
        self.scene_obstacles = tuple(obstacles)
        self.bounds = None if bounds is None else np.asarray(bounds, dtype=np.float64)
        self.held = held
        self.resting_object = resting_object
        self.obstacles = tuple(obstacles) + ((resting_object,) if resting_object is not None else ())
        n_links = len(robot.links)
        gripper = [link.name in robot.gripper_links for link in robot.links]
        centers, radii = spheres.centers, spheres.radii
        frames, owners = spheres.frames, spheres.links
        link_frame = [link.frame for link in robot.links]
        held_arrays = _held_arrays(robot, held, self.obstacles, n_links)
        if held is not None:  # the object: one more piece, riding on the tcp's frame
            local_c, local_r = cover(held.shape.geometry(), SphereSettings())
            placed = robot.tcp @ np.linalg.inv(held.grasp)
            centers = np.concatenate([centers, local_c @ placed[:3, :3].T + placed[:3, 3]])
            radii = np.concatenate([radii, local_r])
            frames = np.concatenate([frames, np.full(len(local_r), robot.tcp_frame)])
            owners = np.concatenate([owners, np.full(len(local_r), n_links)])
            link_frame.append(robot.tcp_frame)
        pieces = len(link_frame)
        starts = np.searchsorted(owners, np.arange(pieces + 1))
        ignore = np.zeros((pieces, len(self.obstacles)), dtype=np.bool_)
        if resting_object is not None:
            ignore[:n_links, -1] = gripper
        if held is not None:
            ignore[n_links, held_arrays["sup_index"]] = True  # its supports: the from-above test instead
        link_c = np.zeros((pieces, 3))
        link_r = np.zeros(pieces)
        for i in range(pieces):
            link_c[i], link_r[i] = _bounding(centers[starts[i] : starts[i + 1]], radii[starts[i] : starts[i + 1]])
        pairs = [
            (i, j)
            for i in range(n_links)
            for j in range(i + 1, n_links)
            if self_collision and (i, j) not in robot.exempt
        ]
        if held is not None:
            pairs += [(i, n_links) for i in range(n_links) if not gripper[i]]
        self.pairs = np.array(pairs, dtype=np.int64).reshape(-1, 2)
        self._arrays: dict[str, Any] = {
            "lower": robot.lower.astype(np.float64),
            "upper": robot.upper.astype(np.float64),
            "base_r": np.ascontiguousarray(robot.base[:3, :3]),
            "base_t": np.ascontiguousarray(robot.base[:3, 3]),
            "org_r": np.ascontiguousarray(robot.origins[:, :3, :3]),
            "org_t": np.ascontiguousarray(robot.origins[:, :3, 3]),
            "axes": np.ascontiguousarray(robot.axes),
            "prismatic": robot.prismatic.astype(np.bool_),
            "sph_c": np.ascontiguousarray(centers),
            "sph_r": np.ascontiguousarray(radii),
            "sph_frame": frames.astype(np.int64),
            "sph_link": owners.astype(np.int64),
            "link_start": starts.astype(np.int64),
            "link_c": link_c,
            "link_r": link_r,
            "link_frame": np.array(link_frame, dtype=np.int64),
            **obstacle_arrays(self.obstacles),
            "ignore": ignore,
            "pairs": self.pairs,
            "bounds": np.zeros(6) if bounds is None else np.asarray(bounds, dtype=np.float64),
            "has_bounds": bounds is not None,
            **held_arrays,
        }

        a = self._arrays
        #: Whether a link that no joint moves (on ``base_link``'s frame) touches an obstacle or leaves the
        #: bounds: then no configuration is valid. Checked once here, never per configuration.
        self.static_collision = bool(
            collide.static_collides(
                a["base_r"], a["base_t"], a["sph_c"], a["sph_r"], a["sph_frame"], a["sph_link"], a["obs_kind"],
                a["obs_r"], a["obs_t"], a["obs_dims"], a["ignore"], a["bounds"], a["has_bounds"],
            )
        )  # fmt: skip

    def _batch(self, qs: Any) -> NDArray[np.float64]:
        batch = np.ascontiguousarray(qs, dtype=np.float64)
        if batch.ndim != 2 or batch.shape[1] != self.robot.dof:
            raise ValueError(f"qs: expected an (N, {self.robot.dof}) array of joint values, got shape {batch.shape}")
        return batch

    def valid(self, qs: Any) -> NDArray[np.bool_]:
        """For each row of ``qs`` (N, n): inside the joint limits and colliding with nothing."""
        batch = self._batch(qs)
        out = np.empty(len(batch), dtype=np.bool_)
        if self.static_collision:
            out[:] = False
            return out
        a = self._arrays
        collide.valid_batch(
            batch, a["lower"], a["upper"], a["base_r"], a["base_t"], a["org_r"], a["org_t"], a["axes"],
            a["prismatic"], a["sph_c"], a["sph_r"], a["sph_frame"], a["link_start"], a["link_c"], a["link_r"],
            a["link_frame"], a["obs_kind"], a["obs_r"], a["obs_t"], a["obs_dims"], a["obs_bound"], a["ignore"],
            a["pairs"], a["bounds"], a["has_bounds"], a["held_link"], a["held_points"], a["held_disc"],
            a["held_axis"], a["sup_index"], a["sup_top"], a["sup_tol"], out,
        )  # fmt: skip
        return out

    def free_intervals(
        self,
        qs: Any,
        joint: int,
        settings: IntervalSettings | None = None,
        *,
        reach: Any = None,
        move: Any = None,
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
        """For each row of ``qs``: ``(lo, hi, valid)``, the values of ``joint`` (0-based, chain order) around
        the row's own over which the row, the other joints fixed, stays valid for the sphere model
        (within the joint's limits, and within ``reach`` (rad, m; one per row or one for all; default: no
        bound) of the row's own: a caller that needs no more spares the steps beyond); ``valid`` false where
        the row itself is not (then ``lo = hi``).

        ``move`` (rad, m; signed, one per row or one for all; instead of ``reach``): the move the caller
        folds into the interval (:func:`clew_ros.core.manhattan.bounce`); the side it heads for is searched as
        far as the move, the other only as far as the fold can reach past the start (often not at all), so
        ``bounce(q + move, lo, hi)`` is what it is with both sides searched as far as ``|move|``."""
        settings = settings or IntervalSettings()
        batch = self._batch(qs)
        if not 0 <= joint < self.robot.dof:
            raise ValueError(f"joint: expected 0..{self.robot.dof - 1}, got {joint}")
        if reach is not None and move is not None:
            raise ValueError("free_intervals: give reach or move, not both")
        lo = np.empty(len(batch))
        hi = np.empty(len(batch))
        ok = np.empty(len(batch), dtype=np.bool_)
        fold = move is not None
        given = move if fold else (np.inf if reach is None else reach)
        bound = np.ascontiguousarray(np.broadcast_to(given, len(batch)), dtype=np.float64)
        if self.static_collision:
            lo[:] = hi[:] = batch[:, joint]
            ok[:] = False
            return lo, hi, ok
        a = self._arrays
        collide.free_intervals(
            batch, joint, a["lower"], a["upper"], a["base_r"], a["base_t"], a["org_r"], a["org_t"], a["axes"],
            a["prismatic"], a["sph_c"], a["sph_r"], a["sph_frame"], a["link_start"], a["link_c"], a["link_r"],
            a["link_frame"], a["obs_kind"], a["obs_r"], a["obs_t"], a["obs_dims"], a["obs_bound"], a["ignore"],
            a["pairs"], a["bounds"], a["has_bounds"], a["held_link"], a["held_points"], a["held_disc"],
            a["held_axis"], a["sup_index"], a["sup_top"], a["sup_tol"], settings.margin_m, settings.min_step,
            settings.max_steps, bound, fold, lo, hi, ok,
        )  # fmt: skip
        return lo, hi, ok

    def sphere_positions(self, q: Sequence[float]) -> NDArray[np.float64]:
        """Every sphere's centre in ``world`` (S, 3) at ``q`` (compiled forward kinematics)."""
        a = self._arrays
        n = self.robot.dof
        frame_r = np.empty((n + 1, 3, 3))
        frame_t = np.empty((n + 1, 3))
        collide.forward(
            np.asarray(q, dtype=np.float64), a["base_r"], a["base_t"], a["org_r"], a["org_t"], a["axes"],
            a["prismatic"], frame_r, frame_t,
        )  # fmt: skip
        local = self.spheres.centers
        out: NDArray[np.float64] = np.einsum("sij,sj->si", frame_r[self.spheres.frames], local)
        return out + frame_t[self.spheres.frames]
