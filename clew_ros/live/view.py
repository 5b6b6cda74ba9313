"""The live view: a run served over a Foxglove WebSocket on this machine, while it runs.

:class:`LiveView` starts a ``foxglove-sdk`` WebSocket server bound to
127.0.0.1 (never another address) and publishes what it is given: the
world, the landmark tree each time it grows, the run's progress and outcome,
and a plan played back in real time (timed as the node times
``~/trajectory``: :func:`clew_ros.motion.playback.track_from_plan`, played by
:func:`clew_ros.motion.player.play`). It only observes: the planner's
``progress`` callback (:meth:`LiveView.on_progress`) is its way in, and the
plan is the same with it or without it. No rclpy.

Channels (``namespace`` is ``/clew_plan`` unless given):

=============================  ==========================  ==========================================
topic                          schema (encoding)           content
=============================  ==========================  ==========================================
``<namespace>/scene``          ``foxglove.SceneUpdate``    the world: entities ``bounds``,
                               (protobuf)                  ``obstacles``, ``start`` (object and grasp
                                                           points), ``goal``
``<namespace>/landmarks``      ``foxglove.SceneUpdate``    entity ``landmarks``: where the object
                                                           rests at each landmark, its outline there,
                                                           parent -> child edges
``<namespace>/arm``            ``foxglove.SceneUpdate``    entities ``arm`` (links, joints, gripper:
                                                           green open, red closed) and ``object``
``<namespace>/joint_states``   ``foxglove.JointStates``    joints (rad) and ``gripper`` (1.0 holding)
                               (protobuf)                  at each playback sample
``<namespace>/progress``       ``clew_plan.Progress``      ``landmarks``, ``best_distance_m`` (null
                               (JSON)                      before any), ``elapsed_s``
``<namespace>/events``         ``clew_plan.Event``         ``{"kind": ...}``: ``world``, ``outcome``
                               (JSON)                      (``code``, ``message``), ``grasp`` /
                                                           ``ungrasp`` (``grasp``, ``time_s``),
                                                           ``playback_done``
=============================  ==========================  ==========================================

A spatial world (interface.md section 1b) is drawn in 3-D
(:mod:`clew_ros.live.spatial`): ``<namespace>/scene`` holds ``bounds``,
``obstacles``, ``supports``, ``start`` and ``goal`` as solids; two more
channels, ``<namespace>/links`` (``foxglove.SceneUpdate``: the arm's links,
entity ``link/<name>`` each in its link's frame, ``frame_locked``) and
``<namespace>/tf`` (``foxglove.FrameTransforms``: ``world`` -> every link and
``world`` -> ``object`` at the start and at each playback sample) draw the arm
as ``~/world_markers`` and ``/tf`` draw it from a recording; ``/arm`` holds
``gripper`` (the tool centre point) and ``object``; ``/landmarks`` the tcp at
each landmark, the tree's edges and the object's centre at each;
``/joint_states`` the planned joints' URDF names and ``gripper``.

Everything planar is drawn in the frame ``world`` at ``z = 0``. The scene, the
landmarks, the arm and the progress are latched: a client that subscribes
late is sent the latest message of each (to every subscriber of that
channel; a scene update replaces entities of the same id, so nothing is
drawn twice).
"""

from __future__ import annotations

import queue
import threading
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from clew_ros.core.clew import Progress
from clew_ros.core.errors import ParameterError
from clew_ros.core.parameters import PLAYBACK_PARAMETERS, ParameterType, check_joint_count, check_value
from clew_ros.core.plan import Plan
from clew_ros.live.drawings import Drawing, drawing_for
from clew_ros.live.errors import LiveViewError, LiveViewUnavailableError

if TYPE_CHECKING:
    import foxglove
    from foxglove.websocket import ServerListener, WebSocketServer

    from clew_ros.live.messages import LandmarkLike
    from clew_ros.planar.world import World
    from clew_ros.spatial.world import SpatialWorld

__all__ = ["DEFAULT_PORT", "HOST", "LiveView", "is_available"]

#: The only address the server binds: the live view never leaves this machine.
HOST = "127.0.0.1"
#: Foxglove's default WebSocket port.
DEFAULT_PORT = 8765

PROGRESS_SCHEMA: dict[str, Any] = {
    "title": "clew_plan.Progress",
    "type": "object",
    "properties": {
        "landmarks": {"type": "integer", "description": "landmarks in the tree"},
        "best_distance_m": {
            "type": ["number", "null"],
            "description": "smallest goal distance reached so far (m); null before any",
        },
        "elapsed_s": {"type": "number", "description": "seconds since the run started"},
    },
    "required": ["landmarks", "best_distance_m", "elapsed_s"],
}

EVENT_SCHEMA: dict[str, Any] = {
    "title": "clew_plan.Event",
    "type": "object",
    "properties": {
        "kind": {"type": "string", "description": "world, outcome, grasp, ungrasp or playback_done"},
        "world": {"type": "string"},
        "code": {"type": "string", "description": "the outcome code (SUCCEEDED, TIME_LIMIT, ...)"},
        "message": {"type": "string"},
        "landmarks": {"type": "integer"},
        "grasp": {"type": "integer"},
        "time_s": {"type": "number", "description": "seconds since the playback started"},
    },
    "required": ["kind"],
}


#: The node's parameters that time a playback -> the keyword of :class:`LiveView` each sets.
_TIMING = {
    "playback.rate": "rate_hz",
    "trajectory.max_velocity": "max_velocity_rad_s",
    "trajectory.max_acceleration": "max_acceleration_rad_s2",
    "trajectory.joint_speed": "max_velocity_rad_s",  # the deprecated alias of max_velocity wins when set
    "trajectory.grasp_dwell": "grasp_dwell_s",
}


def is_available() -> bool:
    """Whether ``foxglove-sdk`` (the ``live`` extra) can be imported."""
    try:
        import foxglove  # noqa: F401
    except ImportError:
        return False
    return True


class LiveView:
    """A Foxglove WebSocket server on 127.0.0.1 that shows a run: see the module docstring for its channels.

    ``port`` 0 picks a free port (:attr:`port` says which once started).
    ``rate_hz``, ``max_velocity_rad_s``, ``max_acceleration_rad_s2`` (one
    for every joint, or one per joint) and
    ``grasp_dwell_s`` time the playback as the node's ``playback.rate``,
    ``trajectory.max_velocity``, ``trajectory.max_acceleration`` and
    ``trajectory.grasp_dwell`` (their defaults are those parameters').
    ``spatial``: advertise the ``links`` and ``tf`` channels of spatial worlds from the start (see the
    module docstring; without it they are added when a spatial world is published).
    A context manager: ``with LiveView() as view:`` starts and stops it.

    >>> view = LiveView(port=0)                       # doctest: +SKIP
    >>> view.start(); view.publish_world(world)       # doctest: +SKIP
    >>> result = plan(world, progress=view.on_progress)  # doctest: +SKIP
    >>> view.play(Plan.from_result(world, result)); view.stop()  # doctest: +SKIP
    """

    def __init__(
        self,
        *,
        port: int = DEFAULT_PORT,
        namespace: str = "/clew_plan",
        name: str = "clew_plan",
        rate_hz: float = PLAYBACK_PARAMETERS.default("playback.rate"),
        max_velocity_rad_s: float | Sequence[float] = PLAYBACK_PARAMETERS.default("trajectory.max_velocity"),
        max_acceleration_rad_s2: float | Sequence[float] = PLAYBACK_PARAMETERS.default("trajectory.max_acceleration"),
        grasp_dwell_s: float = PLAYBACK_PARAMETERS.default("trajectory.grasp_dwell"),
        spatial: bool = False,
    ) -> None:
        if not 0 <= port <= 65535:
            raise LiveViewError(f"port {port} is not a TCP port, must be in [0, 65535]")
        limits = np.concatenate([np.atleast_1d(max_velocity_rad_s), np.atleast_1d(max_acceleration_rad_s2)])
        if min(rate_hz, grasp_dwell_s, *limits.tolist()) <= 0:
            raise LiveViewError("rate_hz, max_velocity_rad_s, max_acceleration_rad_s2 and grasp_dwell_s must be > 0")
        self._requested_port = port
        self._namespace = namespace.rstrip("/")
        self._name = name
        self._rate_hz = rate_hz
        self._max_velocity_rad_s = max_velocity_rad_s
        self._max_acceleration_rad_s2 = max_acceleration_rad_s2
        self._grasp_dwell_s = grasp_dwell_s
        self._spatial = spatial
        self._server: WebSocketServer | None = None
        self._context: foxglove.Context | None = None
        self._channels: dict[str, Any] = {}
        self._latched: dict[int, tuple[Any, Any]] = {}  # channel id -> (channel, its latest message)
        self._lock = threading.Lock()  # publishing and latching: the latest message is the last one sent
        self._subscribed = threading.Event()
        self._resends: queue.SimpleQueue[int | None] = queue.SimpleQueue()  # channel ids subscribed to
        self._resender: threading.Thread | None = None
        self._stopping = threading.Event()
        self._world: World | SpatialWorld | None = None
        self._drawing: Drawing | None = None  # how the world's kind is drawn

    @classmethod
    def from_parameters(
        cls,
        parameters: Mapping[str, Any],
        *,
        port: int = DEFAULT_PORT,
        joints: int | None = None,
        spatial: bool = False,
    ) -> LiveView:
        """A live view timed by a ``ros__parameters`` tree's ``playback.rate`` and ``trajectory.*`` (the node's;
        absent ones take their defaults; ``trajectory.joint_speed``, if set, is the velocity limit). Raises
        :class:`~clew_ros.core.errors.ParameterError` naming a parameter that is out of range, or (given the
        world's ``joints``) a per-joint limit that does not hold one value per joint."""
        values = {}
        for key, keyword in _TIMING.items():
            group, _, leaf = key.partition(".")
            tree = parameters.get(group) or {}
            if not isinstance(tree, Mapping):
                raise ParameterError(group, f"expected a mapping, got {tree!r:.80}")
            if leaf in tree:
                values[keyword] = check_value(PLAYBACK_PARAMETERS[key], tree[leaf])
                if joints is not None and PLAYBACK_PARAMETERS[key].type is ParameterType.DOUBLE_PER_JOINT:
                    check_joint_count(PLAYBACK_PARAMETERS[key], values[keyword], joints)
        return cls(port=port, spatial=spatial, **values)

    # ------------------------------------------------------------------ life

    @property
    def port(self) -> int:
        """The port the server listens on (raises before :meth:`start`)."""
        if self._server is None:
            raise LiveViewError("the live view is not started")
        return self._server.port

    @property
    def url(self) -> str:
        """``ws://127.0.0.1:<port>``: what to open in Foxglove (Open connection -> Foxglove WebSocket)."""
        return f"ws://{HOST}:{self.port}"

    def topic(self, name: str) -> str:
        """The topic of channel ``name`` (``scene``, ``landmarks``, ``arm``, ...)."""
        return f"{self._namespace}/{name}"

    def start(self) -> LiveView:
        """Start the server; raises :class:`LiveViewUnavailableError` without foxglove-sdk,
        :class:`LiveViewError` when the port cannot be bound."""
        if self._server is not None:
            raise LiveViewError("the live view is started already")
        try:
            import foxglove
            from foxglove.channels import FrameTransformsChannel, JointStatesChannel, SceneUpdateChannel
        except ImportError as error:
            raise LiveViewUnavailableError from error
        # Our own context (channels of other code in this process are not served), kept alive with the server:
        # a context dropped closes its channels.
        self._context = context = foxglove.Context()
        self._channels = {
            "scene": SceneUpdateChannel(self.topic("scene"), context=context),
            "landmarks": SceneUpdateChannel(self.topic("landmarks"), context=context),
            "arm": SceneUpdateChannel(self.topic("arm"), context=context),
            "joint_states": JointStatesChannel(self.topic("joint_states"), context=context),
            "progress": foxglove.Channel(self.topic("progress"), schema=PROGRESS_SCHEMA, context=context),
            "events": foxglove.Channel(self.topic("events"), schema=EVENT_SCHEMA, context=context),
        }
        if self._spatial:
            self._channels["links"] = SceneUpdateChannel(self.topic("links"), context=context)
            self._channels["tf"] = FrameTransformsChannel(self.topic("tf"), context=context)
        self._stopping.clear()
        try:
            self._server = foxglove.start_server(
                name=self._name,
                host=HOST,
                port=self._requested_port,
                context=context,
                server_listener=_listener(self._subscribed, self._resends.put),
            )
        except (RuntimeError, OSError) as error:
            self._close_channels()
            raise LiveViewError(f"cannot serve the live view on {HOST}:{self._requested_port}: {error}") from error
        self._resender = threading.Thread(target=self._resend_latched, name="live-view-latch", daemon=True)
        self._resender.start()
        return self

    def stop(self) -> None:
        """Stop a playback under way and the server; does nothing when not started."""
        self._stopping.set()
        server, self._server = self._server, None
        if server is not None:
            server.stop()
        if self._resender is not None:
            self._resends.put(None)
            self._resender.join()
            self._resender = None
        self._close_channels()

    def __enter__(self) -> LiveView:
        return self.start()

    def __exit__(self, *_exc: object) -> None:
        self.stop()

    def wait_for_client(self, timeout_s: float | None = None) -> bool:
        """Wait until a client has subscribed to a channel (or the view stops); returns whether one has."""
        deadline = None if timeout_s is None else time.monotonic() + timeout_s
        while not self._subscribed.is_set() and not self._stopping.is_set():
            left = None if deadline is None else deadline - time.monotonic()
            if left is not None and left <= 0:
                break
            self._subscribed.wait(0.1 if left is None else min(0.1, left))
        return self._subscribed.is_set()

    # ------------------------------------------------------------------ publishing

    def publish_world(self, world: World | SpatialWorld, *, goal: np.ndarray | None = None) -> None:
        """Publish ``world`` (its goal, or ``goal`` (3,)) and the arm at its start; the world
        :meth:`publish_landmarks` and :meth:`play` draw in from now on. Clears the landmarks. A world drawn in
        3-D (spatial) adds the ``links`` and ``tf`` channels unless the view was made with ``spatial=True``
        (its goal is its own)."""
        drawing = drawing_for(world)
        self._world, self._drawing = world, drawing
        drawing.world(self, world, goal, time.time_ns())
        self.send("events", {"kind": "world", "world": world.name})

    def publish_landmarks(self, landmarks: Iterable[LandmarkLike]) -> None:
        """Publish the landmark tree: a :class:`~clew_ros.core.tree.LandmarkTree` or a plan's landmarks."""
        world, drawing = self._current_world()
        self.send("landmarks", drawing.landmarks(world, landmarks, time.time_ns()), latch=True)

    def publish_progress(self, progress: Progress) -> None:
        """Publish a run's progress (``/progress``) and its landmark tree."""
        best = progress.best_distance if np.isfinite(progress.best_distance) else None
        record = {"landmarks": progress.landmarks, "best_distance_m": best, "elapsed_s": round(progress.elapsed, 4)}
        self.send("progress", record, latch=True)
        self.publish_landmarks(progress.tree)

    def on_progress(self, progress: Progress) -> None:
        """The planner's ``progress`` callback: :meth:`publish_progress`."""
        self.publish_progress(progress)

    def publish_outcome(self, plan: Plan) -> None:
        """Publish a run's outcome (an ``outcome`` event) and the landmarks its plan lists."""
        if plan.landmarks:
            self.publish_landmarks(plan.landmarks)
        self.send(
            "events",
            {"kind": "outcome", "code": plan.code or "", "message": plan.message, "landmarks": len(plan.landmarks)},
        )

    def play(self, plan: Plan, *, stop: threading.Event | None = None) -> bool:
        """Play ``plan`` back in real time on ``/arm`` and ``/joint_states`` (grasp and ungrasp on ``/events``).

        Blocks until the playback ends; returns ``True`` when it played to the end, ``False`` when
        :meth:`stop` or ``stop`` ended it first. A plan without segments plays nothing (``True``).
        """
        from clew_ros.live import messages
        from clew_ros.motion.playback import GripperEvent, TrackState
        from clew_ros.motion.player import play

        world, drawing = self._current_world()
        if not plan.segments:
            return True
        track, names = drawing.track(self, world, plan)

        def wait_stop(timeout_s: float) -> bool:
            if stop is None:
                return self._stopping.wait(timeout_s)
            return self._stopping.wait(timeout_s / 2) or stop.wait(timeout_s / 2)

        def on_sample(state: TrackState) -> None:
            now = time.time_ns()
            drawing.state(self, world, state.joints, state.gripper, state.object_pose, now)
            self.send("joint_states", messages.joint_states(names, state.joints, state.gripper, now))

        def on_event(event: GripperEvent) -> None:
            self.send("events", {"kind": event.kind, "grasp": event.grasp, "time_s": round(event.time_s, 4)})

        end = play(track, self._rate_hz, wait_stop=wait_stop, on_sample=on_sample, on_event=on_event)
        if not end.stopped:
            self.send("events", {"kind": "playback_done", "time_s": round(track.duration_s, 4)})
        return not end.stopped

    def publish_sample(
        self, joint_names: Sequence[str], joints: np.ndarray, gripper: float, object_pose: np.ndarray
    ) -> None:
        """One state of a playback run elsewhere (the node's): the arm, the object and the joint states."""
        from clew_ros.live import messages

        now = time.time_ns()
        world, drawing = self._current_world()
        drawing.state(self, world, joints, gripper, object_pose, now)
        self.send("joint_states", messages.joint_states(list(joint_names), joints, gripper, now))

    def publish_event(self, kind: str, **fields: Any) -> None:
        """One ``events`` message: ``{"kind": kind, **fields}`` (fields JSON-ready)."""
        self.send("events", {"kind": kind, **fields})

    # ------------------------------------------------------------------ internals

    def publish_spatial_sample(self, joints: np.ndarray, gripper: float, object_pose: np.ndarray | None) -> None:
        """One state of a playback run elsewhere (the node's) in a world drawn in 3-D: the links' transforms,
        the tcp and the object, the joint states."""
        world, drawing = self._current_world()
        if not drawing.in_3d:
            raise LiveViewError("publish_spatial_sample: the world published is planar; use publish_sample")
        drawing.state(self, world, np.asarray(joints, dtype=float), gripper, object_pose, time.time_ns())

    @property
    def timing(self) -> _Timing:
        """This view's playback limits, as the node's :class:`~clew_ros.motion.playback.TrackTiming`."""
        return _Timing(self._max_velocity_rad_s, self._max_acceleration_rad_s2, self._grasp_dwell_s)

    def add_3d_channels(self) -> None:
        """The ``links`` and ``tf`` channels, when the view was not made with ``spatial=True`` (advertised to
        the clients connected from now on and to those connected already)."""
        if self._server is None or "tf" in self._channels:
            return
        from foxglove.channels import FrameTransformsChannel, SceneUpdateChannel

        with self._lock:
            self._channels["links"] = SceneUpdateChannel(self.topic("links"), context=self._context)
            self._channels["tf"] = FrameTransformsChannel(self.topic("tf"), context=self._context)

    def _current_world(self) -> tuple[World | SpatialWorld, Drawing]:
        if self._world is None or self._drawing is None:
            raise LiveViewError("publish_world() first: the live view draws in the world it was given")
        return self._world, self._drawing

    def send(self, name: str, message: Any, *, latch: bool = False) -> None:
        """Log ``message`` on channel ``name`` (nothing when not started); ``latch``: keep it for late subscribers."""
        with self._lock:
            channel = self._channels.get(name)
            if self._server is None or channel is None:
                return
            channel.log(message, log_time=time.time_ns())
            if latch:
                self._latched[channel.id()] = (channel, message)

    def _resend_latched(self) -> None:
        """The latch thread: a client subscribed to a channel; send the channel's latest message, if latched.

        Not done in the server's callback itself, which must not wait for :attr:`_lock`.
        """
        while (channel_id := self._resends.get()) is not None:
            with self._lock:
                latest = self._latched.get(channel_id)
                if latest is not None and self._server is not None:
                    latest[0].log(latest[1], log_time=time.time_ns())

    def _close_channels(self) -> None:
        with self._lock:
            for channel in self._channels.values():
                channel.close()
            self._channels = {}
            self._latched = {}
            self._context = None


@dataclass(frozen=True)
class _Timing:
    """This view's playback limits as :class:`~clew_ros.motion.playback.TrackTiming` (the node's names)."""

    velocity_limit_rad_s: float | tuple[float, ...]
    max_acceleration_rad_s2: float | tuple[float, ...]
    grasp_dwell_s: float

    def __init__(self, velocity: float | Sequence[float], acceleration: float | Sequence[float], dwell: float) -> None:
        def plain(value: float | Sequence[float]) -> float | tuple[float, ...]:
            return float(value) if np.ndim(value) == 0 else tuple(float(v) for v in value)  # type: ignore[arg-type, union-attr]

        object.__setattr__(self, "velocity_limit_rad_s", plain(velocity))
        object.__setattr__(self, "max_acceleration_rad_s2", plain(acceleration))
        object.__setattr__(self, "grasp_dwell_s", float(dwell))


def _listener(subscribed: threading.Event, resend: Callable[[int], None]) -> ServerListener:
    """A server listener that sets ``subscribed`` and asks for a resend of each channel subscribed to."""
    from foxglove.websocket import ChannelView, Client, ServerListener

    class Listener(ServerListener):
        def on_subscribe(self, client: Client, channel: ChannelView) -> None:
            subscribed.set()
            resend(channel.id)

    return Listener()
