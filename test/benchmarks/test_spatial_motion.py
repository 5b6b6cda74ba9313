"""``benchmarks.spatial_scenes`` makes valid motion-only problems, the same for the same seed, in MoveIt scene
files the world loader reads; ``benchmarks.spatial_motion`` runs planners by name on them and prints the table.
No speed is checked."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import numpy as np
import pytest
import yaml

pytest.importorskip("trimesh")
pytest.importorskip("urdf_parser_py")

from helpers.straight_planner import straight_line

from benchmarks import spatial_motion, spatial_scenes
from benchmarks.spatial_scenes import FAMILIES, MotionProblem
from clew_ros.spatial.validate import validate_transit, validation_samples
from clew_ros.spatial.world import spatial_world_from_parameters

CASES = [(family, robot) for family in FAMILIES for robot in ("panda", "ur5")]


@pytest.fixture(scope="module")
def generated() -> dict[tuple[str, str], MotionProblem]:
    return {(family, robot): spatial_scenes.generate(family, robot, 3) for family, robot in CASES}


@pytest.mark.parametrize(("family", "robot"), CASES)
def test_a_problem_starts_and_ends_valid_at_its_tcp_targets_and_its_straight_move_collides(
    generated: dict[tuple[str, str], MotionProblem], family: str, robot: str
) -> None:
    problem = generated[family, robot]
    loaded = spatial_scenes.context(problem)
    assert not loaded.checker.static_collision
    assert loaded.checker.valid(np.array([problem.start, problem.goal])).all()
    for q, target in ((problem.start, problem.start_tcp), (problem.goal, problem.goal_tcp)):
        assert np.all(q >= loaded.robot.lower)
        assert np.all(q <= loaded.robot.upper)
        assert np.allclose(loaded.robot.tcp_pose(q), target, atol=1e-5)
    straight = validation_samples(problem.start, problem.goal, np.full(loaded.robot.dof, 0.002))
    assert not loaded.checker.valid(straight).all()  # SceneSettings.nontrivial
    assert np.linalg.norm(problem.goal - problem.start) >= spatial_scenes.SceneSettings().min_distance_rad
    # a joint that may turn whole turns (the UR5's +-2 pi) never makes the goal a needless turn away
    turns = loaded.robot.upper - loaded.robot.lower >= 2 * np.pi
    assert np.all(np.abs(problem.goal - problem.start)[turns] <= np.pi + 1e-9)
    assert turns.any() == (robot == "ur5")
    ids = {item["id"] for item in problem.scene["world"]["collision_objects"]}
    assert "mount" in ids
    assert any(name.startswith((family, "clutter")) for name in ids), ids


def test_the_same_seed_gives_the_same_problem_and_another_seed_another(
    generated: dict[tuple[str, str], MotionProblem],
) -> None:
    first = generated["shelf", "panda"]
    again = spatial_scenes.generate("shelf", "panda", 3)
    assert again.scene_yaml() == first.scene_yaml()
    assert again.start.tobytes() == first.start.tobytes()
    assert again.goal.tobytes() == first.goal.tobytes()
    other = spatial_scenes.generate("shelf", "panda", 4)
    assert other.scene_yaml() != first.scene_yaml()
    assert not np.array_equal(other.goal, first.goal)


def test_the_written_files_load_as_a_motion_only_world_with_the_same_obstacles(
    generated: dict[tuple[str, str], MotionProblem], tmp_path: Path
) -> None:
    problem = generated["bookshelf", "ur5"]
    path = problem.write(tmp_path)
    parameters = yaml.safe_load(path.read_text())["clew_planner"]["ros__parameters"]
    world = spatial_world_from_parameters(parameters, path.parent)
    assert world.object is None
    assert world.goal is not None
    assert np.allclose(world.initial, problem.start, atol=1e-12)
    assert np.allclose(world.goal, problem.goal, atol=1e-12)
    loaded = spatial_scenes.context(problem)
    assert [o.name for o in world.obstacles] == [o.name for o in loaded.obstacles]
    for mine, read in zip(loaded.obstacles, world.obstacles, strict=True):
        assert mine.shape == read.shape
        assert np.allclose(mine.size, read.size)
        assert np.allclose(mine.pose, read.pose, atol=1e-6)
    assert world.checker.valid(np.array([problem.start, problem.goal])).all()
    scene = yaml.safe_load((tmp_path / f"{problem.name}.scene.yaml").read_text())
    assert {item["primitives"][0]["type"] for item in scene["world"]["collision_objects"]} <= {1, 2, 3}
    with pytest.raises(FileExistsError, match="not overwriting"):
        problem.write(tmp_path)
    inline = spatial_world_from_parameters(problem.world_parameters(), tmp_path)  # no scene file
    assert [o.name for o in inline.obstacles] == [o.name for o in world.obstacles]
    for mine, read in zip(inline.obstacles, world.obstacles, strict=True):
        assert np.allclose(mine.pose, read.pose, atol=1e-9)


def test_an_unknown_family_or_robot_is_refused_by_name() -> None:
    with pytest.raises(ValueError, match=r"family: expected one of table, shelf, cage, bookshelf, got 'attic'"):
        spatial_scenes.generate("attic", "panda", 0)
    with pytest.raises(ValueError, match=r"robot: expected one of panda, ur5 or random-K \(K a seed\), got 'kuka'"):
        spatial_scenes.generate("table", "kuka", 0)


def test_planners_are_named_or_given_as_module_function() -> None:
    assert spatial_motion.load_planner("ompl_rrtconnect") is spatial_motion.PLANNERS["ompl_rrtconnect"]
    assert spatial_motion.load_planner("helpers.straight_planner:straight_line") is straight_line
    assert spatial_motion.load_planner("aca") is spatial_motion.aca
    with pytest.raises(
        ValueError, match=r"unknown planner 'rrt'; expected one of ompl_rrtconnect, roboplan_rrtconnect, aca"
    ):
        spatial_motion.load_planner("rrt")
    with pytest.raises(ValueError, match=r"cannot load 'no_such_module:plan'"):
        spatial_motion.load_planner("no_such_module:plan")


def _rows(out: str) -> dict[tuple[str, str], list[str]]:
    rows = {}
    for line in out.splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if len(cells) == 11 and cells[0] not in ("problems", "---"):
            rows[cells[0], cells[1]] = cells[2:]
    return rows


def test_a_tiny_run_prints_a_row_per_planner_and_catches_an_invalid_path(capsys: pytest.CaptureFixture[str]) -> None:
    planners = ["helpers.straight_planner:straight_line", "ompl_rrtconnect"]
    arguments = ["--families", "cage", "--robots", "panda", "--problems", "1", "--time-limit", "2"]
    assert spatial_motion.main([*arguments, "--planners", *planners]) == 0
    out = capsys.readouterr().out
    rows = _rows(out)
    straight = rows["cage panda", "helpers.straight_planner:straight_line"]
    assert straight[0] == "1"  # runs
    assert straight[-2] == "0/1"  # its path is not valid under the sphere checker
    assert rows["all", "helpers.straight_planner:straight_line"] == straight
    if importlib.util.find_spec("ompl") is None:
        assert "ompl_rrtconnect: not run, ompl not importable" in out
        return
    ompl = rows["cage panda", "ompl_rrtconnect"]
    success = float(ompl[1].rstrip("%")) / 100
    assert 0.0 <= success <= 1.0
    if success:
        assert ompl[-2] == "1/1"  # OMPL's simplified path passes the validator at 0.002 rad
        assert float(ompl[5]) > 0  # travel
        assert int(ompl[6].replace(",", "")) > 0  # checks
    assert re.search(r"ompl_rrtconnect / helpers.straight_planner:straight_line: median time [\d.]+", out)


def test_the_aca_plans_valid_paths_on_the_peers_checker_and_the_same_seed_the_same_path() -> None:
    problem = spatial_scenes.generate("table", "panda", 0)
    loaded = spatial_motion.cached_context(problem)  # the context the harness and the peers use
    assert spatial_motion.aca_world(problem).checker is loaded.checker  # the peers' collision model
    result = spatial_motion.aca(problem, 0, 10.0)
    assert result.success, result.message
    assert result.waypoints is not None
    assert np.array_equal(result.waypoints[0], problem.start)
    assert np.array_equal(result.waypoints[-1], problem.goal)
    assert validate_transit(loaded.checker, result.waypoints) == []
    again = spatial_motion.aca(problem, 0, 10.0)
    assert again.waypoints is not None
    assert again.waypoints.tobytes() == result.waypoints.tobytes()


def test_a_tiny_run_of_the_aca_prints_its_row_with_its_paths_checked(capsys: pytest.CaptureFixture[str]) -> None:
    arguments = ["--families", "table", "--robots", "panda", "--problems", "1", "--time-limit", "10"]
    assert spatial_motion.main([*arguments, "--planners", "aca"]) == 0
    row = _rows(capsys.readouterr().out)["table panda", "aca"]
    assert row[0] == "1"  # runs
    assert row[1] == "100%"
    assert float(row[5]) > 0  # travel
    assert row[6] == "-"  # its work is counted in free intervals, not configurations
    assert row[-2] == "1/1"  # valid under the sphere checker at 0.002 rad


def test_ompl_plans_valid_paths_between_the_generated_ends() -> None:
    pytest.importorskip("ompl")
    problem = spatial_scenes.generate("table", "panda", 0)
    result = spatial_motion.ompl_rrtconnect(problem, 0, 10.0)
    assert result.success, result.message
    assert result.waypoints is not None
    assert np.allclose(result.waypoints[0], problem.start)
    assert np.allclose(result.waypoints[-1], problem.goal)
    assert validate_transit(spatial_scenes.context(problem).checker, result.waypoints) == []
    assert result.checks is not None
    assert result.checks > 0


def test_the_exact_reference_finds_the_ends_free_and_the_straight_move_colliding() -> None:
    pytest.importorskip("roboplan.rrt")
    for family in FAMILIES:
        problem = spatial_scenes.generate(family, "panda", 1)
        exact = spatial_motion.exact_scene(problem)
        assert not exact.collides(problem.start), family
        assert not exact.collides(problem.goal), family
        result = spatial_motion.roboplan_rrtconnect(problem, 0, 10.0)
        assert result.success, (family, result.message)
        assert result.waypoints is not None
        assert not exact.path_collides(result.waypoints), family


def _run(success: bool, time_s: float, travel: float | None) -> spatial_motion.Run:
    return spatial_motion.Run(
        planner="p", problem="x", family="table", robot="panda", seed=0, success=success, time_s=time_s,
        cpu_s=time_s, travel_rad=travel, checks=None, waypoints=2 if success else 0, valid=success or None,
        exact_valid=None,
    )  # fmt: skip


def test_the_summary_counts_a_failure_at_the_time_limit_and_travel_over_the_successes_only() -> None:
    runs = [_run(True, 0.1, 2.0), _run(True, 0.3, 4.0), _run(False, 0.01, None), _run(False, 9.0, None)]
    figures = spatial_motion.summary(runs, time_limit_s=5.0)
    assert figures["success"] == 0.5
    assert figures["median_s"] == pytest.approx((0.3 + 5.0) / 2)  # times 0.1, 0.3, 5, 5
    assert figures["p90_s"] == pytest.approx(5.0)
    assert figures["travel_rad"] == pytest.approx(3.0)
    assert figures["valid"] == 2
    assert figures["checks"] is None
    assert figures["exact_valid"] is None


def test_ranges_the_robot_cannot_reach_give_up_with_a_reason() -> None:
    far = spatial_scenes.SceneSettings(shelf_distance_m=(3.0, 3.5), scene_tries=3, target_tries=2)
    with pytest.raises(RuntimeError, match=r"shelf_panda_0: no problem in 3 scenes"):
        spatial_scenes.generate("shelf", "panda", 0, far)
