"""The planner runs without ROS: its packages (the algorithm and the worlds it plans in) never import rclpy."""

import subprocess
import sys
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[2] / "clew_ros"
#: the planner's packages: the algorithm, and the kinds of world it plans in
PLANNER = ("core", "planar", "spatial")


def _sources() -> list[Path]:
    return [path for name in PLANNER for path in sorted((PACKAGE / name).rglob("*.py"))]


def test_planner_sources_do_not_mention_rclpy():
    assert len(_sources()) > 30
    for path in _sources():
        assert "rclpy" not in path.read_text(), path


def test_importing_the_planner_and_cli_loads_no_rclpy():
    modules = [
        ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts).removesuffix(".__init__")
        for path in _sources()
    ] + ["clew_ros.cli.plan"]
    code = (
        "import sys\n"
        + "".join(f"import {m}\n" for m in modules)
        + "assert not [m for m in sys.modules if m.startswith('rclpy')], 'rclpy imported'\nprint('ok')"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok", out.stderr
