"""``package://PKG/rest`` URIs of a spatial world (interface.md section 1b), resolved without a ROS install.

:func:`resolve_package_uri` looks ``PKG`` up in three places, in order: each folder of
``world.robot.package_paths`` (``<folder>/PKG/rest``; the folders relative to the parameter file's), the
ament index (``AMENT_PREFIX_PATH``, when ``ament_index_python`` is installed and the variable set), and each
folder of ``ROS_PACKAGE_PATH`` (``<folder>/PKG``, or the folder itself when it is named ``PKG``). A package
found nowhere raises one :class:`~clew_ros.core.errors.WorldError` naming the package and these three ways.
:func:`package_paths_from_parameters` reads and checks ``world.robot.package_paths``.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from clew_ros.core.errors import WorldError, short_repr

__all__ = ["PACKAGE_PATHS_PARAMETER", "package_paths_from_parameters", "resolve_package_uri"]

#: The parameter that lists the folders holding description packages.
PACKAGE_PATHS_PARAMETER = "world.robot.package_paths"
_SCHEME = "package://"


def package_paths_from_parameters(robot: Mapping[str, Any], folder: Path) -> tuple[Path, ...]:
    """The folders of ``world.robot.package_paths`` (a list of paths; absent: none), relative ones taken
    from ``folder`` (the parameter file's)."""
    from clew_ros.spatial.parameters import world_value

    value = world_value(robot, PACKAGE_PATHS_PARAMETER) or []
    if isinstance(value, str) or not isinstance(value, Sequence) or not all(isinstance(v, str) and v for v in value):
        raise WorldError(
            PACKAGE_PATHS_PARAMETER, f"expected a list of folders that hold ROS packages, got {short_repr(value)}"
        )
    return tuple(Path(v) if Path(v).is_absolute() else folder / v for v in value)


def _ament_share(package: str) -> tuple[Path | None, str]:
    """The package's share directory through the ament index, or ``None`` and why not."""
    if not os.environ.get("AMENT_PREFIX_PATH"):
        return None, "AMENT_PREFIX_PATH is not set"
    try:
        from ament_index_python.packages import get_package_share_directory
    except ImportError:
        return None, "ament_index_python is not installed"
    try:
        return Path(get_package_share_directory(package)), ""
    except (LookupError, ValueError, OSError):
        return None, "not in the ament index"


def _ros_package_path(package: str) -> tuple[Path | None, str]:
    """The package's folder under ``ROS_PACKAGE_PATH`` (``<entry>/PKG`` or an entry named ``PKG``)."""
    entries = [Path(e) for e in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if e]
    if not entries:
        return None, "ROS_PACKAGE_PATH is not set"
    for entry in entries:
        for candidate in (entry / package, entry):
            if candidate.name == package and candidate.is_dir():
                return candidate, ""
    return None, "not under ROS_PACKAGE_PATH"


def resolve_package_uri(uri: str, package_paths: Sequence[Path] = ()) -> Path:
    """The file ``package://PKG/rest`` names: ``<folder>/PKG/rest`` for the first folder of
    ``package_paths`` that holds ``PKG``, else through the ament index, else through ``ROS_PACKAGE_PATH``
    (the module docstring); a :class:`WorldError` on ``world.robot.package_paths`` when none knows ``PKG``."""
    package, _, rest = uri[len(_SCHEME) :].partition("/")
    if not package or package in (".", ".."):
        raise WorldError(PACKAGE_PATHS_PARAMETER, f"{short_repr(uri)}: expected package://PACKAGE/path")
    for folder in package_paths:
        if (folder / package).is_dir():
            return folder / package / rest
    reasons = [
        f"not in world.robot.package_paths ({', '.join(str(p) for p in package_paths)})"
        if package_paths
        else "world.robot.package_paths not given"
    ]
    for lookup in (_ament_share, _ros_package_path):
        found, why = lookup(package)
        if found is not None:
            return found / rest
        reasons.append(why)
    raise WorldError(
        PACKAGE_PATHS_PARAMETER,
        f"package {package!r} of {short_repr(uri, 120)} found nowhere ({'; '.join(reasons)}): list the folder "
        f"that holds {package}/ in world.robot.package_paths (relative to the parameter file), source the "
        "workspace that installs it (ament index), or add it to ROS_PACKAGE_PATH",
    )
