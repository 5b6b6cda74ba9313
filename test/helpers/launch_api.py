"""Stand-ins for the few ``launch`` / ``launch_ros`` classes the launch files use.

ROS 2 launch cannot be installed here (pip has no ``launch`` / ``launch_ros``),
so a launch file is run against these: each keeps the arguments it was given,
so that a test reads exactly what the file hands to launch (package,
executable, name, namespace, parameters, remappings, launch arguments). The
substitutions and conditions also evaluate as launch 3.4 (Jazzy) does
(``launch/substitutions/equals_substitution.py``,
``launch/conditions/evaluate_condition_expression_impl.py``), so that
:func:`started_nodes` tells which nodes a launch would start for given
arguments and with which parameter files. ``PythonExpression`` is not among
them: a launch file that imports it fails to load.
"""

from __future__ import annotations

import math
import runpy
import sys
import types
from pathlib import Path
from typing import Any

import pytest

Context = dict[str, str]


class Recorded:
    """A launch class stand-in: keeps its arguments."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self.args = args
        self.kwargs = kwargs


class LaunchConfiguration(Recorded):
    def perform(self, context: Context) -> str:
        return context[self.args[0]]


def perform(value: Any, context: Context) -> str:
    """A substitution, a plain string or a list of them, performed as launch's ``perform_substitutions``."""
    if isinstance(value, str):
        return value
    if isinstance(value, (list, tuple)):
        return "".join(perform(part, context) for part in value)
    return str(value.perform(context))


def _is_bool(text: str) -> bool:
    return text.lower() in ("true", "false", "1", "0")


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


class EqualsSubstitution(Recorded):
    def perform(self, context: Context) -> str:
        left, right = (perform(side, context) for side in self.args)
        if _is_bool(left) and _is_bool(right):
            return str((left.lower() in ("true", "1")) == (right.lower() in ("true", "1"))).lower()
        if _is_float(left) and _is_float(right):
            return str(math.isclose(float(left), float(right))).lower()
        return str(left == right).lower()


class NotEqualsSubstitution(EqualsSubstitution):
    def perform(self, context: Context) -> str:
        return str(super().perform(context) == "false").lower()


class IfCondition(Recorded):
    def evaluate(self, context: Context) -> bool:
        expression = perform(self.args[0], context).strip().lower()
        if expression in ("true", "1"):
            return True
        if expression in ("false", "0"):
            return False
        raise ValueError(f"invalid condition expression {expression!r}")


class UnlessCondition(IfCondition):
    def evaluate(self, context: Context) -> bool:
        return not super().evaluate(context)


def install(monkeypatch: pytest.MonkeyPatch, share_directory: Path) -> None:
    """Put the stand-ins in ``sys.modules``; the package's share directory is ``share_directory``."""
    modules = {
        "launch": {"LaunchDescription": type("LaunchDescription", (Recorded,), {})},
        "launch.actions": {
            "DeclareLaunchArgument": type("DeclareLaunchArgument", (Recorded,), {}),
            "OpaqueFunction": type("OpaqueFunction", (Recorded,), {}),
        },
        "launch.conditions": {"IfCondition": IfCondition, "UnlessCondition": UnlessCondition},
        "launch.substitutions": {
            "LaunchConfiguration": LaunchConfiguration,
            "EqualsSubstitution": EqualsSubstitution,
            "NotEqualsSubstitution": NotEqualsSubstitution,
        },
        "launch_ros": {},
        "launch_ros.actions": {"Node": type("Node", (Recorded,), {})},
    }
    for name, members in modules.items():
        module = types.ModuleType(name)
        module.__dict__.update(members)
        monkeypatch.setitem(sys.modules, name, module)
    import ament_index_python.packages

    monkeypatch.setattr(
        ament_index_python.packages, "get_package_share_directory", lambda _package: str(share_directory)
    )


def describe(path: Path) -> list[Recorded]:
    """The entities of the launch file's description."""
    description = runpy.run_path(str(path))["generate_launch_description"]()
    return list(description.args[0])


def of_type(entities: list[Recorded], name: str) -> list[Recorded]:
    return [e for e in entities if type(e).__name__ == name]


def started_nodes(path: Path, arguments: Context) -> list[tuple[Recorded, list[Any]]]:
    """The nodes a launch of ``path`` with ``arguments`` starts (their conditions hold), each with its
    ``parameters`` performed (a substitution becomes the text launch hands the node)."""
    entities = describe(path)
    context = {
        argument.args[0]: argument.kwargs.get("default_value", "")
        for argument in of_type(entities, "DeclareLaunchArgument")
    }
    context.update(arguments)
    nodes = of_type(entities, "Node")
    for function in of_type(entities, "OpaqueFunction"):
        nodes += of_type(list(function.kwargs["function"](context)), "Node")
    started = []
    for node in nodes:
        condition = node.kwargs.get("condition")
        if condition is None or condition.evaluate(context):
            parameters = [p if isinstance(p, dict) else perform(p, context) for p in node.kwargs.get("parameters", [])]
            started.append((node, parameters))
    return started
