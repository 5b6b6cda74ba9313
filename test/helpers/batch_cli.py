"""Running ``clew_batch`` in the tests: its command line, its index, plan files compared without wall time."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

__all__ = ["CONFIG", "ROOT", "batch_command", "clew_plan_text", "index_lines", "run_batch_cli", "without_wall_time"]

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "config"


def batch_command(*args: Any) -> list[str]:
    """The command line of ``clew_batch`` (as a module of this checkout)."""
    return [sys.executable, "-m", "clew_ros.cli.batch", *map(str, args)]


def run_batch_cli(*args: Any, timeout: float = 600) -> subprocess.CompletedProcess[str]:
    """Run ``clew_batch`` to its end."""
    return subprocess.run(
        batch_command(*args), capture_output=True, text=True, timeout=timeout, cwd=ROOT, env=dict(os.environ)
    )


def index_lines(out: Path) -> list[dict[str, Any]]:
    """The index's records, in file order."""
    path = out / "index.jsonl"
    return [json.loads(line) for line in path.read_text().splitlines()] if path.exists() else []


def without_wall_time(text: str) -> dict[str, Any]:
    """A plan file's content without ``stats.time_s``, the one field that depends on the clock."""
    document: dict[str, Any] = json.loads(text)
    document["stats"].pop("time_s")
    return document


def clew_plan_text(world: Path, seed: int, output: Path) -> str:
    """The plan file ``clew_plan WORLD --seed S`` writes (run as a module of this checkout)."""
    done = subprocess.run(
        [sys.executable, "-m", "clew_ros.cli.plan", str(world), "-o", str(output), "--seed", str(seed), "-q"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=300,
    )
    assert done.returncode in (0, 1), done.stderr
    return output.read_text()
