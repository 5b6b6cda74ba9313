"""``clew_batch --record``: each job's run recorded as the node would have recorded it (interface.md §4).

The worker records the job's plan with
:func:`clew_ros.batch.plan_recording.record_plan` (the node's own message
builders; synthetic timestamps, no waiting) into a temporary folder of its
own and hands the files back as bytes in its
:class:`~clew_ros.batch.worker.JobOutcome` (:func:`recording_files`), so
that, as with plan files, only the driver writes under the output folder,
whichever executor ran the job. The driver writes them whole
(:func:`write_recording`) to ``recordings/<world file name>/seed_<S>/``: a
rosbag2 folder holding ``metadata.yaml`` and ``<run id>_0.mcap``.

Recording needs the ``ros`` extra (rclpy, the message packages) and ``mcap``;
:func:`recording_unavailable` says, before any job runs, why it cannot be done
here. Without ``--record`` nothing here imports ROS.
"""

from __future__ import annotations

import shutil
import tempfile
import uuid
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from clew_ros.batch.errors import BatchInputError
from clew_ros.batch.files import FOLDER_MODE, check_file_names, write_private
from clew_ros.core.errors import ParameterError
from clew_ros.core.files import private_folders

if TYPE_CHECKING:
    from clew_ros.batch.jobs import BatchWorld
    from clew_ros.core.plan import Plan
    from clew_ros.core.settings import PlannerSettings
    from clew_ros.planar.world import World
    from clew_ros.spatial.world import SpatialWorld

__all__ = [
    "RECORDING_TEXT",
    "RECORD_INSTALL_HINT",
    "check_recording_parameters",
    "has_recording",
    "recording_files",
    "recording_unavailable",
    "write_recording",
]

RECORD_INSTALL_HINT = "pip install 'clew_ros[ros]' (ROS 2 Jazzy's rclpy and messages), or source a ROS 2 Jazzy install"
#: What the events of a batch job's recording say about it.
RECORDING_TEXT = "recorded by clew_batch --record (synthetic timestamps)"


def recording_unavailable() -> str | None:
    """Why runs cannot be recorded here (a package missing, and the install command), or ``None``."""
    try:
        import mcap.writer  # noqa: F401 - what the recorder writes with
        import rosbags.typesys  # noqa: F401 - what the recorder encodes with

        import clew_ros.batch.plan_recording  # noqa: F401 - rclpy and every message package it records
    except ImportError as error:
        return (
            f"recording needs ROS 2 (rclpy and its message packages), mcap and rosbags, which cannot be imported here "
            f"({error}); install them: {RECORD_INSTALL_HINT}"
        )
    return None


def check_recording_parameters(worlds: Sequence[BatchWorld]) -> None:
    """``--record``: the node parameters of every world file (``playback.*``, ``trajectory.*``) checked
    before any job runs; :class:`~clew_ros.batch.errors.BatchInputError` names the file and parameter."""
    from clew_ros.ros.parameters import flatten, node_settings

    for world in worlds:
        try:
            node_settings(flatten(world.parameters), world.problem.world.robot.dof)
        except ParameterError as error:
            raise BatchInputError(str(world.path), str(error)) from None


def recording_files(
    parameters: Mapping[str, Any],
    world: World | SpatialWorld,
    planner: PlannerSettings,
    plan: Plan,
    *,
    start_ns: int,
    folder: Path | None = None,
) -> dict[str, bytes]:
    """The recording of the run that made ``plan``: file name -> content (``metadata.yaml`` and the MCAP).

    ``parameters`` is the world file's tree (its ``playback.*`` and ``trajectory.*`` time the playback,
    as the node would); ``planner`` the job's settings; ``start_ns`` (ns since the epoch) when the job
    started; ``folder`` where a spatial world's relative paths (URDF, SRDF, scene file) start (the
    recording's ``~/world_yaml`` names them absolute, as the node's launch file hands them). Raises
    :class:`~clew_ros.recording.RecordingError` or :class:`~clew_ros.core.errors.ParameterError` (a node
    parameter of the world file is invalid).
    """
    from clew_ros.batch.plan_recording import record_plan
    from clew_ros.kinds import kind_of
    from clew_ros.ros.parameters import flatten, node_settings

    node = node_settings(flatten(parameters), world.robot.dof)
    setup = kind_of(world).setup_of(parameters, Path() if folder is None else folder)
    with tempfile.TemporaryDirectory(prefix="clew_batch_record_") as temporary:
        path = record_plan(
            temporary,
            world,
            plan,
            planner=planner,
            node=node,
            run_id=uuid.uuid4(),
            start_ns=start_ns,
            recording_text=RECORDING_TEXT,
            setup=setup,
        )
        return {file.name: file.read_bytes() for file in sorted(path.iterdir())}


def write_recording(folder: Path, files: Mapping[str, bytes]) -> None:
    """``files`` as the recording ``folder``, whole or not at all: written and synced into a temporary
    sibling folder, which is then renamed to ``folder`` (an older recording there is replaced). Folders
    0700, files 0600; :class:`~clew_ros.batch.files.UnsafeNameError`, before anything is written, for a
    name that is not a plain file name (the names come from the worker)."""
    check_file_names(files)
    private_folders(folder.parent)
    partial = folder.with_name(f".{folder.name}.partial")
    shutil.rmtree(partial, ignore_errors=True)
    partial.mkdir(mode=FOLDER_MODE)
    for name, data in files.items():
        write_private(partial / name, data)
    replaced = folder.with_name(f".{folder.name}.replaced")
    if folder.exists():
        shutil.rmtree(replaced, ignore_errors=True)
        folder.rename(replaced)
    partial.rename(folder)
    shutil.rmtree(replaced, ignore_errors=True)


def has_recording(folder: Path) -> bool:
    """Whether ``folder`` holds a recording (``metadata.yaml`` and an MCAP file)."""
    return (folder / "metadata.yaml").is_file() and any(folder.glob("*.mcap"))
