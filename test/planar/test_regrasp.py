"""Proposals of other grasps and release placements (clew_ros/planar/regrasp.py): every key configuration
holds what it should and is valid, the travel is what the moves add up to, the ways along a move are
as long as the straight one, and the same generator gives the same proposals."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from clew_ros.planar.collision import is_valid
from clew_ros.planar.kinematics import compose, relative, tip_poses, transform_points
from clew_ros.planar.regrasp import ROUTES, ProposalLimits, RegraspSettings, propose, route_waypoints
from clew_ros.planar.search import goal_reached
from clew_ros.planar.world import load_world

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("joints", [2, 3, 6])
def test_every_way_along_a_move_is_as_long_as_the_straight_one(joints: int) -> None:
    rng = np.random.default_rng(joints)
    for _ in range(20):
        a, b = rng.uniform(-3.0, 3.0, (2, joints))
        for route in range(len(ROUTES)):
            path = route_waypoints(a, b, route)
            assert np.array_equal(path[0], a)
            assert np.array_equal(path[-1], b)
            assert np.abs(np.diff(path, axis=0)).sum() == pytest.approx(np.abs(b - a).sum(), abs=1e-12)
            steps = np.diff(path, axis=0)
            assert np.all(steps * np.sign(b - a) >= -1e-15)  # every joint moves one way only


@pytest.mark.parametrize("name", ["figure1", "arm3_regrasp"])
def test_proposals_hold_their_grasps_end_at_the_goal_and_are_valid(name: str) -> None:
    world = load_world(ROOT / "config" / f"{name}.yaml")
    goal = np.asarray(world.object.goal, dtype=float)
    proposals, effort = propose(
        world, world.robot.initial, world.object.initial, goal, np.random.default_rng(3), margin_m=5e-4
    )
    assert proposals
    assert effort.checks > 0
    assert effort.steps > 0
    assert any(len(p.grasps) == 2 for p in proposals)
    for proposal in proposals:
        keys = proposal.keys
        assert len(keys) == 2 * len(proposal.grasps) + 1
        assert np.array_equal(keys[0], world.robot.initial)
        assert proposal.travel == pytest.approx(np.abs(np.diff(keys, axis=0)).sum(), abs=1e-9)
        assert proposal.blocked == sum(route < 0 for route in proposal.routes)
        pose = np.asarray(world.object.initial, dtype=float)
        for step, grasp in enumerate(proposal.grasps):
            hold, end = keys[2 * step + 1], keys[2 * step + 2]
            point = transform_points(pose, world.object.grasps[grasp][None])[0]
            assert np.linalg.norm(tip_poses(world.robot, hold[None])[0, :2] - point) <= 1e-9
            assert is_valid(world, hold[None], pose)[0]
            grasp_rel = relative(tip_poses(world.robot, hold[None])[0], pose)
            pose = compose(tip_poses(world.robot, end[None]), grasp_rel)[0]
            assert is_valid(world, end[None], pose)[0]
        assert goal_reached(world, pose, goal)
    ranks = [p.travel + 8.0 * p.blocked for p in proposals]
    assert ranks == sorted(ranks)
    for k, later in enumerate(proposals):  # no two alike: other grasps, or a key configuration moved
        for earlier in proposals[:k]:
            assert (
                earlier.grasps != later.grasps
                or np.max(np.abs(earlier.keys - later.keys)) > RegraspSettings().distinct_rad
            )


def _proposed_from_start(family: str, seed: int):
    """A generated world, its goal and the proposals from its start (generator 0, margin 0.5 mm)."""
    from clew_ros.worlds import generate

    world = generate(family, seed).world()
    goal = np.asarray(world.object.goal, dtype=float)
    proposals, _ = propose(
        world, world.robot.initial, world.object.initial, goal, np.random.default_rng(0), margin_m=5e-4
    )
    return world, goal, proposals


def _end_pose(world, proposal) -> np.ndarray:
    """Where a proposal leaves the object: its key configurations replayed from the object's start, each
    grasp keeping the object where the configuration holding it found it."""
    pose = np.asarray(world.object.initial, dtype=float)
    for step in range(len(proposal.grasps)):
        hold, end = proposal.keys[2 * step + 1], proposal.keys[2 * step + 2]
        grasp_rel = relative(tip_poses(world.robot, hold[None])[0], pose)
        pose = compose(tip_poses(world.robot, end[None]), grasp_rel)[0]
    return pose


def test_proposals_end_within_a_narrow_goal_angle_tolerance_itself() -> None:
    """regrasp2 seed 40's goal allows 0.1 rad: the inverse kinematics' error (position plus the radius times the
    angle's excess over 0.8 of it) let through goal configurations 0.103 rad off, so every improved plan ended
    off the goal and the first plan was returned unchanged."""
    world, goal, proposals = _proposed_from_start("regrasp2", 40)
    assert proposals
    for proposal in proposals:
        assert goal_reached(world, _end_pose(world, proposal), goal)


def test_grasps_behind_the_base_are_proposed_whichever_way_round_the_arm_starts() -> None:
    """shapes2 seed 50: every grasp point lies behind the base, beyond joint 1's limit from the start; once no
    grasp configuration was found there, so a plan that took the object down once on the way kept its regrasp
    (11.4-13.8 rad, where one transfer of 5.27 rad does)."""
    world, goal, proposals = _proposed_from_start("shapes2", 50)
    one = [p for p in proposals if len(p.grasps) == 1]
    assert one
    assert min(p.travel for p in one) < 6.0
    for proposal in one:  # carried from behind the base onto the goal
        assert goal_reached(world, _end_pose(world, proposal), goal)


def test_a_two_joint_arm_carries_a_grasp_onto_the_edge_of_a_narrow_goal() -> None:
    """shapes2 seed 60 (goal angle tolerance 0.5 rad): the one grasp a single transfer can use reaches the goal
    only 0.49 rad and about a centimetre off it; the goal's inverse kinematics used a quarter of the position's
    tolerance and kept a fifth of the angle's to spare, so no one-transfer proposal was made and every plan kept a
    regrasp (7.43 rad; the grid reference carries the object once in 5.84). Its second pass uses nearly all of
    both, and every proposal still ends within the goal's tolerances."""
    world, goal, proposals = _proposed_from_start("shapes2", 60)
    one = [p for p in proposals if len(p.grasps) == 1]
    assert one
    assert min(p.travel for p in one) < 6.5
    for proposal in proposals:
        assert goal_reached(world, _end_pose(world, proposal), goal)


@pytest.mark.parametrize(("name", "one", "two"), [("single_transfer", True, False), ("arm3_regrasp", False, True)])
def test_proposals_come_with_the_transfers_asked_for(name: str, one: bool, two: bool) -> None:
    world = load_world(ROOT / "config" / f"{name}.yaml")
    goal = np.asarray(world.object.goal, dtype=float)
    proposals, _ = propose(
        world,
        world.robot.initial,
        world.object.initial,
        goal,
        np.random.default_rng(3),
        one_transfer=one,
        two_transfers=two,
    )
    assert proposals
    assert {len(p.grasps) for p in proposals} == {1 if one else 2}


def test_the_same_generator_gives_the_same_proposals() -> None:
    world = load_world(ROOT / "config" / "figure1.yaml")
    goal = np.asarray(world.object.goal, dtype=float)
    runs = [
        propose(world, world.robot.initial, world.object.initial, goal, np.random.default_rng(7))[0] for _ in range(2)
    ]
    assert len(runs[0]) == len(runs[1])
    for a, b in zip(*runs, strict=True):
        assert a.grasps == b.grasps
        assert np.array_equal(a.keys, b.keys)


def test_a_stop_request_ends_the_proposals_early() -> None:
    world = load_world(ROOT / "config" / "figure1.yaml")
    goal = np.asarray(world.object.goal, dtype=float)
    _, effort = propose(world, world.robot.initial, world.object.initial, goal, np.random.default_rng(1))
    cut, less = propose(
        world,
        world.robot.initial,
        world.object.initial,
        goal,
        np.random.default_rng(1),
        limits=ProposalLimits(should_stop=lambda: True),
    )
    assert less.checks < effort.checks
    assert all(len(p.grasps) == 1 for p in cut)  # stopped before the two-transfer search


def test_inverse_kinematics_counts_against_the_checks_allowed() -> None:
    # each step counts step_checks checks: with the same allowance, fewer configurations get checked
    world = load_world(ROOT / "config" / "arm3_regrasp.yaml")
    goal = np.asarray(world.object.goal, dtype=float)
    args = (world, world.robot.initial, world.object.initial, goal)
    _, free = propose(*args, np.random.default_rng(1), limits=ProposalLimits(max_checks=5000))
    _, counted = propose(*args, np.random.default_rng(1), limits=ProposalLimits(max_checks=5000, step_checks=0.5))
    assert counted.checks + 0.5 * counted.steps < free.checks + 0.5 * free.steps
    assert counted.checks < free.checks


@pytest.mark.parametrize(("family", "seed"), [("shelves", 1), ("arm7", 0), ("clutter", 1)])
def test_goal_aligned_grasps_hold_the_placement_with_an_approach_that_holds_the_goal(family: str, seed: int) -> None:
    # a rigid grasp keeps its approach while carried: each grasp configuration at the start comes with a
    # configuration at the goal, and carrying the object from one to the other puts it on the goal. These
    # worlds' witnesses carry the object from its start to the goal with one grasp, so some grasp can.
    from clew_ros.planar.regrasp import _aligned_at, _goal_holds
    from clew_ros.planar.regrasp_keys import Kinematics
    from clew_ros.worlds import generate

    generated = generate(family, seed)
    world = generated.world()
    start = np.asarray(world.robot.initial, dtype=float)
    placement = np.asarray(world.object.initial, dtype=float)
    goal = np.asarray(world.object.goal, dtype=float)
    finals = np.asarray(generated.witness.segments[-1].waypoints[-1], dtype=float)[None]
    kinematics = Kinematics(world, 5e-4)
    holds = _goal_holds(kinematics, start, goal, finals=finals, rng=np.random.default_rng(0))
    aligned = _aligned_at(kinematics, start, placement, holds)
    assert aligned
    for grasp, hold, at_goal in aligned:
        point = transform_points(placement, world.object.grasps[grasp][None])[0]
        assert np.linalg.norm(tip_poses(world.robot, hold[None])[0, :2] - point) <= 1e-9
        assert is_valid(world, hold[None], placement)[0]
        grasp_rel = relative(tip_poses(world.robot, hold[None])[0], placement)
        carried = compose(tip_poses(world.robot, at_goal[None]), grasp_rel)[0]
        assert np.linalg.norm(carried[:2] - goal[:2]) <= 1e-6
        assert abs(np.angle(np.exp(1j * (carried[2] - goal[2])))) <= 1e-6
        assert is_valid(world, at_goal[None], carried)[0]


def test_a_two_joint_arm_gets_no_goal_aligned_grasps() -> None:
    # it holds a placement in at most two ways (the two elbows), which propose tries anyway
    from clew_ros.planar.regrasp import _goal_holds
    from clew_ros.planar.regrasp_keys import Kinematics

    world = load_world(ROOT / "config" / "figure1.yaml")
    rng = np.random.default_rng(0)
    state = rng.bit_generator.state
    start, goal = world.robot.initial, np.asarray(world.object.goal, float)
    assert len(_goal_holds(Kinematics(world, 0.0), start, goal, finals=np.zeros((0, 2)), rng=rng).grasps) == 0
    assert rng.bit_generator.state == state  # nothing drawn: no goal-aligned grasps for two joints


def test_a_two_joint_arms_own_grasp_configurations_cost_no_inverse_kinematics() -> None:
    # they are proposed as they are, and no restart is drawn around them: with or without them, the grasp
    # configurations take the same work
    from clew_ros.planar.regrasp import _grasp_configurations
    from clew_ros.planar.regrasp_keys import Kinematics

    world = load_world(ROOT / "config" / "figure1.yaml")
    start = np.asarray(world.robot.initial, dtype=float)
    placement = np.asarray(world.object.initial, dtype=float)
    own = [(0, start + 0.1), (1, start - 0.1)]
    efforts = []
    for mine in ([], own):
        kinematics = Kinematics(world, 0.0)
        _grasp_configurations(kinematics, start, placement, mine, np.random.default_rng(0))
        efforts.append(kinematics.effort)
    assert efforts[0].steps > 0
    assert efforts[1] == efforts[0]


def test_a_restart_in_place_of_a_seeds_colliding_solution_starts_two_transfer_proposals() -> None:
    # the two-transfer proposals start only from each seed's (the start's and its mirror image's) grasp
    # configuration, not from the restarts' besides it; on arm3_regrasp grasp 1's solutions from both seeds
    # collide at the start placement and only a restart's is valid: it takes the seed's place, so every
    # grasp with a valid configuration keeps one (at most one per seed) for the two-transfer proposals
    from clew_ros.core.settings import PlannerSettings
    from clew_ros.planar.continuous import ContinuousSettings
    from clew_ros.planar.inverse import mirrored
    from clew_ros.planar.regrasp import _grasp_configurations
    from clew_ros.planar.regrasp_keys import Kinematics, directions

    world = load_world(ROOT / "config" / "arm3_regrasp.yaml")
    start = np.asarray(world.robot.initial, dtype=float)
    placement = np.asarray(world.object.initial, dtype=float)
    kinematics = Kinematics(world, ContinuousSettings().min_margin_factor * PlannerSettings().clearance)
    target = transform_points(placement, world.object.grasps[1:2])
    seeds = np.vstack([start, mirrored(world.robot, start[None], directions(world, target))])
    _, own = kinematics.holding(np.vstack([placement, placement]), np.array([1, 1]), seeds)
    assert not own.any()  # the premise: grasp 1's solutions from the start and its mirror image collide
    for seed in range(3):
        first, grasps, drawn = _grasp_configurations(kinematics, start, placement, [], np.random.default_rng(seed))
        assert drawn.any()  # restarts besides a valid solution of their seed stay out of them
        assert set(grasps[~drawn].tolist()) == set(grasps.tolist())
        assert np.bincount(grasps[~drawn]).max() <= 2
        assert 1 in grasps.tolist()
        assert is_valid(world, first, placement).all()


def _aligned_setup(family: str, seed: int):
    from clew_ros.planar.regrasp import _aligned_at, _goal_holds
    from clew_ros.planar.regrasp_keys import Kinematics
    from clew_ros.worlds import generate

    generated = generate(family, seed)
    world = generated.world()
    kinematics = Kinematics(world, 5e-4)
    start = np.asarray(world.robot.initial, dtype=float)
    placement = np.asarray(world.object.initial, dtype=float)
    goal = np.asarray(world.object.goal, dtype=float)
    finals = np.asarray(generated.witness.segments[-1].waypoints[-1], dtype=float)[None]
    holds = _goal_holds(kinematics, start, goal, finals=finals, rng=np.random.default_rng(0))
    return world, kinematics, start, placement, goal, holds, _aligned_at(kinematics, start, placement, holds)


def test_an_aligned_grasp_keeps_its_goal_seed_when_the_plan_holds_the_same_configuration() -> None:
    # the plan's own grasp configurations come first and duplicates are dropped: the row kept must still
    # seed the goal's inverse kinematics with the aligned grasp's goal configuration
    from clew_ros.planar.regrasp import _grasps_at_start

    _, kinematics, start, placement, _, _, aligned = _aligned_setup("shelves", 1)
    assert aligned
    own = [(grasp, hold.copy()) for grasp, hold, _ in aligned]
    begin = _grasps_at_start(kinematics, start, placement, own, aligned, rng=np.random.default_rng(0))
    assert begin is not None
    for _, hold, at_goal in aligned:
        row = int(np.argmin(np.max(np.abs(begin.first - hold), axis=1)))
        assert np.array_equal(begin.first[row], hold)
        assert np.array_equal(begin.goal_seeds[row], at_goal)


def test_regrasps_aligned_at_releases_carry_the_object_onto_the_goal() -> None:
    from clew_ros.planar.regrasp import _and_aligned

    world, kinematics, _, placement, goal, holds, aligned = _aligned_setup("arm7", 0)
    release = np.array([hold for _, hold, _ in aligned])  # the object resting where it is
    placements = np.repeat(placement[None], len(release), axis=0)
    n = world.robot.dof
    none = (np.zeros(0, dtype=int), np.zeros(0, dtype=int), np.zeros((0, n)), np.zeros((0, n)))
    rows, grasps, regrasps, goal_seeds = _and_aligned(
        kinematics, placements, release, np.arange(len(release)), holds=holds.first_per_grasp(), regrasps=none
    )
    assert len(rows) == len(grasps) == len(regrasps) == len(goal_seeds) > 0
    for row, grasp, hold, at_goal in zip(rows, grasps, regrasps, goal_seeds, strict=True):
        point = transform_points(placements[row], world.object.grasps[grasp][None])[0]
        assert np.linalg.norm(tip_poses(world.robot, hold[None])[0, :2] - point) <= 1e-9
        carried = compose(
            tip_poses(world.robot, at_goal[None]), relative(tip_poses(world.robot, hold[None])[0], placements[row])
        )[0]
        assert np.linalg.norm(carried[:2] - goal[:2]) <= 1e-6


def test_restarts_add_valid_grasp_configurations_nearer_the_seed_on_a_redundant_arm() -> None:
    # a ten-joint arm's inverse kinematics from its start folds into collisions or ends far away: solutions
    # from seeds drawn around it are added when valid and nearer
    from clew_ros.planar.regrasp_keys import Kinematics
    from clew_ros.worlds import generate

    world = generate("arm10", 0).world()
    kinematics = Kinematics(world, 5e-4)
    placement = np.asarray(world.object.initial, dtype=float)
    grasps = np.arange(len(world.object.grasps))
    seeds = np.repeat(np.asarray(world.robot.initial, dtype=float)[None], len(grasps), axis=0)
    placements = np.repeat(placement[None], len(grasps), axis=0)

    def holding(rows: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return kinematics.holding(placements[rows], grasps[rows], q)

    own, own_ok = holding(np.arange(len(grasps)), seeds)
    steps = kinematics.effort.steps
    rows, solved, ok = kinematics.restarted(holding, seeds, np.random.default_rng(0))
    assert np.array_equal(rows[: len(grasps)], np.arange(len(grasps)))  # every seed's own solution first
    assert np.array_equal(solved[: len(grasps)], own)
    assert np.array_equal(ok[: len(grasps)], own_ok)
    added = np.arange(len(grasps), len(rows))
    assert len(added) > 0
    assert kinematics.effort.steps - steps > RegraspSettings().restarts * len(grasps)  # the restarts' work is counted
    for k in added:
        row = rows[k]
        assert ok[k]
        point = transform_points(placement, world.object.grasps[grasps[row]][None])[0]
        assert np.linalg.norm(tip_poses(world.robot, solved[k][None])[0, :2] - point) <= 1e-9
        assert is_valid(world, solved[k][None], placement)[0]
        if own_ok[row]:
            assert np.abs(solved[k] - seeds[row]).sum() < np.abs(own[row] - seeds[row]).sum()


def test_a_two_joint_arm_gets_no_restarts() -> None:
    from clew_ros.planar.regrasp_keys import Kinematics

    world = load_world(ROOT / "config" / "figure1.yaml")
    kinematics = Kinematics(world, 0.0)
    rng = np.random.default_rng(0)
    state = rng.bit_generator.state
    seeds = np.repeat(np.asarray(world.robot.initial, dtype=float)[None], 3, axis=0)
    placement = np.asarray(world.object.initial, dtype=float)[None].repeat(3, axis=0)
    rows, _, _ = kinematics.restarted(lambda k, q: kinematics.holding(placement[k], np.arange(3)[k], q), seeds, rng)
    assert np.array_equal(rows, np.arange(3))
    assert rng.bit_generator.state == state


def test_restarts_around_a_configuration_add_ones_nearer_an_origin() -> None:
    # the plan's own grasp configuration: solutions drawn around it are kept when nearer the arm's start
    from clew_ros.planar.regrasp_keys import Kinematics
    from clew_ros.worlds import generate

    generated = generate("arm10", 1)
    world = generated.world()
    kinematics = Kinematics(world, 5e-4)
    witness = generated.witness.segments
    own = np.asarray(witness[1].waypoints[0], dtype=float)[None]  # the witness's grasp configuration
    grasp = np.array([int(witness[1].grasp)])
    placement = np.asarray(world.object.initial, dtype=float)[None]
    start = np.asarray(world.robot.initial, dtype=float)[None]
    rows, solved, ok = kinematics.restarted(
        lambda k, q: kinematics.holding(placement[k], grasp[k], q), own, np.random.default_rng(1), origins=start
    )
    assert np.array_equal(rows, [0, 0])  # its own solution (itself), then one nearer the start
    assert ok.all()
    assert np.abs(solved[0] - own[0]).max() <= 1e-4  # the witness holds its grasp within the tolerance
    assert np.abs(solved[1] - start[0]).sum() < np.abs(own[0] - start[0]).sum()
    assert is_valid(world, solved[1][None], placement[0])[0]
    point = transform_points(placement[0], world.object.grasps[grasp][None][0])[0]
    assert np.linalg.norm(tip_poses(world.robot, solved[1][None])[0, :2] - point) <= 1e-9


def _routes_in_python(world, packed, a, b, resting=None, grasp_rel=None) -> np.ndarray:
    from clew_ros.planar.kernel import clearly_valid

    """The proposals' screen as it was written in numpy until session 17: the compiled screen's reference."""

    def ways(a, b, samples):
        share = (0.5 - 0.5 * np.cos(np.linspace(0.0, np.pi, samples)))[None, :, None]
        out = [a[:, None, :] + share * (b - a)[:, None, :]]
        moved = np.abs(b - a)
        travel = share * moved.sum(axis=1)[:, None, None]
        for order in (np.arange(a.shape[1]), np.arange(a.shape[1])[::-1]):
            before = np.cumsum(moved[:, order], axis=1) - moved[:, order]
            start = np.empty_like(before)
            start[:, order] = before
            done = np.clip((travel - start[:, None, :]) / np.maximum(moved, 1e-300)[:, None, :], 0.0, 1.0)
            out.append(a[:, None, :] + done * (b - a)[:, None, :])
        return out

    route = np.full(len(a), -1)
    samples = 8 * 2 ** np.clip(np.ceil(np.log2(np.maximum(np.abs(b - a).sum(axis=1) / 0.1, 1.0) / 8.0)), 0, 2)
    for count in np.unique(samples).astype(int):
        group = np.flatnonzero(samples == count)
        for index, way in enumerate(ways(a[group], b[group], count)):
            rows = np.flatnonzero(route[group] < 0)
            if not len(rows):
                break
            q = way[rows].reshape(-1, a.shape[1])
            moves = np.repeat(group[rows], count)
            poses = resting[moves] if grasp_rel is None else compose(tip_poses(world.robot, q), grasp_rel[moves])
            ok = clearly_valid(packed, q, poses).reshape(len(rows), -1).all(axis=1)
            route[group[rows[ok]]] = index
    return route


@pytest.mark.parametrize("name", ["figure1", "arm3_regrasp", "arm5_regrasp"])
def test_the_compiled_screen_finds_the_ways_the_numpy_one_found(name: str) -> None:
    import dataclasses

    from clew_ros.planar.collision import packed_world
    from clew_ros.planar.kernel import screen_routes

    world = load_world(ROOT / "config" / f"{name}.yaml")
    packed = dataclasses.replace(packed_world(world), rounding=max(5e-4, packed_world(world).rounding))
    rng = np.random.default_rng(7)
    robot = world.robot
    found = np.zeros(4, dtype=int)  # how often each answer (-1, 0, 1, 2) came
    for transfer in (False, True):
        for spread in (0.1, 0.5, 1.5, 4.0):  # short moves (8 samples) to long ones (32)
            a = rng.uniform(robot.joint_lower, robot.joint_upper, (150, robot.dof))
            b = np.clip(a + rng.normal(0.0, spread, a.shape), robot.joint_lower, robot.joint_upper)
            resting = np.repeat(np.asarray(world.object.initial, float)[None], len(a), axis=0)
            grasp_rel = None
            if transfer:  # held where the tip is at the move's start, as a grasp would hold it
                grasp_rel = relative(tip_poses(robot, a), resting)
                resting = None
            samples = 8 * 2 ** np.clip(np.ceil(np.log2(np.maximum(np.abs(b - a).sum(axis=1) / 0.1, 1.0) / 8.0)), 0, 2)
            got, checked = screen_routes(packed, a, b, samples, resting=resting, grasp_rel=grasp_rel)
            want = _routes_in_python(world, packed, a, b, resting=resting, grasp_rel=grasp_rel)
            assert np.array_equal(got, want)
            assert 0 < checked <= samples.sum() * 3
            found += np.bincount(want + 1, minlength=4)
    # blocked moves and straight ones common, and moves clear only one joint after the other found too
    assert found[0] >= 50, found
    assert found[1] >= 50, found
    assert found[2] + found[3] >= 5, found


def test_the_compiled_screen_refuses_bad_shapes_and_a_missing_mode() -> None:
    from clew_ros.planar.collision import packed_world
    from clew_ros.planar.kernel import screen_routes

    world = load_world(ROOT / "config" / "figure1.yaml")
    packed = packed_world(world)
    a = np.zeros((3, 2))
    rest = np.zeros((3, 3))
    with pytest.raises(ValueError, match="starts, ends, samples"):
        screen_routes(packed, a, np.zeros((2, 2)), np.full(3, 8), resting=rest, grasp_rel=None)
    with pytest.raises(ValueError, match="starts, ends, samples"):
        screen_routes(packed, np.zeros((3, 5)), np.zeros((3, 5)), np.full(3, 8), resting=rest, grasp_rel=None)
    with pytest.raises(ValueError, match="samples: expected at least 2"):
        screen_routes(packed, a, a, np.full(3, 1), resting=rest, grasp_rel=None)
    with pytest.raises(ValueError, match="at rest"):
        screen_routes(packed, a, a, np.full(3, 8), resting=None, grasp_rel=None)
    with pytest.raises(ValueError, match="resting, grasp_rel"):
        screen_routes(packed, a, a, np.full(3, 8), resting=np.zeros((2, 3)), grasp_rel=None)
