"""Security of spatial inputs: every crafted world of :mod:`helpers.security_spatial` is refused by ``clew_plan``
in its own process with exit 2, one line on stderr naming the cap or the reason, no traceback, no line of a
file it was made to open, within 10 s and 1.5 GB; the world loader refuses each with a
:class:`~clew_ros.core.errors.WorldError` before the work its cap bounds; the documented caps are those in force.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from helpers.security_spatial import CASES, SECRET, crafted_worlds

pytest.importorskip("trimesh")
pytest.importorskip("urdf_parser_py")

from clew_ros.cli.parameter_tables import limits_table
from clew_ros.core.errors import WorldError
from clew_ros.core.parameters import LIMITS, Limits
from clew_ros.planar.world import read_parameter_file
from clew_ros.spatial.scene import world_obstacles
from clew_ros.spatial.world import spatial_world_from_parameters

ROOT = Path(__file__).resolve().parents[2]
#: The issue's bounds: refused within 10 s (a process of its own, start-up included) and 1.5 GB.
TIMEOUT_S = 10.0
MAX_RSS_BYTES = 1.5 * 2**30


@pytest.fixture(scope="module")
def worlds(tmp_path_factory: pytest.TempPathFactory) -> list[tuple[str, Path, str]]:
    return list(crafted_worlds(tmp_path_factory.mktemp("crafted")))


@pytest.mark.parametrize("number", range(len(CASES)), ids=[name for name, _, _ in CASES])
def test_clew_plan_refuses_each_crafted_world(worlds: list[tuple[str, Path, str]], number: int, tmp_path: Path) -> None:
    _, world, expected = worlds[number]
    result = subprocess.run(
        [sys.executable, "-m", "clew_ros.cli.plan", str(world), "--output", str(tmp_path / "plan.json")],
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
        check=False,
        cwd=ROOT,
    )
    assert result.returncode == 2, result.stderr
    assert len(result.stderr.splitlines()) == 1, result.stderr
    assert result.stderr.startswith("clew_plan: "), result.stderr
    assert "Traceback" not in result.stderr
    assert expected in result.stderr, result.stderr
    assert SECRET not in result.stderr + result.stdout
    assert not (tmp_path / "plan.json").exists()


#: clew_plan's main in a process that prints its own peak resident set (kB) last.
MEASURED = (
    "import resource, sys\n"
    "from clew_ros.cli.plan import main\n"
    "code = main(sys.argv[1:])\n"
    "print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)\n"
    "sys.exit(code)\n"
)


def test_the_crafted_worlds_stay_within_the_memory_bound(worlds: list[tuple[str, Path, str]], tmp_path: Path) -> None:
    """Each refusal's process, from start to exit 2, peaks below 1.5 GB (its own ``ru_maxrss``)."""
    peaks = {}
    for name, world, _ in worlds:
        result = subprocess.run(
            [sys.executable, "-c", MEASURED, str(world), "--output", str(tmp_path / "plan.json")],
            capture_output=True,
            text=True,
            timeout=TIMEOUT_S,
            check=False,
            cwd=ROOT,
        )
        assert result.returncode == 2, (name, result.stderr)
        peaks[name] = int(result.stdout.split()[-1]) * 1024
    print("\npeak resident set (MB): " + ", ".join(f"{name} {peak / 2**20:.0f}" for name, peak in peaks.items()))
    assert max(peaks.values()) < MAX_RSS_BYTES, peaks


@pytest.mark.parametrize("number", range(len(CASES)), ids=[name for name, _, _ in CASES])
def test_the_loader_refuses_each_crafted_world_naming_the_parameter(
    worlds: list[tuple[str, Path, str]], number: int
) -> None:
    _, world, expected = worlds[number]
    with pytest.raises(WorldError) as caught:
        spatial_world_from_parameters(read_parameter_file(world), world.parent)
    text = str(caught.value)
    assert caught.value.parameter.startswith("world."), text
    assert expected in text, text
    assert "\n" not in text
    assert SECRET not in text


def test_a_scene_of_aliases_is_refused_before_any_obstacle_is_read(worlds: list[tuple[str, Path, str]]) -> None:
    """22,500 obstacles from a few kilobytes: the count is checked first, so a smaller cap changes nothing
    but the number (no obstacle was built: the refusal names no obstacle)."""
    _, world, _ = next(case for case in worlds if case[0].startswith("scene aliases"))
    scene = world.parent / "scene.yaml"
    assert scene.stat().st_size < 2_500
    with pytest.raises(WorldError, match=r"Limits\.max_scene_objects") as caught:
        world_obstacles({"scene_file": str(scene)}, world.parent)
    assert "primitives[" not in str(caught.value)


def test_duplicate_names_are_found_in_linear_time(tmp_path: Path) -> None:
    """4,000 distinct obstacles and two given twice: each repeated name is reported, once."""
    lines = ["world:", "  collision_objects:"]
    ids = [f"o{i}" for i in range(4000)] + ["o7", "o9"]
    lines += [
        f"    - {{id: {name}, primitives: [{{type: box, dimensions: [0.1, 0.1, 0.1]}}], "
        "primitive_poses: [{position: [2, 2, 2], orientation: [0, 0, 0, 1]}]}"
        for name in ids
    ]
    (tmp_path / "scene.yaml").write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.raises(WorldError, match=r"given twice: \['o7', 'o9'\]"):
        world_obstacles({"scene_file": str(tmp_path / "scene.yaml")}, tmp_path)


def test_a_fifo_is_refused_without_waiting_for_a_writer(tmp_path: Path) -> None:
    fifo = tmp_path / "scene.yaml"
    import os

    os.mkfifo(fifo)
    with pytest.raises(WorldError, match="not a regular file"):
        world_obstacles({"scene_file": str(fifo)}, tmp_path)


def test_the_spatial_caps_are_in_the_specification_with_units() -> None:
    table = limits_table()
    spatial = (
        ("max_parameter_file_bytes", "bytes"),
        ("max_urdf_bytes", "bytes"),
        ("max_mesh_file_bytes", "bytes"),
        ("max_mesh_triangles", "triangles"),
        ("max_total_triangles", "triangles"),
        ("max_mesh_scale", "factor"),
        ("max_urdf_links", "links"),
        ("max_urdf_elements", "elements"),
        ("max_mesh_cells", "cells"),
        ("max_split_triangles", "triangles"),
        ("max_solid_cells", "cells"),
        ("max_spheres", "spheres"),
        ("max_scene_file_bytes", "bytes"),
        ("max_scene_objects", "objects"),
        ("max_points", "points"),
    )
    for field, unit in spatial:
        assert f"| `{field}` | `{getattr(LIMITS, field)}` | {unit} |" in table
    assert LIMITS.max_points == Limits().max_points == 1_000_000  # interface.md 3c: state.max_points' default
    parameters = (ROOT / "docs" / "parameters.md").read_text(encoding="utf-8")
    assert table in parameters
    security = (ROOT / "docs" / "security.md").read_text(encoding="utf-8")
    for field, _ in spatial:
        assert f"`{field}`" in security, field


def test_the_shipped_arms_are_well_within_the_caps() -> None:
    """The caps refuse crafted worlds, not the shipped ones: each shipped spatial world loads."""
    for world in sorted((ROOT / "config" / "spatial").glob("*.yaml")):
        if world.name.endswith(".scene.yaml"):
            continue
        loaded = spatial_world_from_parameters(read_parameter_file(world), world.parent)
        assert loaded.spheres.count < LIMITS.max_spheres // 10


@pytest.mark.ros
def test_the_node_refuses_a_crafted_world_at_start_and_keeps_running_where_it_runs(
    worlds: list[tuple[str, Path, str]], tmp_path: Path
) -> None:
    """At start: the node does not start, logging the line clew_plan prints. Running (the development switch
    on): a change to a crafted URDF is refused with that reason, and the node keeps planning its world."""
    pytest.importorskip("rclpy")
    from helpers.node_harness import NodeProcess, Session
    from helpers.rel_node import set_parameters

    _, scaled, _ = worlds[0]  # the URDF's mesh scaled x30
    node = NodeProcess(tmp_path / "refused.log", scaled, {"record.enabled": False})
    try:
        code = node.proc.wait(timeout=60.0)
    finally:
        node.stop()
    assert code != 0
    assert "Limits.max_mesh_scale" in node.output(), node.output()
    assert SECRET not in node.output()

    crafted_urdf = str(scaled.parent / "robot.urdf")
    served = scaled.parent / "served.yaml"
    served.write_text(
        scaled.read_text(encoding="utf-8").replace(crafted_urdf, str(ROOT / "config/robots/panda/panda.urdf")),
        encoding="utf-8",
    )
    node = NodeProcess(
        tmp_path / "served.log", served, {"record.enabled": False, "parameters.allow_runtime_changes": True}
    )
    session = Session(node)
    try:
        [result] = set_parameters(session, {"world.robot.urdf": crafted_urdf}, timeout_s=60.0)
        assert not result.successful
        assert "Limits.max_mesh_scale" in result.reason, result.reason
        response = session.plan(timeout_s=60.0)
        assert response.success, response.message
    finally:
        assert session.close() == 0, node.output()
