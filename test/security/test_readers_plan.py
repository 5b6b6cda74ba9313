"""Plan.read refuses a bad plan file with a PlanFileError naming the file and what is wrong; clew_render exits 2
with one line for it."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest
from helpers.security_files import plan_bytes, world_path

from clew_ros.cli.render import main as clew_render
from clew_ros.core.errors import PlanFileError
from clew_ros.core.plan import Plan, PlanFileLimits

GOOD = json.loads(plan_bytes("figure1_seed0"))


def _changed(path: tuple, value: object) -> str:
    document = copy.deepcopy(GOOD)
    target = document
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    return json.dumps(document)


CASES = {
    "binary": (b"\x89PNG\r\n\x1a\n\xff\xfe\x00", "not UTF-8"),
    "nested": (b"[" * 200_000 + b"]" * 200_000, "nested too deeply"),
    "nested value": (
        plan_bytes("figure1_seed0").replace(
            b'"stats": {', b'"stats": {"x": ' + b"[" * 100_000 + b"]" * 100_000 + b", "
        ),
        "nested too deeply",
    ),
    "NaN": (plan_bytes("figure1_seed0").replace(b"0.0", b"NaN", 1), "NaN is not a number"),
    "Infinity": (_changed(("final_object_pose", 0), float("inf")).encode(), "Infinity is not a number"),
    "overflow": (plan_bytes("figure1_seed0").replace(b"0.0", b"1e400", 1), "too large for a float"),
    "huge integer": (b"7" * 5000, "digits"),
    "string number": (_changed(("segments", 0, "waypoints", 0, 0), "0.5").encode(), "segments[0].waypoints"),
    "boolean number": (_changed(("segments", 0, "waypoints", 0, 0), True).encode(), "segments[0].waypoints"),
    "width": (_changed(("segments", 0, "waypoints"), [[0.0, 0.0, 0.0]]).encode(), "rows of 2 joint values"),
    "landmark width": (_changed(("landmarks", 0, "joints"), [0.0]).encode(), "landmarks[0].joints"),
    "message": (_changed(("message",), {"a": 1}).encode(), "message: expected text"),
    "truncated": (plan_bytes("figure1_seed0")[:200], "invalid JSON"),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_plan_read_refuses_naming_the_file(name: str, tmp_path: Path) -> None:
    data, reason = CASES[name]
    path = tmp_path / "bad plan.json"
    path.write_bytes(data)
    with pytest.raises(PlanFileError) as raised:
        Plan.read(path)
    assert str(raised.value).startswith(str(path))
    assert reason in str(raised.value)


def test_plan_read_refuses_a_file_over_its_limit(tmp_path: Path) -> None:
    path = tmp_path / "plan.json"
    path.write_bytes(plan_bytes("figure1_seed0"))
    assert Plan.read(path).to_dict()["segments"] == GOOD["segments"]  # the real plan reads, whole
    with pytest.raises(PlanFileError, match="larger than 100 bytes"):
        Plan.read(path, limits=PlanFileLimits(max_bytes=100))


@pytest.mark.parametrize("name", ["binary", "nested", "NaN", "width", "huge integer"])
def test_clew_render_exits_2_with_one_line(name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "plan.json"
    path.write_bytes(CASES[name][0])
    code = clew_render([str(path), "-o", str(tmp_path / "out.svg"), "--world", str(world_path("figure1"))])
    err = capsys.readouterr().err
    assert code == 2
    assert len(err.splitlines()) == 1, err
    assert err.startswith(f"clew_render: {path}")
