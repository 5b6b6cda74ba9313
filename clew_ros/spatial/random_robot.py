"""Random serial arms as URDF text, so tests and benchmarks are never tuned to one robot.

:func:`random_robot_urdf` draws, from a :class:`numpy.random.Generator`, a chain ``base_link`` ->
``link_1`` ... ``link_n`` -> ``tool`` of ``n`` revolute joints (``joint_1`` ... ``joint_n``; ``n`` in
:attr:`RandomRobotSettings.joints`): each joint's axis a random unit vector, its origin a random
rotation and a random offset (a link length) from the previous one, its limits a random range. Every link
carries collision geometry along the segment from its own joint to the next one (the base: up to the first
joint; the last link: up to ``tool``, a fixed frame, the tcp): a capsule (a cylinder and a sphere at
each end), a box or a cylinder, of random thickness. The same generator state gives the same bytes.
:func:`random_robot` loads the text with :func:`~clew_ros.spatial.robot.load_robot`.

Links are longer than the thickest geometry's reach from the joint axis on both sides, so links that are
not neighbours never overlap merely by sharing a joint; whether a configuration folds a link into another
is left to the checker, as for any arm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from clew_ros.spatial.robot import RobotModel, load_robot

__all__ = ["BASE_LINK", "TIP_LINK", "RandomRobotSettings", "random_robot", "random_robot_urdf"]

#: The generated chain's root link and its tip (the tcp: ``tool`` at its origin).
BASE_LINK, TIP_LINK = "base_link", "tool"

_SHAPES = ("capsule", "box", "cylinder")


@dataclass(frozen=True)
class RandomRobotSettings:
    """The ranges the parts of a random arm are drawn from (uniformly)."""

    #: Planned (revolute) joints: fewer than 6 cannot reach every orientation, more are redundant.
    joints: tuple[int, int] = (4, 8)
    #: Distance between consecutive joints (m): about a real arm's links (a UR5's are 0.09-0.43 m). The
    #: lower end stays above twice the thickest geometry's reach (see ``radius_m``).
    length_m: tuple[float, float] = (0.15, 0.4)
    #: Half thickness of each link's geometry (m): a capsule's or cylinder's radius, a box's half side
    #: (its corner reaches sqrt(2) times this from the segment).
    radius_m: tuple[float, float] = (0.015, 0.045)
    #: Height of the first joint above the base's origin (m).
    base_height_m: tuple[float, float] = (0.05, 0.25)
    #: Half width of each joint's range (rad), around a centre drawn in ``limit_center_rad``.
    limit_half_width_rad: tuple[float, float] = (1.0, math.pi)
    #: Centre of each joint's range (rad): ranges are not all symmetric about 0.
    limit_center_rad: tuple[float, float] = (-0.5, 0.5)
    #: The last three joints a wrist (``joints`` from 6): their axes z, y and z of their own frames, each
    #: the next one's offset along its own z (in line, as a Panda's or a UR5's wrist nearly is), the tool
    #: beyond the last, their lengths the shortest ``length_m`` allows (+ 5 cm), their ranges a full turn (pi
    #: either side of a centre): the tool reaches an object from above and from the side alike.
    wrist: bool = False

    def __post_init__(self) -> None:
        for name in (
            "joints", "length_m", "radius_m", "base_height_m", "limit_half_width_rad", "limit_center_rad",
        ):  # fmt: skip
            low, high = getattr(self, name)
            if not (math.isfinite(low) and math.isfinite(high) and low <= high):
                raise ValueError(
                    f"RandomRobotSettings.{name}: expected (low, high) with low <= high, got {(low, high)}"
                )
        if self.joints[0] < 1 or not all(isinstance(v, int) for v in self.joints):
            raise ValueError(f"RandomRobotSettings.joints: expected whole numbers >= 1, got {self.joints}")
        for name in ("length_m", "radius_m", "base_height_m", "limit_half_width_rad"):
            if getattr(self, name)[0] <= 0:
                raise ValueError(f"RandomRobotSettings.{name}: expected positive values, got {getattr(self, name)}")
        if self.wrist and self.joints[0] < 6:
            raise ValueError(f"RandomRobotSettings.joints: a wrist needs 6 joints or more, got {self.joints}")
        if self.length_m[0] <= 2 * math.sqrt(2) * self.radius_m[1]:
            raise ValueError(
                "RandomRobotSettings.length_m: expected the shortest link longer than twice the thickest "
                f"geometry's reach (2 sqrt(2) x {self.radius_m[1]} m), got {self.length_m[0]} m"
            )


def _number(value: float) -> str:
    return f"{value:.9g}"


def _numbers(values: np.ndarray | list[float]) -> str:
    return " ".join(_number(float(v)) for v in values)


def _unit(rng: np.random.Generator) -> np.ndarray:
    while True:
        v = rng.normal(size=3)
        norm = float(np.linalg.norm(v))
        if norm > 1e-6:
            return v / norm


def _collisions(rng: np.random.Generator, offset: np.ndarray, settings: RandomRobotSettings) -> list[str]:
    """The ``<collision>`` elements along the segment from the link's origin to ``offset`` (its next joint)."""
    length = float(np.linalg.norm(offset))
    direction = offset / length
    # Rz(yaw) Ry(pitch) takes z onto the direction
    pitch = math.acos(max(-1.0, min(1.0, float(direction[2]))))
    yaw = math.atan2(float(direction[1]), float(direction[0]))
    middle = f'<origin xyz="{_numbers(offset / 2)}" rpy="0 {_number(pitch)} {_number(yaw)}"/>'
    shape = _SHAPES[int(rng.integers(len(_SHAPES)))]
    if shape == "box":
        size = [*(2 * rng.uniform(*settings.radius_m, size=2)), length]
        return [f'<collision>{middle}<geometry><box size="{_numbers(size)}"/></geometry></collision>']
    radius = float(rng.uniform(*settings.radius_m))
    cylinder = f'<cylinder radius="{_number(radius)}" length="{_number(length)}"/>'
    out = [f"<collision>{middle}<geometry>{cylinder}</geometry></collision>"]
    if shape == "capsule":
        sphere = f'<geometry><sphere radius="{_number(radius)}"/></geometry>'
        out += [
            f'<collision><origin xyz="{_numbers(end)}" rpy="0 0 0"/>{sphere}</collision>'
            for end in (np.zeros(3), offset)
        ]
    return out


def random_robot_urdf(
    rng: np.random.Generator, settings: RandomRobotSettings | None = None, name: str = "random_arm"
) -> str:
    """The URDF text of a random serial arm (see the module docstring); same generator state, same bytes."""
    settings = settings or RandomRobotSettings()
    n = int(rng.integers(settings.joints[0], settings.joints[1] + 1))
    # joint k (1..n) sits at offsets[k - 1] in the previous link's frame; tool at offsets[n] in link_n's
    offsets = [np.array([0.0, 0.0, rng.uniform(*settings.base_height_m)])]
    wrist = n - 3 if settings.wrist else n  # joints wrist + 1 .. n: the wrist
    offsets += [_unit(rng) * rng.uniform(*settings.length_m) for _ in range(wrist)]
    short = (settings.length_m[0], settings.length_m[0] + 0.05)
    offsets += [np.array([0.0, 0.0, rng.uniform(*short)]) for _ in range(n - wrist)]
    links = [BASE_LINK] + [f"link_{k}" for k in range(1, n + 1)]
    parts = [f'<?xml version="1.0"?>\n<robot name={quoteattr(name)}>']
    for k, link in enumerate(links):
        collisions = "".join(_collisions(rng, offsets[k], settings))
        parts.append(f"  <link name={quoteattr(link)}>{collisions}</link>")
    parts.append(f"  <link name={quoteattr(TIP_LINK)}/>")
    for k in range(1, n + 1):
        rpy = rng.uniform(-math.pi, math.pi, size=3) if k <= wrist + 1 else np.zeros(3)
        center = float(rng.uniform(*settings.limit_center_rad))
        half = float(rng.uniform(*settings.limit_half_width_rad)) if k <= wrist else math.pi
        axis = _unit(rng) if k <= wrist else np.array([0.0, float(k == wrist + 2), float(k != wrist + 2)])
        parts.append(
            f'  <joint name="joint_{k}" type="revolute"><parent link={quoteattr(links[k - 1])}/>'
            f'<child link={quoteattr(links[k])}/><origin xyz="{_numbers(offsets[k - 1])}" rpy="{_numbers(rpy)}"/>'
            f'<axis xyz="{_numbers(axis)}"/>'
            f'<limit lower="{_number(center - half)}" upper="{_number(center + half)}" effort="10" velocity="1"/>'
            "</joint>"
        )
    parts.append(
        f'  <joint name="tool_joint" type="fixed"><parent link={quoteattr(links[n])}/>'
        f'<child link={quoteattr(TIP_LINK)}/><origin xyz="{_numbers(offsets[n])}" rpy="0 0 0"/></joint>'
    )
    parts.append("</robot>\n")
    return "\n".join(parts)


def random_robot(rng: np.random.Generator, settings: RandomRobotSettings | None = None) -> RobotModel:
    """A random arm (:func:`random_robot_urdf`) loaded as a :class:`~clew_ros.spatial.robot.RobotModel`
    from ``base_link`` to ``tool``."""
    text = random_robot_urdf(rng, settings)
    return load_robot(text, folder=Path.cwd(), base_link=BASE_LINK, tip_link=TIP_LINK, source="random_robot")
