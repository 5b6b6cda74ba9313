"""The brute-force oracle of the free-interval tests: sweep one joint at 1 mrad with the contract's
validity test (shapely), which the compiled kernel never uses."""

from __future__ import annotations

import numpy as np

from clew_ros.planar.collision import is_valid
from clew_ros.planar.manhattan import MAX_MOVE_RAD

SWEEP = np.arange(-6.3, 6.3 + 1e-9, 1e-3)


def sweep_interval(world, q, joint, poses_of):
    """The valid interval around 0 found by testing every 1 mrad (joint limits included), within the
    full turn one move may make. ``poses_of(qs)`` gives the object's poses for configurations ``qs``."""
    qs = np.repeat(q[None], len(SWEEP), axis=0)
    qs[:, joint] += SWEEP
    ok = (qs[:, joint] >= world.robot.joint_lower[joint]) & (qs[:, joint] <= world.robot.joint_upper[joint])
    ok &= is_valid(world, qs, poses_of(qs))
    zero = int(np.argmin(np.abs(SWEEP)))
    assert ok[zero]
    bad = np.flatnonzero(~ok)
    low = bad[bad < zero].max() + 1 if (bad < zero).any() else 0
    high = bad[bad > zero].min() - 1 if (bad > zero).any() else len(SWEEP) - 1
    return max(SWEEP[low], -MAX_MOVE_RAD), min(SWEEP[high], MAX_MOVE_RAD)
