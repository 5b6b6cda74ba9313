"""Manhattan paths and the bouncing technique (paper 1.3.1 and 1.3.3).

A Manhattan path of order ``k`` for an ``n``-joint arm is coded as a real vector
``(k, n)``: "move joint 1 by x_1, then joint 2 by x_2, ..." repeated ``k``
times. Before each move the free interval ``[dmin, dmax]`` of the moving joint
is computed given the moves before it, and the gene is folded into that
interval by a triangular wave (:func:`bounce`). Every real vector therefore
codes a collision-free path. A space decodes a whole population's paths at
once (:meth:`clew_ros.core.space.Space.manhattan`); this module holds the
coding's shared parts.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Counters", "ManhattanPaths", "bounce"]


@dataclass
class Counters:
    """Work done, for stats and benchmarks."""

    clearance_checks: int = 0  # free intervals computed (one per configuration and joint move)
    evaluations: int = 0  # genetic-algorithm individuals evaluated


@dataclass
class ManhattanPaths:
    """Decoded Manhattan paths of a batch."""

    waypoints: np.ndarray  # (B, k * n + 1, n)
    object_poses: np.ndarray  # (B, p): where the object ends

    @property
    def final(self) -> np.ndarray:
        return self.waypoints[:, -1]


def bounce(x: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """Fold ``x`` into ``[low, high]`` with a triangular wave of period ``2 (high - low)``.

    Values inside the interval map to themselves; outside, they bounce off its
    ends. An empty interval (``low == high``) maps everything to ``low``.

    >>> bounce(np.array([0.5, 1.5, -0.25, 2.5]), np.zeros(4), np.ones(4)).tolist()
    [0.5, 0.5, 0.25, 0.5]
    """
    x, low, high = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in (x, low, high)))
    width = high - low
    period = np.where(width > 0.0, 2.0 * width, 1.0)
    u = (x - low) - period * np.floor((x - low) / period)
    folded = np.clip(low + np.where(u <= width, u, period - u), low, high)
    out: np.ndarray = np.where(width > 0.0, folded, low)
    return out
