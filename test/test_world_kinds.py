"""Above the kinds of world, code asks a world's kind (:mod:`clew_ros.kinds`) and never tells kinds apart itself.

Every module of ``clew_ros`` outside the kinds' own packages is read with :mod:`ast` (nothing of it is run):
no ``isinstance(x, World)`` / ``isinstance(x, SpatialWorld)`` (or on their offline problems) and no kind name
(``"planar"``, ``"spatial"``) written as a string in code (docstrings aside). The kinds' own packages are
``core`` (the plan format names its pose widths), ``planar``, ``spatial``, ``kinds`` (the adapters) and
``worlds`` (each generator writes the worlds of its kind). A toy third kind registers and is found.
"""

from __future__ import annotations

import ast
import threading
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from clew_ros import kinds
from clew_ros.core.errors import WorldError
from clew_ros.core.plan import Plan
from clew_ros.kinds import WorldKind

ROOT = Path(__file__).resolve().parents[1] / "clew_ros"

#: Packages that are a kind (or its adapter, or the plan format): they may name kinds.
KIND_PACKAGES = frozenset({"core", "planar", "spatial", "kinds", "worlds"})

#: The classes of the worlds (and of their offline problems) of the registered kinds.
WORLD_CLASSES = frozenset(
    cls.__name__
    for name in kinds.kinds()
    for cls in (kinds.kind_named(name).world_type, kinds.kind_named(name).problem_type)
)


def _modules_above() -> list[Path]:
    return [path for path in sorted(ROOT.rglob("*.py")) if path.relative_to(ROOT).parts[0] not in KIND_PACKAGES]


def _docstrings(tree: ast.AST) -> set[int]:
    """The ids of the string constants that are docstrings (or bare string statements)."""
    return {
        id(node.value)
        for node in ast.walk(tree)
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) and isinstance(node.value.value, str)
    }


def _names(node: ast.AST) -> set[str]:
    return {n.id for n in ast.walk(node) if isinstance(n, ast.Name)} | {
        n.attr for n in ast.walk(node) if isinstance(n, ast.Attribute)
    }


def _kind_checks(path: Path, text: str | None = None) -> list[str]:
    """What ``path`` (or ``text``, read as if it were ``path``) does to tell world kinds apart."""
    source = path.read_text(encoding="utf-8") if text is None else text
    tree = ast.parse(source, filename=str(path))
    docstrings = _docstrings(tree)
    where = path.relative_to(ROOT.parent)
    found = []
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name)
            and node.func.id == "isinstance"
            and len(node.args) == 2
            and _names(node.args[1]) & WORLD_CLASSES
        ):
            found.append(f"{where}:{node.lineno}: isinstance on a world kind: {ast.unparse(node)}")
        if isinstance(node, ast.Constant) and node.value in kinds.kinds() and id(node) not in docstrings:
            found.append(f"{where}:{node.lineno}: the kind name {node.value!r} written above the adapters")
    return found


def test_the_scan_sees_the_modules_above_the_adapters() -> None:
    names = {path.relative_to(ROOT).parts[0] for path in _modules_above()}
    assert {"node", "live", "batch", "client", "cli", "render", "ros", "recording"} <= names
    assert {"planar", "spatial", "kinds"}.isdisjoint(names)


def test_no_module_above_the_adapters_tells_world_kinds_apart() -> None:
    found = [line for path in _modules_above() for line in _kind_checks(path)]
    assert not found, "ask clew_ros.kinds (kind_of, kind_named) instead:\n" + "\n".join(found)


def test_the_scan_finds_what_it_forbids(tmp_path: Path) -> None:
    """The check is no stub: a module that tells a kind apart is caught, each way."""
    module = tmp_path / "bad.py"
    module.write_text(
        '"""planar"""\n'
        "def f(world, kind):\n"
        "    if isinstance(world, (World, int)):\n"
        '        return kind == "spatial"\n'
        "    return isinstance(world, planar.SpatialWorld)\n",
        encoding="utf-8",
    )
    module_under_root = ROOT / "cli" / "bad.py"  # where the scan reports it from
    found = _kind_checks(module_under_root, module.read_text(encoding="utf-8"))
    assert len(found) == 3
    assert sum("isinstance" in line for line in found) == 2
    assert any("'spatial'" in line for line in found)


# --------------------------------------------------------------------------- the registry


@dataclass(frozen=True, eq=False)
class ToyWorld:
    """A point on a line: the whole world of the toy kind."""

    name: str
    start: float
    goal: float


@dataclass(frozen=True)
class ToyProblem:
    world: ToyWorld
    settings: object


class ToyKind(WorldKind):
    """A third kind of world, registered by a test: what a new kind's package adds."""

    name = "toy_line"
    world_type = ToyWorld
    problem_type = ToyProblem

    def problem_from_parameters(self, parameters, folder, *, seed=None, time_limit=None, improve_time=None):  # type: ignore[no-untyped-def]
        tree = parameters["world"]
        return ToyProblem(ToyWorld(tree.get("name", "toy"), float(tree["start"]), float(tree["goal"])), None)

    def warm_up(self, problem):  # type: ignore[no-untyped-def]
        return 0.0

    def plan_problem(self, problem, *, cancel: threading.Event | None = None, progress=None) -> Plan:  # type: ignore[no-untyped-def]
        raise NotImplementedError

    def failed_plan(self, problem, message, elapsed_s):  # type: ignore[no-untyped-def]
        raise NotImplementedError

    def plan(self, world, settings, *, goal, termination, progress):  # type: ignore[no-untyped-def]
        raise NotImplementedError

    def checked_plan(self, world, result):  # type: ignore[no-untyped-def]
        raise NotImplementedError

    def root_tree(self, world):  # type: ignore[no-untyped-def]
        raise NotImplementedError

    def default_goal(self, world):  # type: ignore[no-untyped-def]
        return np.array([world.goal])

    def with_goal(self, world, goal):  # type: ignore[no-untyped-def]
        return ToyWorld(world.name, world.start, float(goal[0]))

    def goal_from_pose_stamped(self, msg, world):  # type: ignore[no-untyped-def]
        return np.array([msg.pose.position.x])

    def goal_message(self, world, goal, time_ns):  # type: ignore[no-untyped-def]
        return None

    def landmark_markers(self, world, landmarks, time_ns):  # type: ignore[no-untyped-def]
        raise NotImplementedError

    def track(self, world, plan, setup, timing):  # type: ignore[no-untyped-def]
        raise NotImplementedError

    def setup_of(self, parameters, folder):  # type: ignore[no-untyped-def]
        return None

    def announce_world(self, out, world, planner, recording, setup):  # type: ignore[no-untyped-def]
        raise NotImplementedError

    def publish_sample(self, out, world, state, *, setup, track, time_ns, recording):  # type: ignore[no-untyped-def]
        raise NotImplementedError

    def record_run(self, run, world, plan, *, planner, node, recording_text, setup):  # type: ignore[no-untyped-def]
        raise NotImplementedError

    def pose_goal(self, msg):  # type: ignore[no-untyped-def]
        return (msg.pose.position.x,)

    def plan_from_trajectory(self, parameters, trajectory, outcome_fields, message):  # type: ignore[no-untyped-def]
        return None


@pytest.fixture
def toy() -> ToyKind:
    kind = kinds.register(ToyKind())
    yield kind
    kinds.unregister(ToyKind.name)


def test_the_two_kinds_are_registered() -> None:
    assert kinds.kinds()[:2] == ("planar", "spatial")
    assert kinds.kind_of_parameters({"world": {}}).name == "planar"  # the default
    assert kinds.kind_of_parameters({}).name == "planar"


def test_a_third_kind_registers_and_is_found(toy: ToyKind, tmp_path: Path) -> None:
    assert "toy_line" in kinds.kinds()
    assert kinds.kind_named("toy_line") is toy
    parameters = {"world": {"kind": "toy_line", "name": "line", "start": 0.0, "goal": 2.5}}
    assert kinds.world_kind(parameters) == "toy_line"
    problem = kinds.problem_from_parameters(parameters, tmp_path)  # the shared offline path dispatches to it
    assert isinstance(problem, ToyProblem)
    assert kinds.kind_of(problem) is toy
    assert kinds.kind_of(problem.world) is toy
    assert kinds.warm_up(problem) == 0.0
    moved = kinds.kind_of(problem.world).with_goal(problem.world, np.array([4.0]))
    assert moved.goal == 4.0


def test_a_kind_registers_once(toy: ToyKind) -> None:
    with pytest.raises(ValueError, match="registered already"):
        kinds.register(ToyKind())


def test_an_unknown_kind_is_refused_naming_world_kind() -> None:
    with pytest.raises(WorldError, match=r"world\.kind.*'planar' or 'spatial'.*'mobile'"):
        kinds.kind_of_parameters({"world": {"kind": "mobile"}})
    with pytest.raises(TypeError, match="no world of a registered kind"):
        kinds.kind_of(object())
    assert "toy_line" not in kinds.kinds()  # the fixture's kind is gone once its test ends
