"""Where the witness goes: the arm and the object along the whole witness, and which candidate obstacles
keep clear of them.

The witness is replayed (:func:`clew_ros.planar.plan.replay`) and sampled densely enough that between
two samples no point of the arm or of the object moves more than ``margin / 2`` (a bound from the
joint steps and the distances along the chain), so an obstacle ``margin`` away from every sample is
at least ``margin / 2`` away from the whole continuous motion. The samples go into two STRtrees,
the arm as link segments (of radius ``link_width / 2``) and the object as polygons.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import shapely

from clew_ros.core.plan import Plan
from clew_ros.planar.kinematics import compose, joint_positions, tip_poses, transform_points
from clew_ros.planar.plan import replay
from clew_ros.planar.world import World

__all__ = ["Sweep"]


def _samples(waypoints: np.ndarray, reach_from: np.ndarray, gap: float) -> np.ndarray:
    """Configurations along straight pieces between ``waypoints`` such that no point moves more than
    ``gap`` (m) between two: a point of the chain beyond joint i is at most ``reach_from[i]`` from it."""
    out = [waypoints[:1]]
    for a, b in itertools.pairwise(waypoints):
        travel = float(np.abs(b - a) @ reach_from)
        count = max(1, math.ceil(travel / gap))
        t = np.arange(1, count + 1)[:, None] / count
        out.append(a + t * (b - a))
    return np.concatenate(out)


class Sweep:
    """The arm and the object along a witness plan, sampled for clearance queries (m)."""

    def __init__(self, world: World, plan: Plan, margin: float) -> None:
        self.world = world
        self.plan = plan
        self.margin = margin
        robot = world.robot
        lengths = np.asarray(robot.link_lengths, float)
        chain_reach = np.cumsum(lengths[::-1])[::-1]  # from joint i to the tip
        arm, objects, configurations = [], [], []
        for motion in replay(world, plan, None):
            held = 0.0
            if motion.grasp_rel is not None:
                held = float(np.hypot(*motion.grasp_rel[:2])) + world.object.radius
            q = _samples(np.asarray(motion.configurations), chain_reach + held + robot.link_width, margin / 2)
            configurations.append(q)
            arm.append(joint_positions(robot, q))
            if motion.grasp_rel is None:
                objects.append(transform_points(motion.object_poses[:1], world.object.polygon))
            else:
                poses = compose(tip_poses(robot, q), motion.grasp_rel)
                objects.append(transform_points(poses, world.object.polygon))
        #: The sampled configurations (N, n) and the object's polygons along the witness (M, V, 2).
        self.configurations = np.concatenate(configurations)
        self.object_vertices = np.concatenate(objects)
        self.arm_points = np.concatenate(arm)  # (N, n + 1, 2)
        links = np.stack([self.arm_points[:, :-1], self.arm_points[:, 1:]], axis=2).reshape(-1, 2, 2)
        self.arm_lines = np.asarray(
            shapely.linestrings(links), dtype=object
        )  # one per link and sample: tight boxes for the tree
        self.object_polygons = np.asarray(shapely.polygons(self.object_vertices), dtype=object)
        self._arm_tree = shapely.STRtree(self.arm_lines)
        self._object_tree = shapely.STRtree(self.object_polygons)
        self._arm_distance = margin + robot.link_width / 2

    def clear(self, geometries: np.ndarray) -> np.ndarray:
        """Whether each shapely geometry keeps at least ``margin`` from the arm and the object along the
        whole witness (``(K,)`` booleans for ``(K,)`` geometries)."""
        geometries = np.asarray(geometries, dtype=object)
        ok = np.ones(len(geometries), dtype=bool)
        for tree, distance in ((self._arm_tree, self._arm_distance), (self._object_tree, self.margin)):
            hits = tree.query_nearest(geometries, max_distance=distance)  # prunes better than a dwithin query
            ok[hits[0]] = False
        return ok

    def distance(self, geometry: shapely.Geometry) -> float:
        """Smallest distance (m) from ``geometry`` to the arm's centre lines and the object along the witness."""
        arm = float(shapely.distance(geometry, self.arm_lines).min()) - self.world.robot.link_width / 2
        placed = float(shapely.distance(geometry, self.object_polygons).min())
        return min(arm, placed)
