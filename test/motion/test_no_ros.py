"""The timed plan needs no ROS: importing every module of ``clew_ros.motion`` loads neither rclpy nor a
message package (the live view and the example follower use it without a node)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

MOTION = Path(__file__).resolve().parents[2] / "clew_ros" / "motion"


def test_importing_motion_loads_no_ros() -> None:
    modules = sorted(f"clew_ros.motion.{path.stem}" for path in MOTION.glob("*.py") if path.stem != "__init__")
    assert "clew_ros.motion.playback" in modules
    code = (
        "import sys\n"
        + "".join(f"import {module}\n" for module in modules)
        + "ros = sorted(m for m in sys.modules if m.split('.')[0] in ('rclpy', 'rosidl_parser', 'action_msgs')"
        " or m.split('.')[0].endswith(('_msgs', '_interfaces')))\n"
        "print(ros)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]", out.stdout
