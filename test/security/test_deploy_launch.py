"""The launch files never evaluate what a user passes them (issue 42).

``params_file`` used to go through ``PythonExpression``: a quote in the path
broke the launch and a crafted value ran Python in the launch process. Now the
files hold no ``PythonExpression`` (nor ``eval`` / ``exec``), read by their
syntax tree, and, run against the launch stand-ins of ``helpers.launch_api``
(which evaluate conditions as launch does), a value with quotes and Python in
it starts exactly one node that is handed the value unchanged as its
parameter file, and runs nothing.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest
import yaml
from helpers.launch_api import install, started_nodes

from clew_ros.planar.world import read_parameter_file

ROOT = Path(__file__).resolve().parents[2]
LAUNCH_FILES = sorted((ROOT / "launch").glob("*.launch.py"))
CONFIG = ROOT / "config"
#: Names that evaluate text as Python, in launch or in the language.
EVALUATORS = {"PythonExpression", "eval", "exec", "compile", "__import__"}


def hostile_values(marker: Path) -> list[str]:
    """``params_file`` values that ran code, or chose the wrong node, through the old PythonExpression."""
    touch = f"__import__('pathlib').Path({str(marker)!r}).touch()"
    return [
        f"x' + str({touch}) + '",  # closes the quote, runs the call, reopens it
        f"' if {touch} else '",
        "' == '' or '",  # the old expression '' == '' or '' != '' chose the node without parameters
        "/data/robot's worlds/figure1.yaml",  # a plain path with a quote broke the old one
        '"; import os #',
    ]


@pytest.fixture
def launch_api(monkeypatch: pytest.MonkeyPatch) -> None:
    install(monkeypatch, ROOT)


def evaluating_names(path: Path) -> set[str]:
    """The names of :data:`EVALUATORS` that ``path`` imports, names or calls."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Name) and node.id in EVALUATORS:
            found.add(node.id)
        elif isinstance(node, ast.Attribute) and node.attr in EVALUATORS:
            found.add(node.attr)
        elif isinstance(node, ast.alias) and node.name.rsplit(".", 1)[-1] in EVALUATORS:
            found.add(node.name)
    return found


@pytest.mark.parametrize("path", LAUNCH_FILES, ids=lambda p: p.name)
def test_launch_files_evaluate_no_text(path: Path) -> None:
    assert evaluating_names(path) == set()


def test_the_syntax_check_sees_python_expression(tmp_path: Path) -> None:
    """The check above finds what the old launch file did (so that its passing means something)."""
    old = tmp_path / "old.launch.py"
    old.write_text(
        "from launch.substitutions import LaunchConfiguration, PythonExpression\n"
        "has_params = PythonExpression([\"'\", LaunchConfiguration('params_file'), \"' != ''\"])\n"
    )
    assert evaluating_names(old) == {"PythonExpression"}


@pytest.mark.usefixtures("launch_api")
def test_params_file_is_handed_over_as_text_never_run(tmp_path: Path) -> None:
    marker = tmp_path / "ran"
    for value in hostile_values(marker):
        started = started_nodes(ROOT / "launch" / "clew_planner.launch.py", {"params_file": value})
        assert len(started) == 1, value
        ((node, parameters),) = started
        assert node.kwargs["executable"] == "clew_planner"
        assert parameters == [value]
    assert not marker.exists()


@pytest.mark.usefixtures("launch_api")
def test_planners_launch_reads_a_world_file_whose_name_has_quotes(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)  # the file name holds no "/": the code in it would touch ./ran
    marker = tmp_path / "ran"
    world = tmp_path / "x'+str(__import__('pathlib').Path('ran').touch())+'.yaml"  # pairs are split at spaces
    world.write_text(yaml.safe_dump({"/**": {"ros__parameters": read_parameter_file(CONFIG / "figure1.yaml")}}))
    started = started_nodes(ROOT / "launch" / "clew_planners.launch.py", {"planners": f"arm:={world}"})
    ((node, (parameters,)),) = started
    assert node.kwargs["namespace"] == "/arm"
    assert parameters["world"] == read_parameter_file(CONFIG / "figure1.yaml")["world"]
    assert not marker.exists()
