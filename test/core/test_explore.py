"""EXPLORE places landmarks farther from the others than random choices would."""

from pathlib import Path

import numpy as np

from clew_ros.core.explore import Explorer
from clew_ros.core.settings import PlannerSettings, Termination
from clew_ros.core.space import Mode, PlanningContext
from clew_ros.core.tree import LandmarkTree
from clew_ros.planar.space import PlanarSpace
from clew_ros.planar.world import load_world

CONFIG = Path(__file__).resolve().parents[2] / "config"


def _explorer(name: str, seed: int) -> tuple[Explorer, PlanningContext, LandmarkTree]:
    """An Explorer on ``config/<name>.yaml`` with the root landmark only."""
    world = load_world(CONFIG / f"{name}.yaml")
    ctx = PlanningContext(PlanarSpace(world), PlannerSettings(seed=seed), np.random.default_rng(seed), Termination(60))
    tree = LandmarkTree(world.robot.initial, world.object.initial)
    return Explorer(ctx, tree), ctx, tree


def test_explore_beats_random_single_manipulation_paths():
    explorer, ctx, tree = _explorer("single_transfer", 3)
    world, settings = ctx.space.world, ctx.settings
    exploration = explorer.explore()
    assert exploration is not None
    assert exploration.moved  # the farthest landmark carried the object away from its start
    landmark = tree.add(**exploration.fields)
    features = ctx.space.landmark_features(tree.joints(), tree.object_poses(), settings.joint_weight)[:1]

    # random single manipulation paths from the same transits
    candidates = [c for c in explorer.transits.values() if c is not None]
    rng = np.random.default_rng(99)
    n = world.robot.dof
    distances = []
    for candidate in candidates:
        genes = rng.normal(0, 1.2, (64, settings.manhattan_order, n))
        paths = ctx.manhattan(candidate.start, genes, Mode.held(candidate.grasp_rel[None]))
        ends = ctx.space.landmark_features(paths.final, paths.object_poses, settings.joint_weight)
        distances.append(np.linalg.norm(ends - features, axis=1))
    distances = np.concatenate(distances)
    assert exploration.distance >= np.percentile(distances, 90)
    assert landmark.parent == 0
    assert landmark.grasp is not None
    # the landmark holds its grasp: tip on the grasp point of the placed object
    from clew_ros.planar.kinematics import tip_poses, transform_points

    tip = tip_poses(world.robot, landmark.joints[None])[0, :2]
    grasp = transform_points(landmark.object_pose, world.object.grasps[landmark.grasp][None])[0]
    assert np.linalg.norm(tip - grasp) <= world.grasp_tolerance


def test_a_transit_missed_once_is_tried_again_before_giving_up():
    # obstacles_32 (benchmarks): from the start placement every grasp's transit can miss on the first
    # draw; the planner used to answer NO_PATH_AT_RESOLUTION after about 1 s for seeds 1 and 2
    from benchmarks.worlds import obstacles_world
    from clew_ros.planar.space import plan
    from clew_ros.planar.world import world_from_parameters

    world = world_from_parameters(obstacles_world(32).parameters)
    for seed in (1, 2):
        result = plan(world, PlannerSettings(seed=seed, time_limit=2.0))
        assert result.outcome.name in ("SUCCEEDED", "TIME_LIMIT"), result.message


def test_forget_failures_keeps_only_found_transits():
    explorer, ctx, _tree = _explorer("figure1", 0)
    found = [explorer.candidate(0, grasp) for grasp in range(len(ctx.space.world.object.grasps))]
    assert any(c is None for c in found)
    assert any(c is not None for c in found)
    explorer.forget_failures()
    assert set(explorer.transits) == {(0, g) for g, c in enumerate(found) if c is not None}


def test_the_transits_of_one_step_are_searched_together_and_each_holds_its_grasp(monkeypatch):
    """EXPLORE's new (landmark, grasp) pairs go to SEARCH_TRANSIT as one batch of islands: every
    found transit ends with the tip on its grasp point, moves validly, and starts at the landmark."""
    from clew_ros.planar import search
    from clew_ros.planar.collision import is_valid
    from clew_ros.planar.kinematics import tip_poses, transform_points
    from clew_ros.planar.plan import CHECK_STEP_RAD

    explorer, ctx, tree = _explorer("arm3_regrasp", 1)
    batches = []
    real = search.search_transits

    def spy(world, context, requests):
        batches.append(len(requests))
        return real(world, context, requests)

    monkeypatch.setattr(search, "search_transits", spy)  # PlanarSpace.search_transits calls it by its name
    assert explorer.explore() is not None
    world = ctx.space.world
    assert batches
    assert max(batches) >= 2
    found = [c for c in explorer.transits.values() if c is not None and c.transit is not None]
    assert found
    for candidate in found:
        landmark = tree[candidate.parent]
        np.testing.assert_allclose(candidate.transit[0], landmark.joints)
        tip = tip_poses(world.robot, candidate.start[None])[0, :2]
        grasp = transform_points(landmark.object_pose, world.object.grasps[candidate.grasp][None])[0]
        assert np.linalg.norm(tip - grasp) <= world.grasp_tolerance
        for a, b in zip(candidate.transit[:-1], candidate.transit[1:], strict=True):
            steps = max(1, int(np.ceil(np.abs(b - a).max() / CHECK_STEP_RAD)))
            qs = a + np.linspace(0, 1, steps + 1)[:, None] * (b - a)
            assert is_valid(world, qs, landmark.object_pose[None]).all()


def test_a_landmark_takes_its_own_grasp_again_with_another_approach_when_asked():
    from clew_ros.planar.kinematics import relative, tip_poses, transform_points
    from clew_ros.planar.reach import REACH, approach_cell, approach_cells, approach_excess

    cells_count = REACH.approach_cells

    explorer, ctx, tree = _explorer("arm3_regrasp", 7)
    exploration = explorer.explore()
    assert exploration is not None
    landmark = tree.add(**exploration.fields)
    world, grasp = ctx.space.world, landmark.grasp
    here = approach_cell(-landmark.grasp_rel[2])
    # its own approach allowed: the landmark itself, no transit
    allowed = np.zeros(cells_count, bool)
    allowed[here] = True
    own = explorer.candidate(landmark.id, grasp, allowed)
    assert own is not None
    assert own.transit is None
    # its own approach refused: a transit from the landmark to the same grasp, held with an allowed approach
    cells = np.arange(cells_count)
    apart = np.abs((cells - here + cells_count // 2) % cells_count - cells_count // 2) > cells_count // 8
    allowed = approach_cells(world, landmark.object_pose, grasp) & apart
    assert allowed.any()
    again = explorer.candidate(landmark.id, grasp, allowed)
    assert again is not None
    assert again.transit is not None
    np.testing.assert_allclose(again.transit[0], landmark.joints)
    tip = tip_poses(world.robot, again.start[None])[0]
    point = transform_points(landmark.object_pose, world.object.grasps[grasp][None])[0]
    assert np.linalg.norm(tip[:2] - point) <= world.grasp_tolerance
    np.testing.assert_allclose(again.grasp_rel, relative(tip, landmark.object_pose), atol=1e-9)
    # an allowed approach, up to the transit's success test (the approach term, times the last link's length,
    # is part of the residual that must end within half the grasp tolerance)
    psi = np.array([-again.grasp_rel[2]])
    assert world.robot.link_lengths[-1] * approach_excess(allowed)(psi)[0] <= 0.5 * world.grasp_tolerance
    assert explorer.candidate(landmark.id, grasp, allowed) is again  # searched once
