"""Arms of the generated worlds: planar chains of 2 to 10 links with joint limits.

Link lengths decrease from the base outwards (with some noise) and add up to the arm's reach; joint 1
turns all the way round or nearly, the other joints have limits between 1.8 and 2.8 rad, sometimes
asymmetric; some arms have capsule links (``link_width`` > 0). Lengths are on a millimetre grid and
limits on a 0.01 rad grid, so the parameter file holds short numbers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ArmShape", "make_arm"]

#: ``joint_1``'s limits when it turns all the way round (the config worlds' value, just inside pi).
FULL_TURN_RAD = 3.14159


@dataclass(frozen=True, eq=False)
class ArmShape:
    """A chain: ``link_lengths`` (n,) m, ``joint_lower`` / ``joint_upper`` (n,) rad, ``link_width`` m."""

    link_lengths: np.ndarray
    joint_lower: np.ndarray
    joint_upper: np.ndarray
    link_width: float

    @property
    def reach(self) -> float:
        """Sum of the link lengths (m)."""
        return float(self.link_lengths.sum())


def make_arm(rng: np.random.Generator, joints: int, reach_m: tuple[float, float] = (1.5, 2.0)) -> ArmShape:
    """An arm of ``joints`` links whose reach is drawn from ``reach_m`` (m), drawn from ``rng``."""
    reach = float(rng.uniform(*reach_m))
    weights = np.linspace(1.0, 0.6, joints) * rng.uniform(0.85, 1.15, joints)
    lengths = np.round(reach * weights / weights.sum(), 3)
    upper = np.round(rng.uniform(1.8, 2.8, joints), 2)
    lower = np.where(rng.random(joints) < 0.3, -np.round(rng.uniform(1.8, 2.8, joints), 2), -upper)
    if rng.random() < 0.7:
        lower[0], upper[0] = -FULL_TURN_RAD, FULL_TURN_RAD
    else:
        upper[0] = round(float(rng.uniform(2.4, 3.1)), 2)
        lower[0] = -upper[0]
    width = 0.0 if rng.random() < 0.5 else round(float(rng.uniform(0.02, 0.05)), 3)
    return ArmShape(lengths, lower, upper, width)
