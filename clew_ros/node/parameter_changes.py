"""Which parameter changes the node refuses before it checks their values, and its own parameters' values.

:func:`locked_or_over_caps` refuses a parameter fixed at start (``LOCKED_PREFIXES``, ``planner.*`` when
``parameters.lock_planner``, ``use_sim_time``) and names beyond the caps; :func:`unknown_parameter` a name the
node does not take. The values themselves are checked by :mod:`clew_ros.ros.parameters`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

from rclpy.node import Node
from rclpy.parameter import Parameter

from clew_ros.core.errors import ParameterError
from clew_ros.core.parameters import RETIRED_PARAMETERS, retired_message
from clew_ros.ros.node_parameters import LOCKED_PREFIXES, PLANNER_LOCK, RUNTIME_CHANGES, SIM_TIME_CHANGES
from clew_ros.ros.parameters import (
    OWN_PREFIXES,
    NodeSettings,
    check_parameter_names,
    descriptor_for,
    is_spatial,
    plain_value,
)

__all__ = ["declare_all", "locked_or_over_caps", "own_values", "unknown_parameter"]


def locked_or_over_caps(parameters: Sequence[Parameter], node: NodeSettings, declared: set[str]) -> str | None:
    """Why a change is refused before it is checked: a parameter fixed at start, or too many or too long
    names (``declared``: the names the node holds now); ``None`` if neither.

    A declared locked parameter is read-only, so rclpy refused it already; this refuses the others: a
    new name under a locked prefix (an obstacle, while the switch is off), and names beyond the caps.
    """
    for p in parameters:
        if not node.allow_runtime_changes and p.name.startswith(LOCKED_PREFIXES):
            return (
                f"{p.name}: fixed at start, like every {', '.join(x + '*' for x in LOCKED_PREFIXES)} "
                f"parameter (start the node with {RUNTIME_CHANGES}: true to change them at run time)"
            )
        if node.lock_planner and p.name.startswith("planner."):
            return f"{p.name}: fixed at start, like every planner.* parameter ({PLANNER_LOCK} is true)"
        if p.name == "use_sim_time" and not node.allow_sim_time_changes:
            return (
                f"use_sim_time: fixed at start (start the node with {SIM_TIME_CHANGES}: true to change it at run time)"
            )
    names = declared | {p.name for p in parameters if p.type_ != Parameter.Type.NOT_SET}
    try:
        check_parameter_names(names)
    except ParameterError as error:
        return f"{error}; nothing was changed"
    return None


def unknown_parameter(parameters: Sequence[Parameter], has_parameter: Callable[[str], bool]) -> str | None:
    """Why a change is refused when it names a parameter the node neither takes nor holds; ``None`` if none."""
    for p in parameters:
        if not p.name.startswith(OWN_PREFIXES) and not has_parameter(p.name):
            return f"{p.name}: unknown parameter; clew_planner takes " + ", ".join(
                prefix + "*" for prefix in OWN_PREFIXES
            )
    return None


def own_values(node: Node) -> dict[str, Any]:
    """Current values of ``node``'s own parameters (:data:`~clew_ros.ros.parameters.OWN_PREFIXES`), by full
    name."""
    values = {}
    for prefix in OWN_PREFIXES:
        group = prefix.rstrip(".")
        for name, parameter in node.get_parameters_by_prefix(group).items():
            # rclpy annotates the values, but they are Parameter objects
            values[f"{group}.{name}"] = plain_value(parameter.value)  # type: ignore[union-attr]
    return values


def declare_all(
    node: Node,
    values: Mapping[str, Any],
    overrides: Mapping[str, Any],
    *,
    allow_runtime_changes: bool,
    lock_planner: bool,
) -> None:
    """Declare every parameter of ``values`` on ``node`` with its descriptor (a retired one: a warning).

    The ``overrides`` (``--params-file`` / ``-p``) are declared already, typed by their value; they get their
    descriptor here. The others are declared with their start values.
    """
    spatial = is_spatial(values)  # a spatial world's world.* are described by the spatial world's specification
    for name, value in values.items():
        if name in RETIRED_PARAMETERS:
            node.get_logger().warning(retired_message(name))
            continue
        descriptor = descriptor_for(
            name, spatial=spatial, allow_runtime_changes=allow_runtime_changes, lock_planner=lock_planner
        )
        if name in overrides and plain_value(node.get_parameter(name).value) == value:
            node.set_descriptor(name, descriptor)
        else:  # not given, or given and changed here (record.directory); an empty list has no parameter type
            if node.has_parameter(name):
                node.undeclare_parameter(name)
            node.declare_parameter(name, None if value == [] else value, descriptor, ignore_override=True)
