"""``clew_plan --foxglove``: the run served live to a WebSocket client, the same plan as without it, and a
clear refusal without foxglove-sdk."""

from __future__ import annotations

import json
import os
import queue
import re
import signal
import socket
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest
import yaml

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "config"


def env(*, shadow: Path | None = None) -> dict[str, str]:
    """This process's environment; ``shadow`` first on PYTHONPATH."""
    out = dict(os.environ)
    paths = [str(shadow)] if shadow else []
    out["PYTHONPATH"] = os.pathsep.join([*paths, str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])
    return out


def clew_plan(*args, extra_env: dict[str, str] | None = None, timeout=200) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "clew_ros.cli.plan", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=timeout,
        cwd=ROOT,
        env=extra_env or env(),
    )


def fast_world(tmp_path: Path, name: str = "figure1") -> Path:
    """``config/<name>.yaml`` with a fast playback (the node's playback and trajectory parameters)."""
    document = yaml.safe_load((CONFIG / f"{name}.yaml").read_text())
    parameters = document["clew_planner"]["ros__parameters"]
    parameters["trajectory"] = {"joint_speed": 20.0, "max_acceleration": 400.0, "grasp_dwell": 0.05}
    parameters["playback"] = {"rate": 50.0}
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(document))
    return path


def without_time(document: dict) -> dict:
    return {**document, "stats": {k: v for k, v in document["stats"].items() if k != "time_s"}}


def test_without_foxglove_sdk_it_names_the_extra_and_exits_2(tmp_path) -> None:
    shadow = tmp_path / "shadow"
    (shadow / "foxglove").mkdir(parents=True)
    (shadow / "foxglove" / "__init__.py").write_text(
        "raise ModuleNotFoundError(\"No module named 'foxglove'\", name='foxglove')\n"
    )
    output = tmp_path / "plan.json"
    result = clew_plan(CONFIG / "figure1.yaml", "--output", output, "--foxglove", extra_env=env(shadow=shadow))
    assert result.returncode == 2, result.stderr
    assert "foxglove-sdk" in result.stderr
    assert "pip install clew_ros[live]" in result.stderr
    assert not output.exists()


class Run:
    """``clew_plan ... --foxglove 0`` in the background; its stderr lines in a queue."""

    def __init__(self, *args: object) -> None:
        self.process = subprocess.Popen(
            [sys.executable, "-m", "clew_ros.cli.plan", *map(str, args), "--foxglove", "0", "--quiet"],
            stderr=subprocess.PIPE,
            text=True,
            cwd=ROOT,
            env=env(),
        )
        self.lines: queue.Queue[str] = queue.Queue()
        self.seen: list[str] = []
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        assert self.process.stderr is not None
        for line in self.process.stderr:
            self.lines.put(line)

    def wait_for_line(self, pattern: str, timeout_s: float = 120.0) -> re.Match[str]:
        while True:
            line = self.lines.get(timeout=timeout_s)
            self.seen.append(line)
            match = re.search(pattern, line)
            if match:
                return match

    def interrupt(self, timeout_s: float = 30.0) -> int:
        self.process.send_signal(signal.SIGINT)
        return self.process.wait(timeout_s)

    def stderr(self) -> str:
        while not self.lines.empty():
            self.seen.append(self.lines.get())
        return "".join(self.seen)

    def kill(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait()


@pytest.fixture
def live_client():
    pytest.importorskip("foxglove")
    pytest.importorskip("websockets")
    pytest.importorskip("google.protobuf")
    from helpers.foxglove_client import FoxgloveClient

    return FoxgloveClient


def test_a_run_served_live_plans_the_same_as_without_and_plays_back_until_ctrl_c(tmp_path, live_client) -> None:
    world = fast_world(tmp_path)
    plain = tmp_path / "plain.json"
    # seed 17: figure1 needs 9 landmarks there, so the tree is seen growing (most seeds need 2 since session 9)
    assert clew_plan(world, "--output", plain, "--seed", 17, "--quiet").returncode == 0
    live = tmp_path / "live.json"
    run = Run(world, "--output", live, "--seed", 17)
    try:
        port = int(run.wait_for_line(r"live view on ws://127\.0\.0\.1:(\d+)").group(1))
        with live_client.connect(port, channels=6) as client:
            received = client.receive_until(
                lambda m: m.topic == "/clew_plan/events" and m.data["kind"] == "playback_done", timeout_s=120
            )
        run.wait_for_line("playing the plan back")
        code = run.interrupt()
    finally:
        run.kill()
    assert code == 0, run.stderr()
    assert "stopping the live view" in run.stderr()
    document = json.loads(live.read_text())
    assert without_time(document) == without_time(json.loads(plain.read_text()))  # same seed, same plan

    topics = {m.topic for m in received}
    assert topics == {
        f"/clew_plan/{name}" for name in ("scene", "landmarks", "arm", "joint_states", "progress", "events")
    }
    scene = next(m for m in received if m.topic == "/clew_plan/scene")
    assert {e["id"] for e in scene.data["entities"]} == {"bounds", "obstacles", "start", "goal"}
    trees = [m for m in received if m.topic == "/clew_plan/landmarks"]
    sizes = [len(m.data["entities"][0]["spheres"]) for m in trees]
    assert sizes[-1] == len(document["landmarks"])
    assert len({s for s in sizes if s}) > 1  # seen growing
    events = [m.data for m in received if m.topic == "/clew_plan/events"]
    outcome = next(e for e in events if e["kind"] == "outcome")
    assert outcome["code"] == document["code"] == "SUCCEEDED"
    last = [m for m in received if m.topic == "/clew_plan/joint_states"][-1].data["joints"]
    assert [j["position"] for j in last[:-1]] == pytest.approx(document["segments"][-1]["waypoints"][-1])


def test_a_failed_run_shows_its_outcome_and_exits_1(tmp_path, live_client) -> None:
    output = tmp_path / "plan.json"
    run = Run(CONFIG / "behind_wall.yaml", "--output", output, "--time-limit", 1)
    try:
        port = int(run.wait_for_line(r"live view on ws://127\.0\.0\.1:(\d+)").group(1))
        with live_client.connect(port, channels=6) as client:
            received = client.receive_until(
                lambda m: m.topic == "/clew_plan/events" and m.data["kind"] == "outcome", timeout_s=60
            )
        code = run.interrupt()
    finally:
        run.kill()
    assert code == 1, run.stderr()
    assert received[-1].data["code"] == json.loads(output.read_text())["code"] == "TIME_LIMIT"


def test_a_busy_port_or_a_bad_playback_parameter_exits_2(tmp_path) -> None:
    pytest.importorskip("foxglove")
    output = tmp_path / "plan.json"
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        result = clew_plan(CONFIG / "figure1.yaml", "--output", output, "--foxglove", busy.getsockname()[1])
    assert result.returncode == 2, result.stderr
    assert "cannot serve the live view" in result.stderr
    world = fast_world(tmp_path)
    text = world.read_text().replace("joint_speed: 20.0", "joint_speed: -1.0")
    world.write_text(text)
    result = clew_plan(world, "--output", output, "--foxglove", 0)
    assert result.returncode == 2, result.stderr
    assert "trajectory.joint_speed" in result.stderr
    assert not output.exists()


def test_a_spatial_run_served_live_draws_the_arm_in_3d(tmp_path, live_client) -> None:
    """The Panda table-to-table world: the scene in 3-D, the links and their transforms, the plan played back."""
    from clew_ros.render.spatial.frames import load_spatial_world
    from clew_ros.spatial.transforms import quaternion_matrix

    source = CONFIG / "spatial" / "panda_table_to_table.yaml"
    document = yaml.safe_load(source.read_text())
    parameters = document["clew_planner"]["ros__parameters"]
    for key in ("urdf", "srdf"):
        parameters["world"]["robot"][key] = str((source.parent / parameters["world"]["robot"][key]).resolve())
    parameters["trajectory"] = {"max_velocity": 20.0, "max_acceleration": 200.0, "grasp_dwell": 0.05}
    parameters["playback"] = {"rate": 25.0}
    world_file = tmp_path / source.name
    world_file.write_text(yaml.safe_dump(document))
    output = tmp_path / "plan.json"
    run = Run(world_file, "--output", output, "--seed", 1)
    try:
        port = int(run.wait_for_line(r"live view on ws://127\.0\.0\.1:(\d+)").group(1))
        with live_client.connect(port, channels=8) as client:
            received = client.receive_until(
                lambda m: m.topic == "/clew_plan/events" and m.data["kind"] == "playback_done", timeout_s=120
            )
        code = run.interrupt()
    finally:
        run.kill()
    assert code == 0, run.stderr()
    planned = json.loads(output.read_text())
    assert planned["code"] == "SUCCEEDED"
    assert {m.topic for m in received} >= {f"/clew_plan/{n}" for n in ("scene", "links", "tf", "arm", "joint_states")}
    scene = next(m for m in received if m.topic == "/clew_plan/scene")
    assert {e["id"] for e in scene.data["entities"]} == {"bounds", "obstacles", "supports", "start", "goal"}
    world = load_spatial_world(world_file)
    links = next(m for m in received if m.topic == "/clew_plan/links")
    assert {e["frame_id"] for e in links.data["entities"]} == {link.name for link in world.robot.links}
    last = [m for m in received if m.topic == "/clew_plan/joint_states"][-1].data["joints"]
    joints = [j["position"] for j in last[:-1]]
    assert joints == pytest.approx(planned["segments"][-1]["waypoints"][-1])
    transforms = [m for m in received if m.topic == "/clew_plan/tf"][-1].data["transforms"]
    for t in transforms:
        if t["child_frame_id"] == "object":
            continue
        v, q = t["translation"], t["rotation"]
        placed = quaternion_matrix([v["x"], v["y"], v["z"]], [q["x"], q["y"], q["z"], q["w"]])
        np.testing.assert_allclose(placed, world.robot.link_poses(joints)[t["child_frame_id"]], atol=1e-6)
