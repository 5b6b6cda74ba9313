"""The modules of ``clew_ros`` import each other without a cycle.

Every module of the package is read with :mod:`ast` (nothing is imported):
each ``import clew_ros.x`` / ``from clew_ros.x import y`` / relative import,
at module level or inside a function, class, ``try`` or ``if`` (``if
TYPE_CHECKING:`` included), is an edge from the importing module to the
imported one (``from clew_ros.x import y`` goes to ``clew_ros.x.y`` when that
is a module, else to ``clew_ros.x``). A package (``__init__.py``) is a node
of its own whose edges are its own imports; importing ``clew_ros.x.y`` is not
counted as importing the package ``clew_ros.x`` (Python runs the package's
``__init__`` first, but a package importing its own submodules is no cycle of
the design). A cycle is printed module by module.

The same edges, read package by package (``clew_ros.<package>``), must point
down :data:`LAYERS`: a package imports only packages of lower rows, never one
of its own row or above, so the packages form a DAG whatever their modules do.
An edge that breaks the order is printed with the modules that make it.
"""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = "clew_ros"
ROOT = Path(__file__).resolve().parents[1] / PACKAGE

#: The packages of ``clew_ros``, lowest row first: a package may import the packages of the rows below its
#: own, nothing else (the packages of one row are independent of each other). Every package is placed here;
#: the root module ``clew_ros`` (the version) imports no package, and any package may import it.
LAYERS: tuple[tuple[str, ...], ...] = (
    ("core",),  # the Ariadne's Clew Algorithm; never imports rclpy
    ("planar", "spatial"),  # the kinds of world the algorithm plans in, side by side
    ("worlds", "motion"),  # clew_world's worlds; a plan timed and played back
    ("scene",),  # one description of what to draw (items, palette) for the picture, RViz and Foxglove
    ("ros",),  # ROS messages, QoS, topics, parameters, frames, URDF: message types, no node
    ("recording",),  # the rosbag2 MCAP writer and reader
    ("render",),  # PNG / GIF / SVG of a world, a plan or a recording
    ("kinds",),  # one adapter per kind of world: what the code above asks a world (a parameter file to a plan)
    ("batch", "live"),  # clew_batch (and its --record); the Foxglove live view
    ("node", "client"),  # the ROS 2 node; PlannerClient and call_plan
    ("cli", "examples"),  # the programs
)


def module_names() -> dict[str, Path]:
    """Dotted name -> file, for every module of the package."""
    modules = {}
    for path in sorted(ROOT.rglob("*.py")):
        parts = path.relative_to(ROOT.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        modules[".".join(parts)] = path
    return modules


def imports_of(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """The package modules ``name`` imports, anywhere in its file."""
    is_package = path.name == "__init__.py"
    package = name if is_package else name.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                source = ".".join(base + ([node.module] if node.module else []))
            else:
                source = node.module or ""
            targets = [
                f"{source}.{alias.name}" if f"{source}.{alias.name}" in modules else source for alias in node.names
            ]
        else:
            continue
        for imported in targets:
            # the longest prefix that is a module of the package (``import numpy.linalg`` has none)
            target = imported
            while target and target not in modules:
                target = target.rpartition(".")[0]
            if target.startswith(PACKAGE) and target != name:
                found.add(target)
    return found


def import_graph() -> dict[str, set[str]]:
    modules = module_names()
    return {name: imports_of(name, path, modules) for name, path in modules.items()}


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One cycle of ``graph`` as ``[a, b, ..., a]``, or ``None``."""
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for child in sorted(graph.get(node, ())):
            if state.get(child) == 1:
                return [*stack[stack.index(child) :], child]
            if child not in state:
                cycle = visit(child)
                if cycle:
                    return cycle
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state:
            cycle = visit(node)
            if cycle:
                return cycle
    return None


def test_the_graph_is_read() -> None:
    graph = import_graph()
    assert "clew_ros.core.explore" in graph["clew_ros.core.clew"]
    assert "clew_ros.core.clew" in graph["clew_ros.planar.space"]
    assert "clew_ros.planar.world" in graph["clew_ros.planar.collision"]
    assert "clew_ros.planar.kernel" in graph["clew_ros.planar.collision"]


def test_every_kind_of_import_is_an_edge(tmp_path: Path) -> None:
    source = tmp_path / "m.py"
    source.write_text(
        "import clew_ros.planar.kernel\n"
        "from clew_ros.planar import geometry\n"
        "from clew_ros.planar.world import World\n"
        "from . import search\n"
        "from ..motion import playback\n"
        "import numpy.linalg\n"
        "def late():\n"
        "    from clew_ros.planar.collision import is_valid\n"
        "    if True:\n"
        "        import clew_ros.planar.plan as plan\n",
        encoding="utf-8",
    )
    found = imports_of("clew_ros.planar.m", source, module_names())
    assert found == {
        "clew_ros.planar.kernel",
        "clew_ros.planar.geometry",
        "clew_ros.planar.world",
        "clew_ros.planar.search",
        "clew_ros.motion.playback",
        "clew_ros.planar.collision",
        "clew_ros.planar.plan",
    }


def test_find_cycle_finds_one() -> None:
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": set()}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None


def test_no_import_cycle() -> None:
    cycle = find_cycle(import_graph())
    assert cycle is None, "import cycle: " + " -> ".join(cycle or [])


def test_world_parsing_does_not_import_collision_checks() -> None:
    assert "clew_ros.planar.collision" not in import_graph()["clew_ros.planar.world"]


def package_of(module: str) -> str | None:
    """``node`` for ``clew_ros.node.worker`` and ``clew_ros.node``; ``None`` for the root module ``clew_ros``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else None


def layer_violations(graph: dict[str, set[str]], layers: tuple[tuple[str, ...], ...]) -> dict[str, list[str]]:
    """``"a -> b"`` for each package ``a`` importing a package ``b`` not in a lower row of ``layers``, with the
    module edges that make it; the root module imports no package."""
    row = {package: level for level, packages in enumerate(layers) for package in packages}
    found: dict[str, list[str]] = {}
    for module, imported in sorted(graph.items()):
        source = package_of(module)
        for target_module in sorted(imported):
            target = package_of(target_module)
            if target is None or target == source:
                continue  # the root, or the package's own modules
            if source is None or row[target] >= row[source]:
                found.setdefault(f"{source or PACKAGE} -> {target}", []).append(f"{module} -> {target_module}")
    return found


def test_every_package_has_its_row() -> None:
    packages = {package_of(name) for name in module_names()} - {None}
    placed = [package for row in LAYERS for package in row]
    assert len(placed) == len(set(placed)), "a package is in two rows of LAYERS"
    assert packages - set(placed) == set(), "place these packages in LAYERS"


def test_the_layering_check_finds_an_upward_and_a_sideways_import() -> None:
    graph = {
        "clew_ros.node.worker": {"clew_ros.ros.messages", "clew_ros.node.run", "clew_ros"},
        "clew_ros.node.call_plan": {"clew_ros.client"},
        "clew_ros.ros.messages": {"clew_ros.node.run"},
        "clew_ros": {"clew_ros.core"},
    }
    assert layer_violations(graph, LAYERS) == {
        "clew_ros -> core": ["clew_ros -> clew_ros.core"],
        "node -> client": ["clew_ros.node.call_plan -> clew_ros.client"],
        "ros -> node": ["clew_ros.ros.messages -> clew_ros.node.run"],
    }


def test_packages_import_only_lower_rows() -> None:
    wrong = layer_violations(import_graph(), LAYERS)
    assert not wrong, "imports against LAYERS:\n" + "\n".join(
        f"{edge}: {', '.join(modules)}" for edge, modules in wrong.items()
    )
