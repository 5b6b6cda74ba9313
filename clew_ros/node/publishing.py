"""What the node publishes (the topics of :mod:`clew_ros.ros.topics`), each message also written to a run's recording.

:class:`Publishing` owns the node's publishers and the ``~/status`` table
(:class:`~clew_ros.node.run.StatusTable`). Every ``publish`` takes the
:class:`~clew_ros.node.run_recording.RunRecording` the message belongs to (a
run's, or :data:`~clew_ros.node.run_recording.NO_RECORDING`) and records the
message there before publishing it. The messages themselves come from
:mod:`clew_ros.ros.messages`.

The arm goes out three ways (interface.md §3): ``~/robot_description`` (the
URDF, with the world), ``/tf`` and ``/tf_static`` (:mod:`~clew_ros.ros.frames`)
and ``~/scene`` markers, at rest (:meth:`Publishing.world`) and at every
playback sample (:meth:`Publishing.arm`). ``/tf`` and ``/tf_static`` are
published where ``tf2_msgs`` is importable (a native install; the PyPI wheels
lack it) and always recorded: :func:`clew_ros.recording.cdr.tf_message` encodes the message once, and
the same bytes are recorded and published.

A spatial world (interface.md section 1b) goes out through :mod:`clew_ros.ros.spatial` instead: its
URDF as ``~/robot_description``, ``/tf_static`` (``world`` to the URDF's root, the fixed joints) and, at
rest and at every playback sample (:meth:`Publishing.spatial_sample`), ``~/joint_states`` with every
movable joint, ``/tf`` with every movable joint's link frame and the object, ``~/object_pose`` and
``~/scene``.

``~/status`` and ``~/feedback`` are built and published under one lock, so
that the latched ``~/status`` never ends on an older snapshot and no
``planning`` feedback follows a run's outcome.
"""

from __future__ import annotations

import importlib.util
import threading
import time
import uuid
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from action_msgs.msg import GoalStatus
from rclpy.node import Node
from std_msgs.msg import String

from clew_ros.core.settings import Outcome, PlannerSettings
from clew_ros.kinds import kind_of
from clew_ros.motion.playback import Track, TrackState
from clew_ros.node.run import Phase, Run, StatusTable
from clew_ros.node.run_recording import RunRecording
from clew_ros.ros import frames, messages, spatial
from clew_ros.ros.topics import TF_TOPICS, TOPICS

if TYPE_CHECKING:
    from clew_ros.live import LiveView
    from clew_ros.planar.world import World
    from clew_ros.ros.spatial import SpatialSetup
    from clew_ros.spatial.world import SpatialWorld
from clew_ros.recording.cdr import tf_message

__all__ = ["Publishing", "have_tf2_msgs"]


def _mesh_simplifier() -> spatial.Simplify | None:
    """The picture package's mesh simplification, for the links drawn in ``~/world_markers`` (``None`` when
    its dependencies are not installed: the links' meshes are left out, their primitives drawn)."""
    try:
        from clew_ros.render.spatial.meshes import simplify
    except ImportError:
        return None
    return simplify


def have_tf2_msgs() -> bool:
    """Whether ``tf2_msgs`` is importable, so that ``/tf`` and ``/tf_static`` are published live."""
    return importlib.util.find_spec("tf2_msgs") is not None


class Publishing:
    """The publishers of ``node`` (:data:`TOPICS`) and its ``~/status`` table.

    ``closing`` is set when the node shuts down: a publish that fails then
    (the context is gone) is not logged.
    """

    def __init__(self, node: Node, closing: threading.Event, *, link_faces: int = 400) -> None:
        self._clock = node.get_clock()
        #: ``markers.link_faces``: triangles per link mesh in ``~/world_markers`` (0: every one)
        self._link_markers = spatial.LinkMarkerSettings(max_link_faces=link_faces)
        self._logger = node.get_logger()
        self._node_name = node.get_name()
        self._closing = closing
        self._publishers = {
            name: node.create_publisher(msg_type, f"~/{name}", qos) for name, (msg_type, qos) in TOPICS.items()
        }
        self._tf_publishers: dict[str, Any] = {}
        if have_tf2_msgs():
            from tf2_msgs.msg import TFMessage

            self._tf_publishers = {
                topic: node.create_publisher(TFMessage, topic, qos) for topic, qos in TF_TOPICS.items()
            }
        self._statuses = StatusTable()
        self._order = threading.Lock()  # ~/status and ~/feedback: see the module docstring
        #: The Foxglove live view (``live.foxglove_port``), set by the node; it mirrors the world, the
        #: landmark tree, progress, events and the playback.
        self.live: LiveView | None = None

    def to_live(self, what: str, send: Callable[[LiveView], None]) -> None:
        """Mirror something to the live view, if there is one; a fault there is logged, never raised."""
        live = self.live
        if live is None:
            return
        try:
            send(live)
        except Exception as error:  # noqa: BLE001 - a viewer never stops a run
            self._logger.error(f"live view: cannot send {what}: {error!r}")

    def now_ns(self) -> int:
        """The node's clock (ns)."""
        return self._clock.now().nanoseconds

    def publish(self, name: str, msg: Any, recording: RunRecording) -> None:
        """Record ``msg`` in ``recording``, then publish it on ``~/<name>``; never raises."""
        publisher = self._publishers[name]
        recording.write(publisher.topic_name, msg, self.now_ns(), publisher.qos_profile)
        try:
            publisher.publish(msg)
        except Exception as error:  # noqa: BLE001 - the context is gone while shutting down
            if not self._closing.is_set():
                self._logger.error(f"cannot publish on {publisher.topic_name}: {error}")

    def world(
        self,
        world: World | SpatialWorld,
        planner: PlannerSettings,
        recording: RunRecording,
        spatial: SpatialSetup | None = None,
    ) -> None:
        """``~/world_yaml``, ``~/world_markers`` and the arm of a problem: ``~/robot_description``,
        ``/tf_static``, and ``/tf`` and ``~/scene`` at the start (arm at ``robot.initial``, gripper open,
        object at its initial pose), as the world's kind puts them out; a spatial world comes with its
        ``spatial`` setup."""
        kind_of(world).announce_world(self, world, planner, recording, spatial)

    def planar_world(self, world: World, planner: PlannerSettings, recording: RunRecording) -> None:
        """:meth:`world` for a planar world."""
        for name, msg in messages.world_messages(world, planner, self._node_name, self.now_ns()):
            self.publish(name, msg, recording)
        self.publish_tf(frames.static_transforms(world.robot), self.now_ns(), recording, static=True)
        self.to_live("the world", lambda live: live.publish_world(world, goal=world.object.goal))
        self.arm(world, world.robot.initial, 0.0, world.object.initial, time_ns=self.now_ns(), recording=recording)

    def planar_sample(
        self, world: World, track: Track, state: TrackState, *, time_ns: int, recording: RunRecording
    ) -> None:
        """One played-back state of a planar run: ``~/joint_states``, ``~/object_pose``, ``/tf`` and ``~/scene``."""
        for name, msg in messages.playback_messages(track.joint_names, state, time_ns):
            self.publish(name, msg, recording)
        self.arm(world, state.joints, state.gripper, state.object_pose, time_ns=time_ns, recording=recording)

    def spatial_world(
        self, world: SpatialWorld, setup: SpatialSetup, planner: PlannerSettings, recording: RunRecording
    ) -> None:
        now = self.now_ns()
        self.publish("world_yaml", spatial.world_yaml_message(setup, world, planner, self._node_name), recording)
        markers = spatial.world_markers(world, now, self._link_markers, simplify=_mesh_simplifier())
        self.publish("world_markers", markers, recording)
        self.publish("robot_description", String(data=setup.description), recording)
        self.publish_tf(spatial.static_transforms(setup, world), now, recording, static=True)
        self.to_live("the world", lambda live: live.publish_world(world))
        pose = None if world.object is None else np.asarray(world.object.initial, dtype=float)
        velocities = np.zeros(world.robot.dof)
        self._spatial_state(
            world, setup, world.initial, velocities, gripper=0.0, object_pose=pose, time_ns=now, recording=recording
        )

    def spatial_sample(
        self, world: SpatialWorld, setup: SpatialSetup, state: TrackState, *, time_ns: int, recording: RunRecording
    ) -> None:
        """One played-back state of a spatial run: ``~/joint_states`` (every movable joint of the URDF),
        ``~/object_pose``, ``/tf`` (every link, the object) and ``~/scene``."""
        pose = None if world.object is None else state.object_pose
        self._spatial_state(
            world,
            setup,
            state.joints,
            state.velocities,
            gripper=state.gripper,
            object_pose=pose,
            time_ns=time_ns,
            recording=recording,
        )

    def _spatial_state(
        self,
        world: SpatialWorld,
        setup: SpatialSetup,
        joints: np.ndarray,
        velocities: np.ndarray,
        *,
        gripper: float,
        object_pose: np.ndarray | None,
        time_ns: int,
        recording: RunRecording,
    ) -> None:
        self.publish("joint_states", spatial.joint_state(setup, world, joints, time_ns, velocities), recording)
        if object_pose is not None:
            self.publish("object_pose", spatial.pose_stamped(object_pose, time_ns), recording)
        self.publish_tf(spatial.state_transforms(setup, world, joints, object_pose), time_ns, recording)
        self.publish("scene", spatial.scene_markers(world, joints, gripper, object_pose, time_ns), recording)
        self.to_live("a state", lambda live: live.publish_spatial_sample(joints, gripper, object_pose))

    def arm(
        self,
        world: World,
        joints: Sequence[float] | np.ndarray,
        gripper: float,
        object_pose: np.ndarray,
        *,
        time_ns: int,
        recording: RunRecording,
    ) -> None:
        """``/tf`` (the arm's joints and the object) and ``~/scene`` at one state, stamped ``time_ns``."""
        self.publish_tf(frames.state_transforms(world.robot, joints, gripper, object_pose), time_ns, recording)
        self.publish(
            "scene",
            messages.scene_markers(world, np.asarray(joints, dtype=float), gripper, object_pose, time_ns),
            recording,
        )
        names = world.robot.joint_names
        self.to_live("a state", lambda live: live.publish_sample(names, np.asarray(joints), gripper, object_pose))

    def publish_tf(
        self,
        transforms: Sequence[frames.FrameTransform | spatial.SpatialTransform],
        time_ns: int,
        recording: RunRecording,
        *,
        static: bool = False,
    ) -> None:
        """``transforms`` stamped ``time_ns`` on ``/tf`` (or ``/tf_static``): recorded, and published where
        ``tf2_msgs`` is installed; never raises."""
        topic = "/tf_static" if static else "/tf"
        publisher = self._tf_publishers.get(topic)
        if not recording.is_open and publisher is None:
            return
        try:
            message = tf_message(transforms, time_ns)
        except Exception as error:  # noqa: BLE001 - rosbags not installed: the run goes on without TF
            self._logger.error(f"cannot encode {topic}: {error!r}")
            return
        if recording.is_open:
            recording.write(topic, message, self.now_ns(), TF_TOPICS[topic])
        if publisher is None:
            return
        try:
            publisher.publish(message.data)  # serialized bytes, published as they are
        except Exception as error:  # noqa: BLE001 - the context is gone while shutting down
            if not self._closing.is_set():
                self._logger.error(f"cannot publish on {topic}: {error}")

    def event(
        self, run_id: uuid.UUID, event: str, recording: RunRecording, /, at_s: float | None = None, **fields: Any
    ) -> None:
        """One ``~/events`` message; ``time`` is ``at_s`` if given (grasp events), else wall-clock seconds.

        ``fields`` go into the message (``recording=`` among them: the text of the run's recording).
        """
        self.publish(
            "events", messages.event_message(run_id, event, time.time() if at_s is None else at_s, **fields), recording
        )
        if event != "landmark":  # the live view draws landmarks as a tree
            plain = {k: v for k, v in fields.items() if v is None or isinstance(v, (str, int, float, bool))}
            self.to_live("an event", lambda live: live.publish_event(event, run_id=run_id.hex, **plain))

    def feedback(self, run: Run, phase: str) -> None:
        """``~/feedback`` of ``run`` with ``phase``."""
        self.publish(
            "feedback",
            messages.feedback_status(
                run.id,
                landmarks=run.landmarks,
                best_distance=run.best_distance,
                elapsed_s=time.monotonic() - run.start_s,
                phase=phase,
            ),
            run.recording,
        )

    def refusal(
        self, code: Outcome, message: str, source: str, recording: RunRecording, goal_stamp_ns: int | None = None
    ) -> str:
        """A request that does not become a run: a UUID of its own, status aborted, an ``aborted`` event
        (with the request's ``goal_stamp_ns``, if any).

        Returns ``run <id>: <CODE>: <message>``.
        """
        run_id = uuid.uuid4()
        self.set_status(run_id, self.now_ns(), GoalStatus.STATUS_ABORTED)
        self.publish_status(recording)
        request = {} if goal_stamp_ns is None else {"goal_stamp_ns": goal_stamp_ns}
        self.event(
            run_id,
            "aborted",
            recording,
            code=code.name,
            code_value=code.value,
            message=message,
            source=source,
            **request,
        )
        return f"run {run_id.hex}: {code.name}: {message}"

    # ------------------------------------------------------------------ ~/status (with feedback, in order)

    def set_status(self, run_id: uuid.UUID, stamp_ns: int, status: int, *, current: bool = False) -> None:
        """Enter a run's status in the table (published by the next :meth:`publish_status`); ``current``:
        the node's current run, listed first."""
        with self._order:
            self._statuses.set(run_id, stamp_ns, status, current=current)

    def publish_status(self, recording: RunRecording) -> None:
        """``~/status``: every run of the table."""
        with self._order:
            self._publish_status(recording)

    def planning_progress(self, run: Run) -> None:
        """While ``run`` plans: ``~/feedback`` (``planning``) and ``~/status``."""
        with self._order:
            if run.phase is Phase.PLANNING:
                self.feedback(run, Phase.PLANNING.value)
                self._publish_status(run.recording)

    def outcome(self, run: Run) -> None:
        """``run``'s outcome on ``~/feedback`` (its code as ``phase``) and ``~/status``."""
        if run.outcome is None:
            raise ValueError(f"run {run.hex} has no outcome yet")
        with self._order:
            self.feedback(run, run.outcome.name)
            self._statuses.set(run.id, run.accepted_ns, run.status)
            self._publish_status(run.recording)

    def _publish_status(self, recording: RunRecording) -> None:
        self.publish("status", messages.goal_status_array(self._statuses.entries(), self.now_ns()), recording)
