"""A spatial run recorded as the node records it, without a node: the shipped Panda table-to-table world and
its witness plan, written through :class:`~clew_ros.recording.RunRecorder` with the node's own builders
(:mod:`clew_ros.ros.spatial`, :func:`~clew_ros.motion.spatial.spatial_track`,
:func:`~clew_ros.ros.events.spatial_plan_fields`): ``~/world_yaml``, ``~/world_markers``,
``~/robot_description``, ``/tf_static``, ``~/landmarks``, ``~/trajectory``, the ``accepted`` and
``succeeded`` events, and the playback's ``~/joint_states``, ``~/object_pose``, ``/tf``, ``~/scene`` and grasp
events. A few seconds, no planning (the witness is a checked plan); the node's own recording is tested in
test/node/test_spatial.py.
"""

from __future__ import annotations

import uuid
from pathlib import Path

from clew_ros.core.plan import Plan
from clew_ros.core.settings import PlannerSettings
from clew_ros.motion.player import scheduled_samples
from clew_ros.motion.spatial import spatial_track
from clew_ros.planar.world import read_parameter_file
from clew_ros.recording import RunRecorder
from clew_ros.recording.cdr import tf_message
from clew_ros.render.spatial.meshes import simplify
from clew_ros.ros import messages, spatial
from clew_ros.ros.events import spatial_plan_fields
from clew_ros.ros.parameters import NodeSettings
from clew_ros.ros.topics import TF_TOPICS, TOPICS

CONFIG = Path(__file__).resolve().parents[2] / "config" / "spatial"
WORLD_FILE = CONFIG / "panda_table_to_table.yaml"
WITNESS = CONFIG / "panda_table_to_table.witness.json"
NODE = "clew_planner"
_NS = 1_000_000_000


def record_witness(
    directory: Path, *, start_ns: int = 1_700_000_000 * _NS, urdf: str | None = None, succeeded: bool = True
) -> Path:
    """Record the witness run in ``directory``; return the run's directory. ``urdf``: the path
    ``~/world_yaml`` names for the URDF instead of the real one (a recording carried to another machine);
    ``succeeded=False``: the run is aborted (``TIME_LIMIT``) after its start, no trajectory."""
    tree = read_parameter_file(WORLD_FILE)
    world, setup = spatial.load_spatial(tree, WORLD_FILE.parent)
    planner = PlannerSettings.from_parameters({"planner": tree.get("planner", {})})
    plan = Plan.read(WITNESS)
    node = NodeSettings()
    track = spatial_track(world, plan, setup.joints, node)
    run_id = uuid.UUID(int=0x45B)
    recorder = RunRecorder(directory, run_id.hex, node_name=NODE)

    def write(name: str, msg: object, time_ns: int) -> None:
        recorder.write(f"/{NODE}/{name}", msg, time_ns, qos=TOPICS[name][1])

    def tf(transforms: list[spatial.SpatialTransform], time_ns: int, static: bool = False) -> None:
        topic = "/tf_static" if static else "/tf"
        recorder.write(topic, tf_message(transforms, time_ns), time_ns, qos=TF_TOPICS[topic])

    def event(name: str, time_ns: int, **fields: object) -> None:
        write("events", messages.event_message(run_id, name, time_ns / _NS, **fields), time_ns)

    with recorder:
        now = start_ns
        world_yaml = spatial.world_yaml_message(setup, world, planner, NODE)
        if urdf is not None:
            world_yaml.data = world_yaml.data.replace(str((CONFIG.parent / "robots/panda/panda.urdf").resolve()), urdf)
            assert urdf in world_yaml.data
        write("world_yaml", world_yaml, now)
        write("world_markers", spatial.world_markers(world, now, simplify=simplify), now)
        write("robot_description", messages.String(data=setup.description), now)
        tf(spatial.static_transforms(setup, world), now, static=True)
        tf(spatial.state_transforms(setup, world, world.initial, world.object.initial), now)
        event("accepted", now, source="plan", world=world.name)
        now += _NS
        if not succeeded:
            event("aborted", now, code="TIME_LIMIT", message="no plan within the time limit")
            return recorder.close()
        write("landmarks", spatial.landmark_markers(world, plan.landmarks, now), now)
        write("trajectory", messages.joint_trajectory(track, now), now)
        event("succeeded", now, code="SUCCEEDED", message="witness", **spatial_plan_fields(track, has_object=True))
        for t_s, state, events in scheduled_samples(track, 10.0):
            stamp = now + round(t_s * _NS)
            write("joint_states", spatial.joint_state(setup, world, state.joints, stamp, state.velocities), stamp)
            write("object_pose", spatial.pose_stamped(state.object_pose, stamp), stamp)
            tf(spatial.state_transforms(setup, world, state.joints, state.object_pose), stamp)
            write("scene", spatial.scene_markers(world, state.joints, state.gripper, state.object_pose, stamp), stamp)
            for grip in events:
                event(grip.kind, stamp, grasp=grip.grasp)
    assert recorder.error is None, recorder.error
    return recorder.path
