"""``clew_planners``: several ``clew_planner`` nodes in one process, each in a namespace with its own world.

    clew_planners [NAMESPACE:=WORLD.yaml ...] [--ros-args -p planner.time_limit:=10 --params-file MORE.yaml ...]

Each pair starts the node ``/<NAMESPACE>/clew_planner``, serving the
parameters of WORLD.yaml: the section ``clew_plan`` reads, whatever its node
key (``clew_planner:``, ``/**:``, ...), so the files of ``config/`` serve as
they are. Without pairs: the worlds ``figure1``, ``arm3_regrasp``,
``arm5_regrasp`` and ``single_transfer`` of ``config/``, each in a namespace
of its name. All nodes share one ``MultiThreadedExecutor``
(:func:`clew_ros.node.main.serve`: the same signals and exit codes as
``clew_planner``); each keeps its own parameters, its one-run-at-a-time
policy, its runs' threads and its recordings.

Parameters, weakest first: the world file; then the ``--ros-args``
parameters (``-p``, ``--params-file``), which apply to every node, as if
each were started with ``clew_planner --ros-args --params-file WORLD.yaml
<your --ros-args>``; a ``--params-file`` section keyed with a node's full
name (``/arm_a/clew_planner:``) reaches that node only.

Recordings: each node records into ``<record.directory>/<NAMESPACE>/<run
id>/`` (its ``record.directory`` parameter is declared so at start, fixed
like the node's; ``ros2 param get`` shows it). ``/tf`` and ``/tf_static`` are remapped into the namespace
(``/<NAMESPACE>/tf``), since every planner names its frames alike.

Exit codes: 0 after a clean shutdown; 2 when an argument or a world is
invalid (a message names it: the pair on stderr, a parameter in one error
log of its node).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import yaml
from rclpy.utilities import remove_ros_args

from clew_ros.node.main import serve
from clew_ros.node.namespaces import (
    PAIR_SEPARATOR,
    TF_REMAPPINGS,
    PlannerArgumentError,
    PlannerSpec,
    demo_pairs,
    parse_planner_pairs,
    world_parameters,
)
from clew_ros.node.planner_node import PlannerNode
from clew_ros.ros.parameters import default_world_file

__all__ = ["main", "node_arguments", "ros_parameter_arguments"]

#: ROS arguments that set parameters, each followed by its value; ``clew_planners`` gives them to every node.
PARAMETER_FLAGS = ("-p", "--param", "--params-file")
#: Remapping flags, and the remappings refused: each node's name and namespace are clew_planners' to give.
REMAP_FLAGS = ("-r", "--remap")
REFUSED_REMAPS = ("__ns:=", "__node:=", "__name:=")


def main(argv: list[str] | None = None) -> int:
    """Start the planners of the command line in one process; return the exit code (2: bad arguments)."""
    args = list(sys.argv if argv is None else argv)
    parser = _parser()
    options = parser.parse_args(remove_ros_args(args)[1:])
    try:
        _check_remaps(args)
        pairs = options.planners or demo_pairs(default_world_file().parent)
        specs = parse_planner_pairs(pairs)
        worlds = [world_parameters(spec) for spec in specs]
    except PlannerArgumentError as error:
        parser.error(str(error))  # exits 2
    parameter_args = ros_parameter_arguments(args)
    return serve(args, lambda: _build_planners(specs, worlds, parameter_args))


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="clew_planners",
        description="Several clew_planner nodes in one process, each in a namespace with its own world.",
        epilog="ROS arguments follow --ros-args; their parameters (-p, --params-file) apply to every node "
        "and win over the world files.",
    )
    parser.add_argument(
        "planners",
        nargs="*",
        metavar=f"NAMESPACE{PAIR_SEPARATOR}WORLD.yaml",
        help="a planner /NAMESPACE/clew_planner serving WORLD.yaml (default: figure1, arm3_regrasp, "
        "arm5_regrasp and single_transfer of config/, each in a namespace of its name)",
    )
    return parser


def _check_remaps(args: Sequence[str]) -> None:
    for flag, value in _ros_flag_values(args, REMAP_FLAGS):
        if value.startswith(REFUSED_REMAPS):
            raise PlannerArgumentError(
                f"--ros-args {flag} {value}: each planner's name and namespace come from its "
                f"NAMESPACE{PAIR_SEPARATOR}WORLD.yaml; expected no {value.split(':=')[0]} remapping"
            )


def ros_parameter_arguments(args: Sequence[str]) -> list[str]:
    """The parameter arguments of ``args``' ``--ros-args`` blocks (``-p X``, ``--param X``,
    ``--params-file F``), in order, ready to follow a node's world file in its own arguments."""
    return [token for pair in _ros_flag_values(args, PARAMETER_FLAGS) for token in pair]


def _ros_flag_values(args: Sequence[str], flags: Sequence[str]) -> list[tuple[str, str]]:
    """``(flag, value)`` for each of ``flags`` inside a ``--ros-args`` block of ``args`` (up to ``--``)."""
    found = []
    inside = False
    tokens = iter(args)
    for token in tokens:
        if token == "--ros-args":
            inside = True
        elif token == "--":
            inside = False
        elif inside and token in flags:
            value = next(tokens, None)
            if value is not None:
                found.append((token, value))
    return found


def node_arguments(world_file: Path, parameter_args: Sequence[str]) -> list[str]:
    """One node's own ROS arguments: its world file (keyed ``/**``), then the command line's parameters
    (later ones win), then the ``/tf`` remappings of :data:`~clew_ros.node.namespaces.TF_REMAPPINGS`."""
    remaps = [token for source, target in TF_REMAPPINGS for token in ("-r", f"{source}:={target}")]
    return ["--ros-args", "--params-file", str(world_file), *parameter_args, *remaps]


def _build_planners(
    specs: Sequence[PlannerSpec], worlds: Sequence[dict[str, Any]], parameter_args: Sequence[str]
) -> list[PlannerNode]:
    """One :class:`PlannerNode` per spec; on a :class:`StartupError` the nodes built so far are destroyed."""
    nodes: list[PlannerNode] = []
    try:
        # the world files are read as the nodes are created: the scratch copies can go right after
        with tempfile.TemporaryDirectory(prefix="clew_planners_") as scratch:
            for index, (spec, world) in enumerate(zip(specs, worlds, strict=True)):
                # keyed /** in the node's own arguments: it reaches this node, whatever its namespace
                world_file = Path(scratch) / f"planner_{index}.yaml"
                world_file.write_text(yaml.safe_dump({"/**": {"ros__parameters": world}}), encoding="utf-8")
                node = PlannerNode(
                    namespace=spec.namespace,
                    cli_args=node_arguments(world_file, parameter_args),
                    record_subdirectory=spec.namespace.strip("/"),
                )
                nodes.append(node)
                node.get_logger().info(
                    f"world file {spec.world_file}; recording directory {node.get_parameter('record.directory').value}"
                )
    except BaseException:  # StartupError (already logged) or anything else: no node is left behind
        for node in nodes:
            node.shutdown_runs()
            node.destroy_node()
        raise
    return nodes


if __name__ == "__main__":
    raise SystemExit(main())
