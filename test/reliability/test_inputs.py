"""Reliability: bad input to the world loader and to ``clew_plan`` (no ROS graph).

Property: every parameter tree ends either in a valid ``World`` or in a
``WorldError`` naming a ``world.*`` parameter, never in another exception;
``clew_plan`` exits 2 with the parameter on stderr and no traceback, or
(for a valid world) 0 / 1 with a plan file whose ``code`` names the outcome.
"""

from __future__ import annotations

import json
import math
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import pytest
import yaml
from helpers.rel_worlds import (
    BASE_WORLD,
    FIXED_BAD_WORLDS,
    bad_worlds,
    many_obstacles,
    random_trees,
)
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from clew_ros.core.errors import ParameterError, WorldError
from clew_ros.core.settings import PlannerSettings
from clew_ros.planar.collision import check_start_and_goal
from clew_ros.planar.world import MAX_LINKS, World, read_parameter_file, world_from_parameters

CLEW_PLAN = [sys.executable, "-m", "clew_ros.cli.plan"]
ROOT = Path(__file__).resolve().parents[2]
#: A run ends within planner.time_limit + this (s), as the planner measures it: the planner looks at the
#: clock between steps of well under 0.1 s on an idle machine; on a loaded 2-core machine CPU contention
#: stretches a step several times, so the slack is 1 s. Overshooting it means a step that never looks.
TIME_LIMIT_SLACK_S = 1.0


def load(tree: dict) -> World | WorldError:
    """The loader's answer: a World or the WorldError; any other exception fails the test."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # shapely / numpy overflow chatter on huge values
        try:
            return check_start_and_goal(world_from_parameters(tree))
        except WorldError as error:
            return error


def assert_names_a_world_parameter(error: WorldError) -> None:
    assert error.parameter == "world" or error.parameter.startswith("world."), error
    assert str(error).startswith(error.parameter + ": ")
    assert error.expected, "the message should be short and say what was expected"
    assert len(str(error)) < 2000, "the message should be short and say what was expected"


def set_path(tree: dict, path: tuple[str, ...], value) -> dict:
    node = tree
    for key in path[:-1]:
        node = node.setdefault(key, {})
    node[path[-1]] = value
    return tree


def mutated(path: tuple[str, ...], value) -> dict:
    return set_path(json.loads(json.dumps(BASE_WORLD)), path, value)


# --------------------------------------------------------------------------- (a) the loader


def test_the_base_world_is_valid() -> None:
    assert isinstance(load(json.loads(json.dumps(BASE_WORLD))), World)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(bad_worlds())
def test_loader_answers_malformed_worlds_with_a_world_error(tree: dict) -> None:
    answer = load(tree)
    if isinstance(answer, WorldError):
        assert_names_a_world_parameter(answer)
    else:
        assert isinstance(answer, World)
        assert answer.robot.dof >= 2
        for array in (answer.bounds, answer.robot.link_lengths, answer.object.polygon, answer.object.grasps):
            assert all(math.isfinite(v) for v in array.ravel())


@settings(max_examples=100, deadline=None)
@given(random_trees)
def test_loader_answers_random_trees_with_a_world_error(tree) -> None:
    answer = load({"world": tree})
    assert isinstance(answer, WorldError), "a random tree is never a whole world"
    assert_names_a_world_parameter(answer)


@settings(max_examples=30, deadline=None)
@given(st.one_of(st.none(), st.integers(), st.text(max_size=5), st.lists(st.integers(), max_size=3)))
def test_loader_answers_a_tree_that_is_no_mapping(tree) -> None:
    with pytest.raises(WorldError) as caught:
        world_from_parameters(tree)
    assert caught.value.parameter in ("ros__parameters", "world")


@pytest.mark.parametrize(
    ("label", "path", "value", "parameter"), FIXED_BAD_WORLDS, ids=[c[0] for c in FIXED_BAD_WORLDS]
)
def test_fixed_bad_worlds_name_their_parameter(label: str, path, value, parameter: str) -> None:
    answer = load(mutated(path, value))
    assert isinstance(answer, WorldError), label
    assert answer.parameter == parameter, answer


@pytest.mark.parametrize("value", [1e300, -1e7, 10**400, 2**63, 1e-320])
def test_huge_and_tiny_numbers(value) -> None:
    """Beyond +-1e6 (m or rad) the geometry loses precision: refused; tiny numbers are numbers."""
    answer = load(mutated(("world", "object", "goal"), [0.6, 1.1, value]))
    if abs(value) > 1e6:
        assert isinstance(answer, WorldError), answer
        assert answer.parameter == "world.object.goal", answer
    else:
        assert isinstance(answer, World)


def test_too_many_links_are_refused() -> None:
    n = MAX_LINKS + 1
    tree = json.loads(json.dumps(BASE_WORLD))
    robot = tree["world"]["robot"]
    robot.update(link_lengths=[1.7 / n] * n, joint_lower=[-3.0] * n, joint_upper=[3.0] * n, initial=[0.0] * n)
    answer = load(tree)
    assert isinstance(answer, WorldError)
    assert answer.parameter == "world.robot.link_lengths"


def test_thousands_of_obstacles_load() -> None:
    count = 3000
    tree = json.loads(json.dumps(BASE_WORLD))
    tree["world"]["obstacle_names"], tree["world"]["obstacles"] = many_obstacles(count)
    answer = load(tree)
    assert isinstance(answer, World)
    assert len(answer.obstacles) == count


# --------------------------------------------------------------------------- parameter files


FILE_CASES = {
    "not_utf8": b"\xff\xfe\x00clew_planner: {}\n",
    "yaml_syntax": b"clew_planner:\n  ros__parameters: [unclosed\n",
    "not_a_mapping": b"- 1\n- 2\n",
    "no_node_key": b"other_node:\n  ros__parameters: {}\n",
    "params_not_mapping": b"clew_planner:\n  ros__parameters: 7\n",
    "python_tag": b"clew_planner: !!python/object/apply:os.system ['true']\n",
    "huge_integer": b"clew_planner:\n  ros__parameters:\n    world: {bounds: [" + b"9" * 5000 + b", 0, 1, 1]}\n",
    "deep_nesting": b"clew_planner: " + b"[" * 1000 + b"]" * 1000 + b"\n",
    "empty": b"",
}


@pytest.mark.parametrize("label", list(FILE_CASES))
def test_unreadable_parameter_files_name_the_file(tmp_path: Path, label: str) -> None:
    path = tmp_path / f"{label}.yaml"
    path.write_bytes(FILE_CASES[label])
    with pytest.raises(WorldError) as caught:
        read_parameter_file(path)
    assert caught.value.parameter == str(path) or caught.value.parameter.startswith("clew_planner")


def test_special_files_are_refused(tmp_path: Path) -> None:
    for path in (tmp_path, Path("/dev/zero"), tmp_path / "missing.yaml"):
        with pytest.raises(WorldError) as caught:
            read_parameter_file(path)
        assert caught.value.parameter == str(path)


@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("time_limit", 10**400),
        ("time_limit", math.nan),
        ("time_limit", -1.0),
        ("seed", 1.5),
        ("seed", 2**31),
        ("population", "many"),
        ("resolution", math.inf),
        ("unknown_knob", 1),
    ],
)
def test_bad_planner_settings_raise_parameter_error(key: str, value) -> None:
    with pytest.raises(ParameterError) as caught:
        PlannerSettings.from_parameters({"planner": {key: value}})
    assert caught.value.parameter == f"planner.{key}"


# --------------------------------------------------------------------------- (b) clew_plan


def parameter_file(path: Path, tree: dict) -> Path:
    path.write_text(yaml.safe_dump({"clew_planner": {"ros__parameters": tree}}))
    return path


def clew_plan(world: Path, output: Path, *extra: str) -> subprocess.Popen:
    return subprocess.Popen(
        [*CLEW_PLAN, str(world), "--output", str(output), "--quiet", *extra],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
    )


def finish(proc: subprocess.Popen, timeout_s: float = 60.0) -> tuple[int, str]:
    _stdout, stderr = proc.communicate(timeout=timeout_s)
    assert "Traceback" not in stderr, stderr
    return proc.returncode, stderr


def check_cli_answer(code: int, stderr: str, output: Path, expected) -> None:
    """``expected``: the loader's answer for the same tree (World or WorldError)."""
    if isinstance(expected, WorldError):
        assert code == 2, stderr
        assert expected.parameter in stderr, stderr
        assert "clew_plan: invalid input: " in stderr
    else:
        assert code in (0, 1), stderr
        document = json.loads(output.read_text())
        assert document["code"]
        assert isinstance(document["message"], str)
        assert document["message"]
        assert document["success"] is (code == 0)
        if code == 1:
            assert document["code"] != "SUCCEEDED"
            assert document["segments"] == []


@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(tree=bad_worlds(max_mutations=2))
def test_clew_plan_on_malformed_worlds(tmp_path_factory: pytest.TempPathFactory, tree: dict) -> None:
    tmp = tmp_path_factory.mktemp("cli")
    world = parameter_file(tmp / "world.yaml", tree)
    code, stderr = finish(clew_plan(world, tmp / "plan.json", "--time-limit", "1"))
    check_cli_answer(code, stderr, tmp / "plan.json", load(read_parameter_file(world)))


def test_clew_plan_fixed_cases(tmp_path: Path) -> None:
    """A handful of fixed bad inputs, run side by side: exit 2, the parameter named, no traceback."""
    (tmp_path / "blocker").write_text("a regular file")
    quick = ROOT / "test" / "worlds" / "node_quick.yaml"
    cases: dict[str, tuple[list[str], str]] = {}

    def case(label: str, tree_or_path, expected: str, *extra: str) -> None:
        path = (
            tree_or_path if isinstance(tree_or_path, Path) else parameter_file(tmp_path / f"{label}.yaml", tree_or_path)
        )
        cases[label] = ([str(path), "--output", str(tmp_path / f"{label}.json"), *extra], expected)

    for label, path, value, parameter in FIXED_BAD_WORLDS[:4]:
        case(label, mutated(path, value), parameter)
    (tmp_path / "binary.yaml").write_bytes(FILE_CASES["not_utf8"])
    case("binary", tmp_path / "binary.yaml", str(tmp_path / "binary.yaml"))
    case(
        "huge_time_limit",
        set_path(json.loads(json.dumps(BASE_WORLD)), ("planner", "time_limit"), 10**400),
        "planner.time_limit",
    )
    case("nan_time_limit_flag", quick, "planner.time_limit", "--time-limit", "nan")
    cases["output_under_a_file"] = ([str(quick), "--output", str(tmp_path / "blocker" / "plan.json")], "--output")

    procs = {
        label: subprocess.Popen(
            [*CLEW_PLAN, *args, "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT
        )
        for label, (args, _expected) in cases.items()
    }
    for label, proc in procs.items():
        code, stderr = finish(proc)
        assert code == 2, f"{label}: exit {code}: {stderr}"
        assert cases[label][1] in stderr, f"{label}: {stderr}"


def test_clew_plan_failures_carry_a_code_and_the_time_limit_holds(tmp_path: Path) -> None:
    """Every failure writes ``success: false``, a ``code`` and a message (exit 1).

    The behind-wall world (config/behind_wall.yaml) with ``--time-limit 2`` ends within the limit plus
    :data:`TIME_LIMIT_SLACK_S` as the planner measures it (``stats.time_s``); the process's wall time adds
    Python's start-up. The out-of-reach goal is refused before any search.
    """
    unreachable = ROOT / "test" / "worlds" / "node_unreachable.yaml"
    walled = ROOT / "config" / "behind_wall.yaml"
    limit = 2.0
    started = time.monotonic()
    procs = {
        "GOAL_OUT_OF_REACH": clew_plan(unreachable, tmp_path / "a.json"),
        "TIME_LIMIT": clew_plan(walled, tmp_path / "b.json", "--time-limit", str(limit)),
    }
    for (code_name, proc), output in zip(procs.items(), (tmp_path / "a.json", tmp_path / "b.json"), strict=True):
        code, stderr = finish(proc)
        assert code == 1, stderr
        document = json.loads(output.read_text())
        assert document["success"] is False, document
        assert document["message"], document
        assert document["segments"] == []
        assert document["final_object_pose"] is None
        if code_name == "TIME_LIMIT":
            wall = time.monotonic() - started
            print(
                f"\nclew_plan on config/behind_wall.yaml, --time-limit {limit}: {document['code']} after "
                f"{document['stats']['time_s']:.3f} s planning, {wall:.2f} s wall (process start included)"
            )
            assert document["code"] in ("TIME_LIMIT", "NO_PATH_AT_RESOLUTION"), document["code"]
            assert document["stats"]["time_s"] <= limit + TIME_LIMIT_SLACK_S, document["stats"]
        else:
            assert document["code"] == code_name
            assert document["stats"]["evaluations"] == 0, document["stats"]  # refused before any search
        assert document["code"] in stderr


@pytest.mark.parametrize(("links", "obstacles"), [(MAX_LINKS, 0), (2, 5000)], ids=["max_links", "5000_obstacles"])
def test_the_time_limit_holds_on_big_worlds(links: int, obstacles: int) -> None:
    """The longest piece of work between two looks at the clock is bounded: the planner stops
    within limit + :data:`TIME_LIMIT_SLACK_S` even when one genetic-algorithm evaluation is expensive."""
    from clew_ros.planar.space import plan

    tree = read_parameter_file(ROOT / "test" / "worlds" / "node_quick.yaml")
    if links > 2:
        tree["world"]["robot"].update(
            link_lengths=[1.7 / links] * links,
            joint_lower=[-3.0] * links,
            joint_upper=[3.0] * links,
            initial=[0.0] * links,
        )
    if obstacles:
        tree["world"]["obstacle_names"], tree["world"]["obstacles"] = many_obstacles(obstacles)
    limit = 1.0
    result = plan(check_start_and_goal(world_from_parameters(tree)), PlannerSettings(time_limit=limit, seed=0))
    print(
        f"\n{links} links, {obstacles} obstacles, time limit {limit} s: {result.outcome.name} after "
        f"{result.stats['time_s']:.3f} s"
    )
    assert result.stats["time_s"] <= limit + TIME_LIMIT_SLACK_S, result.stats


@pytest.mark.parametrize("sig", [signal.SIGINT], ids=["SIGINT"])  # SIGTERM takes the same handler
def test_clew_plan_signal_cancels_and_writes_the_plan_file(tmp_path: Path, sig: int) -> None:
    walled = ROOT / "config" / "behind_wall.yaml"
    output = tmp_path / "plan.json"
    proc = subprocess.Popen(
        [*CLEW_PLAN, str(walled), "--output", str(output), "--time-limit", "60"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
    )
    try:
        line = proc.stderr.readline()  # the first progress line: planning for a second already
        assert line.startswith("clew_plan: "), line
        sent = time.monotonic()
        proc.send_signal(sig)
        # liveness: the process ends at the signal, not at its 60 s time limit; communicate's 10 s (far
        # beyond what a loaded 2-core machine needs to write the file and exit) fails the test otherwise
        _stdout, rest = proc.communicate(timeout=10.0)
        latency = time.monotonic() - sent
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    print(f"\nclew_plan {sig.name}: exit {proc.returncode} after {1000 * latency:.0f} ms")
    assert "Traceback" not in rest, rest
    assert proc.returncode == 1, rest
    document = json.loads(output.read_text())
    assert document["code"] == "CANCELED", document
    assert document["success"] is False, document
