"""The live view served over a WebSocket on 127.0.0.1: a client subscribes to every channel and decodes
what it receives; the world, the landmark tree as it grows, the outcome and the plan played back."""

from __future__ import annotations

import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("foxglove")
pytest.importorskip("websockets")
pytest.importorskip("google.protobuf")

from helpers.foxglove_client import FoxgloveClient, Received

from clew_ros.core.clew import Progress
from clew_ros.core.errors import ParameterError
from clew_ros.core.settings import PlannerSettings
from clew_ros.live import HOST, LiveView, LiveViewError
from clew_ros.planar.kinematics import joint_positions, transform_points
from clew_ros.planar.plan import checked_plan, replay
from clew_ros.planar.space import plan
from clew_ros.planar.world import load_world

CONFIG = Path(__file__).resolve().parents[2] / "config"
CHANNELS = 6
#: Fast playback: a plan of figure1 plays in about 2 s.
FAST = {"max_velocity_rad_s": 20.0, "max_acceleration_rad_s2": 400.0, "grasp_dwell_s": 0.05, "rate_hz": 50.0}


@pytest.fixture(scope="module")
def world():
    return load_world(CONFIG / "figure1.yaml")


@pytest.fixture
def view():
    with LiveView(port=0, **FAST) as live:
        yield live


@contextmanager
def connect(view: LiveView) -> Iterator[FoxgloveClient]:
    with FoxgloveClient.connect(view.port, channels=CHANNELS) as client:
        assert view.wait_for_client(5.0)
        yield client


def of(messages: list[Received], name: str) -> list[Received]:
    return [m for m in messages if m.topic == f"/clew_plan/{name}"]


def dots(message: Received) -> np.ndarray:
    (entity,) = message.data["entities"]
    return np.array([[s["pose"]["position"]["x"], s["pose"]["position"]["y"]] for s in entity["spheres"]])


def test_it_listens_on_127_0_0_1_only(view) -> None:
    tcp = Path("/proc/net/tcp")
    if not tcp.exists():
        pytest.skip("needs Linux /proc/net/tcp")
    listening = [line.split() for line in tcp.read_text().splitlines()[1:] if line.split()[3] == "0A"]
    ours = [fields[1] for fields in listening if int(fields[1].split(":")[1], 16) == view.port]
    assert ours == [f"0100007F:{view.port:04X}"]  # 127.0.0.1, little-endian
    tcp6 = Path("/proc/net/tcp6")
    if tcp6.exists():
        listening6 = [line.split() for line in tcp6.read_text().splitlines()[1:] if line.split()[3] == "0A"]
        assert not [f for f in listening6 if int(f[1].split(":")[1], 16) == view.port]
    assert view.url == f"ws://{HOST}:{view.port}"


def test_advertised_channels_and_schemas(view) -> None:
    with connect(view) as client:
        advertised = {c["topic"]: (c["schemaName"], c["encoding"]) for c in client.channels.values()}
    assert advertised == {
        "/clew_plan/scene": ("foxglove.SceneUpdate", "protobuf"),
        "/clew_plan/landmarks": ("foxglove.SceneUpdate", "protobuf"),
        "/clew_plan/arm": ("foxglove.SceneUpdate", "protobuf"),
        "/clew_plan/joint_states": ("foxglove.JointStates", "protobuf"),
        "/clew_plan/progress": ("clew_plan.Progress", "json"),
        "/clew_plan/events": ("clew_plan.Event", "json"),
    }
    assert client.server_info["name"] == "clew_plan"


def test_a_client_that_connects_late_is_sent_the_world_the_tree_and_the_arm(view, world) -> None:
    view.publish_world(world)
    with connect(view) as client:
        received = {m.topic: m for m in (client.receive() for _ in range(3))}
    assert set(received) == {"/clew_plan/scene", "/clew_plan/landmarks", "/clew_plan/arm"}
    scene = {e["id"] for e in received["/clew_plan/scene"].data["entities"]}
    assert scene == {"bounds", "obstacles", "start", "goal"}
    assert len(dots(received["/clew_plan/landmarks"])) == 0
    arm = received["/clew_plan/arm"].data["entities"][0]
    chain = joint_positions(world.robot, world.robot.initial[None])[0]
    assert np.allclose([[p["x"], p["y"]] for p in arm["lines"][0]["points"]], chain)


def test_a_run_live_the_tree_as_it_grows_the_outcome_and_the_plan_played_back(view, world) -> None:
    view.publish_world(world)
    with connect(view) as client:
        updates: list[Progress] = []

        def observe(progress: Progress) -> None:
            updates.append(progress)
            view.on_progress(progress)

        result = plan(world, PlannerSettings(seed=0), progress=observe)
        planned = checked_plan(world, result)
        assert planned.success
        view.publish_outcome(planned)
        assert view.play(planned)
        received = client.receive_until(lambda m: m.topic.endswith("/events") and m.data["kind"] == "playback_done")

    # the tree growing: each progress with its tree, then the plan's landmarks (the empty tree of
    # publish_world may come first: it is latched, sent when the client subscribed)
    assert [m.data["landmarks"] for m in of(received, "progress")] == [p.landmarks for p in updates]
    grown = [len(dots(m)) for m in of(received, "landmarks")]
    assert [n for n in grown if n] == [*(p.landmarks for p in updates), len(planned.landmarks)]
    assert updates[-1].landmarks == len(planned.landmarks)
    final = dots(of(received, "landmarks")[-1])
    assert np.allclose(final, [lm.object_pose[:2] for lm in planned.landmarks])

    # the outcome, then one grasp per transfer and an ungrasp between, then the end of the playback
    events = [m.data for m in of(received, "events")]
    assert events[0] == {
        "kind": "outcome",
        "code": "SUCCEEDED",
        "message": planned.message,
        "landmarks": len(planned.landmarks),
    }
    kinds = [e["kind"] for e in events[1:]]
    transfers = [s for s in planned.segments if s.kind == "transfer"]
    assert kinds.count("grasp") == len(transfers)
    assert kinds[-1] == "playback_done"
    assert [e["grasp"] for e in events if e["kind"] == "grasp"] == [s.grasp for s in transfers]

    # the arm moves through the plan and stops at its end, holding the object at its final pose
    states = of(received, "joint_states")
    assert len(states) >= 10
    last = states[-1].data["joints"]
    assert [j["name"] for j in last] == [*world.robot.joint_names, "gripper"]
    assert np.allclose([j["position"] for j in last[:-1]], planned.segments[-1].waypoints[-1])
    assert last[-1]["position"] == 1.0
    final_arm = {e["id"]: e for e in of(received, "arm")[-1].data["entities"]}
    outline = np.array([[p["x"], p["y"]] for p in final_arm["object"]["lines"][0]["points"]])
    *_, motion = replay(world, planned)
    assert np.allclose(outline, transform_points(motion.object_poses[-1], world.object.polygon))
    times = [m.log_time_ns for m in received]
    assert times == sorted(times)


def test_stop_ends_a_playback_under_way(world) -> None:
    slow = LiveView(port=0, max_velocity_rad_s=0.1)
    slow.start()
    slow.publish_world(world)
    planned = checked_plan(world, plan(world, PlannerSettings(seed=0)))
    ended: list[bool] = []
    player = threading.Thread(target=lambda: ended.append(slow.play(planned)))
    player.start()
    time.sleep(0.3)
    slow.stop()
    player.join(5.0)
    assert ended == [False]
    stop = threading.Event()
    stop.set()
    with LiveView(port=0) as other:
        other.publish_world(world)
        assert other.play(planned, stop=stop) is False


def test_misuse_and_a_busy_port_are_refused(world) -> None:
    with LiveView(port=0) as live:
        with pytest.raises(LiveViewError, match="publish_world"):
            live.publish_landmarks([])
        with pytest.raises(LiveViewError, match="started already"):
            live.start()
        with pytest.raises(LiveViewError, match="cannot serve"), LiveView(port=live.port):
            pass
    with pytest.raises(LiveViewError, match="not started"):
        _ = LiveView().port
    with pytest.raises(LiveViewError, match="TCP port"):
        LiveView(port=70000)
    LiveView().stop()  # never started: nothing to do


def test_timing_comes_from_the_node_parameters() -> None:
    live = LiveView.from_parameters({"playback": {"rate": 40}, "trajectory": {"joint_speed": 2.5}}, port=0)
    with live:
        assert live.port > 0
    with pytest.raises(ParameterError, match=r"trajectory\.grasp_dwell"):
        LiveView.from_parameters({"trajectory": {"grasp_dwell": 0.0}})
    with pytest.raises(ParameterError, match="playback"):
        LiveView.from_parameters({"playback": 3})
    # per-joint limits: one per joint of the world, when the world's joint count is given
    per_joint = {"trajectory": {"max_velocity": [1.0, 2.5], "max_acceleration": 4}}
    LiveView.from_parameters(per_joint, joints=2)
    with pytest.raises(ParameterError, match=r"^trajectory\.max_velocity: .*\(3: joint_1, joint_2, joint_3\)"):
        LiveView.from_parameters(per_joint, joints=3)
    with pytest.raises(LiveViewError, match="must be > 0"):
        LiveView(max_velocity_rad_s=[1.0, 0.0])


def test_the_live_view_loads_no_rclpy_and_no_foxglove_until_started() -> None:
    code = (
        "import sys\nimport clew_ros.live, clew_ros.live.view\n"
        "assert not [m for m in sys.modules if m.startswith(('rclpy', 'foxglove'))], 'imported'\n"
        "clew_ros.live.LiveView(port=0).start().stop()\n"
        "assert 'foxglove' in sys.modules and not [m for m in sys.modules if m.startswith('rclpy')]\nprint('ok')"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"


def test_port_zero_picks_a_free_port_that_is_in_use_while_served() -> None:
    with LiveView(port=0) as live, socket.create_connection((HOST, live.port), timeout=5):
        pass
