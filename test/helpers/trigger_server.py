"""A minimal std_srvs/srv/Trigger server, run as a subprocess by the tests.

    python trigger_server.py SERVICE_NAME

Answers every call with ``success=True`` and ``message="pid=<its pid>"`` so a
test can tell that the answer came from this very process. Prints ``ready``
once the service exists; exits 0 on SIGINT or SIGTERM.
"""

import os
import sys

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from std_srvs.srv import Trigger


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
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
