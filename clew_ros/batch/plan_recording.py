"""A plan recorded as the node would have recorded its run, without a node (``clew_batch --record``).

:func:`record_plan` writes one run's recording (interface.md §4, through
:class:`clew_ros.recording.RunRecorder`) from a plan already made: the topics
of interface.md §3 that a run puts out and that mean something offline, with
the node's names (``/<node_name>/...``) and QoS, built by the node's own
builders (:mod:`~clew_ros.ros.messages`, :mod:`~clew_ros.ros.frames`,
:func:`~clew_ros.motion.playback.node_track`,
:func:`~clew_ros.motion.player.scheduled_samples`). In order:

- at ``start_ns`` (the run accepted): ``~/status`` (accepted), ``~/world_yaml``,
  ``~/world_markers``, ``~/robot_description``, ``/tf_static``, ``/tf`` and
  ``~/scene`` of the arm at rest, ``~/goal_pose`` (the configured goal), the
  ``accepted`` event and ``~/status`` (executing);
- when planning ended (``start_ns`` + the plan's ``stats.time_s``): a
  ``landmark`` event per landmark past the root, ``~/landmarks`` (the plan's
  landmark tree), ``~/trajectory`` (a plan found), ``~/status`` (the outcome)
  and the outcome event (``succeeded`` / ``aborted`` / ``canceled``);
- a plan found is then played back from that time at ``playback.rate``:
  ``~/joint_states``, ``~/object_pose``, ``/tf`` and ``~/scene`` per sample and
  the ``grasp`` / ``ungrasp`` events, each stamped with its time on the
  track, with no waiting.

A spatial world (interface.md section 1b) is recorded as the node records its runs
(:mod:`clew_ros.ros.spatial`): ``~/world_yaml`` with its setup's parameters,
``~/joint_states`` with every movable joint of the URDF, ``/tf`` with every
link, the ``succeeded`` event with the plan's ``segments`` and
``final_object_pose`` (:func:`~clew_ros.ros.events.spatial_plan_fields`), so
that ``clew_render``, ``clew_replay`` and Foxglove read it as they read the
node's; a motion-only query has no ``~/goal_pose`` or ``~/object_pose``.

Timestamps are synthetic: nothing here reads a clock. ``~/feedback`` is not
recorded (the plan file does not hold the planner's progress).
"""

from __future__ import annotations

import uuid
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from action_msgs.msg import GoalStatus
from std_msgs.msg import String

from clew_ros.core.plan import Plan
from clew_ros.core.settings import PlannerSettings
from clew_ros.kinds import kind_of
from clew_ros.motion.playback import node_track
from clew_ros.motion.player import scheduled_samples
from clew_ros.motion.spatial import spatial_track
from clew_ros.recording import RecordingError, RunRecorder
from clew_ros.recording.cdr import tf_message
from clew_ros.ros import frames, messages, spatial
from clew_ros.ros.events import (
    accepted_fields,
    landmark_fields,
    outcome_event,
    outcome_fields,
    outcome_status,
    spatial_plan_fields,
)
from clew_ros.ros.parameters import NodeSettings
from clew_ros.ros.qos import GOAL_QOS
from clew_ros.ros.topics import TF_TOPICS, TOPICS

if TYPE_CHECKING:
    from clew_ros.planar.world import World
    from clew_ros.ros.spatial import SpatialSetup
    from clew_ros.spatial.world import SpatialWorld

__all__ = ["record_plan"]

_NS_PER_S = 1_000_000_000


class _Run:
    """One recorded run: its recorder, names, and the messages it writes."""

    def __init__(self, recorder: RunRecorder, run_id: uuid.UUID, node_name: str, start_ns: int) -> None:
        self.recorder = recorder
        self.run_id = run_id
        self.node_name = node_name
        self.start_ns = start_ns

    def write(self, name: str, msg: object, time_ns: int) -> None:
        """``msg`` on ``~/<name>`` at ``time_ns``, with the QoS the node offers there."""
        self.recorder.write(f"/{self.node_name}/{name}", msg, time_ns, qos=TOPICS[name][1])

    def tf(
        self,
        transforms: list[frames.FrameTransform] | list[spatial.SpatialTransform],
        time_ns: int,
        *,
        static: bool = False,
    ) -> None:
        topic = "/tf_static" if static else "/tf"
        self.recorder.write(topic, tf_message(transforms, time_ns), time_ns, qos=TF_TOPICS[topic])

    def status(self, status: int, time_ns: int) -> None:
        self.write("status", messages.goal_status_array([(self.run_id, self.start_ns, status)], time_ns), time_ns)

    def event(self, event: str, time_s: float, time_ns: int, /, **fields: object) -> None:
        """One ``~/events`` message: ``event`` whose ``time`` is ``time_s``, written at ``time_ns``."""
        self.write("events", messages.event_message(self.run_id, event, time_s, **fields), time_ns)

    def arm(self, world: World, joints: np.ndarray, gripper: float, object_pose: np.ndarray, time_ns: int) -> None:
        """``/tf`` and ``~/scene`` at one state of the arm, as ``Publishing.arm`` puts them out."""
        self.tf(frames.state_transforms(world.robot, joints, gripper, object_pose), time_ns)
        self.write("scene", messages.scene_markers(world, joints, gripper, object_pose, time_ns), time_ns)

    def spatial_state(  # noqa: PLR0917 - one state of the arm, as the node's Publishing puts it out
        self,
        world: SpatialWorld,
        setup: SpatialSetup,
        joints: np.ndarray,
        velocities: np.ndarray,
        gripper: float,
        object_pose: np.ndarray | None,
        time_ns: int,
    ) -> None:
        """``~/joint_states``, ``~/object_pose`` (a world with an object), ``/tf`` and ``~/scene`` at one state of
        a spatial arm, as ``Publishing.spatial_sample`` puts them out."""
        self.write("joint_states", spatial.joint_state(setup, world, joints, time_ns, velocities), time_ns)
        if object_pose is not None:
            self.write("object_pose", spatial.pose_stamped(object_pose, time_ns), time_ns)
        self.tf(spatial.state_transforms(setup, world, joints, object_pose), time_ns)
        self.write("scene", spatial.scene_markers(world, joints, gripper, object_pose, time_ns), time_ns)

    def record_planar(  # the kind's record_run: a planar run
        self, world: World, plan: Plan, *, planner: PlannerSettings, node: NodeSettings, recording_text: str
    ) -> None:
        _accepted(self, world, plan, planner, recording_text)
        _concluded(self, world, plan, node, recording_text)

    def record_spatial(  # the kind's record_run: a spatial run
        self,
        world: SpatialWorld,
        setup: SpatialSetup,
        plan: Plan,
        *,
        planner: PlannerSettings,
        node: NodeSettings,
        recording_text: str,
    ) -> None:
        _spatial_accepted(self, world, setup, planner, recording_text)
        _spatial_concluded(self, world, setup, plan, node, recording_text)


def record_plan(
    directory: str | Path,
    world: World | SpatialWorld,
    plan: Plan,
    *,
    planner: PlannerSettings,
    node: NodeSettings,
    run_id: uuid.UUID,
    start_ns: int,
    node_name: str = "clew_planner",
    recording_text: str = "recorded offline",
    setup: SpatialSetup | None = None,
) -> Path:
    """Record the run that made ``plan`` in ``world`` as ``<directory>/<run id hex>/``; return that directory.

    Parameters
    ----------
    directory:
        Existing directory that receives the run's directory.
    planner, node:
        The run's settings (``~/world_yaml`` carries the planner's; the node's time the playback).
    run_id:
        The run's UUID (``~/status``, the events, the names of the directory and the MCAP file).
    start_ns:
        When the run was accepted (ns since the epoch): the first message's time.
    node_name:
        The node whose topics the recording holds (``/<node_name>/status``, ...).
    recording_text:
        What the ``accepted`` and outcome events say about the recording.
    setup:
        A spatial ``world``'s setup (:func:`clew_ros.ros.spatial.load_spatial`); ``None`` for a planar world.

    Raises
    ------
    RecordingError
        The recording cannot be created or written (the message says why).
    """
    recorder = RunRecorder(directory, run_id.hex, node_name=node_name)
    with recorder:
        run = _Run(recorder, run_id, node_name, start_ns)
        kind_of(world).record_run(
            run, world, plan, planner=planner, node=node, recording_text=recording_text, setup=setup
        )
    if recorder.error:
        raise RecordingError(recorder.error)
    return recorder.path


def _accepted(run: _Run, world: World, plan: Plan, planner: PlannerSettings, recording_text: str) -> None:
    """The run's start: status accepted, its world and the arm at rest, its goal, the ``accepted`` event."""
    now = run.start_ns
    run.status(GoalStatus.STATUS_ACCEPTED, now)
    for name, msg in messages.world_messages(world, planner, run.node_name, now):
        run.write(name, msg, now)
    run.tf(frames.static_transforms(world.robot), now, static=True)
    run.arm(world, world.robot.initial, 0.0, world.object.initial, now)
    goal = world.object.goal
    run.recorder.write(f"/{run.node_name}/goal_pose", messages.goal_pose_stamped(goal, now), now, qos=GOAL_QOS)
    fields = accepted_fields(source="plan", world=world.name, goal=goal, seed=planner.seed, recording=recording_text)
    run.event("accepted", now / _NS_PER_S, now, **fields)
    run.status(GoalStatus.STATUS_EXECUTING, now)


def _concluded(run: _Run, world: World, plan: Plan, node: NodeSettings, recording_text: str) -> None:
    """Planning over: the landmarks, the trajectory, the outcome; then the playback of a plan found."""
    time_s = float(plan.stats.get("time_s", 0.0))
    now = run.start_ns + round(time_s * _NS_PER_S)
    for landmark in plan.landmarks[1:]:
        run.event("landmark", now / _NS_PER_S, now, **landmark_fields(landmark))
    run.write("landmarks", messages.landmark_markers(plan.landmarks, now, world.object.polygon), now)
    outcome = plan.outcome
    if outcome is None:
        raise ValueError("a plan without an outcome code cannot be recorded as a run")
    track = node_track(world, plan, node) if plan.success else None
    if track is not None:
        run.write("trajectory", messages.joint_trajectory(track, now), now)
    run.status(outcome_status(outcome), now)
    fields = outcome_fields(
        outcome, plan.message, landmarks=len(plan.landmarks), time_s=time_s, recording=recording_text
    )
    run.event(outcome_event(outcome), now / _NS_PER_S, now, **fields)
    if track is None:
        return
    for t_s, state, events in scheduled_samples(track, node.playback_rate_hz):
        stamp = now + round(t_s * _NS_PER_S)
        for name, msg in messages.playback_messages(track.joint_names, state, stamp):
            run.write(name, msg, stamp)
        run.arm(world, state.joints, state.gripper, state.object_pose, stamp)
        for event in events:
            run.event(event.kind, float(event.time_s), stamp, grasp=event.grasp)


def _spatial_goal(world: SpatialWorld) -> np.ndarray:
    """What the run plans to (the node's ``default_goal``): the object's goal placement, or a motion-only
    query's joint goal."""
    return np.asarray(world.goal if world.object is None else world.object.goal, dtype=float)


def _mesh_simplifier() -> spatial.Simplify | None:
    """The arm's meshes simplified as the node draws them in ``~/world_markers`` (so that ``clew_render`` draws
    the arm from the recording alone); ``None`` without the picture package's dependencies."""
    try:
        from clew_ros.render.spatial.meshes import simplify
    except ImportError:
        return None
    return simplify


def _spatial_accepted(
    run: _Run, world: SpatialWorld, setup: SpatialSetup, planner: PlannerSettings, recording_text: str
) -> None:
    """A spatial run's start, as the node announces it: status, the world, the URDF, the arm at rest, the goal."""
    now = run.start_ns
    run.status(GoalStatus.STATUS_ACCEPTED, now)
    run.write("world_yaml", spatial.world_yaml_message(setup, world, planner, run.node_name), now)
    run.write("world_markers", spatial.world_markers(world, now, simplify=_mesh_simplifier()), now)
    run.write("robot_description", String(data=setup.description), now)
    run.tf(spatial.static_transforms(setup, world), now, static=True)
    pose = None if world.object is None else np.asarray(world.object.initial, dtype=float)
    run.spatial_state(world, setup, world.initial, np.zeros(world.robot.dof), 0.0, pose, now)
    goal = _spatial_goal(world)
    if world.object is not None:
        run.recorder.write(f"/{run.node_name}/goal_pose", spatial.pose_stamped(goal, now), now, qos=GOAL_QOS)
    fields = accepted_fields(source="plan", world=world.name, goal=goal, seed=planner.seed, recording=recording_text)
    run.event("accepted", now / _NS_PER_S, now, **fields)
    run.status(GoalStatus.STATUS_EXECUTING, now)


def _spatial_concluded(  # noqa: PLR0917 - the run, its world and what ended it
    run: _Run, world: SpatialWorld, setup: SpatialSetup, plan: Plan, node: NodeSettings, recording_text: str
) -> None:
    """A spatial run's end: the landmarks, the trajectory, the outcome (with the plan's segments), the playback."""
    time_s = float(plan.stats.get("time_s", 0.0))
    now = run.start_ns + round(time_s * _NS_PER_S)
    for landmark in plan.landmarks[1:]:
        run.event("landmark", now / _NS_PER_S, now, **landmark_fields(landmark))
    run.write("landmarks", spatial.landmark_markers(world, plan.landmarks, now), now)
    outcome = plan.outcome
    if outcome is None:
        raise ValueError("a plan without an outcome code cannot be recorded as a run")
    track = spatial_track(world, plan, setup.joints, node) if plan.success else None
    if track is not None:
        run.write("trajectory", messages.joint_trajectory(track, now), now)
    run.status(outcome_status(outcome), now)
    fields = outcome_fields(
        outcome, plan.message, landmarks=len(plan.landmarks), time_s=time_s, recording=recording_text
    )
    if track is not None:
        fields |= spatial_plan_fields(track, has_object=world.object is not None)
    run.event(outcome_event(outcome), now / _NS_PER_S, now, **fields)
    if track is None:
        return
    for t_s, state, events in scheduled_samples(track, node.playback_rate_hz):
        stamp = now + round(t_s * _NS_PER_S)
        pose = None if world.object is None else state.object_pose
        run.spatial_state(world, setup, state.joints, state.velocities, state.gripper, pose, stamp)
        for event in events:
            run.event(event.kind, float(event.time_s), stamp, grasp=event.grasp)
