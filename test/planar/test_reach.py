"""The reach bounds are necessary conditions: they refuse only what no arm pose can do."""

from pathlib import Path

import numpy as np

from clew_ros.planar.kinematics import compose, relative, tip_poses
from clew_ros.planar.reach import goal_within_reach, within_reach
from clew_ros.planar.world import load_world

CONFIG = Path(__file__).resolve().parents[2] / "config"


def test_within_reach_is_the_annulus_the_links_sweep():
    world = load_world(CONFIG / "figure1.yaml")
    lengths = world.robot.link_lengths
    base = world.robot.base
    outer = float(lengths.sum())
    inner = max(0.0, 2.0 * float(lengths.max()) - outer)
    direction = np.array([np.cos(0.3), np.sin(0.3)])
    assert within_reach(world, base + 0.999 * outer * direction)
    assert not within_reach(world, base + 1.001 * outer * direction)
    assert within_reach(world, base + 1.001 * outer * direction, slack=0.01 * outer)
    if inner > 0:
        assert not within_reach(world, base + 0.5 * inner * direction)


def test_every_tip_the_arm_reaches_is_within_reach():
    world = load_world(CONFIG / "arm3_regrasp.yaml")
    rng = np.random.default_rng(0)
    q = rng.uniform(-np.pi, np.pi, size=(500, world.robot.dof))
    tips = tip_poses(world.robot, q)[:, :2]
    assert all(within_reach(world, tip, slack=1e-9) for tip in tips)


def test_goal_within_reach_accepts_poses_the_arm_can_hold_and_refuses_far_ones():
    world = load_world(CONFIG / "figure1.yaml")
    rng = np.random.default_rng(1)
    grasp_rel = relative(np.zeros(3), np.array([0.02, 0.0, 0.0]))  # object just beyond the tip
    q = rng.uniform(-np.pi, np.pi, size=(200, world.robot.dof))
    held = compose(tip_poses(world.robot, q), grasp_rel)
    assert all(goal_within_reach(world, grasp_rel, pose) for pose in held)
    far = world.robot.base + 3.0 * float(world.robot.link_lengths.sum())
    assert not goal_within_reach(world, grasp_rel, np.array([far[0], far[1], 0.0]))


def test_approach_cells_keep_every_angle_the_arm_holds_a_grasp_with():
    from clew_ros.planar.kinematics import wrap_angle
    from clew_ros.planar.reach import REACH, approach_cells

    cells_count = REACH.approach_cells

    world = load_world(CONFIG / "arm3_regrasp.yaml")
    rng = np.random.default_rng(2)
    grasp = 0
    point = world.object.grasps[grasp]
    refused = 0
    for _ in range(300):
        q = rng.uniform(-np.pi, np.pi, world.robot.dof)
        tip = tip_poses(world.robot, q[None])[0]
        psi = rng.uniform(-np.pi, np.pi)  # the last link's direction in the object frame
        theta = tip[2] - psi
        c, s = np.cos(theta), np.sin(theta)
        pose = np.array([tip[0] - c * point[0] + s * point[1], tip[1] - s * point[0] - c * point[1], theta])
        cells = approach_cells(world, pose, grasp)
        cell = int(np.floor(wrap_angle(np.array([psi]))[0] % (2 * np.pi) / (2 * np.pi) * cells_count))
        assert cells[cell % cells_count], (q, psi)
        # with a spread, nearby orientations of the object keep the cell too
        assert approach_cells(world, pose + np.array([0.0, 0.0, 0.2]), grasp, angle_spread=0.25)[cell % cells_count]
        refused += int(np.sum(~cells))
    assert refused > 0, "the bound should refuse some approach angles"


def test_two_link_grasps_finds_the_configuration_that_holds_a_grasp():
    from clew_ros.planar.collision import is_valid
    from clew_ros.planar.kinematics import transform_points
    from clew_ros.planar.reach import two_link_grasps

    world = load_world(CONFIG / "figure1.yaml")
    rng = np.random.default_rng(4)
    grasp = 1
    point = world.object.grasps[grasp]
    found = empty = 0
    for _ in range(200):
        q = rng.uniform(world.robot.joint_lower, world.robot.joint_upper)
        tip = tip_poses(world.robot, q[None])[0]
        theta = rng.uniform(-np.pi, np.pi)
        c, s = np.cos(theta), np.sin(theta)
        pose = np.array([tip[0] - c * point[0] + s * point[1], tip[1] - s * point[0] - c * point[1], theta])
        holds = two_link_grasps(world, pose, grasp)
        target = transform_points(pose, point[None])[0]
        assert np.all(
            np.linalg.norm(tip_poses(world.robot, holds)[:, :2] - target, axis=1) <= 0.5 * world.grasp_tolerance + 1e-9
        )
        if len(holds):
            assert is_valid(world, holds, pose[None]).all()
            found += 1
        if is_valid(world, q[None], pose[None])[0]:
            assert len(holds), (q, pose)  # a valid holding configuration exists: never refused
        else:
            empty += int(not len(holds))
    assert found > 0
    assert empty > 0


def test_approach_excess_is_zero_in_allowed_cells_and_grows_outside():
    from clew_ros.planar.reach import REACH, approach_excess

    cells_count = REACH.approach_cells

    cells = np.zeros(cells_count, bool)
    cells[: cells_count // 4] = True  # psi in [0, pi/2)
    excess = approach_excess(cells)
    assert np.allclose(excess(np.array([0.1, 0.7, 1.4])), 0.0)
    far = excess(np.array([np.pi / 2 + 0.2, np.pi / 2 + 0.5, -0.3]))
    np.testing.assert_allclose(far, [0.2, 0.5, 0.3], atol=2 * np.pi / cells_count)


def test_carry_cells_keep_every_approach_that_holds_the_object_there():
    from clew_ros.planar.reach import REACH, carry_cells

    cells_count = REACH.approach_cells

    world = load_world(CONFIG / "figure1.yaml")
    rng = np.random.default_rng(5)
    refused = 0
    for grasp, point in enumerate(world.object.grasps):
        for _ in range(200):
            q = rng.uniform(-np.pi, np.pi, world.robot.dof)
            tip = tip_poses(world.robot, q[None])[0]
            psi = rng.uniform(0.0, 2.0 * np.pi)
            theta = tip[2] - psi
            c, s = np.cos(theta), np.sin(theta)
            pose = np.array([tip[0] - c * point[0] + s * point[1], tip[1] - s * point[0] - c * point[1], theta])
            cells = carry_cells(world, pose, grasp)
            assert cells[int(psi / (2.0 * np.pi) * cells_count) % cells_count], (grasp, q, psi)
            refused += int(np.sum(~cells))
    # figure1's goal lies beyond the bare arm's reach: only in-line approaches carry the bar there
    goal_cells = carry_cells(world, world.object.goal, 1)
    assert 0 < goal_cells.sum() < cells_count / 2


def test_holding_configurations_hold_the_grasp_within_the_limits_and_validly():
    from clew_ros.planar.collision import is_valid
    from clew_ros.planar.kinematics import joint_positions, transform_points
    from clew_ros.planar.reach import holding_configurations

    for name in ("arm3_regrasp", "arm5_regrasp"):
        world = load_world(CONFIG / f"{name}.yaml")
        pose = world.object.initial
        found_any = False
        for grasp in range(len(world.object.grasps)):
            holds = holding_configurations(world, pose, grasp)
            again = holding_configurations(world, pose, grasp)
            np.testing.assert_array_equal(holds, again)  # the same request, the same answer
            if not len(holds):
                continue
            found_any = True
            target = transform_points(pose, world.object.grasps[grasp][None])[0]
            tips = joint_positions(world.robot, holds)[:, -1]
            assert np.all(np.linalg.norm(tips - target, axis=1) <= 0.5 * world.grasp_tolerance)
            assert np.all((holds >= world.robot.joint_lower) & (holds <= world.robot.joint_upper))
            assert is_valid(world, holds, pose[None]).all()
        assert found_any, name


def test_holding_configurations_are_empty_beyond_reach():
    import dataclasses

    from clew_ros.planar.reach import holding_configurations

    world = load_world(CONFIG / "arm3_regrasp.yaml")
    far = np.array([world.robot.reach + 0.5, 0.0, 0.0]) + np.r_[world.robot.base, 0.0]
    bounds = np.array([-5.0, -5.0, 5.0, 5.0])
    world = dataclasses.replace(world, bounds=bounds)
    assert len(holding_configurations(world, far, 0)) == 0


def test_goal_approach_core_keeps_the_approaches_most_goal_holds_use():
    from benchmarks.worlds import obstacles_world
    from clew_ros.planar.collision import is_valid
    from clew_ros.planar.inverse import solve_point
    from clew_ros.planar.reach import REACH, approach_cell, carry_cells, goal_approach_core

    cells_count = REACH.approach_cells
    from clew_ros.planar.world import world_from_parameters

    # obstacles_32: the bar's goal lies 2.03 m from the base of a 1.7 m arm; held by an end, only approaches
    # within about 47 degrees of in line can carry it there, and the nearly straight arm has room only near 0
    world = world_from_parameters(obstacles_world(32).parameters)
    goal, grasp = world.object.goal, 0
    core = goal_approach_core(world, goal, grasp)
    assert core is not None
    np.testing.assert_array_equal(core, goal_approach_core(world, goal, grasp))  # the same request, the same answer
    bound = carry_cells(world, goal, grasp)
    assert not np.any(core & ~bound)  # every core approach can carry the object there
    assert 0 < core.sum() < bound.sum() / 2
    # an approach outside the core that still holds the goal validly: possible, but not where holds crowd
    psi = np.radians(40.0)
    assert not core[approach_cell(psi)]
    theta = np.linspace(-np.pi, np.pi, 721)
    point = world.object.grasps[grasp]
    c, s = np.cos(theta), np.sin(theta)
    targets = np.column_stack([goal[0] + c * point[0] - s * point[1], goal[1] + s * point[0] + c * point[1]])
    seeds = np.random.default_rng(3).uniform(world.robot.joint_lower, world.robot.joint_upper, (len(theta), 3))
    solved = solve_point(world.robot, seeds, targets, angles=theta + psi, angle_tolerance=0.0, tolerance_m=1e-6)
    poses = np.column_stack([np.broadcast_to(goal[:2], (len(theta), 2)), theta])
    holds = (solved.error <= 1e-4) & is_valid(world, solved.q, poses)
    assert holds.any()
    assert len(core) == cells_count


def test_goal_approach_core_is_none_when_nothing_holds_the_goal():
    import dataclasses

    from clew_ros.planar.reach import goal_approach_core

    world = load_world(CONFIG / "arm3_regrasp.yaml")
    world = dataclasses.replace(world, bounds=np.array([-5.0, -5.0, 5.0, 5.0]))
    far = np.array([world.robot.reach + 1.0, 0.0, 0.0]) + np.r_[world.robot.base, 0.0]
    assert goal_approach_core(world, far, 0) is None


def test_goal_approach_core_windows_wrap_around_and_zero_is_no_smoothing():
    from clew_ros.planar import reach

    world = load_world(CONFIG / "figure1.yaml")
    goal = world.object.goal
    wide = reach.goal_approach_core(world, goal, 0)
    assert wide is not None
    assert wide.shape == (reach.REACH.approach_cells,)
    # the bar taken by its (-0.4, 0) end in line with the last link: psi = 0, where the cells wrap around
    assert wide[0]
    assert wide[-1]
    unsmoothed = reach.ReachSettings(goal_core_window_rad=0.0)
    narrow = reach.goal_approach_core(world, goal, 0, settings=unsmoothed)
    assert narrow is not None
    assert narrow.shape == (reach.REACH.approach_cells,)
    assert 0 < narrow.sum() < wide.sum()
    turned = goal.copy()
    turned[0] = -0.0  # the same goal: the same sample
    np.testing.assert_array_equal(reach.goal_approach_core(world, turned, 0, settings=unsmoothed), narrow)


def test_a_planar_tunings_reach_settings_reach_the_transits_holding_configurations(monkeypatch):
    """PlanarTuning.reach is what SEARCH_TRANSIT's holds are solved with (a benchmark varies a copy, not the
    module's defaults): the 2-joint rings' points and the solver's iterations of arms of more joints."""
    import dataclasses

    from clew_ros.core.settings import PlannerSettings
    from clew_ros.planar import search
    from clew_ros.planar.reach import ReachSettings, holding_configurations, two_link_grasps
    from clew_ros.planar.space import PlanarTuning, plan

    asked: list[tuple[str, int]] = []

    def rings(*args, probes, **kwargs):
        asked.append(("probes", probes))
        return two_link_grasps(*args, probes=probes, **kwargs)

    def sampled(*args, iterations, **kwargs):
        asked.append(("iterations", iterations))
        return holding_configurations(*args, iterations=iterations, **kwargs)

    monkeypatch.setattr(search, "two_link_grasps", rings)
    monkeypatch.setattr(search, "holding_configurations", sampled)
    tuning = PlanarTuning(reach=dataclasses.replace(ReachSettings(), two_link_probes=5, hold_iterations=31))
    for name in ("figure1", "arm3_regrasp"):  # 2 joints, then 3
        result = plan(load_world(CONFIG / f"{name}.yaml"), PlannerSettings(seed=0, improve_time=0.0), tuning=tuning)
        assert result.success, result.message
    assert ("probes", 5) in asked
    assert ("iterations", 31) in asked
    assert set(asked) == {("probes", 5), ("iterations", 31)}  # never the module's defaults
