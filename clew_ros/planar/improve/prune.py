"""Back-and-forth pruning that needs no checking: a transfer put down and taken again where the arm stopped
becomes one transfer (collinear waypoints and loops go by :func:`clew_ros.planar.kernel.pruned_path`)."""

from __future__ import annotations

import numpy as np

from clew_ros.planar.improve.pieces import _Piece


def _joined_regrasps(pieces: list[_Piece], same_rad: float) -> list[_Piece]:
    """``pieces`` with each transfer that is put down and taken again by the same grasp without the arm moving
    (a transit of no joint travel between two transfers of one grasp) made one transfer: the arm and the
    object move exactly as before, the object held the same way (the tip and the object did not move in
    between), so nothing needs checking, and the plan has one transfer fewer. Configurations within ``same_rad`` (rad,
    largest joint difference) count as the same."""
    joined: list[_Piece] = []
    for piece in pieces:
        if len(joined) >= 2 and piece.kind == "transfer" and [p.kind for p in joined[-2:]] == ["transfer", "transit"]:
            carried, still = joined[-2], joined[-1]
            junction = np.vstack([carried.waypoints[-1:], still.waypoints, piece.waypoints[:1]])
            if piece.grasp == carried.grasp and float(np.abs(junction - junction[0]).max()) <= same_rad:
                joined[-2:] = [
                    _Piece(
                        "transfer",
                        carried.grasp,
                        np.vstack([carried.waypoints, piece.waypoints[1:]]),
                        carried.start_pose,
                        carried.grasp_rel,
                    )
                ]
                continue
        joined.append(piece)
    return joined
