"""clew_ros.spatial.checker and its kernels: forward kinematics, distances, validity, free intervals."""

from __future__ import annotations

import math
import re
from dataclasses import replace

import numpy as np
import pytest

from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.kernels.collide import clearance_of_sphere
from clew_ros.spatial.robot import RobotModel
from clew_ros.spatial.scene import Obstacle, make_obstacle, obstacle_arrays
from clew_ros.spatial.spheres import SphereModel
from clew_ros.spatial.transforms import pose_matrix


def box(name: str, size: list[float], pose: list[float]) -> Obstacle:
    return make_obstacle(name, "box", size, pose_matrix(pose), f"world.obstacles.{name}")


def clutter(seed: int, count: int = 30) -> list[Obstacle]:
    """Boxes, cylinders and spheres around a Panda (none touching its base)."""
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < count:
        xyz = rng.uniform([-0.8, -0.8, 0.0], [0.8, 0.8, 1.1])
        if math.hypot(xyz[0], xyz[1]) < 0.3:
            continue
        shape = ["box", "cylinder", "sphere"][len(out) % 3]
        size = {"box": rng.uniform(0.04, 0.2, 3), "cylinder": rng.uniform(0.03, 0.15, 2), "sphere": [0.06]}[shape]
        pose = pose_matrix([*xyz, *rng.uniform(-math.pi, math.pi, 3)])
        out.append(make_obstacle(f"o{len(out)}", shape, size, pose, "world.obstacles"))
    return out


def test_compiled_forward_kinematics_matches_the_model(panda: RobotModel, panda_spheres: SphereModel) -> None:
    checker = SpatialChecker(panda, panda_spheres)
    rng = np.random.default_rng(0)
    for q in rng.uniform(panda.lower, panda.upper, size=(5, panda.dof)):
        frames = panda.frames(q)[panda_spheres.frames]
        expected = np.einsum("sij,sj->si", frames[:, :3, :3], panda_spheres.centers) + frames[:, :3, 3]
        np.testing.assert_allclose(checker.sphere_positions(q), expected, atol=1e-12)


@pytest.mark.parametrize("shape", ["box", "cylinder", "sphere"])
def test_sphere_obstacle_distance_agrees_with_dense_samples(shape: str) -> None:
    rng = np.random.default_rng(1)
    size = {"box": [0.3, 0.2, 0.1], "cylinder": [0.3, 0.1], "sphere": [0.12]}[shape]
    obstacle = make_obstacle("o", shape, size, pose_matrix([0.1, -0.2, 0.3, 0.4, -0.5, 0.6]), "o")
    packed = obstacle_arrays([obstacle])
    # the obstacle's solid, sampled on a fine grid in its own frame
    if shape == "box":
        half = np.array(size) / 2
    elif shape == "cylinder":
        half = np.array([size[1], size[1], size[0] / 2])
    else:
        half = np.array([size[0]] * 3)
    grid = np.stack(np.meshgrid(*[np.linspace(-h, h, 41) for h in half], indexing="ij"), -1).reshape(-1, 3)
    if shape == "cylinder":
        grid = grid[np.hypot(grid[:, 0], grid[:, 1]) <= size[1]]
    if shape == "sphere":
        grid = grid[np.linalg.norm(grid, axis=1) <= size[0]]
    solid = grid @ obstacle.pose[:3, :3].T + obstacle.pose[:3, 3]
    spacing = 2 * max(half) / 40 * math.sqrt(3)
    for _ in range(200):
        center = obstacle.pose[:3, 3] + rng.uniform(-0.35, 0.35, 3)
        radius = float(rng.uniform(0.01, 0.1))
        signed = clearance_of_sphere(
            center, radius, packed["obs_kind"][0], packed["obs_r"][0], packed["obs_t"][0], packed["obs_dims"][0]
        )
        nearest = float(np.linalg.norm(solid - center, axis=1).min()) - radius
        if nearest > 0.0:  # outside the solid: the exact distance, within the grid's spacing
            assert signed == pytest.approx(nearest, abs=spacing)
        else:
            assert signed <= spacing


def test_validity_obstacles_limits_bounds(panda: RobotModel, panda_spheres: SphereModel) -> None:
    q = np.array([[0.0, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8]])
    tcp = panda.tcp_pose(q[0])[:3, 3]
    assert SpatialChecker(panda, panda_spheres).valid(q).tolist() == [True]
    assert SpatialChecker(panda, panda_spheres, [box("at_tcp", [0.05] * 3, [*tcp, 0, 0, 0])]).valid(q).tolist() == [
        False
    ]
    far = [box("far", [0.05] * 3, [2.0, 2.0, 2.0, 0, 0, 0])]
    assert SpatialChecker(panda, panda_spheres, far).valid(q).tolist() == [True]
    outside = q.copy()
    outside[0, 3] = 0.0  # above joint 4's upper limit (-0.0698)
    assert SpatialChecker(panda, panda_spheres).valid(outside).tolist() == [False]
    roomy = np.array([-1.5, -1.5, -0.5, 1.5, 1.5, 1.5])
    assert SpatialChecker(panda, panda_spheres, bounds=roomy).valid(q).tolist() == [True]
    low_ceiling = roomy.copy()
    low_ceiling[5] = tcp[2] + 0.05
    assert SpatialChecker(panda, panda_spheres, bounds=low_ceiling).valid(q).tolist() == [False]


def test_a_table_touching_the_base_makes_every_configuration_invalid(
    panda: RobotModel, panda_spheres: SphereModel
) -> None:
    table = box("table", [1.0, 1.0, 0.04], [0.0, 0.0, -0.01, 0, 0, 0])
    checker = SpatialChecker(panda, panda_spheres, [table])
    assert checker.static_collision
    assert not checker.valid(np.zeros((3, panda.dof)) + (panda.lower + panda.upper) / 2).any()


def test_self_collision_folds(panda: RobotModel, panda_spheres: SphereModel) -> None:
    checker = SpatialChecker(panda, panda_spheres)
    rng = np.random.default_rng(2)
    qs = rng.uniform(panda.lower, panda.upper, size=(2000, panda.dof))
    valid = checker.valid(qs)
    # a random Panda configuration folds onto itself now and then, but not mostly
    assert 0.02 < 1 - valid.mean() < 0.5
    # with every pair exempted, the same configurations are all valid
    assert SpatialChecker(panda, panda_spheres, self_collision=False).valid(qs).all()


def test_bad_batches_are_refused(panda: RobotModel, panda_spheres: SphereModel) -> None:
    checker = SpatialChecker(panda, panda_spheres)
    with pytest.raises(ValueError, match=re.escape("qs: expected an (N, 7) array")):
        checker.valid(np.zeros((3, 6)))
    with pytest.raises(ValueError, match=re.escape("joint: expected 0..6")):
        checker.free_intervals(np.zeros((1, 7)), 7)


def test_free_intervals_are_free_at_two_milliradians(panda: RobotModel, panda_spheres: SphereModel) -> None:
    checker = SpatialChecker(panda, panda_spheres, clutter(3))
    rng = np.random.default_rng(4)
    qs = rng.uniform(panda.lower, panda.upper, size=(400, panda.dof))
    qs = qs[checker.valid(qs)][:40]
    assert len(qs) >= 20
    widths = []
    for joint in range(panda.dof):
        lo, hi, ok = checker.free_intervals(qs, joint)
        assert ok.all()
        assert np.all((panda.lower[joint] <= lo) & (lo <= qs[:, joint]) & (qs[:, joint] <= hi))
        assert np.all(hi <= panda.upper[joint])
        widths.extend(hi - lo)
        for b in range(len(qs)):
            values = np.append(np.arange(lo[b], hi[b], 0.002), hi[b])
            moved = np.repeat(qs[b][None], len(values), axis=0)
            moved[:, joint] = values
            assert checker.valid(moved).all(), (joint, b)
    assert np.mean(widths) > 0.3  # the intervals are of use, not a point each


def test_free_interval_of_an_invalid_configuration_is_its_point(panda: RobotModel, panda_spheres: SphereModel) -> None:
    q = np.array([[0.0, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8]])
    tcp = panda.tcp_pose(q[0])[:3, 3]
    checker = SpatialChecker(panda, panda_spheres, [box("at_tcp", [0.05] * 3, [*tcp, 0, 0, 0])])
    lo, hi, ok = checker.free_intervals(q, 2)
    assert (lo[0], hi[0], ok[0]) == (q[0, 2], q[0, 2], False)


def test_an_interval_stops_before_an_obstacle(panda: RobotModel, panda_spheres: SphereModel) -> None:
    q = np.array([[0.0, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8]])
    tcp = panda.tcp_pose(q[0])[:3, 3]
    # a post beside the hand: turning joint 1 (about z) one way hits it, the other way is open to the limit
    angle = math.atan2(tcp[1], tcp[0]) + 0.6
    radius = math.hypot(tcp[0], tcp[1])
    post = make_obstacle(
        "post",
        "cylinder",
        [2.0, 0.03],
        pose_matrix([radius * math.cos(angle), radius * math.sin(angle), 1.0, 0, 0, 0]),
        "p",
    )
    lo, hi, ok = SpatialChecker(panda, panda_spheres, [post]).free_intervals(q, 0)
    assert ok[0]
    assert 0.05 < hi[0] < 0.6
    assert lo[0] == panda.lower[0]


def test_the_resting_object_blocks_every_link_but_the_gripper(panda: RobotModel, panda_spheres: SphereModel) -> None:
    q = np.array([[0.0, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8]])
    tcp = panda.tcp_pose(q[0])
    held = make_obstacle("object", "box", [0.03, 0.03, 0.03], tcp, "world.object")
    gripper = replace(panda, gripper_links=("panda_hand", "panda_leftfinger", "panda_rightfinger"))
    assert SpatialChecker(gripper, panda_spheres, resting_object=held).valid(q).tolist() == [True]
    assert SpatialChecker(panda, panda_spheres, resting_object=held).valid(q).tolist() == [False]
    elbow = panda.link_poses(q[0])["panda_link4"]
    at_elbow = make_obstacle("object", "box", [0.03, 0.03, 0.03], elbow, "world.object")
    assert SpatialChecker(gripper, panda_spheres, resting_object=at_elbow).valid(q).tolist() == [False]
    # the intervals follow the same rule: free for the gripper around the object, sampled at 2 mrad
    checker = SpatialChecker(gripper, panda_spheres, clutter(3)[:10], resting_object=held)
    for joint in range(panda.dof):
        lo, hi, ok = checker.free_intervals(q, joint)
        assert ok[0]
        values = np.append(np.arange(lo[0], hi[0], 0.002), hi[0])
        moved = np.repeat(q, len(values), axis=0)
        moved[:, joint] = values
        assert checker.valid(moved).all()
        if joint == 6:  # the last joint turns the hand about the object: nothing but the gripper is near
            assert hi[0] - lo[0] > 1.0
