"""The planner core runs without ROS: it never imports rclpy."""

import subprocess
import sys
from pathlib import Path

CORE = Path(__file__).resolve().parents[2] / "clew_ros" / "core"


def test_core_sources_do_not_mention_rclpy():
    for path in CORE.glob("*.py"):
        assert "rclpy" not in path.read_text(), path


def test_importing_the_core_and_cli_loads_no_rclpy():
    modules = [f"clew_ros.core.{p.stem}" for p in CORE.glob("*.py") if p.stem != "__init__"] + ["clew_ros.cli.plan"]
    code = (
        "import sys\n"
        + "".join(f"import {m}\n" for m in modules)
        + "assert not [m for m in sys.modules if m.startswith('rclpy')], 'rclpy imported'\nprint('ok')"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok", out.stderr
