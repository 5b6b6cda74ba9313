"""Shared test setup.

DDS traffic must stay on this machine (interface.md §5), and parallel test
runs must not meet. The environment is set here, at import time, so that it
is in place before any test module imports rclpy and before any subprocess
inherits it: discovery is LOCALHOST only, with no static peers, and
ROS_DOMAIN_ID, unless already set (make test and .ci/run set it), is derived
from this process's pid.
"""

import os

import pytest

os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ["ROS_STATIC_PEERS"] = ""
os.environ.setdefault("ROS_DOMAIN_ID", str(os.getpid() % 90 + 10))


@pytest.fixture(scope="session", autouse=True)
def ros_localhost_env() -> dict[str, str]:
    """The ROS 2 network settings every test and subprocess runs with."""
    assert os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    return {
        "ROS_AUTOMATIC_DISCOVERY_RANGE": os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"],
        "ROS_DOMAIN_ID": os.environ["ROS_DOMAIN_ID"],
    }
