"""Several planners in namespaces: which world each one serves and where it records (no rclpy).

``clew_planners`` (:mod:`clew_ros.node.multi`) and
``launch/clew_planners.launch.py`` both take a list of
``NAMESPACE:=WORLD.yaml`` pairs: one ``clew_planner`` node per pair, named
``/<NAMESPACE>/clew_planner``, serving the world file's parameters. This
module reads those pairs (:func:`parse_planner_pairs`), the world file of
each (:func:`world_parameters`: the section ``clew_plan`` reads, whatever
its node key, since a ``clew_planner:`` key would not reach a node in a
namespace) and gives each planner a recording directory of its own
(:func:`namespaced_directory`: ``<record.directory>/<NAMESPACE>``), so that
planners that share a ``record.directory`` never share a directory.

Errors are :class:`PlannerArgumentError`, naming the argument at fault and
what was expected.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from clew_ros.core.errors import ClewError
from clew_ros.ros.node_parameters import NODE_PARAMETERS
from clew_ros.ros.spatial import resolved_parameters

__all__ = [
    "DEMO_WORLDS",
    "PAIR_SEPARATOR",
    "TF_REMAPPINGS",
    "PlannerArgumentError",
    "PlannerSpec",
    "demo_pairs",
    "launch_parameters",
    "namespaced_directory",
    "parse_planner_pairs",
    "world_parameters",
]

#: Between a namespace and its world file: ``arm_a:=config/figure1.yaml``.
PAIR_SEPARATOR = ":="
#: The worlds of ``config/`` served when no pair is given, each in a namespace named after it.
DEMO_WORLDS = ("figure1", "arm3_regrasp", "arm5_regrasp", "single_transfer")
#: Each planner's ``/tf`` and ``/tf_static`` go into its namespace (``/<NAMESPACE>/tf``), as multi-robot
#: launch files do (Nav2's among them): every planner names its frames ``world``, ``link_1``, ...
TF_REMAPPINGS = (("/tf", "tf"), ("/tf_static", "tf_static"))

# A ROS 2 namespace: tokens of letters, digits and underscores, not starting with a digit, joined by '/'.
_TOKEN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


class PlannerArgumentError(ClewError, ValueError):
    """A ``NAMESPACE:=WORLD.yaml`` argument is invalid; the message names it and says what was expected."""


@dataclass(frozen=True)
class PlannerSpec:
    """One planner to start: its namespace (absolute, ``/arm_a``) and the world file it serves."""

    namespace: str
    world_file: Path

    @property
    def node_name(self) -> str:
        """The planner's fully qualified node name, ``/<namespace>/clew_planner``."""
        return f"{self.namespace}/clew_planner"


def parse_planner_pairs(arguments: Iterable[str]) -> list[PlannerSpec]:
    """``["arm_a:=a.yaml", "arm_b:=b.yaml"]`` -> one :class:`PlannerSpec` per argument, in order.

    A namespace may be nested (``robots/arm_a``) and may start with ``/``;
    namespaces must differ. The world files are not read here. Raises
    :class:`PlannerArgumentError` naming the argument at fault.
    """
    specs: list[PlannerSpec] = []
    seen: dict[str, str] = {}
    for argument in arguments:
        namespace_text, separator, file_text = argument.partition(PAIR_SEPARATOR)
        if not separator or not file_text:
            raise PlannerArgumentError(f"{argument!r}: expected NAMESPACE{PAIR_SEPARATOR}WORLD.yaml")
        namespace = _namespace(argument, namespace_text)
        if namespace in seen:
            raise PlannerArgumentError(
                f"{argument!r}: namespace {namespace} is given twice (also by {seen[namespace]!r}); "
                "expected one planner per namespace"
            )
        seen[namespace] = argument
        specs.append(PlannerSpec(namespace, Path(file_text)))
    return specs


def _namespace(argument: str, text: str) -> str:
    tokens = text.strip("/").split("/") if text.strip("/") else []
    if not tokens or not all(_TOKEN.fullmatch(token) and "__" not in token for token in tokens):
        raise PlannerArgumentError(
            f"{argument!r}: expected a namespace of names made of letters, digits and single underscores, "
            f"not starting with a digit, joined by '/' (like arm_a or robots/arm_a), got {text!r}"
        )
    return "/" + "/".join(tokens)


def demo_pairs(config_directory: Path) -> list[str]:
    """The pairs served when none is given: each world of :data:`DEMO_WORLDS` in a namespace of its name."""
    return [f"{name}{PAIR_SEPARATOR}{config_directory / (name + '.yaml')}" for name in DEMO_WORLDS]


def world_parameters(spec: PlannerSpec) -> dict[str, Any]:
    """The parameter tree of ``spec``'s world file (its ``ros__parameters``, as ``clew_plan`` reads them: the
    files a spatial world names, ``world.robot.urdf``, ``world.robot.srdf`` and ``world.scene_file``, made
    absolute relative to the world file's folder, not the process's working directory).

    Raises :class:`PlannerArgumentError` naming the argument when the file
    cannot be read; the values themselves are checked by the node.
    """
    try:
        return resolved_parameters(spec.world_file)
    except ClewError as error:
        raise PlannerArgumentError(f"{spec.namespace.lstrip('/')}{PAIR_SEPARATOR}{spec.world_file}: {error}") from None


def namespaced_directory(directory: str, namespace: str) -> str:
    """``directory`` with the namespace's path appended: ``("~/runs", "/robots/arm_a")`` -> ``~/runs/robots/arm_a``.

    ``~`` is left for the node to expand (as in ``record.directory``).
    """
    return f"{directory.rstrip('/')}/{namespace.strip('/')}"


def launch_parameters(spec: PlannerSpec, record_directory: str = "") -> dict[str, Any]:
    """The parameters ``launch/clew_planners.launch.py`` gives ``spec``'s planner: its world file's, with
    ``record.directory`` set to ``<base>/<namespace>``.

    ``base`` is ``record_directory`` when given (the launch argument), else
    the world file's ``record.directory``, else the node's default.
    """
    parameters = world_parameters(spec)
    record = parameters.get("record")
    record = dict(record) if isinstance(record, dict) else {}
    base = record_directory or record.get("directory") or NODE_PARAMETERS.default("record.directory")
    record["directory"] = namespaced_directory(str(base), spec.namespace)
    return {**parameters, "record": record}
