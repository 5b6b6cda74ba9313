"""The robot of a spatial world: a URDF's chain from ``base_link`` to ``tip_link``, packed once.

:func:`load_robot` parses the URDF (``urdf_parser_py``) and folds it into frames: frame 0 is ``base_link``;
frame ``j`` (1..n) is the child side of the j-th planned joint, which moves it by ``origins[j - 1] @
motion(axes[j - 1], q[j - 1])`` from frame ``j - 1``. Fixed joints, and movable joints that are not planned
(fingers, held at their ``fixed_joint_positions``), are folded into the constant ``origins`` and into each
link's ``offset`` in the frame it rides on. Every link keeps its ``<collision>`` geometry (box, cylinder,
sphere, mesh). Every malformed input raises :class:`~clew_ros.core.errors.WorldError` naming the parameter
or URDF element at fault and what was expected.
"""

from __future__ import annotations

import io
import math
import re
import xml.etree.ElementTree as ET
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.errors import WorldError, short_repr
from clew_ros.core.files import FileRefusedError, read_regular_file
from clew_ros.core.parameters import LIMITS, Limits
from clew_ros.spatial.packages import package_paths_from_parameters, resolve_package_uri
from clew_ros.spatial.parameters import checked_value, world_value
from clew_ros.spatial.transforms import axis_motion, pose_matrix

__all__ = [
    "CONTINUOUS_LIMIT_RAD",
    "Geometry",
    "GivenMeshes",
    "LinkModel",
    "RobotModel",
    "RobotOptions",
    "load_robot",
    "read_text",
    "resolve_uri",
    "robot_from_parameters",
]

Matrix = NDArray[np.float64]

#: Limits given to a ``continuous`` joint (rad): two full turns wide, so a plan may turn it either way.
CONTINUOUS_LIMIT_RAD = 2.0 * math.pi

_MOVABLE = ("revolute", "continuous", "prismatic")


@dataclass(frozen=True, eq=False)
class Geometry:
    """One ``<collision>`` of a link.

    ``kind`` is ``box``, ``cylinder``, ``sphere`` or ``mesh``; ``size`` as ``shape_msgs/SolidPrimitive``
    dimensions (box ``[x, y, z]`` full extents, cylinder ``[height, radius]`` along its z, sphere
    ``[radius]``; empty for a mesh), m. ``origin`` is its 4x4 pose in the link's frame. A mesh keeps its
    (scaled) ``vertices`` (m) and triangle ``faces``, and ``source`` (the resolved file).
    """

    link: str
    kind: str
    size: tuple[float, ...]
    origin: Matrix
    vertices: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 3)))
    faces: NDArray[np.int64] = field(default_factory=lambda: np.zeros((0, 3), dtype=np.int64))
    source: str = ""


@dataclass(frozen=True, eq=False)
class LinkModel:
    """A link: the frame it rides on (0 = ``base_link``, j = after the j-th planned joint), its 4x4
    ``offset`` in that frame, and its collision geometry."""

    name: str
    frame: int
    offset: Matrix
    geometries: tuple[Geometry, ...]


@dataclass(frozen=True, eq=False)
class RobotModel:
    """A URDF's serial chain, folded into ``n`` planned joints (see the module docstring).

    ``joint_names`` are the planned joints in chain order; ``prismatic[j]`` tells a prismatic joint
    (m) from a revolute one (rad); ``lower`` / ``upper`` their limits; ``origins`` (n, 4, 4) and ``axes``
    (n, 3, unit) their kinematics; ``base`` is frame 0 in ``world`` (``base_pose``); ``tcp_frame`` /
    ``tcp`` the tool centre point (frame n and its 4x4 pose there). ``links`` are the links with
    collision geometry; ``parents[i]`` the index of link i's nearest ancestor with geometry (-1: none);
    ``exempt`` the pairs of link indices (i < j) never checked against each other (SRDF
    ``disable_collisions``, a link and its parent, links on one frame). ``fixed_positions`` the
    values of the movable joints that are not planned.
    """

    name: str
    urdf: str
    base_link: str
    tip_link: str
    joint_names: tuple[str, ...]
    prismatic: NDArray[np.bool_]
    lower: NDArray[np.float64]
    upper: NDArray[np.float64]
    origins: NDArray[np.float64]
    axes: NDArray[np.float64]
    base: Matrix
    tcp_frame: int
    tcp: Matrix
    links: tuple[LinkModel, ...]
    parents: tuple[int, ...]
    exempt: frozenset[tuple[int, int]]
    gripper_links: tuple[str, ...]
    fixed_positions: Mapping[str, float]
    #: How far (m) every link's collision geometry is grown (``world.robot.padding``; MoveIt's link padding).
    padding: float = 0.0
    #: ``continuous[j]``: planned joint j is a URDF ``continuous`` joint whose limits still span a full turn
    #: (equal modulo 2 pi, a move takes the short way round: :mod:`clew_ros.spatial.turns`); empty: none.
    continuous: NDArray[np.bool_] = field(default_factory=lambda: np.zeros(0, dtype=bool))

    @property
    def dof(self) -> int:
        return len(self.joint_names)

    def link_index(self, name: str) -> int:
        return next(i for i, link in enumerate(self.links) if link.name == name)

    def frames(self, q: Sequence[float]) -> NDArray[np.float64]:
        """The ``n + 1`` frames in ``world`` (4x4 each) at joint values ``q`` (a reference, in numpy)."""
        out = np.empty((self.dof + 1, 4, 4))
        out[0] = self.base
        for j in range(self.dof):
            out[j + 1] = out[j] @ self.origins[j] @ axis_motion(self.axes[j], q[j], prismatic=self.prismatic[j])
        return out

    def link_poses(self, q: Sequence[float]) -> dict[str, Matrix]:
        """Every link's 4x4 pose in ``world`` at ``q`` (numpy reference)."""
        frames = self.frames(q)
        return {link.name: frames[link.frame] @ link.offset for link in self.links}

    def tcp_pose(self, q: Sequence[float]) -> Matrix:
        """The tool centre point's 4x4 pose in ``world`` at ``q``."""
        pose: Matrix = self.frames(q)[self.tcp_frame] @ self.tcp
        return pose


# ----------------------------------------------------------------------------------------- files, URIs


def resolve_uri(uri: str, folder: Path, parameter: str, package_paths: Sequence[Path] = ()) -> Path:
    """The file a URDF mesh ``filename`` or a parameter's path names: ``package://PKG/rest``
    (:func:`~clew_ros.spatial.packages.resolve_package_uri`: ``package_paths``, the ament index,
    ``ROS_PACKAGE_PATH``), ``file://`` absolute, or a path relative to ``folder``."""
    if uri.startswith("package://"):
        return resolve_package_uri(uri, package_paths)
    if uri.startswith("file://"):
        return Path(uri[len("file://") :])
    path = Path(uri)
    return path if path.is_absolute() else folder / path


def read_text(path: Path, parameter: str, limits: Limits = LIMITS) -> str:
    """A URDF or SRDF file's text: a regular file of at most ``Limits.max_urdf_bytes``, UTF-8."""
    return _capped_text(path, parameter, limits.max_urdf_bytes, "Limits.max_urdf_bytes")


@contextmanager
def _quiet_urdf_parser() -> Iterator[list[str]]:
    """urdf_parser_py reports unknown elements on stderr; collect them instead (the core does not print)."""
    from urdf_parser_py.xml_reflection import core  # type: ignore[import-untyped]

    messages: list[str] = []
    saved = core.on_error
    core.on_error = messages.append
    try:
        yield messages
    finally:
        core.on_error = saved


# ----------------------------------------------------------------------------------------- parsing


def _parse_urdf(text: str, parameter: str) -> Any:
    try:
        from urdf_parser_py.urdf import URDF  # type: ignore[import-untyped]
    except ImportError:
        raise WorldError(parameter, "reading a URDF needs urdf_parser_py (pip install 'clew_ros[spatial]')") from None
    try:
        with _quiet_urdf_parser():
            return URDF.from_xml_string(text.encode("utf-8") if text.lstrip().startswith("<?xml") else text)
    except ET.ParseError as error:
        raise WorldError(parameter, f"expected URDF XML, the text does not parse: {error}") from None
    except Exception as error:  # noqa: BLE001  # urdf_parser_py raises bare Exceptions for missing attributes
        raise WorldError(parameter, f"expected a valid URDF <robot>: {_unquoted(error)}") from None


def _origin(element: Any) -> Matrix:
    origin = getattr(element, "origin", None)
    if origin is None:
        return np.eye(4)
    xyz = list(origin.xyz) if origin.xyz is not None else [0.0, 0.0, 0.0]
    rpy = list(origin.rpy) if origin.rpy is not None else [0.0, 0.0, 0.0]
    return pose_matrix([*xyz, *rpy])


def _positive(values: Sequence[float], where: str, parameter: str) -> tuple[float, ...]:
    out = tuple(float(v) for v in values)
    if not all(math.isfinite(v) and v > 0.0 for v in out):
        raise WorldError(parameter, f"{where}: expected positive finite sizes, got {short_repr(list(out))}")
    return out


def _load_mesh(
    path: Path, scale: Sequence[float] | None, where: str, parameter: str, limits: Limits = LIMITS
) -> tuple[Matrix, Any]:
    try:
        import trimesh
    except ImportError:
        raise WorldError(
            parameter, f"{where}: reading meshes needs trimesh (pip install 'clew_ros[spatial]')"
        ) from None
    factors = None if scale is None else _mesh_scale(scale, where, parameter, limits)
    data = _mesh_bytes(path, where, parameter, limits)
    try:
        mesh = trimesh.load(io.BytesIO(data), file_type=path.suffix.lstrip(".").lower(), force="mesh", process=True)
    except Exception as error:  # noqa: BLE001  # trimesh and its loaders raise many kinds for a bad file
        raise WorldError(
            parameter, f"{where}: cannot read mesh {str(path)!r} ({type(error).__name__}; expected STL, OBJ or DAE)"
        ) from None
    vertices = np.asarray(getattr(mesh, "vertices", np.zeros((0, 3))), dtype=np.float64)
    faces = np.asarray(getattr(mesh, "faces", np.zeros((0, 3))), dtype=np.int64)
    if len(faces) == 0 or not np.all(np.isfinite(vertices)):
        raise WorldError(parameter, f"{where}: mesh {str(path)!r} holds no triangles (expected STL, OBJ or DAE)")
    if len(faces) > limits.max_mesh_triangles:
        raise WorldError(
            parameter,
            f"{where}: mesh {str(path)!r} holds {len(faces)} triangles, more than Limits.max_mesh_triangles "
            f"({limits.max_mesh_triangles})",
        )
    if factors is not None:
        vertices = vertices * np.asarray(factors)
    return vertices, faces


def _geometries(
    link: Any, folder: Path, parameter: str, package_paths: Sequence[Path] = (), budget: _MeshBudget | None = None
) -> tuple[Geometry, ...]:
    from urdf_parser_py import urdf  # type: ignore[import-untyped]

    budget = budget or _MeshBudget(LIMITS)
    out = []
    for k, collision in enumerate(link.collisions):
        where = f"<link name={link.name!r}> <collision> {k}"
        shape, origin = collision.geometry, _origin(collision)
        if isinstance(shape, urdf.Box):
            size = _positive(shape.size or [], f"{where} <box size>", parameter)
            if len(size) != 3:
                raise WorldError(parameter, f"{where} <box size>: expected 3 numbers")
            out.append(Geometry(link.name, "box", size, origin))
        elif isinstance(shape, urdf.Cylinder):
            height, radius = _positive([shape.length, shape.radius], f"{where} <cylinder>", parameter)
            out.append(Geometry(link.name, "cylinder", (height, radius), origin))
        elif isinstance(shape, urdf.Sphere):
            out.append(Geometry(link.name, "sphere", _positive([shape.radius], f"{where} <sphere>", parameter), origin))
        elif isinstance(shape, urdf.Mesh) and budget.given is not None:  # named only, never opened
            vertices, faces = budget.take_given(link.name, k, origin, where, parameter)
            out.append(Geometry(link.name, "mesh", (), origin, vertices, faces, str(shape.filename or "")))
        elif isinstance(shape, urdf.Mesh):
            path = resolve_uri(shape.filename or "", folder, parameter, package_paths)
            vertices, faces = budget.load(path, shape.scale, where, parameter)
            out.append(Geometry(link.name, "mesh", (), origin, vertices, faces, str(path)))
        else:
            raise WorldError(parameter, f"{where}: expected box, cylinder, sphere or mesh geometry")
    return tuple(out)


def _disabled_pairs(srdf_text: str, links: set[str], parameter: str) -> set[tuple[str, str]]:
    try:
        root = ET.fromstring(srdf_text)
    except ET.ParseError as error:
        raise WorldError(parameter, f"expected SRDF XML, the text does not parse: {error}") from None
    if root.tag != "robot":
        raise WorldError(parameter, f"expected an SRDF <robot> element, got <{root.tag}>")
    pairs = set()
    for element in root.iter("disable_collisions"):
        a, b = element.get("link1"), element.get("link2")
        for name in (a, b):
            if name is None or name not in links:
                raise WorldError(parameter, f"<disable_collisions> names link {name!r}, which the URDF lacks")
        pairs.add((str(a), str(b)))
    return pairs


def _limits(joint: Any, parameter: str) -> tuple[float, float]:
    if joint.type == "continuous":
        return -CONTINUOUS_LIMIT_RAD, CONTINUOUS_LIMIT_RAD
    limit = joint.limit
    if limit is None or limit.lower is None or limit.upper is None:
        raise WorldError(
            parameter, f"<joint name={joint.name!r}>: expected <limit lower upper> on a {joint.type} joint"
        )
    lower, upper = float(limit.lower), float(limit.upper)
    if not (math.isfinite(lower) and math.isfinite(upper) and lower <= upper):
        raise WorldError(
            parameter, f"<joint name={joint.name!r}> <limit>: expected lower <= upper, got {lower}, {upper}"
        )
    return lower, upper


def _axis(joint: Any, parameter: str) -> NDArray[np.float64]:
    axis = np.asarray(joint.axis if joint.axis is not None else [1.0, 0.0, 0.0], dtype=np.float64)
    norm = float(np.linalg.norm(axis))
    if axis.shape != (3,) or not math.isfinite(norm) or norm < 1e-9:
        raise WorldError(parameter, f"<joint name={joint.name!r}> <axis xyz>: expected a non-zero 3-vector")
    return axis / norm


def _narrowed(
    urdf_limits: NDArray[np.float64], given: Any, names: Sequence[str], parameter: str, lower: bool
) -> NDArray[np.float64]:
    if given is None:
        return urdf_limits
    try:
        values = np.asarray([float(v) for v in given], dtype=np.float64)
    except (TypeError, ValueError):
        values = np.zeros(0)
    if isinstance(given, str) or values.shape != urdf_limits.shape or not np.all(np.isfinite(values)):
        raise WorldError(parameter, f"expected {len(names)} finite numbers (joints {', '.join(names)})")
    wider = values < urdf_limits - 1e-12 if lower else values > urdf_limits + 1e-12
    if np.any(wider):
        j = int(np.argmax(wider))
        raise WorldError(
            parameter, f"may only narrow the URDF's limits: {names[j]} {values[j]} is outside its {urdf_limits[j]}"
        )
    return values


def _tree(robot: Any, base_link: str, tip_link: str, source: str) -> tuple[dict[str, Any], str]:
    """Each link's parent joint, and the root link; every reference checked."""
    names = {link.name for link in robot.links}
    for key, name in (("base_link", base_link), ("tip_link", tip_link)):
        if name not in names:
            raise WorldError(f"world.robot.{key}", f"link {name!r} is not in the URDF; its links: {sorted(names)}")
    for joint in robot.joints:
        for end in (joint.parent, joint.child):
            if end not in names:
                raise WorldError(source, f"<joint name={joint.name!r}> names link {end!r}, which the URDF lacks")
        if joint.type not in (*_MOVABLE, "fixed"):
            raise WorldError(
                source,
                f"<joint name={joint.name!r}>: type {joint.type!r} is not supported "
                "(expected revolute, continuous, prismatic or fixed)",
            )
    parent_joint = {joint.child: joint for joint in robot.joints}
    roots = sorted(names - set(parent_joint))
    if len(roots) != 1:
        raise WorldError(source, f"expected one root link (a tree), found {roots or 'none (a cycle)'}")
    return parent_joint, roots[0]


def _planned(parent_joint: Mapping[str, Any], base_link: str, tip_link: str) -> list[Any]:
    """The movable joints from ``base_link`` down to ``tip_link``, in chain order."""
    chain: list[Any] = []
    link = tip_link
    while link != base_link:
        if link not in parent_joint:
            raise WorldError(
                "world.robot.tip_link", f"link {tip_link!r} is not below base_link {base_link!r} in the URDF"
            )
        chain.append(parent_joint[link])
        link = parent_joint[link].parent
    planned = [joint for joint in reversed(chain) if joint.type in _MOVABLE]
    if not planned:
        raise WorldError("world.robot.tip_link", f"no movable joint between {base_link!r} and {tip_link!r}")
    return planned


def _fixed_positions(
    robot: Any, planned: Sequence[str], names: Sequence[str], values: Sequence[float], source: str
) -> dict[str, float]:
    """The movable joints that are not planned: given values, or 0 clamped to their limits; mimic joints
    follow theirs."""
    if len(names) != len(values):
        raise WorldError("world.robot.fixed_joint_positions", "expected one value per world.robot.fixed_joint_names")
    by_name = {joint.name: joint for joint in robot.joints}
    fixed: dict[str, float] = {}
    for name, value in zip(names, values, strict=True):
        if name not in by_name or by_name[name].type not in _MOVABLE or name in planned:
            raise WorldError("world.robot.fixed_joint_names", f"{name!r} is not a movable joint outside the chain")
        lower, upper = _limits(by_name[name], source)
        if not lower <= float(value) <= upper:
            raise WorldError(
                "world.robot.fixed_joint_positions", f"{name} = {value} is outside its limits [{lower}, {upper}]"
            )
        fixed[name] = float(value)
    for joint in robot.joints:
        if joint.type in _MOVABLE and joint.name not in planned and joint.name not in fixed:
            mimic = getattr(joint, "mimic", None)
            if mimic is not None and mimic.joint in planned:
                raise WorldError(
                    source, f"<joint name={joint.name!r}> mimics planned joint {mimic.joint!r}: not supported"
                )
            lower, upper = _limits(joint, source)
            fixed[joint.name] = min(max(0.0, lower), upper)
    for joint in robot.joints:
        mimic = getattr(joint, "mimic", None)
        if mimic is not None and joint.name not in names and mimic.joint in fixed:
            fixed[joint.name] = (mimic.multiplier or 1.0) * fixed[mimic.joint] + (mimic.offset or 0.0)
    return fixed


def _reference(
    robot: Any, root: str, planned: Sequence[str], fixed: Mapping[str, float], axes: Mapping[str, Matrix]
) -> tuple[dict[str, Matrix], dict[str, int]]:
    """Every link's pose in the root link with the planned joints at 0 (others at ``fixed``), and the frame
    each link rides on (the number of planned joints above it)."""
    children: dict[str, list[Any]] = {}
    for joint in robot.joints:
        children.setdefault(joint.parent, []).append(joint)
    index = {name: j + 1 for j, name in enumerate(planned)}
    pose, frame_of = {root: np.eye(4)}, {root: 0}
    stack = [root]
    while stack:
        parent = stack.pop()
        for joint in children.get(parent, []):
            motion = np.eye(4)
            if joint.name in fixed:
                motion = axis_motion(axes[joint.name], fixed[joint.name], prismatic=joint.type == "prismatic")
            pose[joint.child] = pose[parent] @ _origin(joint) @ motion
            frame_of[joint.child] = index.get(joint.name, frame_of[parent])
            stack.append(joint.child)
    return pose, frame_of


def _exempt(
    links: Sequence[LinkModel], parents: Sequence[int], srdf_text: str | None, names: set[str]
) -> frozenset[tuple[int, int]]:
    """Link pairs never checked: a link and its parent, links on one frame, the SRDF's ``disable_collisions``."""
    exempt = {(min(i, p), max(i, p)) for i, p in enumerate(parents) if p >= 0}
    exempt |= {(i, j) for i in range(len(links)) for j in range(i + 1, len(links)) if links[i].frame == links[j].frame}
    if srdf_text is not None:
        index = {link.name: i for i, link in enumerate(links)}
        for a, b in _disabled_pairs(srdf_text, names, "world.robot.srdf"):
            if a in index and b in index and a != b:
                exempt.add((min(index[a], index[b]), max(index[a], index[b])))
    return frozenset(exempt)


@dataclass(frozen=True)
class RobotOptions:
    """What a world adds to a URDF's chain (interface.md section 1b), each as its ``world.robot.*`` parameter
    says: ``srdf_text`` (its ``disable_collisions`` pairs), ``joint_lower`` / ``joint_upper`` (narrowing the
    URDF's limits; ``None``: the URDF's), ``fixed_joint_names`` / ``fixed_joint_positions`` (the other
    movable joints), ``gripper_links``, ``package_paths`` (the folders that hold the packages of ``package://``
    mesh URIs, before the ament index) and ``meshes``: the meshes themselves (a recording's), so that no file
    the URDF names is opened."""

    srdf_text: str | None = None
    joint_lower: Sequence[float] | None = None
    joint_upper: Sequence[float] | None = None
    fixed_joint_names: Sequence[str] = ()
    fixed_joint_positions: Sequence[float] = ()
    gripper_links: Sequence[str] = ()
    package_paths: Sequence[Path] = ()
    meshes: GivenMeshes | None = None


def load_robot(
    urdf_text: str,
    *,
    folder: Path,
    base_link: str,
    tip_link: str,
    tcp: Sequence[float] = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    base_pose: Sequence[float] = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    source: str = "world.robot.urdf",
    options: RobotOptions | None = None,
) -> RobotModel:
    """Parse a URDF (its text; ``folder`` resolves relative mesh paths) into a :class:`RobotModel`.

    ``source`` names the parameter the URDF came from, for errors. Poses are ``[x, y, z, roll, pitch, yaw]``
    (m, rad): ``tcp`` in ``tip_link``'s frame, ``base_pose`` of ``base_link`` in ``world``. ``options``: what
    the world adds (:class:`RobotOptions`; default none).
    """
    options = options or RobotOptions()
    srdf_text, meshes, package_paths = options.srdf_text, options.meshes, options.package_paths
    _check_robot_text(urdf_text, srdf_text, source, LIMITS)
    robot = _parse_urdf(urdf_text, source)
    _check_origins(robot, source)
    names = {link.name for link in robot.links}
    parent_joint, root = _tree(robot, base_link, tip_link, source)
    planned = _planned(parent_joint, base_link, tip_link)
    planned_names = [joint.name for joint in planned]
    fixed = _fixed_positions(robot, planned_names, options.fixed_joint_names, options.fixed_joint_positions, source)
    axes = {joint.name: _axis(joint, source) for joint in robot.joints if joint.type in _MOVABLE}
    pose, frame_of = _reference(robot, root, planned_names, fixed, axes)
    frame_pose = [pose[base_link]] + [pose[joint.child] for joint in planned]
    inverse = [np.linalg.inv(f) for f in frame_pose]

    limits = np.array([_limits(joint, source) for joint in planned])
    lower = _narrowed(limits[:, 0], options.joint_lower, planned_names, "world.robot.joint_lower", lower=True)
    upper = _narrowed(limits[:, 1], options.joint_upper, planned_names, "world.robot.joint_upper", lower=False)
    if np.any(lower > upper):
        raise WorldError("world.robot.joint_lower", "expected joint_lower <= joint_upper for every joint")
    for name in options.gripper_links:
        if name not in names:
            raise WorldError("world.robot.gripper_links", f"link {name!r} is not in the URDF")

    budget = _MeshBudget(LIMITS, meshes)
    links = tuple(
        LinkModel(link.name, frame_of[link.name], inverse[frame_of[link.name]] @ pose[link.name], geometries)
        for link in robot.links
        if (geometries := _geometries(link, folder, source, package_paths, budget))
    )
    index = {link.name: i for i, link in enumerate(links)}
    parents = tuple(_collision_parent(link.name, parent_joint, index) for link in links)
    tcp_matrix = inverse[frame_of[tip_link]] @ pose[tip_link] @ pose_matrix(_pose(tcp, "world.robot.tcp"))
    return RobotModel(
        name=str(robot.name or ""),
        urdf=urdf_text,
        base_link=base_link,
        tip_link=tip_link,
        joint_names=tuple(planned_names),
        prismatic=np.array([joint.type == "prismatic" for joint in planned]),
        lower=lower,
        upper=upper,
        origins=np.array([inverse[j] @ frame_pose[j + 1] for j in range(len(planned))]),
        axes=np.array([axes[name] for name in planned_names]),
        base=pose_matrix(_pose(base_pose, "world.robot.base_pose")),
        tcp_frame=frame_of[tip_link],
        tcp=tcp_matrix,
        links=links,
        parents=parents,
        exempt=_exempt(links, parents, srdf_text, names),
        gripper_links=tuple(options.gripper_links),
        fixed_positions=dict(fixed),
        continuous=_wrapping(planned, lower, upper),
    )


def _wrapping(planned: Sequence[Any], lower: NDArray[np.float64], upper: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Which planned joints are ``continuous`` with limits still a full turn wide (not narrowed below it)."""
    kinds = np.array([joint.type == "continuous" for joint in planned], dtype=bool)
    return kinds & (upper - lower >= 2.0 * math.pi - 1e-9)


def _collision_parent(name: str, parent_joint: Mapping[str, Any], index: Mapping[str, int]) -> int:
    """The index of the nearest ancestor of link ``name`` that has collision geometry (-1: none)."""
    while name in parent_joint:
        name = parent_joint[name].parent
        if name in index:
            return index[name]
    return -1


def _pose(value: Any, parameter: str) -> list[float]:
    try:
        out = [float(v) for v in value]
    except (TypeError, ValueError):
        raise WorldError(parameter, f"expected a pose [x, y, z, roll, pitch, yaw], got {short_repr(value)}") from None
    if len(out) != 6 or not all(math.isfinite(v) for v in out):
        raise WorldError(
            parameter, f"expected a pose of 6 finite numbers [x, y, z, roll, pitch, yaw], got {short_repr(value)}"
        )
    return out


def _strings(tree: Mapping[str, Any], key: str) -> list[str]:
    value = world_value(tree, f"world.robot.{key}")
    if value is None:
        return []
    if isinstance(value, str) or not all(isinstance(v, str) for v in value):
        raise WorldError(f"world.robot.{key}", f"expected a list of names, got {short_repr(value)}")
    return list(value)


def _floats(tree: Mapping[str, Any], key: str) -> list[float]:
    value = world_value(tree, f"world.robot.{key}")
    if value is None:
        return []
    try:
        out = [float(v) for v in value]
    except (TypeError, ValueError):
        raise WorldError(f"world.robot.{key}", f"expected a list of numbers, got {short_repr(value)}") from None
    if isinstance(value, str) or not all(math.isfinite(v) for v in out):
        raise WorldError(f"world.robot.{key}", f"expected a list of finite numbers, got {short_repr(value)}")
    return out


def robot_from_parameters(robot: Mapping[str, Any], folder: Path, meshes: GivenMeshes | None = None) -> RobotModel:
    """The robot of a ``world.robot`` parameter tree (interface.md section 1b); relative paths are read from
    ``folder`` (the parameter file's). ``meshes``: the URDF's meshes given (:func:`load_robot`). Defaults,
    required keys and the scalars' checks: :data:`~clew_ros.spatial.parameters.SPATIAL_WORLD_PARAMETERS`."""
    has_file, has_text = "urdf" in robot, "description" in robot
    if has_file == has_text:
        raise WorldError("world.robot.urdf", "expected exactly one of world.robot.urdf and world.robot.description")
    base_link = checked_value(robot, "world.robot.base_link")
    tip_link = checked_value(robot, "world.robot.tip_link")
    packages = package_paths_from_parameters(robot, folder)
    if has_file:
        path = resolve_uri(checked_value(robot, "world.robot.urdf"), folder, "world.robot.urdf", packages)
        text, urdf_folder, source = read_text(path, "world.robot.urdf"), path.parent, "world.robot.urdf"
    else:
        if not isinstance(robot["description"], str):
            raise WorldError("world.robot.description", "expected the URDF text")
        text, urdf_folder, source = robot["description"], folder, "world.robot.description"
    srdf = None
    if "srdf" in robot:
        srdf_path = resolve_uri(checked_value(robot, "world.robot.srdf"), folder, "world.robot.srdf", packages)
        srdf = read_text(srdf_path, "world.robot.srdf")
    options = RobotOptions(
        srdf_text=srdf,
        joint_lower=world_value(robot, "world.robot.joint_lower"),
        joint_upper=world_value(robot, "world.robot.joint_upper"),
        fixed_joint_names=_strings(robot, "fixed_joint_names"),
        fixed_joint_positions=_floats(robot, "fixed_joint_positions"),
        gripper_links=_strings(robot, "gripper_links"),
        package_paths=packages,
        meshes=meshes,
    )
    model = load_robot(
        text,
        folder=urdf_folder,
        base_link=base_link,
        tip_link=tip_link,
        tcp=world_value(robot, "world.robot.tcp"),
        base_pose=world_value(robot, "world.robot.base_pose"),
        source=source,
        options=options,
    )
    return replace(model, padding=checked_value(robot, "world.robot.padding"))


# ----------------------------------------------------------------------------------------- caps


def _capped_text(path: Path, parameter: str, limit: int, cap: str) -> str:
    """A regular file's UTF-8 text, refused beyond ``limit`` bytes (``cap``) without quoting what it holds."""
    try:
        data = read_regular_file(path, limit, cap)
    except FileRefusedError as error:
        raise WorldError(parameter, f"cannot read {str(path)!r}: {error}") from None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as error:
        raise WorldError(
            parameter, f"cannot read {str(path)!r}: expected UTF-8 text ({error.reason} at byte {error.start})"
        ) from None


def _check_robot_text(urdf_text: str, srdf_text: str | None, source: str, limits: Limits) -> None:
    """The URDF and SRDF texts held to ``Limits.max_urdf_bytes``, the URDF's elements to
    ``Limits.max_urdf_elements`` and its links and joints to ``Limits.max_urdf_links``, before the URDF parser
    (whose work grows with them) sees them."""
    for text, parameter in ((urdf_text, source), (srdf_text, "world.robot.srdf")):
        if text is not None and len(text.encode("utf-8", "surrogatepass")) > limits.max_urdf_bytes:
            raise WorldError(
                parameter,
                f"the text holds {len(text.encode('utf-8', 'surrogatepass'))} bytes, more than "
                f"Limits.max_urdf_bytes ({limits.max_urdf_bytes})",
            )
    try:
        root = ET.fromstring(urdf_text)
    except ET.ParseError as error:
        raise WorldError(source, f"expected URDF XML, the text does not parse: {error}") from None
    elements = sum(1 for _ in root.iter())
    if elements > limits.max_urdf_elements:
        raise WorldError(
            source,
            f"the URDF has {elements} XML elements, more than Limits.max_urdf_elements ({limits.max_urdf_elements})",
        )
    for tag in ("link", "joint"):
        count = sum(1 for _ in root.iter(tag))
        if count > limits.max_urdf_links:
            raise WorldError(
                source,
                f"the URDF has {count} <{tag}> elements, more than Limits.max_urdf_links ({limits.max_urdf_links})",
            )


def _unquoted(error: BaseException) -> str:
    """An error's message with every quoted value left out and cut to 160 characters: what the URDF parser
    says about an element, without repeating what a file holds."""
    text = re.sub(r"'[^']*'|\"[^\"]*\"", "'...'", " ".join(str(error).split()))
    return text if len(text) <= 160 else text[:157] + "..."


def _check_origins(robot: Any, source: str) -> None:
    """Every ``<origin xyz rpy>`` of the URDF's joints and collisions: finite numbers (a NaN would reach every
    frame and every collision check)."""
    elements = [(f"<joint name={j.name!r}>", j) for j in robot.joints]
    elements += [
        (f"<link name={link.name!r}> <collision> {k}", c) for link in robot.links for k, c in enumerate(link.collisions)
    ]
    for where, element in elements:
        origin = getattr(element, "origin", None)
        values = [*(getattr(origin, "xyz", None) or ()), *(getattr(origin, "rpy", None) or ())]
        try:
            finite = all(math.isfinite(float(v)) for v in values)
        except (TypeError, ValueError):
            finite = False
        if not finite:
            raise WorldError(source, f"{where} <origin>: expected finite xyz and rpy")


def _mesh_scale(scale: Sequence[float], where: str, parameter: str, limits: Limits) -> tuple[float, ...]:
    """A ``<mesh scale>``: positive, finite, each factor at most ``Limits.max_mesh_scale``."""
    factors = _positive(scale, f"{where} scale", parameter)
    if max(factors) > limits.max_mesh_scale:
        raise WorldError(
            parameter,
            f"{where} <mesh scale>: factor {max(factors):g} is more than Limits.max_mesh_scale "
            f"({limits.max_mesh_scale:g})",
        )
    return factors


def _mesh_bytes(path: Path, where: str, parameter: str, limits: Limits) -> bytes:
    """A mesh file's bytes: a regular file of at most ``Limits.max_mesh_file_bytes``."""
    try:
        return read_regular_file(path, limits.max_mesh_file_bytes, "Limits.max_mesh_file_bytes")
    except FileRefusedError as error:
        raise WorldError(parameter, f"{where}: mesh file {str(path)!r}: {error}") from None


#: A URDF's meshes given rather than read: link name -> its meshes' triangle corners (m, (3t, 3) each, in the
#: link's frame, scaled and placed by the collision's origin), in the order of the link's mesh collisions (as
#: ``~/world_markers`` draws them).
GivenMeshes = Mapping[str, Sequence[NDArray[np.float64]]]


class _MeshBudget:
    """The meshes of one robot: each file read once (a file named by many links costs one read), or taken
    from ``given``; their triangles held to ``Limits.max_total_triangles`` as they come."""

    def __init__(self, limits: Limits, given: GivenMeshes | None = None) -> None:
        self.limits = limits
        self.given = given
        self.triangles = 0
        self._read: dict[tuple[str, tuple[float, ...] | None], tuple[Matrix, Any]] = {}
        self._taken: dict[str, int] = {}

    def take_given(self, link: str, k: int, origin: Matrix, where: str, parameter: str) -> tuple[Matrix, Any]:
        """The next given mesh of ``link``, in its collision's own frame (``origin`` undone)."""
        assert self.given is not None
        index = self._taken.get(link, 0)
        corners = self.given.get(link, ())
        if index >= len(corners):
            raise WorldError(parameter, f"{where}: the mesh is not among the meshes given (a recording's markers)")
        self._taken[link] = index + 1
        placed = np.asarray(corners[index], dtype=np.float64).reshape(-1, 3)
        if len(placed) == 0 or len(placed) % 3 or not np.all(np.isfinite(placed)):
            raise WorldError(parameter, f"{where}: the mesh given is not a list of triangles")
        self._count(len(placed) // 3, where, parameter)
        if len(placed) // 3 > self.limits.max_mesh_triangles:
            raise WorldError(parameter, f"{where}: the mesh given holds more than Limits.max_mesh_triangles triangles")
        vertices = (placed - origin[:3, 3]) @ origin[:3, :3]
        return vertices, np.arange(len(placed), dtype=np.int64).reshape(-1, 3)

    def _count(self, triangles: int, where: str, parameter: str) -> None:
        self.triangles += triangles
        if self.triangles > self.limits.max_total_triangles:
            raise WorldError(
                parameter,
                f"{where}: the robot's meshes hold more than Limits.max_total_triangles "
                f"({self.limits.max_total_triangles}) triangles",
            )

    def load(self, path: Path, scale: Sequence[float] | None, where: str, parameter: str) -> tuple[Matrix, Any]:
        key = (str(path), None if scale is None else tuple(float(v) for v in scale))
        if key not in self._read:
            self._read[key] = _load_mesh(path, scale, where, parameter, self.limits)
        vertices, faces = self._read[key]
        self._count(len(faces), where, parameter)
        return vertices, faces
