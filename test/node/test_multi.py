"""``clew_planners``: its arguments, each node's own ROS arguments, and refusals at start.

Four planners at work on one graph: test/client/test_many_planners.py.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
import yaml

rclpy = pytest.importorskip("rclpy")

from clew_ros.node.multi import main, node_arguments, ros_parameter_arguments  # noqa: E402

CONFIG = Path(__file__).resolve().parents[2] / "config"
START_TIMEOUT_S = 60.0


def test_the_command_line_parameters_go_to_every_node_after_its_world() -> None:
    argv = [
        "clew_planners",
        "a:=a.yaml",
        "--ros-args",
        "-p",
        "planner.seed:=3",
        "--log-level",
        "warn",
        "--params-file",
        "more.yaml",
        "--param",
        "record.enabled:=false",
        "--",
        "-p",
        "not_ros",
        "--ros-args",
        "-r",
        "x:=y",
        "-p",
        "planner.time_limit:=5",
    ]
    parameters = ros_parameter_arguments(argv)
    assert parameters == [
        *("-p", "planner.seed:=3", "--params-file", "more.yaml", "--param", "record.enabled:=false"),
        *("-p", "planner.time_limit:=5"),
    ]
    assert node_arguments(Path("/tmp/w.yaml"), parameters) == [
        *("--ros-args", "--params-file", "/tmp/w.yaml", *parameters),
        *("-r", "/tf:=tf", "-r", "/tf_static:=tf_static"),
    ]


@pytest.mark.parametrize(
    ("arguments", "expected"),
    [
        (["arm_a"], "'arm_a': expected NAMESPACE:=WORLD.yaml"),
        (["a:=x.yaml", "a:=y.yaml"], "namespace /a is given twice"),
        (["a:=/nonexistent/w.yaml"], "a:=/nonexistent/w.yaml: /nonexistent/w.yaml: cannot read the parameter file"),
        (["a:=x.yaml", "--ros-args", "-r", "__ns:=/other"], "-r __ns:=/other: each planner's name and namespace"),
    ],
)
def test_bad_arguments_exit_2_naming_them(capsys: pytest.CaptureFixture[str], arguments, expected: str) -> None:
    with pytest.raises(SystemExit) as exit_code:
        main(["clew_planners", *arguments])
    assert exit_code.value.code == 2
    error = capsys.readouterr().err
    assert "clew_planners: error: " in error
    assert expected in error


@pytest.mark.ros
def test_an_invalid_world_stops_every_planner_with_exit_2(tmp_path: Path) -> None:
    document = yaml.safe_load((CONFIG / "single_transfer.yaml").read_text())
    document["clew_planner"]["ros__parameters"]["world"]["robot"]["initial"] = [9.0, 0.0]
    broken = tmp_path / "broken.yaml"
    broken.write_text(yaml.safe_dump(document))
    process = subprocess.run(
        [
            sys.executable,
            "-m",
            "clew_ros.node.multi",
            f"/tbad{tmp_path.name[-6:]}/good:={CONFIG / 'figure1.yaml'}",
            f"/tbad{tmp_path.name[-6:]}/broken:={broken}",
            "--ros-args",
            "-p",
            f"record.directory:={tmp_path / 'records'}",
        ],
        capture_output=True,
        text=True,
        timeout=START_TIMEOUT_S,
    )
    output = process.stdout + process.stderr
    assert process.returncode == 2, output
    errors = [line for line in output.splitlines() if "ERROR" in line]
    assert len(errors) == 1, output
    assert "broken.clew_planner" in errors[0], output  # the node's logger names the namespace
    assert "world.robot.initial" in errors[0], output
    assert "Traceback" not in output
    assert not (tmp_path / "records").exists()  # no run was started
