"""Free intervals against brute-force sweeps; bouncing; decoded paths are valid."""

import itertools
from pathlib import Path

import numpy as np
import pytest
from helpers.sweep import sweep_interval

from clew_ros.core.manhattan import bounce
from clew_ros.planar.collision import is_valid
from clew_ros.planar.kinematics import compose, tip_poses
from clew_ros.planar.manhattan import free_intervals, run_manhattan
from clew_ros.planar.plan import CHECK_STEP_RAD
from clew_ros.planar.world import load_world

CONFIG = Path(__file__).resolve().parents[2] / "config"


@pytest.mark.parametrize("name", ["single_transfer", "arm3_regrasp"])
@pytest.mark.parametrize("mode", ["transit", "transfer"])
def test_free_intervals_match_brute_force(name, mode):
    world = load_world(CONFIG / f"{name}.yaml")
    rng = np.random.default_rng(7)
    # carried in line beyond the tip, just clear of it
    rel = np.array([float(world.object.polygon[:, 0].max()) + 0.02, 0.0, 0.0])
    checked = 0
    for _ in range(5000):
        if checked == 4:
            break
        q = rng.uniform(world.robot.joint_lower, world.robot.joint_upper)
        if mode == "transit":
            poses_of = lambda qs: world.object.initial  # noqa: E731
            kwargs = {"object_poses": world.object.initial[None]}
        else:
            poses_of = lambda qs: compose(tip_poses(world.robot, qs), rel)  # noqa: E731
            kwargs = {"grasp_rel": rel[None]}
        if not is_valid(world, q[None], poses_of(q[None]))[0]:
            continue
        checked += 1
        for joint in range(world.robot.dof):
            low, high = free_intervals(world, q[None], joint, margin_m=0.0, **kwargs)
            brute_low, brute_high = sweep_interval(world, q, joint, poses_of)
            assert low[0] == pytest.approx(brute_low, abs=2e-3)
            assert high[0] == pytest.approx(brute_high, abs=2e-3)
    assert checked == 4


def test_margin_shrinks_the_interval():
    world = load_world(CONFIG / "single_transfer.yaml")
    q = np.array([[0.3, 0.2]])
    exact = free_intervals(world, q, 0, object_poses=world.object.initial[None], margin_m=0.0)
    kept = free_intervals(world, q, 0, object_poses=world.object.initial[None], margin_m=0.05)
    assert kept[1][0] < exact[1][0]
    assert kept[0][0] > exact[0][0]


def test_bounce_lands_inside_the_interval():
    rng = np.random.default_rng(1)
    low = -rng.uniform(0, 3, 10000)
    high = rng.uniform(0, 3, 10000)
    low[:100] = 0.0
    high[:100] = 0.0
    x = rng.normal(0, 20, 10000)
    y = bounce(x, low, high)
    assert np.all(y >= low)
    assert np.all(y <= high)
    inside = (x >= low) & (x <= high)
    np.testing.assert_allclose(y[inside], x[inside])


def test_the_compiled_bounce_is_the_coding_of_core_manhattan():
    """The decoding kernel folds genes exactly as :func:`clew_ros.core.manhattan.bounce` says."""
    from clew_ros.planar.kernel import bounce_array

    rng = np.random.default_rng(3)
    low = -rng.uniform(0.0, 2.0, 500)
    high = rng.uniform(0.0, 2.0, 500)
    high[:50] = low[:50]  # empty intervals
    x = rng.normal(0.0, 5.0, 500)
    np.testing.assert_allclose(bounce(x, low, high), bounce_array(x, low, high), rtol=0, atol=1e-12)


def test_bounce_is_a_triangle_wave():
    low, high = np.array([-1.0]), np.array([2.0])
    # period 6: x and x + 6 agree, and the wave reflects at the ends
    for x in (-4.0, -1.5, 0.3, 2.5, 7.0):
        assert bounce(np.array([x]), low, high)[0] == pytest.approx(bounce(np.array([x + 6.0]), low, high)[0])
    assert bounce(np.array([2.5]), low, high)[0] == pytest.approx(1.5)
    assert bounce(np.array([-1.5]), low, high)[0] == pytest.approx(-0.5)


@pytest.mark.parametrize("name", ["figure1", "arm5_regrasp"])
def test_every_decoded_path_is_valid_at_the_checking_step(name):
    world = load_world(CONFIG / f"{name}.yaml")
    rng = np.random.default_rng(5)
    n = world.robot.dof
    genes = rng.normal(0, 3, (16, 2, n))
    paths = run_manhattan(world, world.robot.initial, genes, object_poses=world.object.initial[None])
    moved = 0
    for waypoints in paths.waypoints:
        for a, b in itertools.pairwise(waypoints):
            steps = max(1, int(np.ceil(np.abs(b - a).max() / CHECK_STEP_RAD)))
            qs = a + np.linspace(0, 1, steps + 1)[:, None] * (b - a)
            assert is_valid(world, qs, world.object.initial).all()
            moved += np.abs(b - a).max() > 1e-6
    assert moved > 20  # the genes really moved the arm
