"""clew_ros.spatial runs without ROS: it never imports rclpy."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

SPATIAL = Path(__file__).resolve().parents[2] / "clew_ros" / "spatial"


def test_spatial_sources_do_not_mention_rclpy() -> None:
    for path in SPATIAL.rglob("*.py"):
        assert "rclpy" not in path.read_text(), path


def test_importing_the_spatial_package_loads_no_rclpy() -> None:
    modules = sorted(
        ".".join(("clew_ros", *p.relative_to(SPATIAL.parent).with_suffix("").parts))
        for p in SPATIAL.rglob("*.py")
        if p.stem != "__init__"
    )
    code = "import sys\n" + "".join(f"import {m}\n" for m in modules)
    code += "assert not [m for m in sys.modules if m.startswith('rclpy')], 'rclpy imported'\nprint('ok')"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"
    assert len(modules) >= 6
