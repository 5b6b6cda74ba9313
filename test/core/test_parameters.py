"""The parameter specification (clew_ros.core.parameters): tables, the one checker, the README tables."""

from __future__ import annotations

import math
import re
from dataclasses import fields
from pathlib import Path

import pytest

from clew_ros.cli.parameter_tables import main, markdown_tables, update_markdown
from clew_ros.core.errors import ParameterError, short_repr
from clew_ros.core.parameters import (
    OBSTACLE_PARAMETER,
    PLANNER_PARAMETERS,
    REQUIRED,
    WORLD_PARAMETERS,
    ParameterSpec,
    ParameterType,
    check_joint_count,
    check_value,
)
from clew_ros.core.settings import PlannerSettings
from clew_ros.ros.node_parameters import NODE_PARAMETERS
from clew_ros.spatial.parameters import SPATIAL_OBSTACLE_PARAMETERS, SPATIAL_WORLD_PARAMETERS

README = Path(__file__).resolve().parents[2] / "docs" / "parameters.md"  # where the tables are
TABLES = (WORLD_PARAMETERS, PLANNER_PARAMETERS, NODE_PARAMETERS)


def test_readme_tables_are_generated_from_the_specification() -> None:
    """docs/parameters.md holds the tables markdown_tables() makes; after a change to the specification run
    ``python -m clew_ros.cli.parameter_tables --update docs/parameters.md``."""
    text = README.read_text(encoding="utf-8")
    assert update_markdown(text) == text, "run: python -m clew_ros.cli.parameter_tables --update docs/parameters.md"
    for name, table in markdown_tables().items():
        assert table in text, name
    for table in TABLES:
        for spec in table.values():
            assert f"| `{spec.name}` |" in text, spec.name


def test_the_tables_hold_the_spatial_world_and_the_world_as_it_is_now() -> None:
    """docs/parameters.md has a row for every spatial world.* parameter (its own table, beside the planar
    world's) and every state.* parameter (the node's table), each as its spec says."""
    tables = markdown_tables()
    assert list(tables) == ["world", "spatial_world", "planner", "node"]
    spatial = tables["spatial_world"].splitlines()[2:]
    specs = [*SPATIAL_WORLD_PARAMETERS.values(), *SPATIAL_OBSTACLE_PARAMETERS.values()]
    assert sorted(row.split(" | ")[0].removeprefix("| ") for row in spatial) == sorted(f"`{s.name}`" for s in specs)
    assert (
        "| `world.robot.padding` | double | `0.0` | m | [0.0, 1.0] | fixed (dev switch) | How far (m)"
        in tables["spatial_world"]
    )
    assert "| `world.goal_angle_tolerance` | double | `pi` | rad | [0.0, 2 pi] |" in tables["spatial_world"]
    assert "| `world.kind` | string | none |" in tables["world"]  # planar: the default kind
    states = [name for name in NODE_PARAMETERS if name.startswith("state.")]
    assert len(states) == 11
    for name in states:
        assert f"| `{name}` |" in tables["node"], name
    text = README.read_text(encoding="utf-8")
    assert tables["spatial_world"] in text


def test_the_update_and_check_commands(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    stale = README.read_text(encoding="utf-8").replace(
        "| `planner.seed` | integer | `0` |", "| `planner.seed` | integer | `7` |"
    )
    path = tmp_path / "parameters.md"
    path.write_text(stale, encoding="utf-8")
    assert main(["--check", str(path)]) == 1
    assert main(["--update", str(path)]) == 0
    assert main(["--check", str(path)]) == 0
    assert path.read_text(encoding="utf-8") == README.read_text(encoding="utf-8")
    (tmp_path / "none.md").write_text("no tables here\n", encoding="utf-8")
    assert main(["--check", str(tmp_path / "none.md")]) == 2
    assert "no generated table" in capsys.readouterr().err
    assert main([]) == 0
    assert "| `world.obstacles.<name>` |" in capsys.readouterr().out


def test_tables_are_well_formed() -> None:
    names = [spec.name for table in TABLES for spec in table.values()] + [OBSTACLE_PARAMETER.name]
    assert len(names) == len(set(names))
    for table in TABLES:
        for key, spec in table.items():
            assert spec.name == table.prefix + key
            assert spec.description.endswith(".")
            assert "\n" not in spec.description
            numbers = (ParameterType.INTEGER, ParameterType.DOUBLE, ParameterType.DOUBLE_PER_JOINT)
            if spec.type in numbers and table is not WORLD_PARAMETERS:
                assert spec.limits is not None, spec.name
            if spec.required or spec.default is None:
                continue
            if spec.type in (ParameterType.DOUBLE_ARRAY, ParameterType.STRING_ARRAY):
                continue
            assert check_value(spec, spec.default) == spec.default, spec.name  # defaults pass their own check
            assert type(check_value(spec, spec.default)) is spec.type.python_type


def test_planner_settings_follow_the_table() -> None:
    assert [f.name for f in fields(PlannerSettings)] == list(PLANNER_PARAMETERS)
    defaults = PlannerSettings()
    for key, spec in PLANNER_PARAMETERS.items():
        assert getattr(defaults, key) == spec.default
    assert PlannerSettings.from_parameters({}) == defaults
    assert PlannerSettings.from_parameters({"planner": {"seed": 3.0, "time_limit": 2}}, seed=5) == PlannerSettings(
        seed=5, time_limit=2.0
    )
    with pytest.raises(ParameterError, match=r"^planner\.speed: unknown parameter; known: seed, time_limit"):
        PlannerSettings.from_parameters({"planner": {"speed": 1}})


def test_required_parameters_have_no_default() -> None:
    assert WORLD_PARAMETERS["bounds"].required
    assert WORLD_PARAMETERS["bounds"].default is REQUIRED
    with pytest.raises(KeyError, match=r"world\.bounds is required"):
        WORLD_PARAMETERS.default("bounds")
    assert WORLD_PARAMETERS.default("goal_angle_tolerance") == math.pi
    assert WORLD_PARAMETERS.default("obstacle_names") is None


SEED = PLANNER_PARAMETERS["seed"]
LIMIT = PLANNER_PARAMETERS["time_limit"]
UNBOUNDED = ParameterSpec("test.x", ParameterType.DOUBLE, 1.0, "Anything finite.")
VELOCITY = NODE_PARAMETERS["trajectory.max_velocity"]
PER_JOINT = "trajectory.max_velocity: expected a number for every joint or a list with one per joint, got "

CHECKS = [
    (SEED, 5, 5),
    (SEED, 5.0, 5),
    (SEED, 1.5, "planner.seed: expected an integer, got 1.5"),
    (SEED, math.nan, "planner.seed: expected an integer, got nan"),
    (SEED, True, "planner.seed: expected an integer, got True"),
    (SEED, "3", "planner.seed: expected an integer, got '3'"),
    (SEED, -1, "planner.seed: expected a value in [0, 2147483647], got -1"),
    (SEED, 2**31, "planner.seed: expected a value in [0, 2147483647], got 2147483648"),
    (LIMIT, 2, 2.0),
    (LIMIT, math.inf, "planner.time_limit: expected a value in [0.01, 3600.0], got inf"),
    (LIMIT, math.nan, "planner.time_limit: expected a value in [0.01, 3600.0], got nan"),
    (LIMIT, [1.0], "planner.time_limit: expected a number, got [1.0]"),
    (LIMIT, None, "planner.time_limit: expected a number, got None"),
    (UNBOUNDED, -1e300, -1e300),
    (UNBOUNDED, math.inf, "test.x: expected a finite number, got inf"),
    (NODE_PARAMETERS["record.enabled"], False, False),
    (NODE_PARAMETERS["record.enabled"], 1, "record.enabled: expected true or false, got 1"),
    (NODE_PARAMETERS["record.directory"], "runs", "runs"),
    (NODE_PARAMETERS["record.directory"], "", "record.directory: expected a non-empty string, got ''"),
    # per-joint limits: one number for every joint, or a list with one per joint (joint_limits.yaml)
    (VELOCITY, 2, 2.0),
    (VELOCITY, [1, 2.5, 1000], (1.0, 2.5, 1000.0)),
    (VELOCITY, (0.5,), (0.5,)),
    (VELOCITY, 0.0, "trajectory.max_velocity: expected a value in [0.001, 1000.0], got 0.0"),
    (VELOCITY, [1.0, -2.0], "trajectory.max_velocity: expected a value in [0.001, 1000.0] for joint_2, got -2.0"),
    (VELOCITY, [math.nan], "trajectory.max_velocity: expected a value in [0.001, 1000.0] for joint_1, got nan"),
    (VELOCITY, [1.0, "fast"], "trajectory.max_velocity: expected a number for joint_2, got 'fast'"),
    (VELOCITY, [1.0, [2.0]], "trajectory.max_velocity: expected a number for joint_2, got [2.0]"),
    (VELOCITY, [True], "trajectory.max_velocity: expected a number for joint_1, got True"),
    (VELOCITY, [], PER_JOINT + "an empty list"),
    (VELOCITY, "fast", PER_JOINT + "'fast'"),
    (VELOCITY, None, PER_JOINT + "None"),
]


@pytest.mark.parametrize(("spec", "value", "expected"), CHECKS, ids=[f"{c[0].name}={c[1]!r}" for c in CHECKS])
def test_check_value(spec: ParameterSpec, value, expected) -> None:
    if isinstance(expected, str) and expected.startswith(spec.name + ":"):
        with pytest.raises(ParameterError) as caught:
            check_value(spec, value)
        assert str(caught.value) == expected
        assert caught.value.parameter == spec.name
    else:
        result = check_value(spec, value)
        assert result == expected
        assert type(result) is type(expected)


def test_a_per_joint_list_holds_one_value_per_joint() -> None:
    check_joint_count(VELOCITY, 2.0, 3)  # one number: every joint
    check_joint_count(VELOCITY, None, 3)  # unset
    check_joint_count(VELOCITY, (1.0, 2.0, 3.0), 3)
    with pytest.raises(ParameterError) as caught:
        check_joint_count(VELOCITY, (1.0, 2.0), 3)
    assert caught.value.parameter == "trajectory.max_velocity"
    assert str(caught.value) == (
        "trajectory.max_velocity: expected a number for every joint or a list with one per joint "
        "(3: joint_1, joint_2, joint_3), got a list of 2"
    )


def test_arrays_are_the_world_parsers() -> None:
    with pytest.raises(TypeError, match="world parser"):
        check_value(WORLD_PARAMETERS["bounds"], [0.0, 0.0, 1.0, 1.0])


def test_short_repr() -> None:
    assert short_repr("abc") == "'abc'"
    assert short_repr("a" * 200) == "'" + "a" * 76 + "..."
    assert len(short_repr(list(range(100)), 20)) == 20
    assert short_repr(10**5000) == "an integer of about 5000 digits"


def test_a_retired_parameter_still_loads_with_a_warning() -> None:
    with pytest.warns(FutureWarning, match=r"planner\.max_sweep_steps is retired"):
        settings = PlannerSettings.from_parameters({"planner": {"max_sweep_steps": 48, "seed": 3}})
    assert settings.seed == 3
    assert not hasattr(settings, "max_sweep_steps")
    with pytest.raises(ParameterError, match=r"planner\.max_sweep_step\b"):
        PlannerSettings.from_parameters({"planner": {"max_sweep_step": 48}})  # a misspelt name is still an error


def test_the_world_as_it_is_now_has_the_contracts_defaults() -> None:
    """Every state.* parameter of docs/interface.md section 3c is specified, with the default the contract
    gives it, and read only (the contract: read-only while running)."""
    text = (Path(__file__).resolve().parents[2] / "docs" / "interface.md").read_text(encoding="utf-8")
    section = text[text.index("## 3c.") : text.index("## 4.")]
    written = dict(re.findall(r"`(state\.[a-z_]+)`(?: \(|, )(true|false|\d[\d.,]*\d)\b", section))
    assert len(written) == 11
    for name, default in written.items():
        spec = NODE_PARAMETERS[name]
        word = default.replace(",", "")
        assert spec.default == (word == "true" if word in ("true", "false") else float(word)), name
        assert spec.read_only, name
