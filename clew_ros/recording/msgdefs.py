"""Message definitions as rosbag2 stores them: ``ros2msg`` full text and type hashes.

rosbag2 (``LocalMessageDefinitionSource``) stores, for each message type, the
type's own ``.msg`` file followed by every type it depends on, recursively,
each preceded by a line of 80 ``=`` and a ``MSG: pkg/Type`` line, in the
order of a depth-first walk over the sorted dependency names. This module
does the same from the ``.msg`` files installed with the message packages
(``share/<pkg>/msg/<Type>.msg``), so that a recording written here carries the
same schema text as one written by ``ros2 bag record``.

A type whose package is not installed but that the node records
(``tf2_msgs/msg/TFMessage``: the PyPI ROS wheels lack ``tf2_msgs``) takes its
own text and its type hash from ``rosbags``' type store of ROS 2 Jazzy
(:func:`typestore`; comment-free text, as rosbags writes it); its dependencies
still come from the installed files.
"""

from __future__ import annotations

import functools
import importlib
import importlib.util
import json
import os
import re
import sys
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

from clew_ros.recording.errors import RecordingError

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

__all__ = [
    "DELIMITER",
    "learn_types",
    "message_class",
    "message_definition",
    "message_type_name",
    "type_description_hash",
    "typestore",
]

#: The line that separates definitions in a ``ros2msg`` full text.
DELIMITER = "=" * 80 + "\n"

# Same pattern and primitive set as rosbag2's parse_msg_dependencies.
_FIELD_TYPE = re.compile(r"(?:^|\n)\s*([a-zA-Z0-9_/]+)(?:\[[^\]]*\])?\s+")
_PRIMITIVES = frozenset(
    {
        "bool",
        "byte",
        "char",
        "float32",
        "float64",
        "int8",
        "uint8",
        "int16",
        "uint16",
        "int32",
        "uint32",
        "int64",
        "uint64",
        "string",
    }
)
_TYPE_NAME = re.compile(r"^([A-Za-z][A-Za-z0-9_]*)/(?:([A-Za-z][A-Za-z0-9_]*)/)?([A-Za-z][A-Za-z0-9_]*)$")
_MAX_DEPTH = 50

_TYPESTORE_LOCK = threading.Lock()
_typestores: list[Typestore] = []


def typestore() -> Typestore:
    """The process's ``rosbags`` type store: ROS 2 Jazzy's types, and those :func:`learn_types` added.

    Made once (about 0.4 s the first time), thread safe.
    """
    with _TYPESTORE_LOCK:
        if not _typestores:
            from rosbags.typesys import Stores, get_typestore

            _typestores.append(get_typestore(Stores.ROS2_JAZZY))
        return _typestores[0]


@functools.cache
def learn_types(type_name: str, definition: str) -> bool:
    """Add to :func:`typestore` the types of a ``ros2msg`` full text (``definition`` of ``type_name``) that it does
    not know yet. True when the store now defines every type of the text as the text does (so rosbags encodes
    ``type_name`` as a reader of that text decodes it); False when the text cannot be parsed or the store knew a
    type otherwise (another distribution's message files). Cached: a type is parsed once per process."""
    if not definition.strip():
        return False
    try:
        from rosbags.typesys import get_types_from_msg

        found = get_types_from_msg(definition, type_name)
        store = typestore()
    except Exception:  # noqa: BLE001 - rosbags' parser refuses it (or rosbags is not installed)
        return False
    with _TYPESTORE_LOCK:
        new = {name: fields for name, fields in found.items() if name not in store.fielddefs}
        if new:
            store.register(new)
    return type_name in found and all(store.fielddefs.get(name) == fields for name, fields in found.items())


def message_type_name(message: Any) -> str:
    """The ``pkg/msg/Type`` name of an rclpy message instance or class.

    >>> from std_msgs.msg import String  # doctest: +SKIP
    >>> message_type_name(String())      # doctest: +SKIP
    'std_msgs/msg/String'
    """
    cls = message if isinstance(message, type) else type(message)
    parts = cls.__module__.split(".")
    if len(parts) < 2 or parts[1] not in ("msg", "srv", "action"):
        raise TypeError(f"{cls.__module__}.{cls.__name__} is not a generated ROS 2 message class")
    return f"{parts[0]}/{parts[1]}/{cls.__name__}"


def _split(type_name: str) -> tuple[str, str, str]:
    match = _TYPE_NAME.match(type_name)
    if match is None:
        raise RecordingError(f"{type_name!r} is not a ROS 2 type name (expected pkg/msg/Type)")
    package, namespace, name = match.groups()
    return package, namespace or "msg", name


#: What :func:`message_class` takes: ``<package>/msg|srv|action/<Name>`` as ROS 2 names them.
_INTERFACE_NAME = re.compile(r"^([a-z][a-z0-9_]{0,99})/(msg|srv|action)/([A-Z][A-Za-z0-9_]{0,99})$")


def _prefixes() -> Iterator[Path]:
    for prefix in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep):
        if prefix:
            yield Path(prefix)
    yield Path(sys.prefix)


@functools.cache
def _installed_interface(package: str, namespace: str, name: str) -> bool:
    """Whether the ament index of an install prefix lists ``package``'s interface ``namespace/name``
    (``Trigger_Request`` is listed as ``srv/Trigger.srv``). Reads files only; imports nothing."""
    for prefix in _prefixes():
        index = prefix / "share" / "ament_index" / "resource_index" / "rosidl_interfaces" / package
        try:
            listed = index.read_text(encoding="utf-8").split()
        except (OSError, UnicodeDecodeError):
            continue
        for line in listed:
            folder, _, file_name = line.partition("/")
            stem = file_name.rsplit(".", 1)[0]
            if folder == namespace and (stem == name or (namespace != "msg" and name.startswith(stem + "_"))):
                return True
    return False


def message_class(type_name: str) -> type:
    """Import the rclpy message class of ``pkg/msg|srv|action/Type``.

    The name comes from a file: it must be a ROS 2 interface name whose package's interface is listed
    in an installed ament index before anything is imported (a name cannot make Python import a module
    of its choice). :class:`RecordingError` otherwise.
    """
    match = _INTERFACE_NAME.match(type_name)
    if match is None:
        raise RecordingError(f"{type_name!r:.120} is not a ROS 2 interface name (expected package/msg/Name)")
    package, namespace, name = match.groups()
    if not _installed_interface(package, namespace, name):
        raise RecordingError(f"message type {type_name} is not installed (no installed interface package lists it)")
    try:
        module = importlib.import_module(f"{package}.{namespace}")
        message: type = getattr(module, name)
    except (ImportError, AttributeError):
        raise RecordingError(
            f"message type {type_name} is not installed (cannot import {package}.{namespace}.{name})"
        ) from None
    if not hasattr(message, "_TYPE_SUPPORT") and not hasattr(message, "__import_type_support__"):
        raise RecordingError(f"{type_name} is not a generated ROS 2 message class")
    return message


def _share_candidates(package: str) -> Iterator[Path]:
    for prefix in _prefixes():
        yield prefix / "share" / package
    try:  # a native install: <prefix>/lib/pythonX.Y/site-packages/<pkg> -> <prefix>/share/<pkg>
        spec = importlib.util.find_spec(package)
    except (ImportError, ValueError):
        spec = None
    if spec is not None and spec.origin:
        for parent in list(Path(spec.origin).resolve().parents)[1:6]:
            yield parent / "share" / package


@functools.cache
def _interface_file(package: str, namespace: str, name: str, suffix: str) -> Path | None:
    for share in _share_candidates(package):
        path = share / namespace / f"{name}{suffix}"
        if path.is_file():
            return path
    return None


@functools.cache
def _msg_text(type_name: str) -> str:
    package, namespace, name = _split(type_name)
    path = _interface_file(package, namespace, name, ".msg")
    if path is not None:
        return path.read_text()
    try:  # not installed: rosbags' definition of the type (comment-free)
        text, _md5 = typestore().gendefhash(f"{package}/{namespace}/{name}", {}, ros_version=2)
    except Exception:  # noqa: BLE001 - rosbags does not know it either (TypesysError)
        raise RecordingError(
            f"no .msg file for {type_name} (looked for share/{package}/{namespace}/{name}.msg "
            "under AMENT_PREFIX_PATH and the Python prefix) and rosbags does not know it"
        ) from None
    return text


def _dependencies(text: str, package: str) -> list[str]:
    found = set()
    for match in _FIELD_TYPE.finditer(text):
        field_type = match.group(1)
        if field_type in _PRIMITIVES:
            continue
        found.add(field_type if "/" in field_type else f"{package}/{field_type}")
    return sorted(found)  # std::set order, as rosbag2


@functools.cache
def message_definition(type_name: str) -> str:
    """The ``ros2msg`` full text of ``type_name`` (``pkg/msg/Type``), as rosbag2 writes it.

    A type whose ``.msg`` file is not installed has rosbags' text (comment-free);
    :class:`RecordingError` when neither knows one of the types.
    """
    seen: set[str] = set()

    def walk(name: str, depth: int) -> str:
        if depth <= 0:
            raise RecordingError(f"message definition of {type_name} nests too deeply")
        text = _msg_text(name)
        result = text
        for dependency in _dependencies(text, _split(name)[0]):
            if dependency not in seen:
                seen.add(dependency)
                result += "\n" + DELIMITER + f"MSG: {dependency}\n" + walk(dependency, depth - 1)
        return result

    return walk(type_name, _MAX_DEPTH)


@functools.cache
def type_description_hash(type_name: str) -> str:
    """The ``RIHS01_...`` type hash from the installed ``<Type>.json``, else rosbags' (computed from its
    definitions), or ``''`` when neither knows the type."""
    try:
        package, namespace, name = _split(type_name)
    except RecordingError:
        return ""
    path = _interface_file(package, namespace, name, ".json")
    full = f"{package}/{namespace}/{name}"
    if path is None:
        try:
            return typestore().hash_rihs01(full)
        except Exception:  # noqa: BLE001 - rosbags does not know it (TypesysError)
            return ""
    try:
        hashes = json.loads(path.read_text()).get("type_hashes", [])
    except (OSError, ValueError):
        return ""
    for entry in hashes:
        if entry.get("type_name") == full:
            return str(entry.get("hash_string", ""))
    return ""
