"""The proof that a regrasp is needed: it holds for figure1 and its variants, never for a world one
transfer solves, and a sampled search for a single-transfer hold on the regrasp2 family finds none."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from clew_ros.planar.kinematics import compose, relative, wrap_angle
from clew_ros.planar.world import World, load_world
from clew_ros.worlds import generate
from clew_ros.worlds.regrasp import regrasp_needed

CONFIG = Path(__file__).resolve().parents[2] / "config"


@pytest.mark.parametrize(("name", "needed"), [("figure1", True), ("arm3_regrasp", True), ("single_transfer", False)])
def test_config_worlds(name: str, needed: bool) -> None:
    world = load_world(CONFIG / f"{name}.yaml")
    assert (regrasp_needed(world) is not None) == needed
    if world.robot.dof == 2:
        assert _single_transfer_hold(world) != needed


def _two_link(world: World, points: np.ndarray) -> np.ndarray:
    """Both elbow solutions ``(M, 2, 2)`` (solution, joint) for tip positions ``points`` ``(M, 2)``; NaN
    where out of reach."""
    l1, l2 = (float(v) for v in world.robot.link_lengths)
    v = points - world.robot.base
    cosine = (np.sum(v * v, axis=1) - l1 * l1 - l2 * l2) / (2 * l1 * l2)
    elbow = np.where(np.abs(cosine) <= 1, np.arccos(np.clip(cosine, -1, 1)), np.nan)
    elbows = np.stack([elbow, -elbow], axis=1)  # (M, 2)
    shoulders = np.arctan2(v[:, 1], v[:, 0])[:, None] - np.arctan2(l2 * np.sin(elbows), l1 + l2 * np.cos(elbows))
    return np.stack([shoulders, elbows], axis=2)


def _single_transfer_hold(world: World, samples: int = 721) -> bool:
    """Whether some grasp, taken at the start (tip on the grasp point or a ring around it), can be
    held to a goal pose within the tolerances (sampled), ignoring obstacles and joint limits."""
    start, goal = world.object.initial, world.object.goal
    ring = np.linspace(0.0, 2 * math.pi, 12, endpoint=False)
    circle = np.column_stack([np.cos(ring), np.sin(ring)])
    around = np.vstack([[0.0, 0.0], 0.9 * world.grasp_tolerance * circle])
    thetas = goal[2] + np.linspace(-world.goal_angle_tolerance, world.goal_angle_tolerance, samples)
    offsets = np.vstack([[0.0, 0.0], 0.9 * world.goal_tolerance * circle])
    goals = np.array([[goal[0] + dx, goal[1] + dy, t] for dx, dy in offsets for t in thetas])
    for grasp in world.object.grasps:
        point = compose(start, np.array([*grasp, 0.0]))[:2]
        q = _two_link(world, point + around).reshape(-1, 2)
        q = q[~np.isnan(q).any(axis=1)]
        tips = np.column_stack([_tip_position(world, q), q.sum(axis=1)])
        for rel in relative(tips, np.broadcast_to(start, tips.shape)):
            wanted = compose(goals, relative(rel, np.zeros(3)))  # the tip pose that puts the object there
            reached = _two_link(world, wanted[:, :2])  # (M, 2, 2)
            error = np.abs(wrap_angle(reached.sum(axis=2) - wanted[:, 2:3]))
            if np.nanmin(error, initial=np.inf) < 2e-3:
                return True
    return False


def _tip_position(world: World, q: np.ndarray) -> np.ndarray:
    l1, l2 = (float(v) for v in world.robot.link_lengths)
    x = world.robot.base[0] + l1 * np.cos(q[:, 0]) + l2 * np.cos(q.sum(axis=1))
    y = world.robot.base[1] + l1 * np.sin(q[:, 0]) + l2 * np.sin(q.sum(axis=1))
    return np.column_stack([x, y])


def test_the_sampled_search_finds_the_single_transfer_of_single_transfer() -> None:
    assert _single_transfer_hold(load_world(CONFIG / "single_transfer.yaml"))


@pytest.mark.parametrize("seed", range(3))
def test_regrasp2_worlds_need_a_regrasp(seed: int) -> None:
    generated = generate("regrasp2", seed)
    world = generated.world()
    assert regrasp_needed(world) is not None
    assert generated.witness.grasp_count >= 2
    assert not _single_transfer_hold(world)
