"""Straight joint-space moves checked where the plan validator checks them (its 0.002 rad samples)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.validate import ValidationSettings, validation_samples

__all__ = ["straight_samples_clear"]

Array = NDArray[np.float64]


def straight_samples_clear(
    checker: SpatialChecker,
    starts: Array,
    ends: Array,
    *,
    coarse_every: int,
    settings: ValidationSettings,
    refine: int = 2,
) -> NDArray[np.bool_]:
    """Whether each straight joint-space move ``starts[i] -> ends[i]`` is valid at every configuration the
    validator checks (steps of at most 0.002 rad per revolute joint, 0.001 m per prismatic one): first at
    every ``coarse_every``-th of those samples (cheap refusals), then at all of them; where two neighbouring
    samples lie near a contact (the sphere model does not clear both), ``refine - 1`` more between them (the
    middle), so
    that a move the validator accepts does not graze between its samples either (another planner's samples,
    or a part of the move, fall elsewhere)."""
    robot = checker.robot
    steps = np.where(robot.prismatic, settings.step_m, settings.step_rad)
    samples = [validation_samples(a, b, steps) for a, b in zip(starts, ends, strict=True)]
    clear = np.ones(len(samples), dtype=bool)
    near: list[NDArray[np.bool_]] = [np.zeros(0, dtype=bool)] * len(samples)
    for stride in (coarse_every, 1):
        pick = np.flatnonzero(clear)
        if not len(pick):
            break
        parts = [samples[i][::stride] if stride > 1 else samples[i] for i in pick]
        if stride > 1:
            parts = [np.vstack([p, samples[i][-1:]]) for p, i in zip(parts, pick, strict=True)]
        owners = np.repeat(pick, [len(p) for p in parts])
        valid, spheres = checker.valid_and_on_spheres(np.vstack(parts), groups=owners)
        bounds = np.cumsum([0, *(len(p) for p in parts)])
        for a, i in enumerate(pick):
            clear[i] = bool(valid[bounds[a] : bounds[a + 1]].all())
            near[i] = ~spheres[bounds[a] : bounds[a + 1]]
    pick = np.flatnonzero(clear)
    if refine > 1 and checker.exact and len(pick):
        # neighbouring samples either of which the spheres do not clear: refine - 1 more between them
        firsts = [np.flatnonzero(near[i][:-1] | near[i][1:]) for i in pick]
        owner = np.repeat(pick, [len(f) for f in firsts])
        if len(owner):
            lows = np.vstack([samples[i][f] for i, f in zip(pick, firsts, strict=True)])
            highs = np.vstack([samples[i][f + 1] for i, f in zip(pick, firsts, strict=True)])
            share = (np.arange(1, refine) / refine)[None, :, None]
            between = (lows[:, None, :] + share * (highs - lows)[:, None, :]).reshape(-1, robot.dof)
            valid, _ = checker.valid_and_on_spheres(between, groups=np.repeat(owner, refine - 1))
            fine = valid.reshape(len(lows), refine - 1).all(axis=1)
            clear[np.unique(owner[~fine])] = False
    return clear
