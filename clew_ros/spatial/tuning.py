"""The spatial planner's tuning beyond ``planner.*`` (:class:`SpatialTuning`)."""

from __future__ import annotations

from dataclasses import dataclass, field

from clew_ros.core.settings import ManyJoints, SearchSettings

__all__ = ["SpatialTuning"]


@dataclass(frozen=True)
class SpatialTuning:
    """Every tuning value of a spatial run beyond ``planner.*``; a benchmark or a test plans with a copy."""

    search: SearchSettings = field(default_factory=SearchSettings)
    #: arms of many joints as core has them, but with the GA rounds kept when a job has ``straight``
    #: targets: a 7-joint arm decodes a generation in milliseconds, and the straight moves to inverse
    #: kinematics' targets miss behind any obstacle
    many: ManyJoints = field(default_factory=lambda: ManyJoints(transit_ga=True, transfer_ga=True))
    #: largest joint move (rad, max over joints) of the step that sets a carried object down: beyond it
    #: the linearised inverse kinematics from the decoded end rarely lands near it, and the move sweeps far
    settle_max_rad: float = 0.8
    #: highest (m) a carried object may be above a support and still be set down on it by that step; a
    #: little above (``settle_rise_m``) is allowed too (the object's face a few mm below the top)
    settle_drop_m: float = 0.3
    settle_rise_m: float = 0.01
    #: a transit holds its grasp when the tcp is this close (m, rad) to it: the object then rides on the
    #: nominal grasp within the plan file's 1e-4 replay tolerance
    hold_tolerance_m: float = 1e-5
    hold_tolerance_rad: float = 1e-5
    #: a transfer reaches the goal when the object's face is this close (rad) to the goal's face down,
    #: besides world.goal_tolerance on the centre and world.goal_angle_tolerance on the yaw
    face_tolerance_rad: float = 1e-3
    #: straight moves (count, nearest first) SEARCH tries to the targets inverse kinematics found
    straight_probes: int = 8
    #: a straight move is checked first at every this-many-th sample of the validator's (cheap refusals),
    #: then at every sample
    coarse_every: int = 16
    #: weight (m/rad) of the tcp's and the object's angles against their positions in SEARCH's objectives
    angle_weight_m: float = 0.1
    #: shortcuts tried per segment of a found plan (the improvement's work, deterministic)
    shortcut_tries: int = 48
    #: motion-only queries: weight (m/rad) of the joint distance to the goal in SEARCH_TRANSIT's objective
    motion_weight: float = 0.1
    #: motion-only queries: landmarks (count) EXPLORE places at most (each followed by a SEARCH_TRANSIT
    #: to the goal) before the run gives up with NO_PATH_AT_RESOLUTION's epsilon test
    motion_landmarks: int = 200
