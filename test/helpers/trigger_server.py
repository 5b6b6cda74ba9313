"""A minimal std_srvs/srv/Trigger server, run as a subprocess by the tests.

    python trigger_server.py SERVICE_NAME

Answers every call with ``success=True`` and ``message="pid=<its pid>"`` so a
test can tell that the answer came from this very process. Prints ``ready``
once the service exists; exits 0 on SIGINT or SIGTERM (after tearing DDS down, for at most ``TEARDOWN_S``).
"""

import contextlib
import os
import sys
import threading

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from std_srvs.srv import Trigger

#: How long (s) the server waits for DDS to tear down before it exits anyway.
TEARDOWN_S = 5.0


class TriggerServer(Node):
    """Offers one Trigger service that reports this process's pid."""

    def __init__(self, service_name: str) -> None:
        super().__init__("trigger_server")
        self.create_service(Trigger, service_name, self.on_trigger)

    def on_trigger(self, request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        del request  # Trigger requests are empty
        response.success = True
        response.message = f"pid={os.getpid()}"
        return response


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 1:
        print("usage: trigger_server.py SERVICE_NAME", file=sys.stderr)
        return 2
    rclpy.init()
    node = TriggerServer(args[0])
    print("ready", flush=True)
    with contextlib.suppress(KeyboardInterrupt, ExternalShutdownException):
        rclpy.spin(node)
    # Tear DDS down, but not for longer than TEARDOWN_S: a response writer still holding an answer to a request
    # its client gave up on (the test asks again after 5 s) has blocked Fast DDS's teardown for more than 30 s
    # in a full test run on a loaded 2-core machine; the process's exit releases it all the same.
    teardown = threading.Thread(target=_teardown, args=(node,), daemon=True)
    teardown.start()
    teardown.join(TEARDOWN_S)
    sys.stdout.flush()
    os._exit(0)


def _teardown(node: Node) -> None:
    node.destroy_node()
    rclpy.try_shutdown()


if __name__ == "__main__":
    raise SystemExit(main())
