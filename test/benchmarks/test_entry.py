"""``python -m benchmarks``: one entry listing every command; ``compare`` runs a command on two revisions."""

import importlib.util
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from benchmarks.__main__ import COMMANDS
from benchmarks.compare import numbers, ratios

ROOT = Path(__file__).resolve().parents[2]


def _benchmarks(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "benchmarks", *args], cwd=ROOT, capture_output=True, text=True, check=False, timeout=300
    )


def _in_a_repository() -> bool:
    if shutil.which("git") is None:
        return False
    return subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, check=False).returncode == 0


def test_the_entry_alone_lists_every_command_with_what_it_measures():
    done = _benchmarks()
    assert done.returncode == 0, done.stderr
    listed = dict(re.findall(r"^  (\S+)\s+(.+)$", done.stdout, flags=re.MULTILINE))
    assert list(listed) == list(COMMANDS)
    assert all(listed[name] == command.what for name, command in COMMANDS.items())


def test_an_unknown_command_exits_2_naming_the_choices():
    done = _benchmarks("families")
    assert done.returncode == 2
    assert "'families'" in done.stderr
    assert all(name in done.stderr for name in COMMANDS)


def test_every_command_runs_a_module_with_a_main_and_the_entry_passes_its_arguments():
    for name, command in COMMANDS.items():
        spec = importlib.util.find_spec(f"benchmarks.{command.module}")
        assert spec is not None, name
        assert spec.origin is not None, name
        assert "\ndef main(argv: list[str] | None = None) -> int:" in Path(spec.origin).read_text(), name
    done = _benchmarks("grid_reference", "--help")
    assert done.returncode == 0, done.stderr
    assert "--max-transfers" in done.stdout  # the module's own options: the arguments reached its main


def test_numbers_are_found_by_place_booleans_and_non_finite_values_aside():
    value = {"a": 1, "ok": True, "runs": [{"t": 0.5, "name": "x"}, {"t": float("nan")}], "nested": {"b": 2.5}}
    assert dict(numbers(value)) == {"a": 1.0, "runs[0].t": 0.5, "nested.b": 2.5}


def test_ratios_are_medians_after_over_before_on_the_places_both_sides_have():
    before = [{"t": 2.0, "n": 0, "only_before": 1}, {"t": 4.0, "n": 0, "only_before": 1}, {"t": 3.0, "n": 0}]
    after = [{"t": 1.0, "n": 5, "only_before": 2}, {"t": 2.0, "n": 5}, {"t": 9.0, "n": 5}]
    rows = {place: (old, new, ratio) for place, old, new, ratio in ratios(before, after)}
    assert rows == {"t": (3.0, 2.0, pytest.approx(2.0 / 3.0)), "n": (0.0, 5.0, None)}


@pytest.mark.skipif(not _in_a_repository(), reason="needs git and a git checkout (compare exports a revision)")
def test_compare_runs_the_command_on_the_revision_and_on_this_checkout():
    done = _benchmarks("compare", "--baseline", "HEAD", "grid_reference", "--help")
    assert done.returncode == 0, done.stderr
    assert "## before (HEAD), round 1: exit 0" in done.stdout
    assert "## after (this checkout), round 1: exit 0" in done.stdout
    assert done.stdout.count("usage: python -m benchmarks.reference") == 2  # both trees' module answered


def test_compare_names_a_revision_git_does_not_know():
    done = _benchmarks("compare", "--baseline", "no-such-revision-41", "planner_runs", "figure1")
    assert done.returncode == 2
    assert "--baseline" in done.stderr
    assert "no-such-revision-41" in done.stderr


def test_docs_list_every_command_in_the_command_table():
    """docs/benchmarks.md's "Every benchmark command" table names each command, with the module it runs."""
    text = (ROOT / "docs" / "benchmarks.md").read_text()
    table = text[text.index("### Every benchmark command") : text.index("### Comparing two revisions")]
    rows = re.findall(r"^\| `(\w+)[^`]*` \(`(\w+)`\) \|", table, flags=re.MULTILINE)
    assert rows == [(name, command.module) for name, command in COMMANDS.items()]


@pytest.mark.skipif(not _in_a_repository(), reason="needs git and a git checkout (compare exports a revision)")
def test_compare_hands_a_run_by_run_command_to_its_paired_mode():
    done = _benchmarks("compare", "--baseline", "HEAD", "generated_families", "--help")
    assert done.returncode == 0, done.stderr
    assert "usage: python -m benchmarks compare --baseline REV generated_families" in done.stdout
    assert "--config-worlds" in done.stdout  # the paired mode's own options
    refused = _benchmarks("compare", "--baseline", "HEAD", "--rounds", "3", "suite", "--only", "figure1")
    assert refused.returncode == 2
    assert "--rounds: not used by 'suite'" in refused.stderr
