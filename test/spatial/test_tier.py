"""Validity decided on the exact geometry (interface.md section 1b, "Collision geometry"): the sphere models
settle what they can, coal decides the rest (clew_ros.spatial.tier, clew_ros.spatial.kernels.band)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("coal")
pytest.importorskip("pinocchio")

import coal

from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.exact import ExactChecker
from clew_ros.spatial.robot import RobotModel, robot_from_parameters
from clew_ros.spatial.scene import Obstacle
from clew_ros.spatial.spheres import SphereModel, SphereSettings, inner_cover
from clew_ros.spatial.straight import straight_samples_clear
from clew_ros.spatial.tier import link_shapes, robot_distance
from clew_ros.spatial.validate import ValidationSettings, validate_transit
from clew_ros.spatial.world import SpatialWorld
from clew_ros.worlds.spatial import generate_spatial

from .conftest import CONFIG, PANDA

# a Panda posture reaching forward, its hand well clear of the floor
REACH = np.array([0.3, 0.4, -0.2, -1.9, 0.1, 2.3, 0.6])


def wall_at(robot: RobotModel, q: np.ndarray, gap: float, normal: np.ndarray) -> Obstacle:
    """A 2 cm board facing the hand along ``normal`` (world), moved in until the robot's exact geometry at ``q``
    is ``gap`` m from it (``gap`` < 0: that deep inside it), by bisection on the coal distance."""
    tcp = robot.tcp_pose(q)[:3, 3]
    size = (0.02, 0.3, 0.3)
    rotation = np.eye(4)
    x = normal / np.linalg.norm(normal)
    y = np.cross(x, [0.0, 0.0, 1.0]) if abs(x[2]) < 0.9 else np.cross(x, [1.0, 0.0, 0.0])
    y /= np.linalg.norm(y)
    rotation[:3, :3] = np.stack([x, y, np.cross(x, y)], axis=1)

    def pose(offset: float) -> np.ndarray:
        out = rotation.copy()
        out[:3, 3] = tcp + offset * x
        return out

    low, high = 0.0, 0.5  # distance falls as the offset does
    for _ in range(60):
        middle = (low + high) / 2
        if robot_distance(robot, q, coal.Box(*size), pose(middle)) > max(gap, 0.0):
            high = middle
        else:
            low = middle
    return Obstacle("wall", "box", size, pose(high + min(gap, 0.0)))


def test_fingers_two_mm_from_a_wall_are_valid_one_mm_inside_are_not(
    panda: RobotModel, panda_spheres: SphereModel
) -> None:
    side = panda.tcp_pose(REACH)[:3, 1]  # the fingers close along the tcp's y
    near = wall_at(panda, REACH, 0.002, side)
    inside = wall_at(panda, REACH, -0.001, side)
    assert robot_distance(panda, REACH, coal.Box(*near.size), near.pose) == pytest.approx(0.002, abs=2e-5)
    spheres_alone = SpatialChecker(panda, panda_spheres, [near], exact=False)
    assert not spheres_alone.valid(REACH[None])[0], "the spheres reach past 2 mm: the exact geometry must decide"
    assert SpatialChecker(panda, panda_spheres, [near]).valid(REACH[None])[0]
    assert not SpatialChecker(panda, panda_spheres, [inside]).valid(REACH[None])[0]


def test_padding_grows_every_link(panda: RobotModel, panda_spheres: SphereModel) -> None:
    near = wall_at(panda, REACH, 0.002, panda.tcp_pose(REACH)[:3, 1])
    assert SpatialChecker(replace(panda, padding=0.001), panda_spheres, [near]).valid(REACH[None])[0]
    assert not SpatialChecker(replace(panda, padding=0.003), panda_spheres, [near]).valid(REACH[None])[0]


def test_padding_is_read_and_checked() -> None:
    robot = robot_from_parameters({**PANDA, "padding": 0.004}, CONFIG)
    assert robot.padding == 0.004
    with pytest.raises(ValueError, match=r"^world\.robot\.padding: expected a value in \[0\.0, 1\.0\], got -0\.01$"):
        robot_from_parameters({**PANDA, "padding": -0.01}, CONFIG)


def test_a_move_that_grazes_at_mid_step_is_refused(panda: RobotModel, panda_spheres: SphereModel) -> None:
    """Both ends 10+ cm clear, the middle 0.5 mm inside a wall: the straight move is refused by the planner's
    check and by the validator, naming the piece."""
    start, end = REACH.copy(), REACH.copy()
    start[0] -= 0.4
    end[0] += 0.4
    middle = (start + end) / 2
    down = np.array([0.0, 0.0, -1.0])  # the hand grazes a board under it
    board = wall_at(panda, middle, -0.0005, down)
    checker = SpatialChecker(panda, panda_spheres, [board])
    assert checker.valid(np.stack([start, end])).all()
    assert not checker.valid(middle[None])[0]
    settings = ValidationSettings()
    assert not straight_samples_clear(checker, start[None], end[None], coarse_every=8, settings=settings)[0]
    problems = validate_transit(checker, np.stack([start, end]))
    assert len(problems) == 1
    assert problems[0].startswith("piece 0")


def test_the_spheres_never_call_a_collision_free_and_the_tiers_agree_with_pinocchio() -> None:
    """Random configurations in generated worlds: the sphere model alone never calls free what collides on the
    exact geometry (pinocchio + coal, with its own kinematics), and the two tiers answer as it does."""
    checked = disagreements = sphere_misses = band = 0
    for robot_kind, seed in (("panda", 3), ("ur5", 4), ("random", 5)):
        world: SpatialWorld = generate_spatial("spatial_shelf", seed, robot_kind).world()
        reference = ExactChecker(world)
        rng = np.random.default_rng(seed)
        qs = rng.uniform(world.robot.lower, world.robot.upper, size=(300, world.robot.dof))
        truth = np.array([not reference.configuration_problem(q) for q in qs])
        alone = SpatialChecker(world.robot, world.spheres, world.obstacles, world.bounds, exact=False).valid(qs)
        tiers = world.checker.valid(qs)
        checked += len(qs)
        sphere_misses += int((alone & ~truth).sum())
        disagreements += int((tiers != truth).sum())
        band += int((truth & ~alone).sum())
    assert sphere_misses == 0
    assert disagreements == 0
    assert band > 0, "no configuration near a contact was drawn: the test would prove nothing"


def test_inner_spheres_lie_inside_the_geometry(panda: RobotModel, panda_spheres: SphereModel) -> None:
    inner = panda_spheres.inner
    assert inner is not None
    assert inner.count > 0
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    for i, (link, shapes) in enumerate(zip(panda.links, link_shapes(panda), strict=True)):
        for k in range(inner.starts[i], inner.starts[i + 1]):
            centre, radius = inner.centers[k], inner.radii[k]
            for shape, local in shapes:
                if not isinstance(shape, coal.BVHModelOBBRSS):
                    continue
                # the distance from the centre to the mesh's surface is at least the radius (meshes are
                # surfaces to coal), or the sphere belongs to another of the link's geometries
                result.clear()
                at = coal.Transform3s(np.eye(3), centre)
                coal.distance(
                    coal.Sphere(1e-9), at, shape, coal.Transform3s(local[:3, :3], local[:3, 3]), request, result
                )
                assert result.min_distance >= radius - 1e-6 or len(shapes) > 1, (link.name, k)
    for size in ((0.1, 0.04, 0.3), (0.02, 0.02, 0.02)):
        geometry = replace(panda.links[0].geometries[0], kind="box", size=size, origin=np.eye(4))
        centres, radii = inner_cover(geometry, SphereSettings())
        assert (np.abs(centres) + radii[:, None] <= np.asarray(size) / 2 + 1e-12).all()
    for size in ((0.3, 0.05), (0.02, 0.2)):
        geometry = replace(panda.links[0].geometries[0], kind="cylinder", size=size, origin=np.eye(4))
        centres, radii = inner_cover(geometry, SphereSettings())
        assert (np.hypot(centres[:, 0], centres[:, 1]) + radii <= size[1] + 1e-12).all()
        assert (np.abs(centres[:, 2]) + radii <= size[0] / 2 + 1e-12).all()


def test_free_intervals_near_a_contact_are_free_on_the_exact_geometry() -> None:
    """Rows the spheres refuse but the exact geometry accepts get intervals (sampled at 0.002 rad with the
    clearance that covers what lies between): every configuration drawn inside them is free on pinocchio's."""
    world = generate_spatial("spatial_shelf", 3, "panda").world()
    reference = ExactChecker(world)
    rng = np.random.default_rng(11)
    qs = rng.uniform(world.robot.lower, world.robot.upper, size=(1500, world.robot.dof))
    alone = SpatialChecker(world.robot, world.spheres, world.obstacles, world.bounds, exact=False)
    near = qs[world.checker.valid(qs) & ~alone.valid(qs)][:12]
    assert len(near) >= 5
    widths = []
    for joint in range(world.robot.dof):
        lo, hi, ok = world.checker.free_intervals(near, joint)
        assert ok.all()
        widths += (hi - lo).tolist()
        for q, a, b in zip(near, lo, hi, strict=True):
            for value in np.linspace(a, b, 25):
                row = q.copy()
                row[joint] = value
                assert not reference.configuration_problem(row), (joint, value)
    assert np.median(widths) > 0.01


def test_a_box_in_a_bin_a_centimetre_from_its_walls_is_taken_out(tmp_path: Path) -> None:
    """The Panda's table-to-table world with a bin around the box, its walls 1 cm from it: the spheres alone
    reach no grasp there; on the exact geometry the box is grasped, lifted out straight and set down at the
    goal, a plan the validator and pinocchio's exact check both accept."""
    import yaml

    from clew_ros.core.settings import PlannerSettings
    from clew_ros.planar.world import read_parameter_file
    from clew_ros.spatial.exact import exact_problems
    from clew_ros.spatial.offline import checked_plan
    from clew_ros.spatial.space import SpatialSpace, plan
    from clew_ros.spatial.world import spatial_world_from_parameters

    tree = read_parameter_file(CONFIG / "spatial" / "panda_table_to_table.yaml")
    world_tree = tree["world"]
    for key in ("urdf", "srdf"):
        world_tree["robot"][key] = str((CONFIG / "spatial" / world_tree["robot"][key]).resolve())
    x, y, half, gap, wall, top, height = 0.5, 0.3, 0.02, 0.01, 0.01, 0.12, 0.07
    out = half + gap + wall / 2
    walls = {
        "bin_n": ([2 * (half + gap + wall), wall, height], [x, y + out]),
        "bin_s": ([2 * (half + gap + wall), wall, height], [x, y - out]),
        "bin_e": ([wall, 2 * (half + gap), height], [x + out, y]),
        "bin_w": ([wall, 2 * (half + gap), height], [x - out, y]),
    }
    world_tree["obstacle_names"] = [*world_tree["obstacle_names"], *walls]
    for name, (size, (cx, cy)) in walls.items():
        world_tree["obstacles"][name] = {"shape": "box", "size": size, "pose": [cx, cy, top + height / 2, 0, 0, 0]}
    path = tmp_path / "bin.yaml"
    path.write_text(yaml.safe_dump({"clew_planner": {"ros__parameters": tree}}))
    world = spatial_world_from_parameters(read_parameter_file(path), tmp_path)
    result = plan(world, PlannerSettings(seed=0, time_limit=30.0))
    assert result.success, result.message
    assert checked_plan(world, result).code == "SUCCEEDED"
    assert exact_problems(world, result) == []
    transfer = result.segments[1]
    assert transfer.kind == "transfer"
    assert transfer.grasp is not None
    alone = SpatialSpace(replace(world, checker=replace_checker(world)))
    held = alone.transfer_checker(alone.grasp_rel(transfer.grasp))
    assert not held.valid(np.asarray(transfer.waypoints)).all(), "the spheres alone would refuse the lift"


def replace_checker(world: SpatialWorld) -> SpatialChecker:
    """``world``'s checker deciding on the spheres alone."""
    return SpatialChecker(world.robot, world.spheres, world.obstacles, world.bounds, exact=False)


def test_the_exact_reference_grows_the_links_by_the_padding(panda: RobotModel, panda_spheres: SphereModel) -> None:
    """pinocchio + coal's reference (clew_ros.spatial.exact) reads world.robot.padding as the planner does."""
    from clew_ros.spatial.transforms import matrix_pose
    from clew_ros.spatial.world import spatial_world_from_parameters

    near = wall_at(panda, REACH, 0.002, panda.tcp_pose(REACH)[:3, 1])
    tree = {
        "world": {
            "kind": "spatial",
            "robot": {**PANDA, "initial": REACH.tolist(), "goal": REACH.tolist()},
            "obstacle_names": ["wall"],
            "obstacles": {"wall": {"shape": "box", "size": list(near.size), "pose": matrix_pose(near.pose)}},
        }
    }
    for padding, collides in ((0.001, False), (0.003, True)):
        tree["world"]["robot"]["padding"] = padding
        world = spatial_world_from_parameters(tree, CONFIG)
        assert bool(ExactChecker(world).configuration_problem(REACH)) is collides
        assert bool(world.checker.valid(REACH[None])[0]) is not collides
