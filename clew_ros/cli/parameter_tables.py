"""``python -m clew_ros.cli.parameter_tables [--update FILE | --check FILE]``: docs/parameters.md's tables.

The tables are generated from the one parameter specification
(:mod:`clew_ros.core.parameters`, :mod:`clew_ros.spatial.parameters`, :mod:`clew_ros.ros.node_parameters`):
:func:`markdown_tables` (``world``, ``spatial_world``, ``planner``, ``node``) and the caps (``limits``). Without
options they are printed; with ``--update docs/parameters.md`` they are rewritten between their markers; with
``--check docs/parameters.md`` the exit code is 1 when they are out of date.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import re
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from clew_ros.core.parameters import (
    KIND_PARAMETER,
    LIMITS,
    OBSTACLE_PARAMETER,
    PLANNER_PARAMETERS,
    REQUIRED,
    WORLD_PARAMETERS,
    Limits,
    ParameterSpec,
)
from clew_ros.ros.node_parameters import NODE_PARAMETERS
from clew_ros.spatial.parameters import SPATIAL_OBSTACLE_PARAMETERS, SPATIAL_WORLD_PARAMETERS

__all__ = ["limits_table", "main", "markdown_tables", "marked_tables", "update_markdown"]

_BEGIN = (
    "<!-- BEGIN generated parameter table: {} (python -m clew_ros.cli.parameter_tables --update docs/parameters.md) -->"
)
_END = "<!-- END generated parameter table: {} -->"


def _cell(value: Any) -> str:
    """A default or a limit as docs/parameters.md shows it (``pi`` for math.pi, YAML's ``true``/``false``)."""
    if value is REQUIRED:
        return "required"
    if value is None:
        return "none"
    if isinstance(value, bool):
        return f"`{str(value).lower()}`"
    if isinstance(value, float) and value == math.pi:
        return "`pi`"
    return f"`{value}`"


def _bound(value: float) -> str:
    """An end of a range: ``pi`` and ``2 pi`` for the angles, else as Python writes it."""
    return {math.pi: "pi", 2.0 * math.pi: "2 pi"}.get(value, str(value))


def _literal(text: str) -> str:
    return text.replace("|", "\\|").replace("<", "\\<")  # literal, not HTML


def _rows(specs: Iterable[ParameterSpec], *, ranges: bool) -> list[str]:
    rows = []
    for spec in specs:
        cells = [f"`{spec.name}`", spec.type.value, _cell(spec.default), spec.unit]
        if ranges:
            cells.append(f"[{_bound(spec.limits[0])}, {_bound(spec.limits[1])}]" if spec.limits else "")
        cells.append(spec.at_run_time)
        cells.append(_literal(spec.description))
        rows.append("| " + " | ".join(cells) + " |")
    return rows


def limits_table() -> str:
    """The caps of :data:`LIMITS` as a Markdown table: the field, its value, what it caps."""
    rows = ["| limit | value | unit | caps |", "|---|---|---|---|"]
    rows.extend(
        f"| `{field.name}` | `{getattr(LIMITS, field.name)}` | {_LIMIT_UNIT[field.name]} | "
        f"{_literal(_LIMIT_TEXT[field.name])} |"
        for field in dataclasses.fields(Limits)
    )
    return "\n".join(rows)


#: What docs/parameters.md says each cap limits (the comments of :class:`Limits` say why).
_LIMIT_TEXT = {
    "max_links": "links of the robot (world.robot.link_lengths)",
    "max_obstacles": "obstacles (world.obstacle_names)",
    "max_polygon_vertices": "vertices of one polygon (world.obstacles.<name>, world.object.polygon)",
    "max_world_vertices": "vertices of all the world's polygons together",
    "max_grasps": "grasps (world.object.grasps)",
    "max_parameters": "parameters one node holds, at start and after a change",
    "max_name_chars": "characters of a parameter name, an obstacle name or world.name",
    "max_string_chars": "characters of a string parameter (record.directory)",
    "max_quoted_chars": "characters of a ~/goal_pose frame_id quoted in logs and events (printable only)",
    "max_parameter_file_bytes": "size of a parameter file, before it is parsed",
    "max_urdf_bytes": "size of a URDF or SRDF (world.robot.urdf, .description, .srdf), before it is parsed",
    "max_mesh_file_bytes": "size of one mesh file a URDF names, before it is read",
    "max_mesh_triangles": "triangles of one mesh",
    "max_total_triangles": "triangles of all the robot's meshes",
    "max_mesh_scale": "each factor of a URDF <mesh scale>",
    "max_urdf_links": "links, and joints, of a URDF",
    "max_urdf_elements": "XML elements of a URDF, counted before the URDF parser reads it",
    "max_mesh_cells": "cells of one mesh's voxel grid for the sphere model (from its extent, before voxelising)",
    "max_split_triangles": "triangles of one mesh split to the voxel size (estimated before splitting)",
    "max_solid_cells": "cells of one mesh's voxelised solid the sphere cover chooses among",
    "max_spheres": "spheres of the robot's sphere model",
    "max_scene_file_bytes": "size of a planning scene file (world.scene_file), before it is parsed",
    "max_scene_objects": "primitives of a planning scene's collision objects, counted after YAML aliases expand",
    "max_points": "points of one ~/points cloud (the highest state.max_points)",
    "max_recorded_refusals": "refused requests recorded in the current run's recording (the rest: published only)",
}
#: The unit of each cap.
_LIMIT_UNIT = {
    "max_links": "links",
    "max_obstacles": "obstacles",
    "max_polygon_vertices": "vertices",
    "max_world_vertices": "vertices",
    "max_grasps": "grasps",
    "max_parameters": "parameters",
    "max_name_chars": "characters",
    "max_string_chars": "characters",
    "max_quoted_chars": "characters",
    "max_parameter_file_bytes": "bytes",
    "max_urdf_bytes": "bytes",
    "max_mesh_file_bytes": "bytes",
    "max_mesh_triangles": "triangles",
    "max_total_triangles": "triangles",
    "max_mesh_scale": "factor",
    "max_urdf_links": "links",
    "max_urdf_elements": "elements",
    "max_mesh_cells": "cells",
    "max_split_triangles": "triangles",
    "max_solid_cells": "cells",
    "max_spheres": "spheres",
    "max_scene_file_bytes": "bytes",
    "max_points": "points",
    "max_scene_objects": "objects",
    "max_recorded_refusals": "events",
}
assert set(_LIMIT_UNIT) == set(_LIMIT_TEXT)
assert list(_LIMIT_TEXT) == [field.name for field in dataclasses.fields(Limits)]


def _with_obstacles(specs: Iterable[ParameterSpec], obstacles: Iterable[ParameterSpec]) -> list[ParameterSpec]:
    """``specs`` with the obstacles' pattern rows after ``world.obstacle_names``."""
    out = list(specs)
    at = next(i for i, spec in enumerate(out) if spec.name == "world.obstacle_names") + 1
    return out[:at] + list(obstacles) + out[at:]


def markdown_tables() -> dict[str, str]:
    """docs/parameters.md's tables, by name (``world``, ``spatial_world``, ``planner``, ``node``): Markdown, a
    line per parameter.

    The column "at run time" says whether ``ros2 param set`` may change the parameter while the node runs:
    ``settable``; ``fixed`` (taken at start); ``fixed (dev switch)``: fixed unless the node was started
    with ``parameters.allow_runtime_changes: true``.
    """
    world_header = ["| name | type | default | unit | at run time | meaning |", "|---|---|---|---|---|---|"]
    ranged_header = [
        "| name | type | default | unit | range | at run time | meaning |",
        "|---|---|---|---|---|---|---|",
    ]
    world = _with_obstacles([KIND_PARAMETER, *WORLD_PARAMETERS.values()], [OBSTACLE_PARAMETER])
    spatial = _with_obstacles(SPATIAL_WORLD_PARAMETERS.values(), SPATIAL_OBSTACLE_PARAMETERS.values())
    return {
        "world": "\n".join(world_header + _rows(world, ranges=False)),
        "spatial_world": "\n".join(ranged_header + _rows(spatial, ranges=True)),
        "planner": "\n".join(ranged_header + _rows(PLANNER_PARAMETERS.values(), ranges=True)),
        "node": "\n".join(ranged_header + _rows(NODE_PARAMETERS.values(), ranges=True)),
    }


def _optional_tables() -> dict[str, str]:
    """Tables :func:`update_markdown` rewrites only where their markers are (``limits``)."""
    return {"limits": limits_table()}


def update_markdown(text: str) -> str:
    """``text`` (docs/parameters.md) with each generated table between its markers replaced by :func:`markdown_tables`.

    Raises :class:`ValueError` when a table's markers are missing.
    """
    for name, table in markdown_tables().items():
        begin, end = _BEGIN.format(name), _END.format(name)
        match = re.search(re.escape(begin) + r"\n.*?" + re.escape(end), text, re.DOTALL)
        if match is None:
            raise ValueError(f"no generated table '{name}': expected a line {begin!r}, the table, then {end!r}")
        text = f"{text[: match.start()]}{begin}\n{table}\n{end}{text[match.end() :]}"
    for name, table in _optional_tables().items():
        begin, end = _BEGIN.format(name), _END.format(name)
        match = re.search(re.escape(begin) + r"\n.*?" + re.escape(end), text, re.DOTALL)
        if match is not None:
            text = f"{text[: match.start()]}{begin}\n{table}\n{end}{text[match.end() :]}"
    return text


def marked_tables() -> str:
    """Every generated table between its markers, as :func:`update_markdown` finds them."""
    tables = {**markdown_tables(), **_optional_tables()}
    return "\n".join(f"{_BEGIN.format(name)}\n{table}\n{_END.format(name)}\n" for name, table in tables.items())


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m clew_ros.cli.parameter_tables", description=__doc__.split("\n")[0])
    parser.add_argument("--update", metavar="FILE", type=Path, help="rewrite the generated tables of FILE in place")
    parser.add_argument("--check", metavar="FILE", type=Path, help="exit 1 when the tables of FILE are out of date")
    args = parser.parse_args(argv)
    if args.update is None and args.check is None:
        print(marked_tables())
        return 0
    path = args.update or args.check
    text = path.read_text(encoding="utf-8")
    try:
        updated = update_markdown(text)
    except ValueError as error:
        print(f"{path}: {error}", file=sys.stderr)
        return 2
    if args.check is not None:
        if updated != text:
            print(
                f"{path}: the parameter tables are out of date; run "
                f"python -m clew_ros.cli.parameter_tables --update {path}",
                file=sys.stderr,
            )
            return 1
        return 0
    if updated != text:
        path.write_text(updated, encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
