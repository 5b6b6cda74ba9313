"""Hyper-redundant arms (15 to 40 links) on a figure-1-like task: a bar taken from a shelf into a slot.

The arm's 1.8 m reach is split into equal, decreasing (each link 0.85 of the one before: the last are
millimetres long) or random lengths, with loose (about +-2.5 rad) or tight (about +-0.5 rad) limits;
joint 1 turns all the way round. The variant is a function of the seed (:func:`variant_of`), so six
consecutive seeds give every variant.

The witness bends the arm in three *virtual joints*: joint 1, and two groups of consecutive joints
that each turn by the same angle (a group's bend spread evenly over its joints, so tight limits still
bend it). Its key configurations are solved by Newton's method on those three angles for the tip's
pose; it is made of straight joint-space moves between them:

1. from a start posture, a transit to in front of the bar and in, holding the middle of the long edge
   that faces the base (the bar lies across the arm's direction, the shelf open towards the base);
2. a transfer that pulls the bar out of the shelf and puts it down aside;
3. a transit that backs off and takes the bar by an end, in line with the last link;
4. a transfer to in front of the slot, then in along the slot's axis (steps of :data:`INSERT_STEP_M`).

The shelf (a board beyond the bar and walls at its ends) and the slot (two walls along the bar's
final place, a bottom, the bar sticking out of the mouth) are then built around the start and the
goal, kept when every wall keeps :data:`WALL_MARGIN_M` from the arm and the object along the whole
witness; the witness is validated at 0.002 rad as every family's. The task is designed so that one
regrasp is needed (at the start only the long edge facing the base is free; in the slot only the end
that sticks out), not proved so.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from clew_ros.core.plan import PlanSegment
from clew_ros.planar.collision import is_valid
from clew_ros.planar.kinematics import compose, tip_poses, transform_points, wrap_angle
from clew_ros.planar.world import World
from clew_ros.worlds.arms import FULL_TURN_RAD, ArmShape
from clew_ros.worlds.layouts import Layout, LayoutError, polygons, rectangle
from clew_ros.worlds.shapes import ObjectShape
from clew_ros.worlds.sweep import Sweep
from clew_ros.worlds.witness import Witness, WitnessError, grasp_relation, transfer_valid, transit_valid

__all__ = [
    "SNAKE_JOINTS",
    "WALL_MARGIN_M",
    "SnakeVariant",
    "make_bar",
    "make_snake_arm",
    "simulate_snake",
    "snake_layout",
    "snake_tree",
    "variant_of",
]

#: Joints of the family's arms (drawn uniformly).
SNAKE_JOINTS = tuple(range(15, 41))
#: The arm's reach (m): the sum of its links, as the issue's task.
REACH_M = 1.8
#: Each link of a decreasing arm is this share of the one before.
DECREASE = 0.85
#: Bar length and width (m): figure1's bar.
BAR_SIZE_M = (0.8, 0.1)
#: Step (m) of the tip along the bar's axis while it goes into the slot (one straight move each).
INSERT_STEP_M = 0.04
#: Gap (m) between the bar and the shelf's and slot's walls.
GAP_M = (0.025, 0.04)
#: Least distance (m) of every wall from the arm and the object along the witness.
WALL_MARGIN_M = 0.02
#: Thickness (m) of the walls.
WALL_M = 0.04
#: Bends of the witness's arm (groups of consecutive joints turning together), besides joint 1.
BENDS = 3
#: Random vias tried between two key configurations that a straight move does not join.
VIAS = 64
#: Random starts of the witness's Newton solve for one tip pose.
IK_STARTS = 96


@dataclass(frozen=True)
class SnakeVariant:
    """How the links' lengths are drawn (``equal``, ``decreasing``, ``random``) and their limits
    (``loose``, ``tight``)."""

    lengths: str
    limits: str

    @property
    def name(self) -> str:
        return f"{self.lengths} lengths, {self.limits} limits"


VARIANTS = tuple(
    SnakeVariant(lengths, limits) for limits in ("loose", "tight") for lengths in ("equal", "decreasing", "random")
)


def variant_of(seed: int) -> SnakeVariant:
    """The variant of the world of ``seed``: six consecutive seeds give the six variants."""
    return VARIANTS[seed % len(VARIANTS)]


def make_snake_arm(rng: np.random.Generator, joints: int, variant: SnakeVariant) -> ArmShape:
    """An arm of ``joints`` links adding up to :data:`REACH_M`, lengths on a 0.1 mm grid, capsule width 0."""
    weights: np.ndarray
    if variant.lengths == "equal":
        weights = np.ones(joints)
    elif variant.lengths == "decreasing":
        weights = DECREASE ** np.arange(joints, dtype=float)
    else:
        weights = rng.uniform(0.4, 1.6, joints)
    lengths = np.round(REACH_M * weights / weights.sum(), 4)
    span = (2.2, 2.8) if variant.limits == "loose" else (0.45, 0.7)
    upper = np.round(rng.uniform(*span, joints), 2)
    upper[0] = FULL_TURN_RAD
    return ArmShape(lengths, -upper, upper, 0.0)


def make_bar() -> ObjectShape:
    """Figure1's bar (0.8 m x 0.1 m), grasps at the ends' middles and the long edges' middles."""
    h, w = BAR_SIZE_M[0] / 2, BAR_SIZE_M[1] / 2
    vertices = np.array([[-h, -w], [h, -w], [h, w], [-h, w]])
    grasps = np.array([[h, 0.0], [-h, 0.0], [0.0, -w], [0.0, w]])
    normals = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, -1.0], [0.0, 1.0]])
    return ObjectShape("bar", vertices, grasps, normals)


class _Chain:
    """The arm bent in :data:`BENDS` + 1 virtual joints: joint 1, then groups of consecutive joints each
    turning as one bend spread evenly over its joints; ``q = basis @ z``, ``z`` within ``lower`` / ``upper``."""

    def __init__(self, world: World, rng: np.random.Generator) -> None:
        robot = world.robot
        n = robot.dof
        lengths = robot.link_lengths
        share = np.cumsum(lengths[1:]) / lengths[1:].sum()  # of the links after joint 2's pivot
        cuts = np.sort(rng.uniform(0.2, 0.8, BENDS - 1)) if BENDS > 1 else np.zeros(0)
        edges = [1]
        for cut in cuts:  # each group one joint at least
            edges.append(min(max(int(np.searchsorted(share, cut)) + 2, edges[-1] + 1), n - (BENDS - len(edges))))
        edges.append(n)
        self.basis = np.zeros((n, BENDS + 1))
        self.basis[0, 0] = 1.0
        lower, upper = [robot.joint_lower[0]], [robot.joint_upper[0]]
        for k, (first, stop) in enumerate(itertools.pairwise(edges)):
            size = stop - first
            self.basis[first:stop, k + 1] = 1.0 / size
            lower.append(max(robot.joint_lower[first:stop]) * size)
            upper.append(min(robot.joint_upper[first:stop]) * size)
        self.lower, self.upper = np.array(lower), np.array(upper)
        self.world = world

    def q(self, z: np.ndarray) -> np.ndarray:
        q: np.ndarray = np.asarray(z) @ self.basis.T
        return q

    def tip(self, z: np.ndarray) -> np.ndarray:
        return tip_poses(self.world.robot, np.atleast_2d(self.q(z)))

    def solve(self, target: np.ndarray, starts: np.ndarray, iterations: int = 60) -> np.ndarray:
        """Damped Newton (least-norm steps) from each start ``(M, k)`` towards the tip pose ``target``;
        the solutions within 1e-7 m and 1e-7 rad, ``(K, k)``, K <= M."""
        z = np.clip(np.atleast_2d(starts).astype(float), self.lower, self.upper)
        scale = 0.5  # m per rad of the tip's heading in the residual
        width = z.shape[1]
        eye = np.eye(width) * 1e-7
        for _ in range(iterations):
            # the residual at z and at z moved by 1e-7 along each angle, in one call
            moved = (z[:, None, :] + np.concatenate([np.zeros((1, width)), eye])[None]).reshape(-1, width)
            values = self._residual(moved, target, scale).reshape(len(z), width + 1, 3)
            base = values[:, 0]
            if np.abs(base).max() < 1e-9:
                break
            jacobian = np.transpose(values[:, 1:] - base[:, None], (0, 2, 1)) / 1e-7
            outer = np.einsum("mik,mjk->mij", jacobian, jacobian) + 1e-6 * np.eye(3)
            step = np.einsum("mik,mi->mk", jacobian, np.linalg.solve(outer, base[..., None])[..., 0])
            step *= np.minimum(1.0, 0.3 / np.maximum(np.abs(step).max(axis=1), 1e-12))[:, None]
            z = np.clip(z - step, self.lower, self.upper)
        residual = np.abs(self._residual(z, target, scale)).max(axis=1)
        solved: np.ndarray = z[residual < 1e-7]
        return solved

    def _residual(self, z: np.ndarray, target: np.ndarray, scale: float) -> np.ndarray:
        tip = self.tip(z)
        return np.stack(
            [tip[:, 0] - target[0], tip[:, 1] - target[1], scale * wrap_angle(tip[:, 2] - target[2])], axis=1
        )

    def random(self, rng: np.random.Generator, count: int, direction: float) -> np.ndarray:
        """Random angles: joint 1 within 1.2 rad of ``direction``, each group bent by at most 2 rad (an
        arm more open than curled)."""
        drawn = rng.uniform(-1.0, 1.0, (count, BENDS + 1)) * np.array([1.2] + [2.0] * BENDS)
        drawn[:, 0] += direction
        clipped: np.ndarray = np.clip(drawn, self.lower, self.upper)
        return clipped

    def line(self, z: np.ndarray, tip: np.ndarray, back: float, steps: int) -> list[np.ndarray]:
        """Configurations ``z`` followed along the tip moving ``back`` m against its heading in ``steps``
        (continuation from ``z`` in steps of 1 cm at most, halved where Newton does not converge);
        the last one is ``back`` m away."""
        out = []
        inner = max(1, math.ceil(abs(back) / steps / 0.01))
        done = 0.0
        for k in range(1, steps * inner + 1):
            z = self._follow(z, tip, done, back * k / (steps * inner), 4)
            done = back * k / (steps * inner)
            if k % inner == 0:
                out.append(z)
        return out

    def _follow(self, z: np.ndarray, tip: np.ndarray, start: float, stop: float, halvings: int) -> np.ndarray:
        target = np.array([tip[0] - stop * math.cos(tip[2]), tip[1] - stop * math.sin(tip[2]), tip[2]])
        found = self.solve(target, z[None], iterations=30)
        if len(found) and np.abs(found[0] - z).max() <= 0.3:
            result: np.ndarray = found[0]
            return result
        if not halvings:
            raise WitnessError("the tip cannot follow a straight line there")
        middle = (start + stop) / 2
        return self._follow(self._follow(z, tip, start, middle, halvings - 1), tip, middle, stop, halvings - 1)


def _pose(direction: float, distance: float, heading: float) -> np.ndarray:
    return np.array([distance * math.cos(direction), distance * math.sin(direction), heading])


def _hold(
    chain: _Chain, rng: np.random.Generator, tip: np.ndarray, near: np.ndarray | None, object_pose: np.ndarray | None
) -> np.ndarray:
    """A valid configuration (virtual angles) with the tip at ``tip``, nearest ``near`` when given."""
    starts = chain.random(rng, IK_STARTS, math.atan2(tip[1], tip[0]))
    if near is not None:
        starts[0] = near
    found = chain.solve(tip, starts)
    if not len(found):
        raise WitnessError("no configuration of the bends holds the tip there")
    world = chain.world
    if object_pose is not None:
        found = found[is_valid(world, chain.q(found), np.broadcast_to(object_pose, (len(found), 3)))]
    if not len(found):
        raise WitnessError("every configuration holding the tip there collides")
    if near is None:  # the farthest from the bends' limits
        least: np.ndarray = found[int(np.argmin(np.abs(found[:, 1:] / chain.upper[1:]).max(axis=1)))]
        return least
    result: np.ndarray = found[int(np.argmin(np.abs(found - near).sum(axis=1)))]
    return result


def _joined(
    chain: _Chain,
    rng: np.random.Generator,
    a: np.ndarray,
    b: np.ndarray,
    valid: Callable[[np.ndarray, np.ndarray], np.ndarray],
) -> list[np.ndarray]:
    """``[b]`` when the straight move ``a -> b`` is valid (``valid(starts, ends)`` on configurations
    ``q``), else ``[via, b]`` for the first of random vias about the midpoint joined to both; raises
    :class:`WitnessError` when none is."""
    q_a, q_b = chain.q(a), chain.q(b)
    if valid(q_a[None], q_b[None])[0]:
        return [b]
    spread = np.array([0.6] + [0.9] * BENDS)
    vias = np.clip((a + b) / 2 + rng.normal(0.0, 1.0, (VIAS, BENDS + 1)) * spread, chain.lower, chain.upper)
    q_vias = chain.q(vias)
    ok = valid(np.broadcast_to(q_a, q_vias.shape), q_vias)
    ok[ok] = valid(q_vias[ok], np.broadcast_to(q_b, q_vias[ok].shape))
    if not ok.any():
        raise WitnessError("no straight move or move by way of one via joins two key configurations")
    return [vias[int(np.argmax(ok))], b]


def _to_shelf(
    chain: _Chain, rng: np.random.Generator, alpha: float, side_rel: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Step 1: the bar in the shelf in direction ``alpha``, held in the middle of the long edge facing
    the base; the arm's start, the transit to the grasp, the grasp's angles and the bar's start pose."""
    world, q_of = chain.world, chain.q
    grip = _pose(alpha, REACH_M * float(rng.uniform(0.7, 0.88)), alpha)  # the arm nearly straight
    start_pose = compose(grip, side_rel)
    z_grip = _hold(chain, rng, grip, None, start_pose)
    approach = chain.line(z_grip, grip, float(rng.uniform(0.12, 0.2)), 4)[::-1]
    z_front = approach[0]
    homes = z_front + rng.uniform(-1.0, 1.0, (VIAS, BENDS + 1)) * np.array([1.2] + [0.8] * BENDS)
    starts = np.round(q_of(np.clip(homes, chain.lower, chain.upper)), 6)
    ok = transit_valid(world, starts, q_of(z_front)[None], start_pose)
    if not ok.any():
        raise WitnessError("no straight transit from the start posture")
    initial = starts[int(np.argmax(ok))]
    transit = np.array([initial, *q_of(np.array([*approach, z_grip]))])
    if not transit_valid(world, transit[1:-1], transit[2:], start_pose).all():
        raise WitnessError("the approach to the shelf collides")
    return initial, transit, z_grip, start_pose


def _aside(
    chain: _Chain,
    rng: np.random.Generator,
    z_grip: np.ndarray,
    aside: float,
    *,
    shape: ObjectShape,
    side_rel: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, int, np.ndarray]:
    """Steps 2 and 3: pulled out, put down in direction ``aside`` lying along the radius (held across
    it), then taken by its end nearer the base in line with the last link; the transfer, the transit,
    the end's grasp and the angles holding it."""
    world, q_of = chain.world, chain.q
    width, length = BAR_SIZE_M[1], BAR_SIZE_M[0]
    grip = chain.tip(z_grip)[0]
    pulled = chain.line(z_grip, grip, width + 0.15, 3)
    radial = np.array([math.cos(aside), math.sin(aside)])
    inner = REACH_M * float(rng.uniform(0.45, 0.52))  # the bar's end nearer the base, from the base (m)
    across = aside + float(rng.choice([-1.0, 1.0])) * math.pi / 2
    sideways = np.array([math.cos(across), math.sin(across)])
    put = np.array([*((inner + length / 2) * radial - width / 2 * sideways), across])
    middle_pose = compose(put, side_rel)
    z_put = _hold(chain, rng, put, pulled[-1], middle_pose)

    def held(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return transfer_valid(world, a, b, side_rel)

    transfer = q_of(np.array([z_grip, *pulled, *_joined(chain, rng, pulled[-1], z_put, held)]))
    if not held(transfer[:-1], transfer[1:]).all():
        raise WitnessError("the first transfer collides")
    back = chain.line(z_put, put, 0.12, 3)
    ends = transform_points(middle_pose, shape.grasps[:2])
    end = int(np.argmin(np.linalg.norm(ends, axis=1)))  # grasps 0 and 1 are the ends
    before = np.array([*(ends[end] - 0.15 * radial), aside])
    beside = np.array([*(before[:2] - (0.12 + width) * sideways), aside])

    def resting(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return transit_valid(world, a, b, middle_pose)

    z_beside = _hold(chain, rng, beside, back[-1], middle_pose)
    z_before = _hold(chain, rng, before, z_beside, middle_pose)
    z_end = chain.line(z_before, before, -0.15, 3)
    joins = _joined(chain, rng, back[-1], z_beside, resting) + _joined(chain, rng, z_beside, z_before, resting)
    transit = q_of(np.array([z_put, *back, *joins, *z_end]))
    if not resting(transit[:-1], transit[1:]).all():
        raise WitnessError("the regrasp's transit collides")
    return transfer, transit, end, z_end[-1]


def _into_slot(
    chain: _Chain, rng: np.random.Generator, z_end: np.ndarray, aside: float, *, opposite: float, end_rel: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Step 4: the whole arm turned by joint 1 to about ``opposite``, then out along the radius into
    the slot; the transfer and the bar's final pose."""
    low = max(opposite - 0.9, chain.lower[0] - z_end[0] + aside)  # joint 1 stays within its limits
    high = min(opposite + 0.9, chain.upper[0] - z_end[0] + aside)
    if low >= high:
        raise WitnessError("joint 1 cannot turn the arm to the slot")
    z_turned = z_end.copy()
    z_turned[0] += float(rng.uniform(low, high)) - aside
    entry = chain.tip(z_turned)[0]
    inside = BAR_SIZE_M[0] * float(rng.uniform(0.75, 0.85)) + float(rng.uniform(0.0, 0.1))
    z_in = chain.line(z_turned, entry, -inside, max(2, math.ceil(inside / INSERT_STEP_M)))
    transfer = chain.q(np.array([z_end, z_turned, *z_in]))
    if not transfer_valid(chain.world, transfer[:-1], transfer[1:], end_rel).all():
        raise WitnessError("the second transfer collides")
    return transfer, compose(chain.tip(z_in[-1])[0], end_rel)


def simulate_snake(world: World, shape: ObjectShape, rng: np.random.Generator) -> tuple[Witness, np.ndarray]:
    """The witness in ``world`` (no obstacles yet) and the bar's final pose; raises :class:`WitnessError`."""
    chain = _Chain(world, rng)
    side = 3  # the middle of the long edge at +y: the arm comes from that side
    side_rel = grasp_relation(shape, side, 0.0)
    # joint 1 stops short of +-pi: the shelf on one side, the slot on the other, the way between them
    # away from the back (sign: which side)
    sign = float(rng.choice([-1.0, 1.0]))
    alpha = sign * float(rng.uniform(1.2, 1.9))
    initial, transit1, z_grip, start_pose = _to_shelf(chain, rng, alpha, side_rel)
    aside = alpha - sign * float(rng.uniform(0.9, 1.4))
    transfer1, transit2, end, z_end = _aside(chain, rng, z_grip, aside, shape=shape, side_rel=side_rel)
    end_rel = grasp_relation(shape, end, 0.0)
    transfer2, final_pose = _into_slot(chain, rng, z_end, aside, opposite=alpha - sign * math.pi, end_rel=end_rel)
    segments = (
        PlanSegment("transit", None, transit1),
        PlanSegment("transfer", side, transfer1),
        PlanSegment("transit", None, transit2),
        PlanSegment("transfer", end, transfer2),
    )
    return Witness(initial, start_pose, segments), final_pose


def _walls(pose: np.ndarray, pieces: list[tuple[float, float, float, float]]) -> list[np.ndarray]:
    """Rectangles of :data:`WALL_M` along segments ``(u0, v0, u1, v1)`` given in the frame of ``pose``."""
    ends = [transform_points(pose, np.array([[u0, v0], [u1, v1]])) for u0, v0, u1, v1 in pieces]
    return [rectangle(a, b, WALL_M) for a, b in ends]


def snake_layout(world: World, sweep: Sweep, rng: np.random.Generator, goal: np.ndarray) -> Layout:
    """The shelf around the object's start (open towards the base) and the slot around ``goal``
    (the bar's end sticking out of the mouth); :class:`LayoutError` when a wall comes too near the witness."""
    h, w = BAR_SIZE_M[0] / 2, BAR_SIZE_M[1] / 2
    gap = float(rng.uniform(*GAP_M))
    t = WALL_M / 2
    # the shelf, in the bar's frame at its start: +y faces the base
    shelf = _walls(
        world.object.initial,
        [
            (-h - gap - WALL_M, -w - gap - t, h + gap + WALL_M, -w - gap - t),  # the board beyond the bar
            (-h - gap - t, -w - gap, -h - gap - t, w),  # the walls at the ends, as deep as the bar
            (h + gap + t, -w - gap, h + gap + t, w),
        ],
    )
    # the slot, in the bar's frame at the goal turned so that +x goes in: the end at -x, nearer the
    # base, sticks out of the mouth
    goal = np.asarray(goal, float)
    if np.hypot(*compose(goal, np.array([h, 0.0, 0.0]))[:2]) < np.hypot(*goal[:2]):
        goal = goal + np.array([0.0, 0.0, math.pi])
    mouth = -h + BAR_SIZE_M[0] * float(rng.uniform(0.15, 0.25))
    slot = _walls(
        goal,
        [
            (mouth, -w - gap - t, h + gap + WALL_M, -w - gap - t),
            (mouth, w + gap + t, h + gap + WALL_M, w + gap + t),
            (h + gap + t, -w - gap, h + gap + t, w + gap),
        ],
    )
    clear = sweep.clear(polygons(shelf + slot))
    if not clear.all():
        which = "shelf" if not clear[: len(shelf)].all() else "slot"
        raise LayoutError(f"a wall of the {which} comes too near the witness")
    layout = Layout({}, [f"A shelf open towards the base holds the bar; a slot {gap:.3f} m wider each side takes it."])
    layout.add("shelf", shelf)
    layout.add("slot", slot)
    return layout


def snake_tree(name: str, arm: ArmShape, shape: ObjectShape) -> dict[str, Any]:
    """The ``world`` tree of a family world before its witness (start and goal at the origin)."""
    half = round(REACH_M + BAR_SIZE_M[0] + 0.25, 2)
    return {
        "name": name,
        "bounds": [-half, -half, half, half],
        "robot": {
            "base": [0.0, 0.0],
            "link_lengths": arm.link_lengths.tolist(),
            "link_width": arm.link_width,
            "joint_lower": arm.joint_lower.tolist(),
            "joint_upper": arm.joint_upper.tolist(),
            "initial": [0.0] * len(arm.link_lengths),
            "self_collision": True,
        },
        "object": {
            "polygon": shape.vertices.ravel().tolist(),
            "initial": [0.0, 0.0, 0.0],
            "goal": [0.0, 0.0, 0.0],
            "grasps": shape.grasps.ravel().tolist(),
        },
    }
