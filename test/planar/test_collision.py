"""The validity test of interface.md section 1."""

import copy
from pathlib import Path

import numpy as np
import pytest

from clew_ros.planar.collision import explain_invalid, is_valid
from clew_ros.planar.world import load_world, read_parameter_file, world_from_parameters

CONFIG = Path(__file__).resolve().parents[2] / "config"


def world(**robot_changes):
    tree = copy.deepcopy(read_parameter_file(CONFIG / "single_transfer.yaml"))
    tree["world"]["robot"].update(robot_changes)
    return world_from_parameters(tree)


def test_touching_an_obstacle_counts_as_collision():
    w = world()
    # right_block starts at x = 1.15; a straight arm of reach 2.0 along +x crosses it, one of reach 1.15 touches it
    touching = world(link_lengths=[1.0, 0.15], initial=[0.0, 0.0])
    assert not is_valid(touching, np.zeros((1, 2)), touching.object.initial)[0]
    short = world(link_lengths=[1.0, 0.149], initial=[0.0, 0.0])
    assert is_valid(short, np.zeros((1, 2)), short.object.initial)[0]
    assert "link 2 hits obstacle 'right_block'" in explain_invalid(w, np.zeros(2), w.object.initial)


def test_link_width_makes_capsules():
    thin = world(link_lengths=[1.0, 0.1], initial=[0.0, 0.0])
    wide = world(link_lengths=[1.0, 0.1], initial=[0.0, 0.0], link_width=0.2)
    assert is_valid(thin, np.zeros((1, 2)), thin.object.initial)[0]
    assert not is_valid(wide, np.zeros((1, 2)), wide.object.initial)[0]


def test_bounds_are_closed():
    w = world(link_lengths=[1.2, 1.0])
    # straight up: tip at y = 2.2 = ymax, touching the edge is inside
    q = np.array([[np.pi / 2, 0.0]])
    assert is_valid(w, q, w.object.initial)[0]
    longer = world(link_lengths=[1.2, 1.001])
    assert not is_valid(longer, q, longer.object.initial)[0]
    assert "leaves world.bounds" in explain_invalid(longer, q[0], longer.object.initial)


def test_self_collision_of_non_adjacent_links():
    tree = copy.deepcopy(read_parameter_file(CONFIG / "arm3_regrasp.yaml"))
    w = world_from_parameters(tree)
    folded = np.array([[0.0, 2.7, 2.7]])  # link 3 folds back across link 1
    assert not is_valid(w, folded, w.object.initial)[0]
    assert "self-collision" in explain_invalid(w, folded[0], w.object.initial)
    tree["world"]["robot"]["self_collision"] = False
    w_free = world_from_parameters(tree)
    assert is_valid(w_free, folded, w_free.object.initial)[0]


def test_link_may_touch_the_object_but_not_go_deeper_than_the_tolerance():
    w = world(initial=[0.0, 0.0])
    obj = w.object
    # put the resting object so that its lower edge centre is exactly at the tip of a straight arm along +y
    q = np.array([[np.pi / 2, 0.0]])
    tip_y = 2.0
    half_height = float(obj.polygon[:, 1].max())
    touching = np.array([0.0, tip_y + half_height, 0.0])
    inside_by_half_tol = touching - [0.0, w.grasp_tolerance / 2, 0.0]
    inside_by_twice_tol = touching - [0.0, 2 * w.grasp_tolerance, 0.0]
    w_big = world_from_parameters(_with_bounds(3.0))
    assert is_valid(w_big, q, touching)[0]
    assert is_valid(w_big, q, inside_by_half_tol)[0]
    assert not is_valid(w_big, q, inside_by_twice_tol)[0]


def _with_bounds(extent):
    tree = copy.deepcopy(read_parameter_file(CONFIG / "single_transfer.yaml"))
    tree["world"]["bounds"] = [-extent, -extent, extent, extent]
    tree["world"]["robot"]["initial"] = [0.0, 0.0]
    return tree


def test_batch_matches_single_explanations():
    w = world()
    rng = np.random.default_rng(3)
    q = rng.uniform(-3, 3, (300, 2))
    batch = is_valid(w, q, w.object.initial)
    singles = [explain_invalid(w, c, w.object.initial) is None for c in q]
    assert batch.tolist() == singles
    assert 0 < batch.sum() < len(q)


@pytest.mark.parametrize("name", ["figure1", "arm3_regrasp", "arm5_regrasp", "unreachable"])
def test_broad_phase_never_changes_the_answer(name):
    # the batched test skips shapely where bounding boxes cannot meet: it must agree with the
    # per-configuration explanation everywhere, object poses included (near links and obstacles)
    w = load_world(CONFIG / f"{name}.yaml")
    rng = np.random.default_rng(11)
    n = 400
    q = rng.uniform(w.robot.joint_lower, w.robot.joint_upper, (n, w.robot.dof))
    xmin, ymin, xmax, ymax = w.bounds
    poses = np.column_stack([rng.uniform(xmin, xmax, n), rng.uniform(ymin, ymax, n), rng.uniform(-np.pi, np.pi, n)])
    poses[: n // 2] = w.object.initial
    batch = is_valid(w, q, poses)
    singles = [explain_invalid(w, c, p) is None for c, p in zip(q, poses, strict=False)]
    assert batch.tolist() == singles
    assert 0 < batch.sum() < n


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_compiled_first_pass_never_clears_an_invalid_configuration_in_clutter(seed):
    # objects carried among many boxes (the first pass skips an obstacle whose box is apart from the
    # object's): a configuration it clears is valid by the exact test, and it clears most valid ones
    from helpers.random_boxes import random_boxes

    from clew_ros.planar.collision import packed_world
    from clew_ros.planar.kernel import clearly_valid

    rng = np.random.default_rng(seed)
    boxes = random_boxes(rng, 24, clear_radius=0.5)
    polygon = [0.0, 0.0, 0.3, 0.0, 0.3, 0.06, 0.1, 0.06, 0.1, 0.2, 0.0, 0.2]  # an L: not convex
    tree = {
        "name": f"clutter_{seed}",
        "bounds": [-2.5, -2.5, 2.5, 2.5],
        "robot": {
            "base": [0.0, 0.0],
            "link_lengths": [0.7, 0.6, 0.4],
            "link_width": 0.03,
            "joint_lower": [-3.0] * 3,
            "joint_upper": [3.0] * 3,
            "initial": [0.0] * 3,
        },
        "obstacle_names": list(boxes),
        "obstacles": boxes,
        "object": {"polygon": polygon, "initial": [0.0, 0.3, 0.0], "goal": [0.0, 0.3, 0.0], "grasps": [0, 0]},
    }
    w = world_from_parameters({"world": tree})
    n = 3000
    q = rng.uniform(-3.0, 3.0, (n, 3))
    poses = np.column_stack([rng.uniform(-2.2, 2.2, (n, 2)), rng.uniform(-np.pi, np.pi, n)])
    cleared = clearly_valid(packed_world(w), q, poses)
    exact = is_valid(w, q, poses)
    assert not np.any(cleared & ~exact)
    assert cleared.sum() >= 0.9 * exact.sum()
    assert 50 < exact.sum() < n - 50
