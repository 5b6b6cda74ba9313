"""The spatial world packed for the kernels: named tuples of arrays, like pinocchio's model and data.

numba passes a named tuple of arrays to a compiled function as one argument and reads its fields at no cost, so
every kernel takes a handful of these instead of dozens of arrays: the robot's kinematic :class:`Chain`, its
sphere model (:class:`Spheres`, and :class:`InnerSpheres` for the band), the :class:`Scene` it moves in, the
:class:`HeldObject` it carries, how a free interval steps (:class:`Stepping`), and the scratch one
configuration is worked out in (:class:`Work`, made by the kernels themselves). The field names are the
conventions of :mod:`clew_ros.spatial.kernels.collide`. :class:`clew_ros.spatial.checker.SpatialChecker`
and :class:`clew_ros.spatial.inverse.InverseKinematics` pack them once.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.robot import RobotModel

__all__ = [
    "Chain", "HeldObject", "InnerSpheres", "Model", "Motion", "Scene", "Spheres", "Stepping", "Work", "chain_of",
]  # fmt: skip

Array = NDArray[Any]


class Chain(NamedTuple):
    """The robot's kinematics: joint limits, the base's pose in ``world``, each joint's origin, axis and kind,
    and the tcp (``tcp_r``, ``tcp_t`` in frame ``tcp_frame``)."""

    lower: Array
    upper: Array
    base_r: Array
    base_t: Array
    org_r: Array
    org_t: Array
    axes: Array
    prismatic: Array
    tcp_frame: int
    tcp_r: Array
    tcp_t: Array


class Spheres(NamedTuple):
    """A sphere model by pieces (the links, then the held object): sphere ``k`` at ``sph_c[k]`` (radius
    ``sph_r[k]``) on frame ``sph_frame[k]``, owned by piece ``sph_link[k]``; piece ``i`` owns spheres
    ``link_start[i]:link_start[i + 1]`` and has the bounding sphere ``link_c[i]``, ``link_r[i]`` on frame
    ``link_frame[i]``."""

    sph_c: Array
    sph_r: Array
    sph_frame: Array
    sph_link: Array
    link_start: Array
    link_c: Array
    link_r: Array
    link_frame: Array


class InnerSpheres(NamedTuple):
    """The inner sphere model on the same pieces and frames (:mod:`clew_ros.spatial.kernels.band`): centres,
    radii, each piece's first sphere (a piece may have none)."""

    sph_c: Array
    sph_r: Array
    link_start: Array


class Scene(NamedTuple):
    """The obstacles (kind, rotation, position, dimensions, bounding radius), which piece ignores which obstacle,
    the pairs of pieces checked for self-collision, and the bounds (used when ``has_bounds``)."""

    obs_kind: Array
    obs_r: Array
    obs_t: Array
    obs_dims: Array
    obs_bound: Array
    ignore: Array
    pairs: Array
    bounds: Array
    has_bounds: bool


class HeldObject(NamedTuple):
    """The held object (piece ``held_link``, -1: none): its lowest points and cap radius and axis, and the
    supports it may touch from above (obstacle indices, tops, tolerance)."""

    held_link: int
    held_points: Array
    held_disc: float
    held_axis: Array
    sup_index: Array
    sup_top: Array
    sup_tol: float


class Model(NamedTuple):
    """Everything a validity check reads and never writes: the chain, the outer and inner sphere models, the
    scene and the held object."""

    chain: Chain
    spheres: Spheres
    inner: InnerSpheres
    scene: Scene
    held: HeldObject


class Stepping(NamedTuple):
    """How a free interval steps (:class:`clew_ros.spatial.checker.IntervalSettings`): the clearance (m) every
    step keeps, the shortest step, the most steps each way, and how far each row may go (``reach``, one per
    row; with ``fold``, the signed move the caller folds into the interval)."""

    margin: float
    min_step: float
    max_steps: int
    reach: Array
    fold: bool


class Motion(NamedTuple):
    """One joint's motion while a free interval is stepped: the joint, the configuration it moves (scratch),
    its axis in ``world`` (a point, the frame's origin, and the direction, updated at each step), its kind,
    the stepping's margin (m), shortest step and most steps, and which obstacles, bounds and self pairs can
    limit it at all (:func:`clew_ros.spatial.kernels.intervals.relevance`)."""

    joint: int
    q: Array
    axis_p: Array
    axis_d: Array
    prismatic: bool
    margin: float
    min_step: float
    max_steps: int
    rel_obs: Array
    rel_bounds: Array
    rel_pair: Array


class Work(NamedTuple):
    """Scratch for one configuration: its frames, the (outer) spheres and bounding spheres in ``world``, which
    pieces' spheres are placed, the held object's points and the inner spheres in ``world``."""

    frame_r: Array
    frame_t: Array
    sph_w: Array
    link_w: Array
    placed: Array
    held_w: Array
    inner_w: Array


def chain_of(robot: RobotModel) -> Chain:
    """``robot``'s kinematics packed (contiguous float64 arrays, boolean joint kinds)."""
    return Chain(
        lower=robot.lower.astype(np.float64),
        upper=robot.upper.astype(np.float64),
        base_r=np.ascontiguousarray(robot.base[:3, :3], dtype=np.float64),
        base_t=np.ascontiguousarray(robot.base[:3, 3], dtype=np.float64),
        org_r=np.ascontiguousarray(robot.origins[:, :3, :3], dtype=np.float64),
        org_t=np.ascontiguousarray(robot.origins[:, :3, 3], dtype=np.float64),
        axes=np.ascontiguousarray(robot.axes, dtype=np.float64),
        prismatic=robot.prismatic.astype(np.bool_),
        tcp_frame=int(robot.tcp_frame),
        tcp_r=np.ascontiguousarray(robot.tcp[:3, :3], dtype=np.float64),
        tcp_t=np.ascontiguousarray(robot.tcp[:3, 3], dtype=np.float64),
    )
