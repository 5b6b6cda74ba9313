"""The shipped robots (config/robots), loaded once per test session."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("trimesh")
pytest.importorskip("urdf_parser_py")

from clew_ros.spatial.robot import RobotModel, robot_from_parameters
from clew_ros.spatial.spheres import SphereModel, sphere_model

CONFIG = Path(__file__).resolve().parents[2] / "config"

PANDA = {
    "urdf": "robots/panda/panda.urdf",
    "srdf": "robots/panda/panda.srdf",
    "base_link": "panda_link0",
    "tip_link": "panda_hand_tcp",
}
PANDA_CAPSULES = {**PANDA, "urdf": "robots/panda/panda_capsules.urdf"}
UR5 = {"urdf": "robots/ur5/ur5.urdf", "srdf": "robots/ur5/ur5.srdf", "base_link": "base_link", "tip_link": "tool0"}


@pytest.fixture(scope="session")
def panda() -> RobotModel:
    return robot_from_parameters(PANDA, CONFIG)


@pytest.fixture(scope="session")
def panda_capsules() -> RobotModel:
    return robot_from_parameters(PANDA_CAPSULES, CONFIG)


@pytest.fixture(scope="session")
def ur5() -> RobotModel:
    return robot_from_parameters(UR5, CONFIG)


@pytest.fixture(scope="session")
def panda_spheres(panda: RobotModel) -> SphereModel:
    return sphere_model(panda)


@pytest.fixture(scope="session")
def ur5_spheres(ur5: RobotModel) -> SphereModel:
    return sphere_model(ur5)
