"""How the live view draws each kind of world: one :class:`Drawing` per kind, found by the world's kind.

:class:`~clew_ros.live.view.LiveView` itself never tells the kinds apart: it asks :func:`drawing_for` (by
:func:`clew_ros.kinds.kind_of`) for the drawing of the world it was given. A planar world is drawn by
:mod:`clew_ros.live.messages` at ``z = 0``, a spatial one in 3-D by :mod:`clew_ros.live.spatial`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from clew_ros.kinds import kind_of
from clew_ros.planar.world import WORLD_KIND as PLANAR
from clew_ros.spatial import WORLD_KIND as SPATIAL

if TYPE_CHECKING:
    from clew_ros.core.plan import Plan
    from clew_ros.live.messages import LandmarkLike
    from clew_ros.motion.playback import Track

__all__ = ["Drawing", "drawing_for", "register_drawing"]


class Canvas(Protocol):
    """What a drawing draws on (the live view): its channels and its playback timing."""

    def send(self, name: str, message: Any, *, latch: bool = False) -> None:
        """Log ``message`` on channel ``name``; ``latch``: keep it for late subscribers."""

    def add_3d_channels(self) -> None:
        """The ``links`` and ``tf`` channels, if not there yet."""

    @property
    def timing(self) -> Any: ...


class Drawing:
    """How one kind of world is drawn; ``in_3d``: it needs the ``links`` and ``tf`` channels."""

    in_3d = False

    def world(self, view: Canvas, world: Any, goal: np.ndarray | None, now: int) -> None:
        """The world (its goal, or ``goal``), the arm at its start, the landmarks cleared."""
        raise NotImplementedError

    def landmarks(self, world: Any, landmarks: Iterable[LandmarkLike], now: int) -> Any:
        """The ``landmarks`` channel's message for a landmark tree (or a plan's landmarks)."""
        raise NotImplementedError

    def track(self, view: Canvas, world: Any, plan: Plan) -> tuple[Track, list[str]]:
        """``plan`` timed as the node times it, and the joint names ``joint_states`` carries."""
        raise NotImplementedError

    def state(  # noqa: PLR0917 - one state of the arm and the object
        self, view: Canvas, world: Any, joints: np.ndarray, gripper: float, object_pose: np.ndarray | None, now: int
    ) -> None:
        """The arm and the object at one state."""
        raise NotImplementedError


class PlanarDrawing(Drawing):
    """A planar world at ``z = 0`` (:mod:`clew_ros.live.messages`)."""

    def world(self, view: Canvas, world: Any, goal: np.ndarray | None, now: int) -> None:
        from clew_ros.live import messages

        view.send("scene", messages.world_update(world, now, goal=goal), latch=True)
        view.send("landmarks", messages.landmarks_update(world, [], now), latch=True)
        self.state(view, world, world.robot.initial, 0.0, world.object.initial, now)

    def landmarks(self, world: Any, landmarks: Iterable[LandmarkLike], now: int) -> Any:
        from clew_ros.live import messages

        return messages.landmarks_update(world, landmarks, now)

    def track(self, view: Canvas, world: Any, plan: Plan) -> tuple[Track, list[str]]:
        from clew_ros.motion.playback import track_from_plan

        timing = view.timing
        track = track_from_plan(
            world,
            plan,
            max_velocity_rad_s=timing.velocity_limit_rad_s,
            max_acceleration_rad_s2=timing.max_acceleration_rad_s2,
            grasp_dwell_s=timing.grasp_dwell_s,
        )
        return track, list(track.joint_names[:-1])

    def state(  # noqa: PLR0917 - one state of the arm and the object
        self, view: Canvas, world: Any, joints: np.ndarray, gripper: float, object_pose: np.ndarray | None, now: int
    ) -> None:
        from clew_ros.live import messages

        pose = world.object.initial if object_pose is None else object_pose  # a planar world always has one
        view.send("arm", messages.arm_update(world, joints, gripper, pose, now), latch=True)


class SpatialDrawing(Drawing):
    """A spatial world in 3-D (:mod:`clew_ros.live.spatial`): the scene, the links (latched), the arm."""

    in_3d = True

    def __init__(self, simplify: Callable[[], Any] | None = None) -> None:
        self._simplify = simplify

    def world(self, view: Canvas, world: Any, goal: np.ndarray | None, now: int) -> None:
        from clew_ros.live import spatial

        del goal  # a spatial world's goal is its own
        view.add_3d_channels()
        view.send("scene", spatial.world_update(world, now), latch=True)
        simplify = None if self._simplify is None else self._simplify()
        view.send("links", spatial.links_update(world, now, simplify), latch=True)
        view.send("landmarks", spatial.landmarks_update(world, [], now), latch=True)
        pose = None if world.object is None else np.asarray(world.object.initial, dtype=float)
        self.state(view, world, world.initial, 0.0, pose, now)

    def landmarks(self, world: Any, landmarks: Iterable[LandmarkLike], now: int) -> Any:
        from clew_ros.live import spatial

        return spatial.landmarks_update(world, landmarks, now)

    def track(self, view: Canvas, world: Any, plan: Plan) -> tuple[Track, list[str]]:
        """A spatial plan timed as the node times it: the URDF's velocity limits and this view's."""
        from clew_ros.motion.spatial import UrdfTree, spatial_track

        track = spatial_track(world, plan, UrdfTree(world.robot.urdf), view.timing)
        return track, list(track.joint_names)

    def state(  # noqa: PLR0917 - one state of the arm and the object
        self, view: Canvas, world: Any, joints: np.ndarray, gripper: float, object_pose: np.ndarray | None, now: int
    ) -> None:
        from clew_ros.live import messages, spatial

        pose = None if world.object is None else object_pose
        view.send("tf", spatial.transforms(world, joints, pose, now), latch=True)
        view.send("arm", spatial.state_update(world, joints, gripper, pose, now), latch=True)
        view.send("joint_states", messages.joint_states(list(world.robot.joint_names), joints, gripper, now))


def _mesh_simplifier() -> Callable[[np.ndarray, np.ndarray, int], tuple[np.ndarray, np.ndarray]] | None:
    """The picture package's mesh simplification for the links' meshes (``None`` without its dependencies:
    the links' primitives alone are drawn)."""
    try:
        from clew_ros.render.spatial.meshes import simplify
    except ImportError:
        return None
    return simplify


_DRAWINGS: dict[str, Drawing] = {PLANAR: PlanarDrawing(), SPATIAL: SpatialDrawing(_mesh_simplifier)}


def register_drawing(kind: str, drawing: Drawing) -> None:
    """How the live view draws the worlds of the kind called ``kind`` (a new kind's drawing)."""
    _DRAWINGS[kind] = drawing


def drawing_for(world: Any) -> Drawing:
    """The drawing of ``world``'s kind."""
    return _DRAWINGS[kind_of(world).name]
