"""The validity checker of a spatial world, batched over configurations, in two tiers.

:class:`SpatialChecker` packs a robot's sphere models, the obstacles and the bounds once into arrays and
answers for whole batches (``(N, n)`` arrays of planned-joint values): :meth:`~SpatialChecker.valid`
(joint limits, obstacles and bounds, self-collision over the pairs not exempted) and
:meth:`~SpatialChecker.free_intervals` (the interval of one joint, the others fixed, that is free). The outer
spheres cover the URDF's geometry, so what they call free is free; where they touch something, the inner
spheres (inside the geometry) prove a collision, and the contacts left between the two are decided on the
exact geometry (:mod:`clew_ros.spatial.kernels.band`, :mod:`clew_ros.spatial.tier`), grown by
``world.robot.padding``. Touching counts as colliding.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.kernels import band, collide, intervals
from clew_ros.spatial.kernels.packed import HeldObject, InnerSpheres, Model, Scene, Spheres, Stepping, chain_of
from clew_ros.spatial.placements import MovableObject, Support
from clew_ros.spatial.robot import RobotModel
from clew_ros.spatial.scene import Obstacle, obstacle_arrays
from clew_ros.spatial.spheres import SphereModel, SphereSettings, cover, inner_cover
from clew_ros.spatial.tier import ExactTier

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
    #: Where the sphere model cannot clear a row (the band, near contact), the interval is sampled at this
    #: step (rad, or m for a prismatic joint): each sample checked on the exact geometry with the clearance
    #: that proves the configurations between two samples free too.
    band_step: float = 0.002
    #: At most this many such samples each way in each of ``band_stages`` stages, each stage's step
    #: ``band_growth`` times the last's (checked with a clearance as much larger: far from any contact the
    #: interval grows fast); past them, where the spheres clear the row again, the conservative steps go on.
    band_samples: int = 12
    band_stages: int = 3
    band_growth: float = 4.0


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


def _held_arrays(robot: RobotModel, held: Held | None, obstacles: Sequence[Obstacle], n_links: int) -> HeldObject:
    """The held object packed for the kernels: its piece's index (-1: none), its corners (a box) or cap
    centres (a cylinder) and its axis in the tcp's frame, its radius (0 for a box), and the supports it may
    touch from above: their obstacle indices and tops."""
    if held is None:
        return HeldObject(
            held_link=-1, held_points=np.zeros((0, 3)), held_disc=0.0, held_axis=np.zeros(3),
            sup_index=np.zeros(0, dtype=np.int64), sup_top=np.zeros(0), sup_tol=0.0,
        )  # fmt: skip
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
    return HeldObject(
        held_link=n_links,
        held_points=np.ascontiguousarray(points @ placed[:3, :3].T + placed[:3, 3]),
        held_disc=disc,
        held_axis=np.ascontiguousarray(placed[:3, 2]),
        sup_index=np.array([names.index(s.name) for s in held.supports], dtype=np.int64),
        sup_top=np.array([s.top for s in held.supports], dtype=np.float64),
        sup_tol=float(held.tolerance_m),
    )


def _inner_arrays(
    spheres: SphereModel, held: Held | None, placed: NDArray[np.float64], tcp_frame: int, n_links: int
) -> InnerSpheres:
    """The inner spheres packed for :mod:`~clew_ros.spatial.kernels.band` (centres, radii, each piece's first
    sphere): the links' (:attr:`SphereModel.inner`), then the held object's (``placed`` in frame ``tcp_frame``)."""
    inner = spheres.inner
    centres = np.zeros((0, 3)) if inner is None else inner.centers
    radii = np.zeros(0) if inner is None else inner.radii
    owners = np.zeros(0, dtype=np.int64) if inner is None else inner.links
    if held is not None:
        local_c, local_r = inner_cover(held.shape.geometry(), SphereSettings())
        centres = np.concatenate([centres, local_c @ placed[:3, :3].T + placed[:3, 3]])
        radii = np.concatenate([radii, local_r])
        owners = np.concatenate([owners, np.full(len(local_r), n_links)])
    pieces = n_links + (held is not None)
    return InnerSpheres(
        np.ascontiguousarray(centres, dtype=np.float64),
        np.ascontiguousarray(radii, dtype=np.float64),
        np.searchsorted(owners, np.arange(pieces + 1)).astype(np.int64),
    )


def _levers(
    robot: RobotModel,
    centres: NDArray[np.float64],
    radii: NDArray[np.float64],
    *,
    frames: NDArray[np.int64],
    owners: NDArray[np.int64],
    pieces: int,
) -> NDArray[np.float64]:
    """Per joint and piece (n, pieces): a bound (m) on how far from the joint's axis a point of the piece can be,
    0 where the joint does not move it: the origins down the chain from the frame the joint turns to the piece's
    frame (prismatic joints at their longest), then the piece's farthest sphere in its frame."""
    reach = np.linalg.norm(centres, axis=1) + radii
    far = np.zeros(pieces)
    frame_of = np.zeros(pieces, dtype=np.int64)
    np.maximum.at(far, owners, reach)
    frame_of[owners] = frames
    chain = np.linalg.norm(robot.origins[:, :3, 3], axis=1)
    chain = chain + np.where(robot.prismatic, np.maximum(np.abs(robot.lower), np.abs(robot.upper)), 0.0)
    out = np.zeros((robot.dof, pieces))
    for j in range(robot.dof):
        for p in range(pieces):
            if frame_of[p] >= j + 1:
                out[j, p] = chain[j + 1 : frame_of[p]].sum() + far[p]
    return out


def _stepping(settings: IntervalSettings, reach: NDArray[np.float64], fold: bool) -> Stepping:
    """How :func:`clew_ros.spatial.kernels.intervals.free_intervals` steps: ``settings``, with ``reach`` (one per
    row) and ``fold``."""
    return Stepping(settings.margin_m, settings.min_step, settings.max_steps, reach, fold)


class SpatialChecker:
    """Validity and free intervals of one robot among obstacles, inside bounds (spheres, then the exact geometry)."""

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
        exact: bool = True,
        band_intervals: bool = True,
    ) -> None:
        """``bounds``: ``[xmin, ymin, zmin, xmax, ymax, zmax]`` (m) or ``None`` (unbounded);
        ``self_collision`` false leaves every pair of links unchecked. ``resting_object``: the object where it
        rests (in transit), an obstacle to every link but the robot's ``gripper_links``. ``held``: the object
        in the hand (in transfer), its conservative spheres riding on the tcp's frame, checked against the
        obstacles (its supports only from below their top), the bounds and every link but the
        ``gripper_links``. ``exact`` (default): where the spheres cannot settle a contact, the exact geometry
        decides (:mod:`clew_ros.spatial.tier`); false: the spheres alone (conservative, never exact).
        ``band_intervals`` false: :meth:`free_intervals` are the spheres' alone (a row near a contact gets none)
        while :meth:`valid` still decides on the exact geometry."""
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
        radii = radii + robot.padding  # the links grown by world.robot.padding (not the held object)
        placed = robot.tcp @ np.linalg.inv(held.grasp) if held is not None else np.eye(4)
        if held is not None:  # the object: one more piece, riding on the tcp's frame
            local_c, local_r = cover(held.shape.geometry(), SphereSettings())
            centers = np.concatenate([centers, local_c @ placed[:3, :3].T + placed[:3, 3]])
            radii = np.concatenate([radii, local_r])
            frames = np.concatenate([frames, np.full(len(local_r), robot.tcp_frame)])
            owners = np.concatenate([owners, np.full(len(local_r), n_links)])
            link_frame.append(robot.tcp_frame)
        pieces = len(link_frame)
        starts = np.searchsorted(owners, np.arange(pieces + 1))
        self.exact, self.band_intervals = exact, band_intervals
        self._tier: ExactTier | None = None
        self._held_pose = None if held is None else (held.shape, placed)
        ignore = np.zeros((pieces, len(self.obstacles)), dtype=np.bool_)
        if resting_object is not None:
            ignore[:n_links, -1] = gripper
        if held is not None:
            ignore[n_links, held_arrays.sup_index] = True  # its supports: the from-above test instead
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
        #: Everything the kernels read, packed once (:mod:`clew_ros.spatial.kernels.packed`).
        self.model = Model(
            chain=chain_of(robot),
            spheres=Spheres(
                sph_c=np.ascontiguousarray(centers),
                sph_r=np.ascontiguousarray(radii),
                sph_frame=frames.astype(np.int64),
                sph_link=owners.astype(np.int64),
                link_start=starts.astype(np.int64),
                link_c=link_c,
                link_r=link_r,
                link_frame=np.array(link_frame, dtype=np.int64),
            ),
            inner=_inner_arrays(spheres, held, placed, robot.tcp_frame, n_links),
            scene=Scene(
                **obstacle_arrays(self.obstacles),
                ignore=ignore,
                pairs=self.pairs,
                bounds=np.zeros(6) if bounds is None else np.asarray(bounds, dtype=np.float64),
                has_bounds=bounds is not None,
            ),
            held=held_arrays,
        )
        #: per joint and piece, how far (m) a point of the piece the joint moves can be from its axis (0: the
        #: joint does not move the piece): the lever of a band step
        self._lever = _levers(robot, centers, radii, frames=frames, owners=owners, pieces=pieces)
        #: Whether a link that no joint moves (on ``base_link``'s frame) touches an obstacle or leaves the
        #: bounds: then no configuration is valid. Checked once here, never per configuration (on the exact
        #: geometry where the spheres touch).
        self.static_collision = bool(collide.static_collides(self.model))
        if self.static_collision and exact:
            self.static_collision = self._static_exact()

    def _batch(self, qs: Any) -> NDArray[np.float64]:
        batch = np.ascontiguousarray(qs, dtype=np.float64)
        if batch.ndim != 2 or batch.shape[1] != self.robot.dof:
            raise ValueError(f"qs: expected an (N, {self.robot.dof}) array of joint values, got shape {batch.shape}")
        return batch

    # -- the exact tier ----------------------------------------------------------------------------------

    @property
    def exact_checks(self) -> int:
        """How many contacts the exact geometry has decided for this checker so far."""
        return 0 if self._tier is None else self._tier.checks

    @property
    def tier(self) -> ExactTier:
        """The exact geometry of this checker's scene (built when first needed)."""
        if self._tier is None:
            bounds = None if self.bounds is None else self.bounds.tolist()
            self._tier = ExactTier(self.robot, self.obstacles, bounds, self._held_pose)
        return self._tier

    def _static_exact(self) -> bool:
        """Whether a link no joint moves touches an obstacle (but those it ignores) or the bounds, exactly."""
        tier = self.tier
        chain, ignore = self.model.chain, self.model.scene.ignore
        frame_r = np.broadcast_to(chain.base_r, (self.robot.dof + 1, 3, 3))
        frame_t = np.broadcast_to(chain.base_t, (self.robot.dof + 1, 3))
        for i, link in enumerate(self.robot.links):
            if link.frame != 0:
                continue
            rows = [(band.OBSTACLE, i, o) for o in range(len(self.obstacles)) if not ignore[i, o]]
            rows += [(band.BOUNDS, i, -1)] if self.bounds is not None else []
            rot, pos = tier.placements(frame_r[None], frame_t[None])
            if not tier.free(np.array(rows, dtype=np.int64).reshape(-1, 3), (rot[0], pos[0])):
                return True
        return False

    def classify(
        self,
        qs: Any,
        margin: float | NDArray[np.float64] = 0.0,
        *,
        moved_only: bool = False,
        groups: NDArray[np.int64] | None = None,
    ) -> NDArray[np.bool_]:
        """For each row: valid on the two tiers (spheres, then the exact geometry for the contacts the spheres
        leave open), every contact kept at least ``margin`` (m; one for every piece, or one per piece, as one
        joint's move gives them: two pieces it both moves, or neither, keep none between them) clear.
        ``moved_only``: each row is one joint's move from a free configuration, the pieces it moves those with a
        margin (:meth:`ExactTier.contact`). ``groups`` (one label per row): only whether every row of a group is
        valid matters (the samples of one straight move), so once a row of a group is refused the group's other
        rows are not decided on the exact geometry (reported refused)."""
        return self._two_tiers(self._batch(qs), margin, moved_only=moved_only, groups=groups)[0]

    def _two_tiers(
        self,
        batch: NDArray[np.float64],
        margin: float | NDArray[np.float64],
        *,
        moved_only: bool = False,
        groups: NDArray[np.int64] | None = None,
        spheres_first: bool = False,
    ) -> tuple[NDArray[np.bool_], NDArray[np.int64]]:
        """:meth:`classify` and each row's status (:data:`~clew_ros.spatial.kernels.band.FREE`: its spheres
        touch nothing). ``spheres_first`` (``margin`` 0): the rows the spheres clear are not classified further,
        as :meth:`valid_and_on_spheres` wants them."""
        margins = np.broadcast_to(np.asarray(margin, dtype=np.float64), (len(self.model.spheres.link_r),))
        margin = float(margins.max(initial=0.0))  # the kernel's: every contact within the largest is listed
        n = len(batch)
        out = np.zeros(n, dtype=np.bool_)
        status = np.full(n, band.CERTAIN, dtype=np.int64)
        if self.static_collision or not n:
            return out, status
        cap = 32
        contacts = np.empty((n, cap, 3), dtype=np.int64)
        counts = np.empty(n, dtype=np.int64)
        frames_r = np.empty((n, self.robot.dof + 1, 3, 3))
        frames_t = np.empty((n, self.robot.dof + 1, 3))
        band.contacts_batch(batch, self.model, (status, contacts, counts, frames_r, frames_t), margin, spheres_first)
        out[status == band.FREE] = True
        overflow = np.flatnonzero(status == band.OVERFLOW)
        if len(overflow):  # more open contacts than the list holds: again, with room for every one
            pieces, pairs, supports = len(self.model.spheres.link_r), len(self.pairs), len(self.model.held.sup_index)
            room = pieces * (len(self.obstacles) + 1) + pairs + supports
            k = len(overflow)
            again = np.empty((k, room, 3), dtype=np.int64)
            sub, sub_counts = np.empty(k, dtype=np.int64), np.empty(k, dtype=np.int64)
            sub_r, sub_t = np.empty((k, self.robot.dof + 1, 3, 3)), np.empty((k, self.robot.dof + 1, 3))
            band.contacts_batch(batch[overflow], self.model, (sub, again, sub_counts, sub_r, sub_t), margin, False)
            if self.exact:
                rot, pos = self.tier.placements(sub_r, sub_t)
            for m, row in enumerate(overflow):
                out[row] = sub[m] == band.FREE or (
                    self.exact
                    and sub[m] == band.BAND
                    and self.tier.free(again[m, : sub_counts[m]], (rot[m], pos[m]), margins, moved_only=moved_only)
                )
        rows = np.flatnonzero(status == band.BAND)
        refused = set() if groups is None else set(groups[(status == band.CERTAIN) | (status == band.OVERFLOW) & ~out])
        if groups is not None:
            rows = rows[~np.isin(groups[rows], list(refused))]
        if self.exact and len(rows):
            rot, pos = self.tier.placements(frames_r[rows], frames_t[rows])
            for k, b in enumerate(rows):
                if groups is not None and groups[b] in refused:
                    continue
                out[b] = self.tier.free(contacts[b, : counts[b]], (rot[k], pos[k]), margins, moved_only=moved_only)
                if groups is not None and not out[b]:
                    refused.add(groups[b])
        return out, status

    def valid_on_spheres(self, qs: Any) -> NDArray[np.bool_]:
        """For each row of ``qs``: inside the joint limits and its (outer) spheres touch nothing: free for
        certain, far enough from every contact for the exact geometry to have nothing to say."""
        batch = self._batch(qs)
        out = np.empty(len(batch), dtype=np.bool_)
        if self.static_collision:
            out[:] = False
            return out
        collide.valid_batch(batch, self.model, out)
        return out

    def valid(self, qs: Any) -> NDArray[np.bool_]:
        """For each row of ``qs`` (N, n): inside the joint limits and colliding with nothing (the spheres
        first; where they touch, the exact geometry decides unless the checker was made with ``exact=False``)."""
        return self.valid_and_on_spheres(qs)[0]

    def valid_and_on_spheres(
        self, qs: Any, groups: NDArray[np.int64] | None = None
    ) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        """:meth:`valid` and :meth:`valid_on_spheres` of the rows of ``qs``, for the price of one (one kernel: the
        rows the spheres refuse are classified on the spot, their frames not computed twice); ``groups``: see
        :meth:`classify` (a row of a refused group may be reported refused)."""
        batch = self._batch(qs)
        if not self.exact:
            spheres = self.valid_on_spheres(batch)
            return spheres.copy(), spheres
        out, status = self._two_tiers(batch, 0.0, groups=groups, spheres_first=True)
        return out, status == band.FREE

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
        self._sphere_intervals(batch, joint, _stepping(settings, bound, fold), (lo, hi, ok))
        if self.exact and self.band_intervals:
            self._band_intervals(batch, joint, settings, bound, (lo, hi, ok))
        return lo, hi, ok

    def _sphere_intervals(
        self,
        batch: NDArray[np.float64],
        joint: int,
        stepping: Stepping,
        out: tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]],
    ) -> None:
        """The sphere model's free intervals (the compiled conservative steps) into ``out`` (lo, hi, ok)."""
        intervals.free_intervals(batch, joint, self.model, stepping, out)

    def _band_intervals(
        self,
        batch: NDArray[np.float64],
        joint: int,
        settings: IntervalSettings,
        bound: NDArray[np.float64],
        out: tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]],
    ) -> None:
        """The rows the spheres refused but the exact geometry accepts (near a contact): their intervals by
        samples ``settings.band_step`` apart, each the middle of a cell it proves free (checked with the
        clearance no point of the robot can lose within half a step, :attr:`_lever`), in stages of steps
        growing ``settings.band_growth`` times; past them, where the spheres clear the row again, the
        conservative steps go on."""
        robot = self.robot
        lo, hi, ok = out
        rows = np.flatnonzero(~ok & (batch >= robot.lower).all(axis=1) & (batch <= robot.upper).all(axis=1))
        if not len(rows):
            return
        rows = rows[self.classify(batch[rows])]
        if not len(rows):
            return
        ok[rows] = True
        lever = np.where(self._lever[joint] > 0, 1.0, 0.0) if robot.prismatic[joint] else self._lever[joint]
        for side in (-1.0, 1.0):  # both sides, as far as the move (a fold may come back past the start)
            mine = rows
            start = batch[mine, joint]
            limit = np.abs(bound[mine])
            room = np.minimum(limit, (robot.upper[joint] - start) if side > 0 else (start - robot.lower[joint]))
            proven = np.zeros(len(mine))
            alive = np.ones(len(mine), dtype=bool)
            active = np.ones(len(mine), dtype=bool)
            for stage in reversed(range(settings.band_stages)):  # the longest steps first (far from contact)
                step = settings.band_step * settings.band_growth**stage
                going = self._band_stage(
                    batch, mine, joint, side * step, margin=lever * step / 2, settings=settings, room=room,
                    proven=proven, alive=active,
                )  # fmt: skip
                alive = going | (alive & ~active)  # rows that cleared every sample stop refining
                active = active & ~going & (proven < room)  # a refusal: the next stage goes on in finer steps
                if stage == 0:
                    alive &= ~active
            reach = np.minimum(proven, room)
            ends = start + side * reach
            onward = np.flatnonzero(alive & (reach < room))  # every sample clear: the conservative steps go on
            if len(onward):
                rest = batch[mine[onward]].copy()
                rest[:, joint] = ends[onward]
                more = (np.empty(len(onward)), np.empty(len(onward)), np.empty(len(onward), dtype=np.bool_))
                left = np.ascontiguousarray(room[onward] - reach[onward])
                self._sphere_intervals(rest, joint, _stepping(settings, left, False), more)
                more_lo, more_hi, more_ok = more
                far = more_hi if side > 0 else more_lo
                ends[onward] = np.where(more_ok, far, ends[onward])
            if side > 0:
                hi[mine] = np.maximum(hi[mine], ends)
            else:
                lo[mine] = np.minimum(lo[mine], ends)

    def _band_stage(
        self,
        batch: NDArray[np.float64],
        mine: NDArray[np.int64],
        joint: int,
        step: float,
        *,
        margin: NDArray[np.float64],
        settings: IntervalSettings,
        room: NDArray[np.float64],
        proven: NDArray[np.float64],
        alive: NDArray[np.bool_],
    ) -> NDArray[np.bool_]:
        """One stage of :meth:`_band_intervals`: ``settings.band_samples`` samples ``step`` apart (signed) past
        what each row has ``proven`` (updated in place), each checked with ``margin`` (m, per piece); the rows
        still going."""
        chunk = 4  # samples a row probes per call (a few past its first refusal are wasted)
        base = proven.copy()
        for k0 in range(0, settings.band_samples, chunk):
            alive = alive & (proven < room)
            live = np.flatnonzero(alive)
            if not len(live):
                break
            ks = np.arange(k0, min(k0 + chunk, settings.band_samples))
            probe = np.repeat(batch[mine[live]], len(ks), axis=0)
            offsets = np.sign(step) * base[live][:, None] + (ks[None, :] + 0.5) * step
            probe[:, joint] = (batch[mine[live], joint][:, None] + offsets).reshape(-1)
            fine = self.classify(probe, margin, moved_only=True).reshape(len(live), len(ks))
            run = np.where(fine.all(axis=1), len(ks), np.argmin(fine, axis=1))  # samples clear in a row
            proven[live] = base[live] + (k0 + run) * abs(step)
            alive[live[run < len(ks)]] = False
        return alive

    def sphere_positions(self, q: Sequence[float]) -> NDArray[np.float64]:
        """Every sphere's centre in ``world`` (S, 3) at ``q`` (compiled forward kinematics)."""
        n = self.robot.dof
        frame_r = np.empty((n + 1, 3, 3))
        frame_t = np.empty((n + 1, 3))
        collide.forward(np.asarray(q, dtype=np.float64), self.model.chain, frame_r, frame_t)
        local = self.spheres.centers
        out: NDArray[np.float64] = np.einsum("sij,sj->si", frame_r[self.spheres.frames], local)
        return out + frame_t[self.spheres.frames]
