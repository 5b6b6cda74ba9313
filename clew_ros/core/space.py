"""What the Ariadne's Clew Algorithm asks of a world: the *space* it plans in.

EXPLORE (:mod:`clew_ros.core.explore`), SEARCH's do-while loop over Manhattan
paths (:mod:`clew_ros.core.search`), the genetic algorithm
(:mod:`clew_ros.core.genetic`), the landmark tree (:mod:`clew_ros.core.tree`)
and the run itself (:func:`clew_ros.core.clew.plan`) use a world only through
this protocol, as OMPL's planners use a StateSpace, a StateValidityChecker and a
ProblemDefinition. A kind of world implements it with its own geometry and
compiled kernels: :class:`clew_ros.planar.space.PlanarSpace` for the planar
chains of section 1 of the contract.

Vocabulary of the protocol (every array is a batch along its first axis):

- a *configuration* ``q``: ``(n,)`` joint angles (rad), ``n`` = :attr:`Space.dof`;
- an *object pose*: the resting object's placement (``(3,)`` planar: x, y, theta);
- a *held pose* ``grasp_rel``: the object's pose in the tool's frame while it is carried;
- a *mode* (:class:`Mode`): the object resting at ``(B, p)`` poses (transit) or carried, its ``(B, p)`` poses
  in the tool's frame (transfer), as SEARCH's jobs and the Manhattan decoding take it;
- an *approach* (:data:`Approach`): a mask of the approaches a space allows a regrasp (planar: cells of the
  last link's angle in the object's frame), opaque to the algorithm, ``None`` for no restriction.

What EXPLORE and SEARCH ask is :class:`Space`; the run around them (:func:`clew_ros.core.clew.plan`) asks a
:class:`PlanningSpace` for the start, the goal, the answers knowable at once, the regrasps' aims and the
improvement of the first plan besides.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, NamedTuple, Protocol

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.manhattan import Counters, ManhattanPaths
from clew_ros.core.settings import ManyJoints, PlannerSettings, SearchSettings, Termination

if TYPE_CHECKING:
    from clew_ros.core.settings import Outcome
    from clew_ros.core.tree import Landmark, Segment

__all__ = [
    "Approach",
    "Improvement",
    "Mode",
    "PathResult",
    "PlanningContext",
    "PlanningSpace",
    "RegraspAims",
    "SearchJob",
    "Space",
    "TransitRequest",
]

#: The approaches a space allows a regrasp, as a mask of its own cells (:meth:`RegraspAims.aim`,
#: :meth:`Space.approach_allows`; planar: cells of the last link's angle, spatial: one, every approach); the
#: algorithm only passes it on, and keys its cache by it.
Approach = NDArray[np.bool_]


class TransitRequest(NamedTuple):
    """One SEARCH_TRANSIT request (:meth:`Space.search_transits`)."""

    start: np.ndarray  # (n,) joints
    object_pose: np.ndarray  # where the object rests
    grasp: int  # the grasp's index
    approach: Approach | None  # the approaches allowed (None: any)


@dataclass(frozen=True)
class Mode:
    """Where the object is along a path: resting at ``poses`` (transit), or carried with ``poses`` its pose in
    the tool's frame (transfer); ``(B, p)``, or ``(1, p)`` for a whole batch."""

    transfer: bool
    poses: np.ndarray

    @classmethod
    def resting(cls, object_poses: np.ndarray) -> Mode:
        """Transit: the object rests at ``object_poses``."""
        return cls(False, object_poses)

    @classmethod
    def held(cls, grasp_rel: np.ndarray) -> Mode:
        """Transfer: the object is carried, ``grasp_rel`` its pose in the tool's frame."""
        return cls(True, grasp_rel)

    @property
    def object_poses(self) -> np.ndarray | None:
        """Where the object rests (transit), else ``None``."""
        return None if self.transfer else self.poses

    @property
    def grasp_rel(self) -> np.ndarray | None:
        """The carried object's pose in the tool's frame (transfer), else ``None``."""
        return self.poses if self.transfer else None

    def with_poses(self, poses: np.ndarray) -> Mode:
        """The same kind of mode at other poses."""
        return Mode(self.transfer, poses)


@dataclass
class SearchJob:
    """One local search (:func:`clew_ros.core.search.local_search`): from ``q0``, minimise
    ``objective(final_q, object_poses)``; refinement drives ``error(q)`` ``(B, m)`` below ``accept``, the
    object as ``mode`` says."""

    q0: np.ndarray
    objective: Callable[[np.ndarray, np.ndarray], np.ndarray]
    error: Callable[[np.ndarray], np.ndarray]
    accept: float
    mode: Mode  # (1, p): the resting object's pose (transit) or its pose in the tool's frame (transfer)
    #: The configurations ``(m, n)`` a search that stalled at ``q`` may be joined to, drawn from a generator
    #: (the space's joins), or ``None``.
    targets: Callable[[np.ndarray, np.random.Generator], np.ndarray] | None = None
    join_within: float = 0.0  # m: a search stalled farther than this from its target is not joined
    #: A configuration ``(n,)`` that meets the target, which the greedy probe heads for
    #: (:func:`clew_ros.core.search.local_search`); ``None``: no probe.
    toward: np.ndarray | None = None
    #: Configurations ``(m, n)`` meeting the target, nearest first, that a straight joint-space move
    #: from ``q0`` may reach (:meth:`Space.straight_probe`, arms of many joints); ``None``: no such probe.
    straight: np.ndarray | None = None

    @property
    def pose(self) -> np.ndarray:
        """The mode's pose ``(p,)``."""
        pose: np.ndarray = self.mode.poses[0]
        return pose


@dataclass
class Improvement:
    """What a space's improvement made of a plan (``segments`` is the first plan when nothing was better)."""

    segments: list[Segment]
    final_object_pose: np.ndarray
    first_travel: float  # rad
    first_transfers: int
    travel: float  # rad
    transfers: int
    shortcuts: int  # straight moves accepted
    work: int  # work units spent (deterministic)
    stopped: bool  # the time limit or cancel cut it short
    refused: str = ""  # why a better plan was not returned: "" (it was, or none was found), or what failed of it


class RegraspAims(Protocol):
    """How SEARCH aims its regrasps in place towards one goal (a space without aiming allows everything)."""

    def retake(self, grasp: int, grasp_rel: np.ndarray) -> bool:
        """Whether the held ``grasp`` (held as ``grasp_rel``), taken again in place, could carry the object
        to the goal where holding it as it is could not (planar: held outside the goal's approach core)."""
        ...

    def aim(self, landmark: Landmark, grasp: int) -> Approach | None:
        """The approach a regrasp of ``grasp`` in place at ``landmark`` aims at; ``None``: that regrasp is
        not worth a transit."""
        ...

    def ranked(self, landmark: Landmark, grasps: list[int]) -> list[int]:
        """``grasps`` (the regrasps in place SEARCH may try at ``landmark``, in a random order) in the order
        to try them (planar: as they are)."""
        ...

    def placements(self, landmark: Landmark, grasp: int, start: np.ndarray) -> list[np.ndarray]:
        """Intermediate placements (object poses), best first, to which ``grasp`` could carry the object from
        ``landmark`` (held at configuration ``start``) and where a grasp serving the goal could take it on
        (SEARCH's aimed regrasp, ``SearchSettings.via_placements``); empty: none proposed."""
        ...


class Space(Protocol):
    """A world as EXPLORE and SEARCH see it (see the module's docstring for the vocabulary)."""

    @property
    def dof(self) -> int:
        """Joints of the arm (the configuration's size)."""
        ...

    @property
    def reach(self) -> float:
        """The arm's reach (m): the scale of SEARCH's refinement and joins."""
        ...

    @property
    def grasp_count(self) -> int:
        """Grasps of the object (the landmark space's ``[grasp]`` dimension)."""
        ...

    def manhattan(
        self,
        q0: np.ndarray,
        genes: np.ndarray,
        mode: Mode,
        *,
        margin_m: float,
        counters: Counters | None,
        should_stop: Callable[[], bool] | None,
        threads: int,
    ) -> ManhattanPaths:
        """Genes ``(B, k, n)`` decoded into collision-free Manhattan paths from ``q0`` ``(B, n)`` in ``mode``:
        each move bounced into its joint's free interval (paper 1.3.1, 1.3.3)."""
        ...

    def single_moves(
        self, q: np.ndarray, moves: np.ndarray, mode: Mode, *, margin_m: float, counters: Counters | None
    ) -> np.ndarray:
        """Joint moves ``(n,)`` applied one joint at a time, each clamped to its free interval: the
        waypoints ``(m, n)`` (SEARCH's refinement, where bouncing would undo the step)."""
        ...

    def held_object_poses(self, q: np.ndarray, grasp_rel: np.ndarray) -> np.ndarray:
        """Where the held object is at configurations ``q`` ``(B, n)``."""
        ...

    def landmark_features(self, joints: np.ndarray, object_poses: np.ndarray, joint_weight: float) -> np.ndarray:
        """Points ``(L, d)`` whose Euclidean distances are the landmark distances EXPLORE maximises."""
        ...

    def goal_distance(self, object_poses: np.ndarray, goal: np.ndarray) -> np.ndarray:
        """How far each object pose is from the goal (m): SEARCH_TRANSFER's objective."""
        ...

    def search_transits(self, ctx: PlanningContext, requests: list[TransitRequest]) -> list[PathResult]:
        """SEARCH_TRANSIT for each request: move the arm, the object at rest, until it holds the grasp."""
        ...

    def search_transfer(
        self, ctx: PlanningContext, q0: np.ndarray, grasp_rel: np.ndarray, goal: np.ndarray
    ) -> PathResult:
        """SEARCH_TRANSFER: carry the object held as ``grasp_rel`` from ``q0`` towards the goal placement."""
        ...

    def straight_probe(
        self,
        ctx: PlanningContext,
        jobs: list[SearchJob],
        q: np.ndarray,
        best: np.ndarray,
        waypoints: list[list[np.ndarray]],
    ) -> None:
        """Before SEARCH's GA rounds, jobs with ``straight`` targets try direct moves to them (arms of many
        joints); kept in ``q``, ``best`` and ``waypoints`` where they get closer."""
        ...

    def approach_allows(self, approach: Approach, grasp_rel: np.ndarray) -> bool:
        """Whether a grasp held as ``grasp_rel`` comes in at an allowed ``approach``."""
        ...


class PlanningSpace(Space, Protocol):
    """A world as the whole run sees it (:func:`clew_ros.core.clew.plan`): EXPLORE's and SEARCH's space, and
    the start, the goal, the answers knowable at once, the regrasps' aims and the improvement."""

    @property
    def initial_joints(self) -> np.ndarray:
        """The start configuration ``(n,)``: the root landmark's joints."""
        ...

    @property
    def initial_object_pose(self) -> np.ndarray:
        """Where the object rests at the start: the root landmark's pose."""
        ...

    @property
    def goal(self) -> np.ndarray:
        """The world's goal placement of the object."""
        ...

    def regrasp_aims(self, goal: np.ndarray) -> RegraspAims:
        """How SEARCH aims regrasps in place towards ``goal`` (computed lazily, once per run)."""
        ...

    def quick_refusal(self, goal: np.ndarray) -> tuple[Outcome, str] | None:
        """An answer knowable at once (a colliding start or goal, a goal out of reach, a proof that no path
        exists), or ``None``."""
        ...

    def improve(
        self, ctx: PlanningContext, segments: list[Segment], object_pose: np.ndarray, goal: np.ndarray
    ) -> Improvement:
        """The first plan made shorter within ``planner.improve_time`` (never longer, never invalid)."""
        ...


@dataclass
class PlanningContext:
    """Everything one planning run shares: the space, settings, randomness, stop test, counters."""

    space: Space
    settings: PlannerSettings
    rng: np.random.Generator
    termination: Termination = field(default_factory=Termination)
    counters: Counters = field(default_factory=Counters)
    #: Random starts of the holding configurations that decide whether a transit is hopeless (more of them
    #: after an EXPLORE round that found no transit at all: the space answers the same request with the same
    #: sample, so a retry must draw a larger one); ``SearchSettings.hold_samples`` at the start.
    hold_samples: int = field(default_factory=lambda: SearchSettings().hold_samples)
    #: Whether a stalled SEARCH_TRANSIT is joined to its holding configurations (the space's joins): only
    #: from an EXPLORE round that found no transit at all to the next that finds one (elsewhere joins cost
    #: more than they save).
    transit_joins: bool = False
    #: how the search adapts to arms of many joints
    many: ManyJoints = field(default_factory=ManyJoints)
    #: SEARCH's own tuning (probes, joins, chains)
    search: SearchSettings = field(default_factory=SearchSettings)

    def manhattan(self, q0: np.ndarray, genes: np.ndarray, mode: Mode) -> ManhattanPaths:
        """:meth:`Space.manhattan` with this run's clearance, counters, stop test and threads."""
        return self.space.manhattan(
            q0,
            genes,
            mode,
            margin_m=self.settings.clearance,
            counters=self.counters,
            should_stop=self.termination,
            threads=self.settings.threads,
        )

    def initial_genes(self, count: int, islands: int | None = None) -> np.ndarray:
        """Random Manhattan genes ``(count, k, n)`` (``(islands, count, k, n)``, standard deviation
        ``SearchSettings.initial_gene_rad``); the first individual (of each island) stays put."""
        n = self.space.dof
        shape = (count, self.settings.manhattan_order, n)
        genes = self.rng.normal(0.0, self.search.initial_gene_rad, size=shape if islands is None else (islands, *shape))
        genes[..., 0, :, :] = 0.0
        return genes


@dataclass
class PathResult:
    success: bool
    waypoints: np.ndarray  # (m, n), starting at the start configuration
    distance: float  # final value of the objective (m)
    grasp_rel: np.ndarray | None = None  # transit: object pose in the end-effector frame at the grasp
    object_pose: np.ndarray | None = None  # transfer: where the object ends
