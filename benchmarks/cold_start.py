"""What the compiled kernel costs at start: compiling it, loading it from numba's cache, and the
first plan against the second.

* ``compile_s``: :func:`clew_ros.planar.kernel.warm_up` in a fresh process with an empty cache
  (``NUMBA_CACHE_DIR`` set to a new directory): the first start after an install.
* ``load_s``: the same in a second fresh process, which loads what the first one cached: every
  later start of the node or ``clew_plan``.
* ``import_s``: importing the planner (numpy, shapely, numba) in a fresh process, for scale.
* ``first_plan_s`` / ``second_plan_s``: in one fresh process, after the warm-up that ``clew_plan``
  and the node do before their first plan, figure1 planned twice with the same seed (the same
  work): what the first plan still pays for (preparing the world's geometry, Python's own caches).
* ``node_first_plan_s`` / ``node_second_plan_s`` (when rclpy is installed): the node
  ``clew_planner`` started fresh on its default world, ``~/plan`` called twice, the planning
  time each answer reports. DDS stays on this machine (``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``,
  a domain of its own unless ``ROS_DOMAIN_ID`` is set).

    python -m benchmarks.cold_start [--world config/figure1.yaml] [--seed 0]

Prints one JSON object.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

_WARM = """
import time
t = time.perf_counter()
import clew_ros.core.clew
imported = time.perf_counter() - t
from clew_ros.planar.kernel import warm_up
t = time.perf_counter()
warm_up()
print(imported, time.perf_counter() - t)
"""

_TWICE = """
import sys, time
from clew_ros.planar.kernel import warm_up
from clew_ros.planar.space import plan
from clew_ros.core.settings import PlannerSettings
from clew_ros.planar.collision import check_start_and_goal
from clew_ros.planar.world import load_world
warm_up()
world = check_start_and_goal(load_world(sys.argv[1]))
times = []
for _ in range(2):
    t = time.perf_counter()
    result = plan(world, PlannerSettings(seed=int(sys.argv[2]), time_limit=60.0))
    times.append(time.perf_counter() - t)
print(times[0], times[1], result.outcome.name)
"""


def _python(code: str, *args: str, env: dict[str, str] | None = None) -> list[str]:
    done = subprocess.run(
        [sys.executable, "-c", code, *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env={**os.environ, **(env or {})},
        check=True,
        timeout=600,
    )
    return done.stdout.split()


def node_first_and_second() -> dict:
    """The node's first and second plan (seconds, as its ``~/plan`` answers report them)."""
    try:
        import rclpy  # noqa: F401
    except ImportError:
        return {"node": "rclpy not installed"}
    namespace = f"/cold_start_{os.getpid()}"
    env = {
        **os.environ,
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
        "ROS_STATIC_PEERS": "",
        "ROS_DOMAIN_ID": os.environ.get("ROS_DOMAIN_ID", str(os.getpid() % 90 + 10)),
    }
    node = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "clew_ros.node.main",
            "--ros-args",
            "-r",
            f"__ns:={namespace}",
            "-p",
            "record.enabled:=false",
        ],
        cwd=ROOT,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    times = []
    try:
        for _ in range(2):
            done = subprocess.run(
                [
                    sys.executable,
                    "-m",
                    "clew_ros.client.call_plan",
                    "--node",
                    f"{namespace}/clew_planner",
                    "--timeout",
                    "120",
                ],
                cwd=ROOT,
                env=env,
                capture_output=True,
                text=True,
                timeout=300,
                check=False,
            )
            found = re.search(r"^plan: .*, ([0-9.]+) s$", done.stdout, re.MULTILINE)  # call_plan's last line
            if not found:
                return {"node": f"no planning time in the answer: {done.stdout.strip()[:200]}"}
            times.append(float(found.group(1)))
    finally:
        node.send_signal(signal.SIGINT)
        try:
            node.wait(timeout=30)
        except subprocess.TimeoutExpired:
            node.kill()
    return {
        "node_first_plan_s": times[0],
        "node_second_plan_s": times[1],
        "node_first_over_second": times[0] / times[1] if times[1] > 0 else None,
    }


def measure(world: Path, seed: int = 0) -> dict:
    with tempfile.TemporaryDirectory(prefix="clew_numba_cache_") as cache:
        env = {"NUMBA_CACHE_DIR": cache}
        started = time.perf_counter()
        imported, compile_s = (float(v) for v in _python(_WARM, env=env))
        compile_wall = time.perf_counter() - started
        started = time.perf_counter()
        _imported, load_s = (float(v) for v in _python(_WARM, env=env))
        load_wall = time.perf_counter() - started
        first, second, outcome = _python(_TWICE, str(world), str(seed), env=env)
    return {
        "compile_s": compile_s,
        "compile_process_wall_s": compile_wall,
        "load_s": load_s,
        "load_process_wall_s": load_wall,
        "import_s": imported,
        "world": str(world),
        "seed": seed,
        "first_plan_s": float(first),
        "second_plan_s": float(second),
        "first_over_second": float(first) / float(second),
        "outcome": outcome,
        **node_first_and_second(),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.cold_start", description=__doc__.split("\n\n")[0])
    parser.add_argument("--world", type=Path, default=ROOT / "config" / "figure1.yaml")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    print(json.dumps(measure(args.world, args.seed)))  # one line: benchmarks.run reads the last line
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
