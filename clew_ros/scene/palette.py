"""The one colour palette of every view of a scene: the pictures, the RViz markers and the Foxglove view.

A colour is named by what it shows (``"obstacle"``, ``"transfer"``, ...) and
is an RGBA value, 0-255 a channel (:class:`Colour`). The renderer paints the
RGB with an opacity of its own; the RViz and Foxglove messages take
:meth:`Colour.fractions` (0-1 a channel).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from types import MappingProxyType

__all__ = ["ON_DARK", "PALETTE", "Colour", "colour"]


@dataclass(frozen=True)
class Colour:
    """An sRGB colour with its opacity: each channel an integer from 0 to 255 (``a`` 255: opaque)."""

    r: int
    g: int
    b: int
    a: int = 255

    def __post_init__(self) -> None:
        for name in ("r", "g", "b", "a"):
            value = getattr(self, name)
            if not isinstance(value, int) or not 0 <= value <= 255:
                raise ValueError(f"colour channel {name}: expected an integer from 0 to 255, got {value!r}")

    @property
    def rgb(self) -> tuple[int, int, int]:
        return (self.r, self.g, self.b)

    @property
    def rgba(self) -> tuple[int, int, int, int]:
        return (self.r, self.g, self.b, self.a)

    def with_alpha(self, alpha: int) -> Colour:
        """The same colour with opacity ``alpha`` (0 to 255)."""
        return replace(self, a=alpha)

    def fractions(self, alpha: float | None = None) -> tuple[float, float, float, float]:
        """``(r, g, b, a)`` as fractions from 0 to 1, as ROS's ``ColorRGBA`` and Foxglove's ``Color`` hold them;
        ``alpha`` (0 to 1) replaces the colour's own opacity."""
        a = self.a / 255 if alpha is None else float(alpha)
        return (self.r / 255, self.g / 255, self.b / 255, a)


#: Every colour of a scene, by what it shows. Opaque: a view sets its own opacity where it fades or overlays.
PALETTE: Mapping[str, Colour] = MappingProxyType(
    {
        "background": Colour(255, 255, 255),  # the picture outside the workspace
        "field": Colour(248, 248, 244),  # the workspace (inside the bounds)
        "field_edge": Colour(80, 80, 80),  # the bounds
        "obstacle": Colour(106, 109, 120),
        "obstacle_edge": Colour(55, 57, 64),
        "start": Colour(45, 95, 200),  # the object where it starts
        "goal": Colour(20, 150, 70),  # the object where it must go
        "grasp": Colour(200, 40, 150),  # the grasp points
        "tree_edge": Colour(150, 100, 200),  # landmark tree: parent -> child
        "tree_node": Colour(115, 60, 175),  # landmark tree: a landmark
        "transit": Colour(80, 130, 210),  # the tip's path with the gripper open
        "transfer": Colour(235, 125, 25),  # the tip's path while holding
        "arm": Colour(45, 45, 52),  # the links and the base
        "joint": Colour(255, 255, 255),  # the joints
        "open": Colour(40, 170, 80),  # the gripper open
        "closed": Colour(215, 45, 45),  # the gripper holding
        "object_rest": Colour(110, 150, 225),  # the object put down
        "object_held": Colour(240, 155, 50),  # the object carried
        "text": Colour(30, 30, 30),
        "label": Colour(255, 255, 255),  # text over a 3-D view's dark background (RViz's landmark ids)
        "muted": Colour(110, 110, 110),  # legend labels
    }
)


#: The colours that a 3-D view's dark background (RViz's and Foxglove's defaults) would swallow, lightened there;
#: every other key is the same in every view.
ON_DARK: Mapping[str, Colour] = MappingProxyType(
    {
        "arm": Colour(200, 200, 210),  # the links: the picture's near-black is invisible on RViz's grey
        "field_edge": Colour(160, 160, 160),  # the bounds
    }
)


def colour(key: str, *, dark_background: bool = False) -> Colour:
    """The palette's colour ``key`` (its :data:`ON_DARK` variant for a view with a dark background); a
    :class:`KeyError` naming the keys there are otherwise."""
    if dark_background and key in ON_DARK:
        return ON_DARK[key]
    try:
        return PALETTE[key]
    except KeyError:
        raise KeyError(f"{key!r} is not a colour of the palette, must be one of {sorted(PALETTE)}") from None
