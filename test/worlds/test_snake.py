"""The ``snake`` family: hyper-redundant arms (15-40 links; equal, decreasing and random lengths; loose
and tight limits) carrying a bar from a shelf into a slot. Every variant, a few seeds: the world is what
the variant says, and its witness (two transfers) is valid at 0.002 rad in the world as a user reads it."""

from __future__ import annotations

import numpy as np
import pytest

from clew_ros.planar.collision import check_start_and_goal
from clew_ros.planar.plan import validate_plan
from clew_ros.planar.world import world_from_parameters
from clew_ros.worlds import FAMILIES, generate
from clew_ros.worlds.snake import DECREASE, REACH_M, VARIANTS, variant_of

#: Two seeds of each of the six variants (seed % 6 picks the variant).
SEEDS = (0, 1, 2, 3, 4, 5, 7, 8, 10, 11, 13, 14)


def test_every_variant_is_covered() -> None:
    assert {variant_of(seed) for seed in SEEDS} == set(VARIANTS)
    assert len(VARIANTS) == 6
    assert min(FAMILIES["snake"].joints) == 15
    assert max(FAMILIES["snake"].joints) == 40


@pytest.mark.parametrize("seed", SEEDS)
def test_the_witness_is_valid_in_the_world_as_read(seed: int) -> None:
    generated = generate("snake", seed)
    world = check_start_and_goal(world_from_parameters(generated.parameters))
    variant = variant_of(seed)
    lengths = world.robot.link_lengths
    assert 15 <= world.robot.dof <= 40
    assert abs(lengths.sum() - REACH_M) < 0.01
    if variant.lengths == "equal":
        assert np.ptp(lengths) <= 2e-4
    elif variant.lengths == "decreasing":
        ideal = DECREASE ** np.arange(len(lengths))
        assert np.abs(lengths - REACH_M * ideal / ideal.sum()).max() <= 5.1e-5  # on the 0.1 mm grid
        assert lengths[-1] < 0.02  # the last links are centimetres or millimetres long
    inner = world.robot.joint_upper[1:]
    assert (inner <= 0.7).all() if variant.limits == "tight" else (inner >= 2.2).all()
    witness = generated.witness
    assert witness.success
    assert witness.grasp_count == 2
    assert validate_plan(world, witness, step_rad=0.002) == []
    assert len(world.obstacles) == 6  # the shelf's three walls and the slot's
    start, goal = world.object.initial, world.object.goal
    assert np.hypot(*(goal[:2] - start[:2])) >= 1.0  # from one side of the arm to the other
