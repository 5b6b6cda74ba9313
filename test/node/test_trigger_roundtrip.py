"""A real ROS 2 round trip: a Trigger server in a subprocess, a client here.

The first test that needs a working DDS graph: it proves that the rclpy
install, the localhost-only discovery and the per-run domain work together.
"""

import os
import subprocess
import sys
import time
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest

rclpy = pytest.importorskip("rclpy")

from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from std_srvs.srv import Trigger  # noqa: E402

HELPER = Path(__file__).parents[1] / "helpers" / "trigger_server.py"
DISCOVERY_TIMEOUT_S = 20.0
CALL_TIMEOUT_S = 5.0
CALL_ATTEMPTS = 3
#: How long the server may take to exit on SIGTERM before it is killed (s): a liveness bound, not a speed
#: figure; a 2-core machine under load has taken over 10 s to tear down DDS.
EXIT_TIMEOUT_S = 30.0


class Server:
    """The helper server subprocess and where its output goes."""

    def __init__(self, service: str, log: Path) -> None:
        self.service = service
        self.log = log
        self._log_file = log.open("wb")
        self.proc = subprocess.Popen(
            [sys.executable, str(HELPER), service],
            stdout=self._log_file,
            stderr=subprocess.STDOUT,
            env=os.environ.copy(),  # LOCALHOST discovery and ROS_DOMAIN_ID from conftest
        )

    def output(self) -> str:
        if not self._log_file.closed:
            self._log_file.flush()
        return self.log.read_text(errors="replace")

    def stop(self) -> int:
        """Stop the server (SIGTERM, then SIGKILL); return its exit code."""
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=EXIT_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._log_file.close()
        return self.proc.returncode


def wait_for_service(client, server: Server) -> bool:
    """Wait for the server's service; give up early if the server has died."""
    deadline = time.monotonic() + DISCOVERY_TIMEOUT_S
    while time.monotonic() < deadline and server.proc.poll() is None:
        if client.wait_for_service(timeout_sec=0.5):
            return True
    return client.service_is_ready()


@pytest.fixture
def trigger_server(tmp_path: Path) -> Iterator[Server]:
    # A service name of its own, so that a stray server elsewhere on the same
    # domain cannot answer in its place.
    server = Server(f"/clew_test/trigger_{uuid.uuid4().hex}", tmp_path / "server.log")
    try:
        yield server
    finally:
        server.stop()


@pytest.mark.ros
def test_trigger_roundtrip(trigger_server: Server) -> None:
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        node = rclpy.create_node("trigger_client", context=context)
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        try:
            client = node.create_client(Trigger, trigger_server.service)
            found = wait_for_service(client, trigger_server)
            assert found, (
                f"{trigger_server.service} not found (waited up to {DISCOVERY_TIMEOUT_S} s); "
                f"server exit code {trigger_server.proc.poll()}, output:\n"
                f"{trigger_server.output()}"
            )

            # A request sent the moment the service is discovered can be lost while DDS still
            # matches the response's reader to the client (a known Fast DDS race, seen once in a
            # fresh-clone CI run): ask again, a few times, as any careful client does.
            for _attempt in range(CALL_ATTEMPTS):
                future = client.call_async(Trigger.Request())
                executor.spin_until_future_complete(future, timeout_sec=CALL_TIMEOUT_S)
                if future.done():
                    break
                client.remove_pending_request(future)
            assert future.done(), f"no response within {CALL_ATTEMPTS} x {CALL_TIMEOUT_S} s"
            response = future.result()
        finally:
            executor.shutdown()
            node.destroy_node()
    finally:
        rclpy.shutdown(context=context)

    assert response.success
    assert response.message == f"pid={trigger_server.proc.pid}"

    # The server's main() handles SIGTERM: it shuts down and exits 0.
    assert trigger_server.stop() == 0, trigger_server.output()
