"""The landmark tree (paper 1.2): segments built from landmarks, history_of, the landmark distance."""

from __future__ import annotations

import itertools

import numpy as np

from clew_ros.core.tree import LandmarkTree, Segment, append_path, append_step
from clew_ros.planar.space import landmark_features


def path(*points) -> np.ndarray:
    return np.array(points, dtype=float)


def test_append_path_merges_same_kind_and_grasp_and_drops_repeated_points() -> None:
    segments: list[Segment] = [Segment("transit", None, [np.zeros(2)])]
    append_path(segments, "transit", None, path([0, 0], [0.5, 0], [0.5, 0]))
    assert len(segments) == 1
    assert np.array(segments[0].waypoints).tolist() == [[0, 0], [0.5, 0]]
    append_path(segments, "transfer", 1, path([0.5, 0], [0.5, 1]))
    assert [(s.kind, s.grasp) for s in segments] == [("transit", None), ("transfer", 1)]
    assert np.array_equal(segments[1].waypoints[0], segments[0].waypoints[-1])  # starts where the last ended
    append_path(segments, "transfer", 1, None)
    append_path(segments, "transfer", 1, path())
    assert len(segments) == 2
    assert len(segments[1].waypoints) == 2


def test_a_regrasp_of_the_same_grasp_is_a_new_transfer() -> None:
    segments: list[Segment] = [Segment("transit", None, [np.zeros(2)])]
    append_step(segments, 0, path([0, 0], [0, 1]), path([0, 1], [1, 1]))
    append_step(segments, 0, None, path([1, 1], [1, 2]))  # keeps holding: the same transfer goes on
    assert [(s.kind, s.grasp) for s in segments] == [("transit", None), ("transfer", 0)]
    append_step(segments, 0, path([1, 2], [2, 2]), path([2, 2], [2, 3]))  # lets go and takes grasp 0 again
    assert [(s.kind, s.grasp) for s in segments] == [
        ("transit", None),
        ("transfer", 0),
        ("transit", None),
        ("transfer", 0),
    ]
    ends = [(np.asarray(a.waypoints[-1]), np.asarray(b.waypoints[0])) for a, b in itertools.pairwise(segments)]
    assert all(np.array_equal(end, start) for end, start in ends)


def test_history_of_follows_the_lineage_only() -> None:
    tree = LandmarkTree(np.zeros(2), np.array([1.0, 0.0, 0.0]))
    first = tree.add(
        parent=0,
        joints=np.array([1.0, 1.0]),
        object_pose=np.array([1.2, 0.0, 0.0]),
        grasp=2,
        grasp_rel=np.zeros(3),
        transit=path([0, 0], [1, 0]),
        transfer=path([1, 0], [1, 1]),
    )
    tree.add(
        parent=0,
        joints=np.array([-1.0, 0.0]),
        object_pose=np.array([0.0, 1.0, 0.0]),
        grasp=1,
        grasp_rel=np.zeros(3),
        transit=path([0, 0], [-1, 0]),
        transfer=path([-1, 0], [-1, -1]),
    )
    third = tree.add(
        parent=first.id,
        joints=np.array([2.0, 1.0]),
        object_pose=np.array([1.5, 0.0, 0.0]),
        grasp=2,
        grasp_rel=np.zeros(3),
        transit=None,
        transfer=path([1, 1], [2, 1]),
    )
    assert [lm.id for lm in tree.lineage(third.id)] == [0, first.id, third.id]
    history = tree.history_of(third.id)
    assert [(s.kind, s.grasp) for s in history] == [("transit", None), ("transfer", 2)]
    assert np.array(history[1].waypoints).tolist() == [[1, 0], [1, 1], [2, 1]]
    assert tree.history_of(0)[0].kind == "transit"
    assert len(tree.history_of(0)) == 1


def test_landmark_features_measure_the_landmark_distance() -> None:
    joints = np.array([[0.0, 0.0], [0.3, -0.4]])
    poses = np.array([[0.0, 0.0, 0.0], [3.0, 4.0, np.pi]])
    features = landmark_features(joints, poses, joint_weight=0.1, object_radius=0.5)
    distance = np.linalg.norm(features[0] - features[1])
    # 5 m apart, opposite orientations (a chord of 2 radii), joints 0.5 rad apart weighted 0.1 m/rad
    assert np.isclose(distance, np.sqrt(5.0**2 + 1.0**2 + 0.05**2))
