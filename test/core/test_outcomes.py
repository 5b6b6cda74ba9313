"""When each outcome is given (issue 46): ``NO_PATH_AT_RESOLUTION`` only on a proof or on the paper's
resolution criterion after EXPLORE covered every (landmark, grasp) pair; otherwise the run goes on until
its time limit and says what it tried. Short limits: the outcomes, not the speed, are asserted."""

from __future__ import annotations

from pathlib import Path

import pytest

from clew_ros.core.explore import Exploration, Explorer
from clew_ros.core.settings import Outcome, PlannerSettings
from clew_ros.planar.space import plan
from clew_ros.planar.world import load_world, world_from_parameters
from clew_ros.worlds import generate

ROOT = Path(__file__).resolve().parents[2]


def _boxed_world() -> dict:
    """A 3-joint arm and a small box closed in a ring of walls it can move in but no link can enter: no
    transit ever reaches a grasp, and no proof says so (the object could reach its goal in the ring)."""
    ring = {
        "south": [0.9, 0.6, 1.5, 0.6, 1.5, 0.65, 0.9, 0.65],
        "north": [0.9, 0.95, 1.5, 0.95, 1.5, 1.0, 0.9, 1.0],
        "west": [0.9, 0.65, 0.95, 0.65, 0.95, 0.95, 0.9, 0.95],
        "east": [1.45, 0.65, 1.5, 0.65, 1.5, 0.95, 1.45, 0.95],
    }
    return {
        "world": {
            "name": "boxed",
            "bounds": [-2.0, -2.0, 2.0, 2.0],
            "robot": {
                "base": [0.0, 0.0],
                "link_lengths": [0.8, 0.6, 0.4],
                "joint_lower": [-3.14159, -2.8, -2.8],
                "joint_upper": [3.14159, 2.8, 2.8],
                "initial": [-1.0, 0.0, 0.0],
            },
            "obstacle_names": list(ring),
            "obstacles": ring,
            "object": {
                "polygon": [-0.1, -0.05, 0.1, -0.05, 0.1, 0.05, -0.1, 0.05],
                "initial": [1.1, 0.8, 0.0],
                "goal": [1.25, 0.8, 0.0],
                "grasps": [0.0, -0.05, 0.0, 0.05, -0.1, 0.0, 0.1, 0.0],
            },
        }
    }


def test_rounds_without_any_transit_end_at_the_time_limit_not_in_a_false_no_path() -> None:
    # every EXPLORE round fails at once (no configuration holds a grasp): the planner used to answer
    # NO_PATH_AT_RESOLUTION ("no grasp of the object can be reached") after 8 such rounds
    world = world_from_parameters(_boxed_world())
    result = plan(world, PlannerSettings(seed=0, time_limit=1.5))
    assert result.outcome is Outcome.TIME_LIMIT, result.message
    assert "EXPLORE rounds without any transit" in result.message
    assert "transit searches" in result.message
    assert len(result.tree) == 1


@pytest.mark.parametrize("seed", [1, 4, 7, 2])
def test_a_many_joint_world_of_the_snake_family_never_gets_no_path(seed: int) -> None:
    world = generate("snake", seed).world()
    result = plan(world, PlannerSettings(seed=0, time_limit=3.0))
    assert result.outcome in {Outcome.SUCCEEDED, Outcome.TIME_LIMIT}, result.message
    if result.outcome is Outcome.TIME_LIMIT:
        assert "tried:" in result.message


@pytest.mark.parametrize(
    ("source", "outcome"),
    [
        ("config/unreachable.yaml", Outcome.NO_PATH_AT_RESOLUTION),
        ("unsolvable_0", Outcome.NO_PATH_AT_RESOLUTION),
        ("unsolvable_1", Outcome.NO_PATH_AT_RESOLUTION),
        ("unsolvable_2", Outcome.NO_PATH_AT_RESOLUTION),
    ],
)
def test_unsolvable_worlds_still_get_their_proof_before_any_search(source: str, outcome: Outcome) -> None:
    if source.startswith("config/"):
        world = load_world(ROOT / source)
    else:
        world = generate("unsolvable", int(source.rsplit("_", 1)[1])).world()
    result = plan(world, PlannerSettings(seed=0, time_limit=30.0))
    assert result.outcome is outcome, result.message
    assert len(result.tree) == 1  # answered by the proof, before EXPLORE placed a landmark
    assert result.stats["evaluations"] == 0


@pytest.mark.parametrize("moved", [True, False])
def test_the_resolution_criterion_needs_an_explore_step_that_moved_the_object(
    moved: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """EXPLORE's every step lands on the landmark it started from (the paper's epsilon_n of 0), every pair
    searched: NO_PATH_AT_RESOLUTION when its path moved the object, but when it could not move it at all (a
    spatial transfer that found no placement to set the object down on) the run goes on to its time limit."""
    world = load_world(ROOT / "config/figure1.yaml")
    original = Explorer.explore

    def explore_in_place(self: Explorer) -> Exploration | None:
        found = original(self)
        if found is None:
            return None
        parent = self.tree[found.fields["parent"]]
        fields = {**found.fields, "joints": parent.joints.copy(), "object_pose": parent.object_pose.copy()}
        return Exploration(fields, 0.0, covered=True, moved=moved)

    monkeypatch.setattr(Explorer, "explore", explore_in_place)
    result = plan(world, PlannerSettings(seed=0, time_limit=1.0, improve_time=0.0))
    if moved:
        assert result.outcome is Outcome.NO_PATH_AT_RESOLUTION, result.message
    else:
        assert result.outcome in {Outcome.TIME_LIMIT, Outcome.SUCCEEDED}, result.message
