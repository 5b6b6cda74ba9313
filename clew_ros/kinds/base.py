"""What a kind of world offers the code above the planner: :class:`WorldKind`, and the registry of kinds.

The node, the live view, ``clew_batch``, ``clew_plan`` and the client never tell the kinds of world apart
themselves: they ask the world's kind (:func:`kind_of`, :func:`kind_named`, :func:`kind_of_parameters`)
for its problem, its plan, its markers, its playback. A kind is one adapter (a :class:`WorldKind`
subclass) registered once with :func:`register`; :mod:`clew_ros.kinds` registers ``planar`` and
``spatial``.
"""

from __future__ import annotations

import threading
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from clew_ros.core.clew import PlanResult, Progress
from clew_ros.core.errors import WorldError
from clew_ros.core.plan import Plan
from clew_ros.core.settings import PlannerSettings, Termination
from clew_ros.core.tree import LandmarkTree

__all__ = [
    "DEFAULT_KIND",
    "WorldKind",
    "kind_named",
    "kind_of",
    "kind_of_parameters",
    "kinds",
    "register",
]


class WorldKind(ABC):
    """One kind of world, as the code above the planner sees it.

    ``name`` is the value of ``world.kind`` that selects it (and a plan file's ``world_kind``);
    ``world_type`` the class of its worlds; ``problem_type`` the class of its offline problems (each with
    ``world`` and ``settings``). A world of the kind ``kind.world_type`` is found by :func:`kind_of`.
    """

    name: str
    world_type: type
    problem_type: type

    # ------------------------------------------------------------------ offline: a parameter tree to a plan

    @abstractmethod
    def problem_from_parameters(
        self,
        parameters: Mapping[str, Any],
        folder: Path,
        *,
        seed: int | None = None,
        time_limit: float | None = None,
        improve_time: float | None = None,
    ) -> Any:
        """The problem of a ``ros__parameters`` tree of this kind (relative paths start at ``folder``);
        raises :class:`~clew_ros.core.errors.ParameterError` naming the parameter at fault."""

    @abstractmethod
    def warm_up(self, problem: Any) -> float:
        """The kernels ``problem`` plans with, compiled before a plan's clock starts; the seconds it took."""

    def warm_up_worker(self, problem: Any) -> None:
        """What a ``clew_batch`` worker process compiles before its first job (nothing unless overridden)."""
        del problem

    @abstractmethod
    def plan_problem(
        self,
        problem: Any,
        *,
        cancel: threading.Event | None = None,
        progress: Callable[[Progress], None] | None = None,
    ) -> Plan:
        """One run of ``problem`` within its time limit (or until ``cancel``), its plan checked in its world."""

    @abstractmethod
    def failed_plan(self, problem: Any, message: str, elapsed_s: float) -> Plan:
        """The ``INTERNAL_ERROR`` plan of a run of ``problem`` that could not finish."""

    # ------------------------------------------------------------------ a run of the node

    @abstractmethod
    def plan(
        self,
        world: Any,
        settings: PlannerSettings,
        *,
        goal: np.ndarray | None,
        termination: Termination,
        progress: Callable[[Progress], None] | None,
    ) -> PlanResult:
        """The planner on ``world`` (``goal``: a goal that replaces the world's, where the kind takes one)."""

    @abstractmethod
    def checked_plan(self, world: Any, result: PlanResult) -> Plan:
        """``result`` as a plan file's plan, validated in ``world`` (a success that fails: ``INTERNAL_ERROR``)."""

    def start_collision_detail(self, world: Any) -> str | None:
        """What touches at the start of ``world`` (appended to a ``START_IN_COLLISION`` message), if known."""
        del world
        return None

    @abstractmethod
    def root_tree(self, world: Any) -> LandmarkTree:
        """The landmark tree's root (the start), as the planner's tree starts."""

    @abstractmethod
    def default_goal(self, world: Any) -> np.ndarray:
        """What ``~/plan`` plans to in ``world``."""

    @abstractmethod
    def with_goal(self, world: Any, goal: np.ndarray) -> Any:
        """``world`` with ``goal`` (a ``~/goal_pose`` request's) as its goal."""

    @abstractmethod
    def goal_from_pose_stamped(self, msg: Any, world: Any) -> np.ndarray:
        """The goal a ``geometry_msgs/PoseStamped`` asks for in ``world``; raises
        :class:`~clew_ros.ros.messages.GoalPoseError` saying why it is refused."""

    @abstractmethod
    def goal_message(self, world: Any, goal: np.ndarray, time_ns: int) -> Any | None:
        """``~/goal_pose`` as a run records it (``None``: a goal that is no pose, e.g. joints)."""

    @abstractmethod
    def landmark_markers(self, world: Any, landmarks: Any, time_ns: int) -> Any:
        """``~/landmarks``: the landmark tree (or a plan's landmarks) as a ``MarkerArray``."""

    @abstractmethod
    def track(self, world: Any, plan: Plan, setup: Any, timing: Any) -> Any:
        """A checked plan timed as ``~/trajectory`` and the playback move along it
        (:class:`~clew_ros.motion.playback.Track`)."""

    def plan_fields(self, world: Any, track: Any) -> dict[str, Any]:
        """What a ``succeeded`` event adds about the plan (nothing unless overridden)."""
        del world, track
        return {}

    def end_state(self, plan: Plan) -> tuple[np.ndarray, tuple[float, ...] | None] | None:
        """Where a successful ``plan`` leaves the arm and the object (for ``state.advance``), if the kind
        follows it."""
        del plan
        return None

    # ------------------------------------------------------------------ publishing a run (node, clew_batch --record)

    @abstractmethod
    def setup_of(self, parameters: Mapping[str, Any], folder: Path) -> Any:
        """What a recording of a world of this kind needs besides the world (``None`` when nothing)."""

    @abstractmethod
    def announce_world(self, out: Any, world: Any, planner: PlannerSettings, recording: Any, setup: Any) -> None:
        """The world, its arm and the arm at rest, put out on ``out`` (the node's
        :class:`~clew_ros.node.publishing.Publishing`)."""

    @abstractmethod
    def publish_sample(
        self, out: Any, world: Any, state: Any, *, setup: Any, track: Any, time_ns: int, recording: Any
    ) -> None:
        """One played-back state of a run, put out on ``out``."""

    @abstractmethod
    def record_run(
        self,
        run: Any,
        world: Any,
        plan: Plan,
        *,
        planner: PlannerSettings,
        node: Any,
        recording_text: str,
        setup: Any,
    ) -> None:
        """A plan written into ``run`` (``clew_batch --record``'s recorder) as the node records its run."""

    # ------------------------------------------------------------------ a client (PlannerClient)

    @abstractmethod
    def pose_goal(self, msg: Any) -> tuple[float, ...]:
        """The goal a ``geometry_msgs/PoseStamped`` names, as this kind's pose numbers."""

    @abstractmethod
    def plan_from_trajectory(
        self, parameters: Mapping[str, Any], trajectory: Any, outcome_fields: Mapping[str, Any], message: str
    ) -> Plan | None:
        """A run's plan rebuilt from its ``~/trajectory`` and its outcome event's fields in the world of
        ``parameters`` (the planner's ``~/world_yaml``); ``None`` while that world cannot be read."""

    # ------------------------------------------------------------------ the live view

    #: Whether the live view draws the kind in 3-D (the ``links`` and ``tf`` channels).
    live_in_3d: bool = False


DEFAULT_KIND = "planar"

_LOCK = threading.Lock()
_BY_NAME: dict[str, WorldKind] = {}
_BY_TYPE: dict[type, WorldKind] = {}


def register(kind: WorldKind) -> WorldKind:
    """Add ``kind`` to the registry (by its name and by its world's class); a name or class registered twice
    is refused (:class:`ValueError`). Returns ``kind``."""
    with _LOCK:
        if kind.name in _BY_NAME or kind.world_type in _BY_TYPE or kind.problem_type in _BY_TYPE:
            raise ValueError(f"the world kind {kind.name!r} (or its world's class) is registered already")
        _BY_NAME[kind.name] = kind
        _BY_TYPE[kind.world_type] = kind
        _BY_TYPE[kind.problem_type] = kind
    return kind


def unregister(name: str) -> None:
    """Remove the kind called ``name`` (tests register a kind of their own, then remove it)."""
    with _LOCK:
        kind = _BY_NAME.pop(name)
        _BY_TYPE.pop(kind.world_type, None)
        _BY_TYPE.pop(kind.problem_type, None)


def kinds() -> tuple[str, ...]:
    """The names of the kinds registered, in the order they were."""
    return tuple(_BY_NAME)


def kind_named(name: str, parameter: str = "world.kind") -> WorldKind:
    """The kind called ``name``; an unknown one raises :class:`~clew_ros.core.errors.WorldError` naming
    ``parameter``."""
    kind = _BY_NAME.get(name) if isinstance(name, str) else None
    if kind is None:
        expected = " or ".join(repr(known) for known in _BY_NAME)
        raise WorldError(parameter, f"expected {expected}, got {name!r:.40}")
    return kind


def kind_of(world_or_problem: Any) -> WorldKind:
    """The kind of a world (or of an offline problem) of a registered kind."""
    for cls in type(world_or_problem).__mro__:
        kind = _BY_TYPE.get(cls)
        if kind is not None:
            return kind
    raise TypeError(f"{type(world_or_problem).__name__} is no world of a registered kind ({', '.join(_BY_NAME)})")


def kind_of_parameters(parameters: Mapping[str, Any]) -> WorldKind:
    """The kind a ``ros__parameters`` tree's ``world.kind`` names (:data:`DEFAULT_KIND` when it names none)."""
    tree = parameters.get("world") if isinstance(parameters, Mapping) else None
    name = tree.get("kind", DEFAULT_KIND) if isinstance(tree, Mapping) else DEFAULT_KIND
    return kind_named(name)
