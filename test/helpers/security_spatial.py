"""Crafted spatial inputs for test/security: worlds, URDFs, meshes and scene files an attacker would write.

Each :func:`crafted_worlds` case is a folder holding ``world.yaml`` (a copy of the shipped Panda
table-to-table world, its files made absolute) and whatever it names, changed in one way that once cost
minutes or gigabytes, read a file it should not, or echoed a file's contents. :data:`SECRET` is the line the
cases hide in files that must never be quoted.
"""

from __future__ import annotations

import copy
import random
import struct
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import yaml

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "config"
WORLD_FILE = CONFIG / "spatial" / "panda_table_to_table.yaml"
PANDA_URDF = CONFIG / "robots" / "panda" / "panda.urdf"
PANDA_SRDF = CONFIG / "robots" / "panda" / "panda.srdf"
MESHES = CONFIG / "robots" / "panda" / "meshes"
#: A line no error message may repeat: the cases put it in files the tools are made to open.
SECRET = "s3cr3t-token-5f1c"


def world_tree() -> dict[str, Any]:
    """The shipped world's ``ros__parameters``, its URDF and SRDF named by absolute path."""
    document = yaml.safe_load(WORLD_FILE.read_text(encoding="utf-8"))
    parameters: dict[str, Any] = document["clew_planner"]["ros__parameters"]
    parameters["world"]["robot"]["urdf"] = str(PANDA_URDF)
    parameters["world"]["robot"]["srdf"] = str(PANDA_SRDF)
    parameters["planner"]["time_limit"] = 5.0
    return parameters


def write_world(folder: Path, parameters: dict[str, Any]) -> Path:
    path = folder / "world.yaml"
    path.write_text(yaml.safe_dump({"clew_planner": {"ros__parameters": parameters}}), encoding="utf-8")
    return path


def urdf_with_meshes(folder: Path, change: Callable[[str], str]) -> Path:
    """The Panda's URDF with its meshes named by absolute path, then ``change``d; written to ``folder``."""
    text = PANDA_URDF.read_text(encoding="utf-8").replace('filename="meshes/', f'filename="{MESHES}/')
    path = folder / "robot.urdf"
    path.write_text(change(text), encoding="utf-8")
    return path


def binary_stl(triangles: list[tuple[tuple[float, float, float], ...]]) -> bytes:
    """A binary STL of ``triangles`` (three corners each)."""
    out = [b"\0" * 80, struct.pack("<I", len(triangles))]
    for corners in triangles:
        out.append(struct.pack("<3f", 0.0, 0.0, 0.0))
        out.extend(struct.pack("<3f", *corner) for corner in corners)
        out.append(b"\0\0")
    return b"".join(out)


def _with_robot(folder: Path, **robot: Any) -> Path:
    parameters = world_tree()
    parameters["world"]["robot"].update(robot)
    return write_world(folder, parameters)


def _with_world(folder: Path, **world: Any) -> Path:
    parameters = world_tree()
    parameters["world"].update(world)
    return write_world(folder, parameters)


def _scaled_mesh(folder: Path) -> Path:
    """The issue's first case: one link's mesh scaled x30 (a voxel grid 27,000 times larger)."""
    urdf = urdf_with_meshes(folder, lambda t: t.replace('link3.stl" />', 'link3.stl" scale="30 30 30" />'))
    return _with_robot(folder, urdf=str(urdf))


def _scaled_within_cap(folder: Path) -> Path:
    """A scale the scale cap lets through (x9): the voxel grid's cap refuses it before voxelising."""
    urdf = urdf_with_meshes(folder, lambda t: t.replace('link3.stl" />', 'link3.stl" scale="9 9 9" />'))
    return _with_robot(folder, urdf=str(urdf))


def _huge_mesh_coordinates(folder: Path) -> Path:
    """A mesh a few triangles big, spanning 20 m: the voxel grid's cap, before voxelising."""
    (folder / "wide.stl").write_bytes(
        binary_stl([((0, 0, 0), (20, 0, 0), (0, 20, 0)), ((0, 0, 0), (0, 20, 0), (0, 0, 20))])
    )
    urdf = urdf_with_meshes(folder, lambda t: t.replace(f"{MESHES}/link3.stl", str(folder / "wide.stl")))
    return _with_robot(folder, urdf=str(urdf))


def _big_triangles(folder: Path) -> Path:
    """Many large overlapping triangles within a small box: splitting them to the voxel size is refused."""
    triangles = [((0.0, 0.0, 0.01 * k), (0.6, 0.0, 0.01 * k), (0.0, 0.6, 0.01 * k)) for k in range(60)]
    (folder / "layers.stl").write_bytes(binary_stl(triangles))
    urdf = urdf_with_meshes(folder, lambda t: t.replace(f"{MESHES}/link3.stl", str(folder / "layers.stl")))
    return _with_robot(folder, urdf=str(urdf))


def _solid_cube(folder: Path) -> Path:
    """A closed cube 0.4 m a side: within the grid's cap, its solid (64,000 cells) is past the solid's cap."""
    corners = [(x, y, z) for x in (0.0, 0.4) for y in (0.0, 0.4) for z in (0.0, 0.4)]
    quads = ((0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3))
    triangles = []
    for a, b, c, d in quads:
        triangles += [(corners[a], corners[b], corners[c]), (corners[a], corners[c], corners[d])]
    (folder / "cube.stl").write_bytes(binary_stl(triangles))
    urdf = urdf_with_meshes(folder, lambda t: t.replace(f"{MESHES}/link3.stl", str(folder / "cube.stl")))
    return _with_robot(folder, urdf=str(urdf))


def _many_boxes(folder: Path) -> Path:
    """One link of 200 thin boxes, each covered by 64 spheres: the sphere model's cap."""
    box = '<collision><geometry><box size="0.02 1 1"/></geometry></collision>'
    link = '<link name="panda_link3">'
    urdf = urdf_with_meshes(folder, lambda t: t.replace(link, link + box * 200, 1))
    return _with_robot(folder, urdf=str(urdf))


def _device_mesh(folder: Path) -> Path:
    urdf = urdf_with_meshes(folder, lambda t: t.replace(f"{MESHES}/link3.stl", "/dev/zero"))
    return _with_robot(folder, urdf=str(urdf))


def _secret_mesh(folder: Path) -> Path:
    (folder / "notes.stl").write_text(f"solid x\n{SECRET} facet\n", encoding="utf-8")
    urdf = urdf_with_meshes(folder, lambda t: t.replace(f"{MESHES}/link3.stl", str(folder / "notes.stl")))
    return _with_robot(folder, urdf=str(urdf))


def _many_links(folder: Path) -> Path:
    links = "".join(f'<link name="extra_{i}"/>' for i in range(5000))
    urdf = urdf_with_meshes(folder, lambda t: t.replace("</robot>", links + "</robot>", 1))
    return _with_robot(folder, urdf=str(urdf))


def _many_collisions(folder: Path) -> Path:
    """A few megabytes of URDF: one link with 100,000 boxes (within the links' cap)."""
    box = '<collision><geometry><box size="0.01 0.01 0.01"/></geometry></collision>'
    link = '<link name="panda_link3">'
    urdf = urdf_with_meshes(folder, lambda t: t.replace(link, link + box * 100_000, 1))
    return _with_robot(folder, urdf=str(urdf))


def _device_urdf(folder: Path) -> Path:
    return _with_robot(folder, urdf="/dev/zero")


def _secret_urdf(folder: Path) -> Path:
    (folder / "notes.txt").write_text(f"{SECRET}\n", encoding="utf-8")
    return _with_robot(folder, urdf=str(folder / "notes.txt"))


def _alias_scene(folder: Path) -> Path:
    """The issue's third case: a scene file of about 2 kB whose YAML aliases expand into 22,500 obstacles
    (one object of 150 primitives, named 150 times)."""
    lines = [
        "b: &b {type: box, dimensions: [0.01, 0.01, 0.01]}",
        "q: &q {position: [2, 2, 2], orientation: [0, 0, 0, 1]}",
        "o: &o {id: o, primitives: ["
        + ", ".join(["*b"] * 150)
        + "], primitive_poses: ["
        + ", ".join(["*q"] * 150)
        + "]}",
        "world: {collision_objects: [" + ", ".join(["*o"] * 150) + "]}",
    ]
    (folder / "scene.yaml").write_text("\n".join(lines) + "\n", encoding="utf-8")
    return _with_world(folder, scene_file=str(folder / "scene.yaml"))


def _device_scene(folder: Path) -> Path:
    return _with_world(folder, scene_file="/dev/zero")


def _secret_scene(folder: Path) -> Path:
    (folder / "notes.txt").write_text(f"world: {SECRET}\n: {SECRET}\n", encoding="utf-8")
    return _with_world(folder, scene_file=str(folder / "notes.txt"))


def _secret_scene_value(folder: Path) -> Path:
    (folder / "notes.txt").write_text(f"world: {{collision_objects: [{SECRET}]}}\n", encoding="utf-8")
    return _with_world(folder, scene_file=str(folder / "notes.txt"))


_SCENE_OBJECT = (
    "  - {id: o%d, primitives: [{type: box, dimensions: [0.1, 0.1, 0.1]}], "
    "primitive_poses: [{position: [2, 2, 2], orientation: [0, 0, 0, 1]}]}\n"
)


def _scene_of_size(folder: Path, size: int) -> Path:
    """A scene file of one collision object after another up to ``size`` bytes."""
    lines, total, k = ["world:\n collision_objects:\n"], 0, 0
    while total < size - 200:
        lines.append(_SCENE_OBJECT % k)
        total += len(lines[-1])
        k += 1
    (folder / "scene.yaml").write_text("".join(lines), encoding="utf-8")
    return _with_world(folder, scene_file=str(folder / "scene.yaml"))


def _scene_at_cap(folder: Path) -> Path:
    """A scene file just within its size cap: parsed (the largest parse the cap allows), then refused."""
    from clew_ros.core.parameters import LIMITS

    return _scene_of_size(folder, LIMITS.max_scene_file_bytes)


def _scene_over_cap(folder: Path) -> Path:
    from clew_ros.core.parameters import LIMITS

    return _scene_of_size(folder, LIMITS.max_scene_file_bytes + 4096)


def _parameter_file_at_cap(folder: Path) -> Path:
    """A parameter file just within its size cap (obstacles far beyond their cap): parsed, then refused."""
    from clew_ros.core.parameters import LIMITS

    path = _many_obstacles(folder)
    text = path.read_text(encoding="utf-8")
    entry = "        z{k}: {{pose: [2, 2, 2, 0, 0, 0], shape: box, size: [0.01, 0.01, 0.01]}}\n"
    marker = "      obstacles:\n"
    assert marker in text
    extra, k = [], 0
    while len(text) + sum(map(len, extra)) < LIMITS.max_parameter_file_bytes - 200:
        extra.append(entry.format(k=k))
        k += 1
    path.write_text(text.replace(marker, marker + "".join(extra), 1), encoding="utf-8")
    return path


def _many_obstacles(folder: Path) -> Path:
    parameters = world_tree()
    world = parameters["world"]
    names = [f"b{i}" for i in range(5001)]
    world["obstacle_names"] = names
    world["obstacles"] = {n: {"shape": "box", "size": [0.01] * 3, "pose": [2, 2, 2, 0, 0, 0]} for n in names}
    world.pop("supports")
    world.pop("object")
    world["robot"]["goal"] = copy.copy(world["robot"]["initial"])
    return write_world(folder, parameters)


#: Each crafted world: (name, writer of ``world.yaml`` in a folder, the cap or reason its refusal names).
CASES: tuple[tuple[str, Callable[[Path], Path], str], ...] = (
    ("mesh scaled x30", _scaled_mesh, "Limits.max_mesh_scale"),
    ("mesh scaled x9", _scaled_within_cap, "Limits.max_mesh_cells"),
    ("mesh 20 m wide", _huge_mesh_coordinates, "Limits.max_mesh_cells"),
    ("large triangles", _big_triangles, "Limits.max_split_triangles"),
    ("solid cube 0.4 m", _solid_cube, "Limits.max_solid_cells"),
    ("200 boxes on a link", _many_boxes, "Limits.max_spheres"),
    ("mesh /dev/zero", _device_mesh, "not a regular file"),
    ("mesh a text file", _secret_mesh, "holds no triangles"),
    ("5,000 URDF links", _many_links, "Limits.max_urdf_links"),
    ("100,000 collisions on a link", _many_collisions, "Limits.max_urdf_elements"),
    ("URDF /dev/zero", _device_urdf, "not a regular file"),
    ("URDF a text file", _secret_urdf, "expected URDF XML"),
    ("scene aliases: 22,500 obstacles", _alias_scene, "Limits.max_scene_objects"),
    ("scene /dev/zero", _device_scene, "not a regular file"),
    ("scene a text file", _secret_scene, "as YAML"),
    ("scene a text value", _secret_scene_value, "world.collision_objects[0]"),
    ("5,001 obstacles", _many_obstacles, "Limits.max_obstacles"),
    ("scene file at its size cap", _scene_at_cap, "Limits.max_scene_objects"),
    ("scene file over its size cap", _scene_over_cap, "Limits.max_scene_file_bytes"),
    ("parameter file at its size cap", _parameter_file_at_cap, "Limits.max_obstacles"),
)


def crafted_worlds(folder: Path) -> Iterator[tuple[str, Path, str]]:
    """Every case of :data:`CASES` written under ``folder``: ``(name, world file, expected text)``."""
    for number, (name, write, expected) in enumerate(CASES):
        case = folder / f"case_{number:02d}"
        case.mkdir(parents=True, exist_ok=True)
        yield name, write(case), expected


def record_start(
    directory: Path, world_file: Path, names: dict[str, str], *, meshes: bool = True, extra_markers: int = 0
) -> Path:
    """A spatial run's start recorded as the node records it (``~/world_yaml``, ``~/world_markers`` with the
    arm's meshes, ``~/robot_description``, ``/tf_static``, ``accepted`` then ``aborted``), its
    ``~/world_yaml`` naming other files: ``names`` maps ``urdf``, ``srdf``, ``scene_file`` to the path the
    recording names instead (a device, a secret); ``meshes=False``: the markers leave the meshes out (as a
    node without the picture package's dependencies draws them); ``extra_markers``: that many more obstacle
    cubes in ``~/world_markers`` (a crafted recording). Returns the run directory."""
    import uuid

    from clew_ros.core.settings import PlannerSettings
    from clew_ros.planar.world import read_parameter_file
    from clew_ros.recording import RunRecorder
    from clew_ros.recording.cdr import tf_message
    from clew_ros.render.spatial.meshes import simplify
    from clew_ros.ros import messages, spatial
    from clew_ros.ros.topics import TF_TOPICS, TOPICS

    tree = read_parameter_file(world_file)
    world, setup = spatial.load_spatial(tree, world_file.parent)
    planner = PlannerSettings.from_parameters({"planner": tree.get("planner", {})})
    run_id = uuid.UUID(int=0x56)
    recorder = RunRecorder(directory, run_id.hex, node_name="clew_planner")
    now = 1_700_000_000 * 10**9

    def write(name: str, msg: object) -> None:
        recorder.write(f"/clew_planner/{name}", msg, now, qos=TOPICS[name][1])

    with recorder:
        world_yaml = spatial.world_yaml_message(setup, world, planner, "clew_planner")
        document = yaml.safe_load(world_yaml.data)
        recorded = document["clew_planner"]["ros__parameters"]["world"]
        for key, path in names.items():
            (recorded["robot"] if key in ("urdf", "srdf") else recorded)[key] = path
        world_yaml.data = yaml.safe_dump(document)
        write("world_yaml", world_yaml)
        markers = spatial.world_markers(world, now, simplify=simplify if meshes else None)
        for k in range(extra_markers):
            cube = copy.deepcopy(next(m for m in markers.markers if m.ns in ("obstacles", "supports")))
            cube.id = 1000 + k
            markers.markers.append(cube)
        write("world_markers", markers)
        write("robot_description", messages.String(data=setup.description))
        recorder.write(
            "/tf_static", tf_message(spatial.static_transforms(setup, world), now), now, qos=TF_TOPICS["/tf_static"]
        )
        write("events", messages.event_message(run_id, "accepted", now / 1e9, source="plan", world=world.name))
        now += 10**9
        write("events", messages.event_message(run_id, "aborted", now / 1e9, code="TIME_LIMIT", message="cut"))
    return recorder.path


# --------------------------------------------------------------------------- fuzz corpus: spatial files


def scene_cases(seed: int = 0) -> Iterator[tuple[str, bytes]]:
    """Malformed planning scene files, from the shipped ``panda_scene.scene.yaml``."""
    from helpers.security_files import bit_flips, insertions, truncations

    rng = random.Random(seed)
    data = (CONFIG / "spatial" / "panda_scene.scene.yaml").read_bytes()
    yield from truncations(data, rng, 10)
    yield from bit_flips(data, rng, 10)
    yield from insertions(data, rng, 8)
    yield "nested YAML", b"world: " + b"[" * 100_000 + b"]" * 100_000
    yield "nested YAML", b"world: {collision_objects: [" + b"{a: " * 5_000 + b"1" + b"}" * 5_000 + b"]}"
    yield (
        "aliases",
        b"a: &a [1, 2]\nb: &b [*a, *a, *a, *a, *a, *a, *a, *a]\nc: &c [*b, *b, *b, *b, *b, *b, *b, *b]\nworld: *c\n",
    )
    yield "NaN or Infinity", data.replace(b"0.55", b".nan", 1)
    yield "NaN or Infinity", data.replace(b"0.04]", b".inf]", 1)
    yield "NaN or Infinity", data.replace(b"0.6, 1.0", b"1e999, 1.0", 1)
    for value in (b"'x'", b"true", b"null", b"{}", b"[[1]]", b"9" * 400):
        yield "wrong types", data.replace(b"[0.6, 1.0, 0.04]", value, 1)
        yield "wrong types", data.replace(b"frame_id: panda_link0", b"frame_id: " + value, 1)
        yield "wrong types", data.replace(b"type: box", b"type: " + value, 1)
        yield "wrong types", data.replace(b"id: table", b"id: " + value, 1)
    yield "binary", rng.randbytes(512)
    yield "binary", b"\xff\xfe" + data.decode().encode("utf-16-le")
    yield "binary", b"\x00" * 300


def urdf_cases(seed: int = 0) -> Iterator[tuple[str, bytes]]:
    """Malformed URDFs, from the Panda's (its meshes named by absolute path)."""
    from helpers.security_files import bit_flips, insertions, truncations

    rng = random.Random(seed)
    text = PANDA_URDF.read_text(encoding="utf-8").replace('filename="meshes/', f'filename="{MESHES}/')
    data = text.encode()
    yield from truncations(data, rng, 8)
    yield from bit_flips(data, rng, 10)
    yield from insertions(data, rng, 8)
    yield (
        "entities",
        (
            b'<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">'
            b'<!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;"><!ENTITY d "&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;">'
            b'<!ENTITY e "&d;&d;&d;&d;&d;&d;&d;&d;&d;&d;"><!ENTITY f "&e;&e;&e;&e;&e;&e;&e;&e;&e;&e;">]>'
            b'<robot name="&f;"><link name="&f;"/></robot>'
        ),
    )
    yield "entities", b'<?xml version="1.0"?><!DOCTYPE r [<!ENTITY x SYSTEM "file:///etc/passwd">]><robot name="&x;"/>'
    yield "nested XML", b"<robot>" + b"<a>" * 50_000 + b"</a>" * 50_000 + b"</robot>"
    yield "many links", text.replace("</robot>", '<link name="x"/>' * 3_000 + "</robot>").encode()
    for value in ("nan", "inf", "-1", "1e999", "x", ""):
        yield "NaN or wrong values", text.replace('scale="', f'scale="{value} ', 1).encode()
        yield "NaN or wrong values", text.replace('lower="', f'lower="{value}" x="', 1).encode()
        yield "NaN or wrong values", text.replace('xyz="0 0 0.333"', f'xyz="{value} 0 0.333"', 1).encode()
        yield (
            "NaN or wrong values",
            text.replace('<mesh filename="', f'<mesh scale="{value} 1 1" filename="', 1).encode(),
        )
    yield "files", text.replace(f"{MESHES}/link1.stl", "/dev/zero").encode()
    yield "files", text.replace(f"{MESHES}/link1.stl", "/etc/hostname").encode()
    yield "files", text.replace(f"{MESHES}/link1.stl", "package://no_such_package/x.stl").encode()
    yield "files", text.replace(f"{MESHES}/link1.stl", str(ROOT)).encode()
    yield "binary", rng.randbytes(512)
    yield "binary", b"\xff\xfe" + text[:2000].encode("utf-16-le")


def mesh_cases(seed: int = 0) -> Iterator[tuple[str, bytes]]:
    """Malformed STL meshes, from the Panda's link 3 (binary STL), plus ASCII and crafted ones."""
    from helpers.security_files import bit_flips, insertions, truncations

    rng = random.Random(seed)
    data = (MESHES / "link3.stl").read_bytes()
    yield from truncations(data, rng, 6)
    yield from bit_flips(data, rng, 6)
    yield from insertions(data, rng, 4)
    yield "huge triangle count", data[:80] + struct.pack("<I", 2**32 - 1) + data[84:]
    yield "NaN or Infinity", data[:96] + struct.pack("<f", float("nan")) + data[100:]
    yield "NaN or Infinity", data[:96] + struct.pack("<f", float("inf")) + data[100:]
    yield "huge coordinates", data[:96] + struct.pack("<f", 3e38) + data[100:]
    yield "ascii", b"solid x\n" + b"facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex nan 1 0\n" * 3
    yield "ascii", b"solid x\nendsolid x\n"
    yield "binary", rng.randbytes(600)
    yield "binary", b""
