"""The quick world of the recording tests and one plan for it, computed once per process.

``test/worlds/rec_quick.yaml`` is small on purpose (2-link arm, no obstacles,
the object a short hop from its goal) so the core plans it in about a second.
"""

from __future__ import annotations

import functools
from pathlib import Path

WORLD_PATH = Path(__file__).resolve().parents[1] / "worlds" / "rec_quick.yaml"
TIME_LIMIT_S = 20.0


@functools.lru_cache(maxsize=1)
def quick_world():
    from clew_ros.planar.world import load_world

    return load_world(WORLD_PATH)


@functools.lru_cache(maxsize=1)
def quick_plan() -> dict:
    """A successful plan for the quick world, as its plan file holds it (a dict); raises if the core finds none."""
    from clew_ros.core.plan import Plan
    from clew_ros.core.settings import PlannerSettings
    from clew_ros.planar.kernel import warm_up
    from clew_ros.planar.space import plan

    world = quick_world()
    warm_up()  # the kernels compiled (a minute on a loaded machine without numba's cache) before the clock starts
    result = plan(world, PlannerSettings(seed=0, time_limit=TIME_LIMIT_S))
    if not result.success:
        raise RuntimeError(f"the core found no plan for {WORLD_PATH.name}: {result.message}")
    return Plan.from_result(world, result).to_dict()
