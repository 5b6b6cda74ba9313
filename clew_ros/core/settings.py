"""Planner settings (``planner.*`` parameters, specified in :mod:`clew_ros.core.parameters`), outcomes and
termination conditions."""

from __future__ import annotations

import enum
import threading
import time
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

from clew_ros.core.errors import ParameterError
from clew_ros.core.genetic import GeneticSettings
from clew_ros.core.parameters import PLANNER_PARAMETERS, RETIRED_PARAMETERS, check_value, retired_message

__all__ = ["PLANNER_PARAMETERS", "ManyJoints", "Outcome", "PlannerSettings", "SearchSettings", "Termination"]


@dataclass(frozen=True)
class ManyJoints:
    """How SEARCH adapts to arms of many joints (issue 46): chosen from the arm's number of joints, so
    that arms of at most 10 joints (every other family, the config worlds) plan as before."""

    #: joints (count) from which SEARCH_TRANSIT first tries straight joint-space moves, checked
    #: continuously, to its holding configurations: on 15-40 joint arms a Manhattan path visits
    #: every joint k times and each move's free interval costs O(n^2) link pairs, so one decoded
    #: path costs about 100x a 4-joint one, and the greedy Manhattan probe, which swings joint 1 first,
    #: rarely gets past a shelf's walls where a straight move does
    straight_probe_joints: int = 11
    #: joints (count) from which SEARCH_TRANSIT first tries the direct straight moves of that probe (to its
    #: :attr:`straight_probes` nearest holds, no retreat and approach), its GA rounds still running when none is
    #: clear: at 7-10 joints a transit's GA costs 140-820 decoded Manhattan paths where a straight move, one
    #: continuous check, is clear from 14 to 18 of 20 random starts to their goals (the OMPL peer's problems), as
    #: RRT-Connect's straight extensions are; below 7 joints the greedy Manhattan probe mostly reaches them
    straight_transit_joints: int = 7
    #: holding configurations (count, nearest first in joint travel) a transit's straight probe tries
    straight_probes: int = 8
    #: starts (count) of the inverse kinematics seeded from the arm's own configuration: the start itself and
    #: this many less one perturbed around it, so that a transit's holds include ones near it in joint space
    #: (solved from random starts only, the transits of loose-limit arms travelled about 6x the witness)
    near_holds: int = 12
    #: spread (rad, standard deviation per joint) of those perturbed starts: large enough to leave a posture
    #: whose nearest hold is blocked, small against a joint's range so the holds stay near the start
    near_spread_rad: float = 0.15
    #: random starts of the holding configurations on such arms (at least; 24 on others): few of them
    #: converge where the arm must be nearly straight, and the straight probe needs some to head for
    hold_samples: int = 96
    #: SEARCH_TRANSFER's straight probe also tries each goal configuration by way of the configuration
    #: with the tip backed along its own heading by this many object radii (m / m), reached in
    #: :attr:`approach_steps` straight moves along that line (the object put in place along the last
    #: link, as a gripper puts an object into a slot)
    approach_radii: float = 2.0
    approach_steps: int = 8
    #: ...and at most this far apart (m of tip travel) on a long line: the inverse kinematics that follows the
    #: line from one step's configuration to the next converges only over short steps
    approach_step_m: float = 0.02
    #: largest sweep (m: ``sum_j |dq_j| R_j``, the bound of :mod:`clew_ros.planar.continuous`) of one compiled
    #: check of the straight probes' moves, the time limit and cancel asked between them: a whole long move of
    #: 39 joints near a contact, checked at once, took over a second and ended a 20 s run at 21 s
    check_sweep_m: float = 1.0
    #: the straight probes first screen each move by checking configurations this far apart (rad, the largest
    #: joint's step): cheap, and the continuous check, which can take seconds on a long move near a contact,
    #: then runs only on moves that look clear
    screen_step_rad: float = 0.05
    #: whether SEARCH_TRANSIT runs its GA rounds on such arms after the straight probe failed: measured on
    #: the snake family, the GA took 90 % of a run (a 40-joint generation decodes 24 paths of 80 moves at
    #: about 5 ms each) and never reached a grasp the straight probe missed; without it EXPLORE moves on to
    #: other pairs and landmarks (a failed pair is tried again, with more holding configurations, after a
    #: round with no transit)
    transit_ga: bool = False
    #: whether SEARCH_TRANSFER runs its GA rounds on such arms after its straight probe failed: on a 39-joint
    #: arm two of them took 75 % of a 10 s run (decoding Manhattan paths) and left EXPLORE 2 landmarks;
    #: without it the transfer is the straight probe's or a join from the grasp (RRT-Connect, when it starts
    #: near the goal), and EXPLORE places more landmarks in the time
    transfer_ga: bool = False
    #: generations (at most) of EXPLORE's GA on such arms: a 39-joint generation decodes 24 transfer paths
    #: (8-25 ms each on the loaded 2-core machine), so 12 generations took about 3 s a landmark and a 20 s run
    #: placed 4-6 landmarks; with 4 the snake worlds 0-11 went from 22/24 to 23/24 plans
    explore_generations: int = 4
    #: largest Manhattan order (``planner.manhattan_order`` is lowered to it) on such arms: each order adds a
    #: move of every joint to a path, and EXPLORE's decoding took 95 % of a 37-joint run at order 2
    manhattan_order: int = 1


@dataclass(frozen=True)
class SearchSettings:
    """SEARCH's and the run's tuning beyond ``planner.*`` (what a user sets): probes, joins, chains, the
    holding configurations' sample. A benchmark or a test varies a copy (``dataclasses.replace``)."""

    #: whether SEARCH_TRANSIT first tries one Manhattan path straight to the nearest holding configuration
    #: before the GA rounds (RRT-Connect's greedy connection, one joint at a time); ``False`` is the search as
    #: the paper has it
    greedy_probe: bool = True
    #: whether SEARCH_TRANSFER's greedy probe heads for the nearest configuration holding the object at the
    #: goal; ``False``: transfers start with the GA (as with :attr:`greedy_probe` off)
    transfer_probe: bool = True
    #: a SEARCH_TRANSFER that stalls closer to the goal than this fraction of the arm's reach (m / m) is
    #: joined to it by RRT-Connect when it can be: the GA's Manhattan paths close the last centimetres slowly
    join_radius: float = 0.3
    #: rounds (count) of that RRT-Connect at most: each extends one tree a step and the other as far as it is
    #: clear; beyond about 30 a join that has not met rarely does, and every round costs continuous checks
    join_rounds: int = 30
    #: margin (x ``planner.clearance``) SEARCH's straight probes and joins keep along their moves, checked
    #: continuously: valid at any checking step with room to spare, as the improvement's moves are
    #: (``ContinuousSettings.min_margin_factor``)
    min_margin_factor: float = 0.5
    #: seeds (count) of the inverse kinematics for the configurations holding the object at the goal: the
    #: stalled configuration and random ones (more find more goal configurations, each costs a solve)
    goal_seeds: int = 8
    #: random starts (count) of the holding configurations that decide whether a transit is hopeless, at the
    #: start of a run; doubled after each EXPLORE round that found no transit at all
    hold_samples: int = 24
    #: ...up to this many samples x joints (768 for 7 joints, 53 for 100): their inverse kinematics is not
    #: interruptible, this keeps one solve to a few tens of milliseconds
    hold_sample_joints: int = 5376
    #: when SEARCH from a landmark fails, the placement its closest transfer reached becomes a landmark and
    #: SEARCH runs again from it, at most this many times in a row (a regrasp where the carried object got
    #: stuck; 4 or 8 planned no more worlds than 2 and cost time: docs/benchmarks.md)
    search_chain: int = 2
    #: whether SEARCH runs from the start before the first EXPLORE: SEARCH_TRANSFER from each grasp that a
    #: transit reaches at the object's initial placement (a departure: the paper's first SEARCH is from
    #: EXPLORE's first landmark, which lies as far from the start as EXPLORE can put it, here perhaps deeper
    #: into the shelf the object starts in); the planar planner keeps the paper's order
    search_from_start: bool = False
    #: when SEARCH from a landmark (and its chain) fails: SEARCH_TRANSFER to at most this many intermediate
    #: placements the space proposes (:meth:`~clew_ros.core.space.RegraspAims.placements`: where a grasp that
    #: holds the object at the goal can take it), SEARCH going on from each it reaches; 0: none (the planar
    #: planner, whose plans stay as they were)
    via_placements: int = 0
    #: whether EXPLORE's new landmark within ``planner.resolution`` of the others ends the run with
    #: NO_PATH_AT_RESOLUTION (the paper's criterion); ``False``: that proves nothing, the run goes on to its time
    #: limit (the spatial planner: its EXPLORE samples a space too large for the criterion to cover)
    resolution_proves: bool = True
    #: an EXPLORE step whose transfer moved the object less than this (m, as the space's goal distance
    #: measures it) did not move it, and its landmark's distance to the others proves nothing (the resolution
    #: criterion, :attr:`Exploration.moved`): well above the few micrometres by which a grasp held within its
    #: tolerance shifts the object, well below any move
    moved_m: float = 1e-3
    #: SEARCH refines an end point by damped least squares once its objective is within this share of the arm's
    #: reach (m / m): the GA's Manhattan paths land within centimetres, the last millimetres need the Jacobian
    refine_radius: float = 0.15
    #: the greedy probe and the GA rounds stop once the objective is within this share of that radius
    #: (dimensionless): close enough for refinement to finish the job, so further generations are wasted
    ga_target_share: float = 0.2
    #: a probe or a GA round counts as progress only when it lowers the objective by more than this (m, the
    #: objective's unit): smaller gains are rounding, and a round that makes none ends SEARCH's loop
    min_progress: float = 1e-4
    #: refinement's damped least-squares steps (count) at most: each costs a finite-difference Jacobian and a
    #: decoded single-joint path; it converges in a few where it can, and stops early when clamped
    refine_iterations: int = 30
    #: damping of refinement's least squares (objective units squared): keeps a step finite near singular postures
    refine_damping: float = 1e-4
    #: largest joint move (rad) of one refinement step: the linearisation holds only near the current posture
    refine_step_rad: float = 0.3
    #: standard deviation (rad) of the random genes a GA population (SEARCH's and EXPLORE's, planar and
    #: spatial) starts from: a first generation's moves span a typical free interval (bouncing folds larger
    #: genes back into it)
    initial_gene_rad: float = 1.2


class Outcome(enum.Enum):
    """Closed set of run outcomes; ``value`` is the numeric code."""

    SUCCEEDED = 0
    INVALID_WORLD = 1
    START_IN_COLLISION = 2
    GOAL_IN_COLLISION = 3
    GOAL_OUT_OF_REACH = 4
    NO_PATH_AT_RESOLUTION = 5
    TIME_LIMIT = 6
    CANCELED = 7
    BUSY = 8
    INTERNAL_ERROR = 9
    START_STATE_UNKNOWN = 10

    @property
    def succeeded(self) -> bool:
        return self is Outcome.SUCCEEDED


@dataclass(frozen=True)
class PlannerSettings:
    """Tuning of the planner: the ``planner.*`` parameters (:data:`PLANNER_PARAMETERS` gives each one's
    default, unit, range and meaning)."""

    seed: int = PLANNER_PARAMETERS.default("seed")
    time_limit: float = PLANNER_PARAMETERS.default("time_limit")
    resolution: float = PLANNER_PARAMETERS.default("resolution")
    clearance: float = PLANNER_PARAMETERS.default("clearance")
    manhattan_order: int = PLANNER_PARAMETERS.default("manhattan_order")
    population: int = PLANNER_PARAMETERS.default("population")
    generations: int = PLANNER_PARAMETERS.default("generations")
    explore_candidates: int = PLANNER_PARAMETERS.default("explore_candidates")
    search_rounds: int = PLANNER_PARAMETERS.default("search_rounds")
    joint_weight: float = PLANNER_PARAMETERS.default("joint_weight")
    threads: int = PLANNER_PARAMETERS.default("threads")
    improve_time: float = PLANNER_PARAMETERS.default("improve_time")

    @property
    def genetic(self) -> GeneticSettings:
        return GeneticSettings(population=self.population, generations=self.generations)

    @classmethod
    def from_parameters(cls, parameters: Mapping[str, Any], **overrides: Any) -> PlannerSettings:
        """From a ``ros__parameters`` tree (its ``planner`` key); ``overrides`` win (``None`` ones are ignored).

        Every value is checked by :func:`~clew_ros.core.parameters.check_value`;
        raises :class:`ParameterError` naming the parameter at fault.
        """
        tree = parameters.get("planner") or {}
        if not isinstance(tree, Mapping):
            raise ParameterError("planner", f"expected a mapping, got {tree!r}")
        values: dict[str, Any] = {}
        for key, value in tree.items():
            if f"planner.{key}" in RETIRED_PARAMETERS:
                warnings.warn(retired_message(f"planner.{key}"), FutureWarning, stacklevel=2)
                continue
            if key not in PLANNER_PARAMETERS:
                raise ParameterError(f"planner.{key}", f"unknown parameter; known: {', '.join(PLANNER_PARAMETERS)}")
            values[key] = value
        values.update({k: v for k, v in overrides.items() if v is not None})
        return cls(**{k: check_value(PLANNER_PARAMETERS[k], v) for k, v in values.items()})


# Every planner.* parameter is a field of PlannerSettings, in the table's order, of the spec's type.
assert [(f.name, f.type) for f in fields(PlannerSettings)] == [
    (key, spec.type.python_type.__name__) for key, spec in PLANNER_PARAMETERS.items()
]


class Termination:
    """When to stop: a deadline, a cancel event, or both (checked often by the planner)."""

    def __init__(self, time_limit_s: float | None = None, cancel: threading.Event | None = None) -> None:
        self.start = time.monotonic()
        self.deadline = None if time_limit_s is None else self.start + time_limit_s
        self.cancel = cancel

    def reason(self) -> Outcome | None:
        """``CANCELED``, ``TIME_LIMIT`` or ``None`` while planning may go on."""
        if self.cancel is not None and self.cancel.is_set():
            return Outcome.CANCELED
        if self.deadline is not None and time.monotonic() >= self.deadline:
            return Outcome.TIME_LIMIT
        return None

    def __call__(self) -> bool:
        return self.reason() is not None

    @property
    def elapsed(self) -> float:
        return time.monotonic() - self.start
