"""Planner settings (``planner.*`` parameters), outcomes and termination conditions."""

from __future__ import annotations

import enum
import threading
import time
from dataclasses import dataclass, fields
from typing import Any, Mapping

from clew_ros.core.errors import ParameterError
from clew_ros.core.genetic import GeneticSettings

__all__ = ["PlannerSettings", "Outcome", "Termination", "PLANNER_PARAMETERS"]


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

    @property
    def succeeded(self) -> bool:
        return self is Outcome.SUCCEEDED


#: name -> (type, default, description, (min, max) or None)
PLANNER_PARAMETERS: dict[str, tuple[type, Any, str, tuple | None]] = {
    "seed": (int, 0, "Seed of the random generator; same seed, same plan.", (0, 2**31 - 1)),
    "time_limit": (float, 30.0, "Seconds before the planner stops and reports TIME_LIMIT.", (0.01, 86400.0)),
    "resolution": (float, 0.01, "EXPLORE stops with NO_PATH_AT_RESOLUTION when a new landmark is closer "
                   "than this to the others (landmark-distance units, m).", (1e-6, 10.0)),
    "clearance": (float, 0.001, "Clearance (m) every planned configuration keeps from what it could hit; "
                  "bounds the motion between checks so plans stay valid at any finer check.", (1e-6, 0.1)),
    "manhattan_order": (int, 2, "Order k of the Manhattan paths optimised (k single paths of n moves).", (1, 8)),
    "population": (int, 24, "Genetic algorithm population size.", (4, 10000)),
    "generations": (int, 12, "Genetic algorithm generations per optimisation.", (1, 10000)),
    "explore_candidates": (int, 4, "Landmark/grasp pairs (m1) tried per EXPLORE step.", (1, 1000)),
    "search_rounds": (int, 3, "Rounds of SEARCH's do-while loop before it gives up.", (1, 100)),
    "joint_weight": (float, 0.1, "Weight (m/rad) of the joint angles in the landmark distance.", (0.0, 10.0)),
    "max_sweep_steps": (int, 48, "Unused: free intervals are closed-form; kept so that parameter files that set it "
                        "still load.", (2, 10000)),
    "threads": (int, 0, "Threads that decode a population's Manhattan paths (0: all cores); the plan does not "
                "depend on it.", (0, 1024)),
}


@dataclass(frozen=True)
class PlannerSettings:
    """Tuning of the planner; see :data:`PLANNER_PARAMETERS` for meanings and units."""

    seed: int = 0
    time_limit: float = 30.0
    resolution: float = 0.01
    clearance: float = 0.001
    manhattan_order: int = 2
    population: int = 24
    generations: int = 12
    explore_candidates: int = 4
    search_rounds: int = 3
    joint_weight: float = 0.1
    max_sweep_steps: int = 48
    threads: int = 0

    @property
    def genetic(self) -> GeneticSettings:
        return GeneticSettings(population=self.population, generations=self.generations)

    @classmethod
    def from_parameters(cls, parameters: Mapping[str, Any], **overrides: Any) -> "PlannerSettings":
        """From a ``ros__parameters`` tree (its ``planner`` key); ``overrides`` win."""
        tree = parameters.get("planner") or {}
        if not isinstance(tree, Mapping):
            raise ParameterError("planner", f"expected a mapping, got {tree!r}")
        values: dict[str, Any] = {}
        for key, value in tree.items():
            if key not in PLANNER_PARAMETERS:
                raise ParameterError(f"planner.{key}", f"unknown parameter; known: {', '.join(PLANNER_PARAMETERS)}")
            values[key] = value
        values.update({k: v for k, v in overrides.items() if v is not None})
        return cls(**{k: check_planner_parameter(k, v) for k, v in values.items()})


def check_planner_parameter(name: str, value: Any) -> Any:
    """Validate one ``planner.<name>`` value; returns it converted, raises :class:`ParameterError`."""
    kind, _default, _description, limits = PLANNER_PARAMETERS[name]
    full = f"planner.{name}"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(full, f"expected {'an integer' if kind is int else 'a number'}, got {_short(value)}")
    if kind is int and (isinstance(value, float) and not value.is_integer()):
        raise ParameterError(full, f"expected an integer, got {value!r}")
    try:
        converted = kind(value)
    except OverflowError:  # an integer too large for a float
        converted = None
    if converted is None or converted != converted or (limits and not limits[0] <= converted <= limits[1]):
        raise ParameterError(full, f"expected a value in [{limits[0]}, {limits[1]}], got {_short(value)}")
    return converted


def _short(value: Any, limit: int = 60) -> str:
    """``repr(value)`` cut to ``limit`` characters (a 400-digit integer is not a message)."""
    try:
        text = repr(value)
    except ValueError:  # an integer of more digits than Python converts to text
        return f"an integer of {value.bit_length()} bits"
    return text if len(text) <= limit else text[:limit - 3] + "..."


assert [f.name for f in fields(PlannerSettings)] == list(PLANNER_PARAMETERS)


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
