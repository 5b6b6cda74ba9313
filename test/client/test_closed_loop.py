"""The closed loop of ``make demo`` (issue 54) with real processes: ``clew_planner`` on the Panda with
``state.joint_states``, ``state.points`` and ``state.advance``, the simulated arm
(``clew_ros.examples.simulated_arm``) and the pick-and-place client
(``clew_ros.examples.pick_and_place_loop``): two goals in a row, a cloud of a cube on a table before the
second. Both runs succeed; the second starts where the first plan ended (the arm at its last waypoint, which
the simulated arm reached, and the object at its final pose), among the cloud's cubes."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

pytest.importorskip("rclpy")
pytest.importorskip("urdf_parser_py")
rosbags_rosbag2 = pytest.importorskip("rosbags.rosbag2")

from helpers.node_harness import HAVE_RECORDER, NodeProcess  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

from clew_ros.ros.spatial import resolved_parameters  # noqa: E402
from clew_ros.spatial.world import spatial_world_from_parameters  # noqa: E402

pytestmark = [pytest.mark.ros, pytest.mark.skipif(not HAVE_RECORDER, reason="the recorder needs mcap")]

WORLD = Path(__file__).resolve().parents[2] / "config" / "spatial" / "panda_table_to_table.yaml"
TYPESTORE = get_typestore(Stores.ROS2_JAZZY)


def _recorded(directory: str, topic_end: str) -> list[Any]:
    with rosbags_rosbag2.Reader(directory) as reader:
        return [
            TYPESTORE.deserialize_cdr(data, connection.msgtype)
            for connection, _, data in reader.messages()
            if connection.topic.endswith(topic_end)
        ]


def test_two_goals_in_a_row_each_from_where_the_last_ended(tmp_path: Path) -> None:
    parameters = resolved_parameters(WORLD)
    world = spatial_world_from_parameters(parameters, WORLD.parent)
    # max_age 5 s: on a loaded machine the node's callbacks can wait a second or two; this test is of the loop
    # (test/node/test_live_state.py tests the refusal of a stale state)
    parameters["state"] = {"joint_states": True, "points": True, "advance": True, "max_age": 5.0}
    params = tmp_path / "world.yaml"
    params.write_text(yaml.safe_dump({"clew_planner": {"ros__parameters": parameters}}))
    node = NodeProcess(
        tmp_path / "node.log",
        params,
        {
            "record.directory": str(tmp_path / "rec"),
            "trajectory.max_velocity": 3.0,
            "trajectory.max_acceleration": 30.0,
        },
    )
    joints = ",".join(f"{n}={v!r}" for n, v in zip(world.robot.joint_names, world.initial.tolist(), strict=True))
    namespace = ["--ros-args", "-r", f"__ns:={node.namespace}"]
    arm = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "clew_ros.examples.simulated_arm",
            "--joints",
            joints,
            "--planner",
            node.name,
            *namespace,
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    summary = tmp_path / "runs.json"
    try:
        loop = subprocess.run(
            [
                sys.executable, "-m", "clew_ros.examples.pick_and_place_loop", "--planner", node.name,
                "--summary", str(summary), "--obstacle", "0.61,0.19,0.12,0.06",
                "0.5,-0.3,0.17,0,0,0.5", "0.5,0.3,0.17,0,0,0", *namespace,
            ],
            capture_output=True,
            text=True,
            timeout=300,
        )  # fmt: skip
    finally:
        arm.send_signal(2)
        arm_out = arm.communicate(timeout=30)[0]
        code = node.stop()
    assert loop.returncode == 0, f"{loop.stdout}\n{loop.stderr}\n{node.output()}"
    assert code == 0, node.output()
    assert arm_out.count("at rest after") == 2, arm_out
    lines = [line for line in loop.stdout.splitlines() if line.startswith("goal ")]
    assert [line.split(": ")[1].split(",")[0] for line in lines] == ["SUCCEEDED", "SUCCEEDED"], loop.stdout
    runs = json.loads(summary.read_text())
    first = _recorded(runs[0]["recording"], "/trajectory")[0]
    snapshot = yaml.safe_load(_recorded(runs[1]["recording"], "/world_yaml")[0].data)
    tree = next(iter(snapshot.values()))["ros__parameters"]["world"]
    assert np.max(np.abs(np.array(tree["robot"]["initial"]) - np.array(first.points[-1].positions))) <= 1e-6
    assert tree["object"]["initial"][:3] == pytest.approx([0.5, -0.3, 0.17], abs=world.tolerances["goal_tolerance"])
    assert any(name.startswith("points/") for name in tree["obstacle_names"]), "the cloud's cubes"
    second = _recorded(runs[1]["recording"], "/trajectory")[0]
    assert np.max(np.abs(np.array(second.points[0].positions) - np.array(first.points[-1].positions))) <= 1e-6
