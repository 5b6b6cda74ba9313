"""The plan (``clew-plan/1``, ``interface.md`` section 2): one type, one reader, one writer, for every kind of world.

:class:`Plan` is what every consumer takes: the validators, the node's
playback, the recording rebuilt from a trajectory, the renderer. It is
written and read only here (:meth:`Plan.to_json` / :meth:`Plan.from_json`).
Replaying and validating a plan need its world: :mod:`clew_ros.planar.plan`
and :mod:`clew_ros.spatial.plan`.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from clew_ros.core.clew import PlanResult
from clew_ros.core.errors import PlanFileError, short_repr
from clew_ros.core.files import FileRefusedError, read_regular_file
from clew_ros.core.settings import Outcome

__all__ = ["FORMAT", "KINDS", "POSE_WIDTH", "Plan", "PlanFileLimits", "PlanLandmark", "PlanSegment", "PlanWorld"]

FORMAT = "clew-plan/1"
#: The segment kinds, in the order a plan alternates them.
KINDS = ("transit", "transfer")
#: ``world_kind`` (section 1b) and the numbers of an object pose in its plans: planar (x, y, theta), spatial
#: (x, y, z, roll, pitch, yaw).
POSE_WIDTH = {"planar": 3, "spatial": 6}


def _numbers(values: Any, depth: int) -> bool:
    """Whether ``values`` is a list nested ``depth`` deep whose leaves are JSON numbers (not strings, not booleans)."""
    if depth == 0:
        return isinstance(values, int | float) and not isinstance(values, bool)
    return isinstance(values, list) and all(_numbers(value, depth - 1) for value in values)


def _array(values: Any, what: str, shape: tuple[int | None, ...]) -> np.ndarray:
    """A read-only array of finite floats of ``shape`` (``None``: any length), or :class:`PlanFileError`
    naming ``what``."""
    wanted = " x ".join("N" if s is None else str(s) for s in shape)
    if not _numbers(values, len(shape)):
        raise PlanFileError(f"{what}: expected an array of numbers of shape {wanted}, got {short_repr(values)}")
    try:
        array = np.array(values, dtype=float)
    except (ValueError, OverflowError):  # ragged lists, integers too large for a float
        raise PlanFileError(f"{what}: expected an array of shape {wanted} of floats") from None
    if array.ndim != len(shape) or any(s is not None and s != a for s, a in zip(shape, array.shape, strict=True)):
        raise PlanFileError(f"{what}: expected an array of shape {wanted}, got shape {array.shape}")
    if not np.all(np.isfinite(array)):
        raise PlanFileError(f"{what}: expected finite numbers, got {short_repr(values)}")
    array.setflags(write=False)
    return array


def _floats(array: np.ndarray) -> list[Any]:
    """Nested lists of Python floats (JSON-ready)."""
    floats: list[Any] = array.tolist()
    return floats


def _optional_int(value: Any, what: str) -> int | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int):
        raise PlanFileError(f"{what}: expected an integer or null, got {value!r:.80}")
    return value


class _JointNamed(Protocol):
    @property
    def joint_names(self) -> Sequence[str]: ...


class PlanWorld(Protocol):
    """What a plan file takes from its world: the world's name and its robot's joint names."""

    @property
    def name(self) -> str: ...

    @property
    def robot(self) -> _JointNamed: ...


@dataclass(frozen=True, eq=False)
class PlanSegment:
    """A transit (``grasp`` None) or a transfer holding ``grasp``; ``waypoints`` (M, n) rad."""

    kind: str
    grasp: int | None
    waypoints: np.ndarray

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "grasp": self.grasp, "waypoints": _floats(self.waypoints)}

    @classmethod
    def from_dict(cls, data: Any, what: str) -> PlanSegment:
        if not isinstance(data, Mapping):
            raise PlanFileError(f"{what}: expected an object with kind, grasp and waypoints")
        kind = data.get("kind")
        if kind not in KINDS:
            raise PlanFileError(f"{what}.kind: expected one of {list(KINDS)}, got {kind!r:.80}")
        return cls(
            kind,
            _optional_int(data.get("grasp"), f"{what}.grasp"),
            _array(data.get("waypoints"), f"{what}.waypoints", (None, None)),
        )


@dataclass(frozen=True, eq=False)
class PlanLandmark:
    """A landmark as the plan lists it: ``joints`` (n,) rad, ``object_pose`` (3,), the held ``grasp``."""

    id: int
    parent: int | None
    joints: np.ndarray
    object_pose: np.ndarray
    grasp: int | None

    def to_dict(self) -> dict[str, Any]:
        return {
            "id": self.id,
            "parent": self.parent,
            "joints": _floats(self.joints),
            "object_pose": _floats(self.object_pose),
            "grasp": self.grasp,
        }

    @classmethod
    def from_dict(cls, data: Any, what: str, pose_width: int = 3) -> PlanLandmark:
        if not isinstance(data, Mapping):
            raise PlanFileError(f"{what}: expected an object with id, parent, joints, object_pose and grasp")
        identifier = _optional_int(data.get("id"), f"{what}.id")
        if identifier is None:
            raise PlanFileError(f"{what}.id: expected an integer")
        return cls(
            identifier,
            _optional_int(data.get("parent"), f"{what}.parent"),
            _array(data.get("joints"), f"{what}.joints", (None,)),
            _array(data.get("object_pose"), f"{what}.object_pose", (pose_width,)),
            _optional_int(data.get("grasp"), f"{what}.grasp"),
        )


@dataclass(frozen=True, eq=False)
class Plan:
    """A plan file's content.

    ``code`` is the run's outcome name (``SUCCEEDED``, ``TIME_LIMIT``, ...;
    ``None`` for a plan rebuilt from a recorded trajectory, which has none);
    ``success`` is true exactly when the plan has segments to follow. A
    failed plan has no segments and no ``final_object_pose``. ``world_kind``
    is ``planar`` or ``spatial`` (section 1b: object poses of 6 numbers; the
    file says ``"world_kind": "spatial"``, a planar plan's file omits it).
    """

    world: str
    joint_names: tuple[str, ...]
    success: bool
    message: str
    code: str | None = None
    segments: tuple[PlanSegment, ...] = ()
    final_object_pose: np.ndarray | None = None
    landmarks: tuple[PlanLandmark, ...] = ()
    stats: Mapping[str, Any] = field(default_factory=dict)
    world_kind: str = "planar"

    @property
    def outcome(self) -> Outcome | None:
        """The :class:`Outcome` named by ``code`` (``None`` when the plan has no code)."""
        return None if self.code is None else Outcome[self.code]

    @property
    def grasp_count(self) -> int:
        """How many times the arm takes the object (transfer segments)."""
        return sum(segment.kind == "transfer" for segment in self.segments)

    @classmethod
    def from_result(cls, world: PlanWorld, result: PlanResult) -> Plan:
        """The plan of a planner run in ``world``."""
        landmarks = tuple(
            PlanLandmark(lm.id, lm.parent, _frozen(lm.joints), _frozen(lm.object_pose), lm.grasp) for lm in result.tree
        )
        segments = tuple(PlanSegment(s.kind, s.grasp, _frozen(s.waypoints)) for s in result.segments)
        return cls(
            world=world.name,
            joint_names=tuple(world.robot.joint_names),
            success=result.success,
            message=result.message,
            code=result.outcome.name,
            segments=segments if result.success else (),
            final_object_pose=_frozen(result.final_object_pose) if result.success else None,
            landmarks=landmarks,
            stats=dict(result.stats),
        )

    def failed(self, outcome: Outcome, message: str) -> Plan:
        """This plan turned into a failure: ``outcome``, ``message``, no segments (landmarks and stats kept)."""
        return replace(self, success=False, code=outcome.name, message=message, segments=(), final_object_pose=None)

    # -- the file: one writer, one reader -------------------------------------------------------------

    def to_dict(self) -> dict[str, Any]:
        """The plan file as a JSON-ready dict, keys in the file's order."""
        document: dict[str, Any] = {
            "format": FORMAT,
            "world": self.world,
            **({} if self.world_kind == "planar" else {"world_kind": self.world_kind}),
            "success": self.success,
            "message": self.message,
        }
        if self.code is not None:
            document["code"] = self.code
        document.update(
            {
                "joint_names": list(self.joint_names),
                "segments": [segment.to_dict() for segment in self.segments],
                "final_object_pose": None if self.final_object_pose is None else _floats(self.final_object_pose),
                "landmarks": [landmark.to_dict() for landmark in self.landmarks],
                "stats": dict(self.stats),
            }
        )
        return document

    def to_json(self) -> str:
        """The plan file's text (deterministic: same plan, same bytes)."""
        return json.dumps(self.to_dict(), indent=1, sort_keys=False) + "\n"

    def write(self, path: str | Path) -> Path:
        """Write the plan file to ``path`` (its folder is created); returns the path."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(self.to_json())
        return path

    @classmethod
    def from_dict(cls, data: Any, *, source: str = "plan") -> Plan:
        """A plan from a parsed plan file; :class:`PlanFileError` names the field at fault."""
        if not isinstance(data, Mapping) or data.get("format") != FORMAT:
            raise PlanFileError(f"{source}: expected a JSON object with format {FORMAT!r}")
        success = data.get("success")
        if not isinstance(success, bool):
            raise PlanFileError(f"{source}: success: expected true or false, got {success!r:.80}")
        world = data.get("world")
        if not isinstance(world, str):
            raise PlanFileError(f"{source}: world: expected the world's name, got {world!r:.80}")
        names = data.get("joint_names")
        if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
            raise PlanFileError(f"{source}: joint_names: expected a list of names, got {names!r:.80}")
        code = data.get("code")
        if code is not None and code not in Outcome.__members__:
            raise PlanFileError(f"{source}: code: expected one of {list(Outcome.__members__)}, got {code!r:.80}")
        segments = data.get("segments")
        landmarks = data.get("landmarks", [])
        stats = data.get("stats", {})
        if not isinstance(segments, list):
            raise PlanFileError(f"{source}: segments: expected a list")
        if not isinstance(landmarks, list):
            raise PlanFileError(f"{source}: landmarks: expected a list")
        if not isinstance(stats, Mapping):
            raise PlanFileError(f"{source}: stats: expected an object")
        message = data.get("message", "")
        if not isinstance(message, str):
            raise PlanFileError(f"{source}: message: expected text, got {short_repr(message)}")
        final = data.get("final_object_pose")
        kind = data.get("world_kind", "planar")
        if not isinstance(kind, str) or kind not in POSE_WIDTH:
            raise PlanFileError(f"{source}: world_kind: expected one of {list(POSE_WIDTH)}, got {kind!r:.80}")
        width = POSE_WIDTH[kind]
        read_segments = tuple(PlanSegment.from_dict(s, f"{source}: segments[{i}]") for i, s in enumerate(segments))
        read_landmarks = tuple(
            PlanLandmark.from_dict(lm, f"{source}: landmarks[{i}]", width) for i, lm in enumerate(landmarks)
        )
        _check_widths(source, len(names), read_segments, read_landmarks)
        return cls(
            world=world,
            joint_names=tuple(names),
            success=success,
            message=message,
            code=code,
            segments=read_segments,
            final_object_pose=None if final is None else _array(final, f"{source}: final_object_pose", (width,)),
            landmarks=read_landmarks,
            stats=dict(stats),
            world_kind=kind,
        )

    @classmethod
    def from_json(cls, text: str | bytes, *, source: str = "plan") -> Plan:
        """A plan from the text of a plan file; :class:`PlanFileError` names ``source`` and what is wrong.

        Strict JSON: ``NaN`` and ``Infinity`` (which Python's ``json`` accepts) and numbers too large for a
        float are refused, as are bytes that are not UTF-8 and nesting deeper than Python's parser goes.
        """
        if isinstance(text, bytes):
            try:
                text = text.decode("utf-8")
            except UnicodeDecodeError as error:
                raise PlanFileError(f"{source}: not a plan file: not UTF-8 text (byte {error.start})") from None
        try:
            data = json.loads(text, parse_constant=_refuse_constant, parse_float=_finite_float)
        except json.JSONDecodeError as error:
            raise PlanFileError(f"{source}: not a plan file: invalid JSON ({error})") from None
        except PlanFileError as error:
            raise PlanFileError(f"{source}: {error}") from None
        except RecursionError:
            raise PlanFileError(f"{source}: not a plan file: JSON nested too deeply") from None
        except ValueError as error:  # an integer of more digits than Python converts
            raise PlanFileError(f"{source}: not a plan file: {error}") from None
        try:
            return cls.from_dict(data, source=source)
        except RecursionError:  # a value nested too deeply to turn into an array
            raise PlanFileError(f"{source}: not a plan file: a value nested too deeply") from None

    @classmethod
    def read(cls, path: str | Path, *, limits: PlanFileLimits | None = None) -> Plan:
        """Read a plan file; :class:`PlanFileError` names the file and says what is wrong with it."""
        limits = limits or PlanFileLimits()
        path = Path(path)
        try:
            data = read_regular_file(path, limits.max_bytes, "PlanFileLimits.max_bytes")
        except FileRefusedError as error:
            raise PlanFileError(f"{path}: cannot read the plan ({error})") from None
        return cls.from_json(data, source=str(path))


@dataclass(frozen=True)
class PlanFileLimits:
    """What :meth:`Plan.read` reads at most."""

    #: Bytes of one plan file. A plan of 10^5 waypoints of 7 joints is about 15 MB; larger is not a plan.
    max_bytes: int = 256 * 2**20


def _refuse_constant(name: str) -> Any:
    raise PlanFileError(f"not a plan file: {name} is not a number a plan may hold")


def _finite_float(text: str) -> float:
    value = float(text)
    if not np.isfinite(value):
        raise PlanFileError(f"not a plan file: {text[:40]} is too large for a float")
    return value


def _check_widths(source: str, joints: int, segments: Sequence[PlanSegment], landmarks: Sequence[PlanLandmark]) -> None:
    """:class:`PlanFileError` unless every waypoint and landmark has one value per joint name."""
    for i, segment in enumerate(segments):
        if segment.waypoints.shape[1] != joints or not len(segment.waypoints):
            raise PlanFileError(f"{source}: segments[{i}].waypoints: expected rows of {joints} joint values")
    for i, landmark in enumerate(landmarks):
        if landmark.joints.shape != (joints,):
            raise PlanFileError(f"{source}: landmarks[{i}].joints: expected {joints} joint values")


def _frozen(values: Any) -> np.ndarray:
    array = np.array(values, dtype=float)
    array.setflags(write=False)
    return array
