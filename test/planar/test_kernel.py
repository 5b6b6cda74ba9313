"""The compiled kernel against brute force on random worlds, its clearance, and its on-disk cache.

The oracle is the contract's validity test (:func:`clew_ros.planar.collision.is_valid`, shapely)
swept at 1 mrad; the kernel never sees it.
"""

from __future__ import annotations

import itertools
import math
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from helpers.random_boxes import random_boxes
from helpers.sweep import sweep_interval

from clew_ros.planar.collision import exactly_valid, is_placement_valid, is_valid
from clew_ros.planar.kinematics import compose, joint_positions, tip_poses, transform_points
from clew_ros.planar.manhattan import free_intervals, run_manhattan
from clew_ros.planar.world import world_from_parameters

ROOT = Path(__file__).resolve().parents[2]


def random_world(seed: int, *, joints: int, obstacles: int, width: float, limit: float, self_collision: bool):
    """A random world: boxes around the base, a random polygon object, a random arm (joint limits
    ``+-limit``, possibly past pi). The start is not checked (tests pick valid configurations)."""
    rng = np.random.default_rng(seed)
    lengths = rng.uniform(0.3, 1.0, joints) * 1.8 / joints + 0.1
    boxes = random_boxes(rng, obstacles, clear_radius=0.5)
    angles = np.sort(rng.uniform(0, 2 * np.pi, rng.integers(3, 7)))
    radii = rng.uniform(0.06, 0.15, len(angles))
    polygon = np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=1)
    parameters = {
        "world": {
            "name": f"random_{seed}",
            "bounds": [-2.5, -2.5, 2.5, 2.5],
            "robot": {
                "base": [0.0, 0.0],
                "link_lengths": lengths.tolist(),
                "link_width": width,
                "joint_lower": [-limit] * joints,
                "joint_upper": [limit] * joints,
                "initial": [0.0] * joints,
                "self_collision": self_collision,
            },
            "obstacle_names": list(boxes),
            "obstacles": boxes,
            "object": {
                "polygon": polygon.ravel().tolist(),
                "initial": [0.0, -1.2, 0.3],
                "goal": [0.0, -1.2, 0.3],
                "grasps": polygon[0].tolist(),
            },
        }
    }
    return world_from_parameters(parameters), rng


def valid_configurations(world, rng, count, poses_of, tries=20000):
    q = rng.uniform(world.robot.joint_lower, world.robot.joint_upper, (tries, world.robot.dof))
    return q[is_valid(world, q, poses_of(q))][:count]


CASES = [  # seed, joints, obstacles, link width, joint limit, self-collision
    (1, 2, 4, 0.0, 3.14159, True),
    (2, 3, 6, 0.04, 4.0, True),  # limits past pi
    (3, 4, 8, 0.02, 3.0, True),
    (4, 5, 3, 0.06, 5.5, True),
    (5, 3, 10, 0.0, 2.5, False),
    (6, 6, 5, 0.03, 3.14159, True),
]


@pytest.mark.parametrize("case", CASES, ids=[f"seed{c[0]}_{c[1]}joints" for c in CASES])
@pytest.mark.parametrize("mode", ["transit", "transfer"])
def test_free_intervals_match_a_brute_force_sweep_on_random_worlds(case, mode):
    seed, joints, obstacles, width, limit, self_collision = case
    world, rng = random_world(
        seed, joints=joints, obstacles=obstacles, width=width, limit=limit, self_collision=self_collision
    )
    rel = np.array([float(np.abs(world.object.polygon).max()) + width + 0.02, 0.0, rng.uniform(-np.pi, np.pi)])
    if mode == "transit":
        poses = rng.uniform((-1.5, -1.5, -np.pi), (1.5, 1.5, np.pi), (200, 3))
        pose = poses[is_placement_valid(world, poses)][0]
        poses_of = lambda qs: np.broadcast_to(pose, (len(qs), 3))  # noqa: E731
        kwargs = {"object_poses": pose[None]}
    else:
        poses_of = lambda qs: compose(tip_poses(world.robot, qs), rel)  # noqa: E731
        kwargs = {"grasp_rel": rel[None]}
    qs = valid_configurations(world, rng, 3, poses_of)
    assert len(qs) == 3, "the random world leaves too little free space"
    for q in qs:
        for joint in range(joints):
            low, high = free_intervals(world, q[None], joint, margin_m=0.0, **kwargs)
            brute_low, brute_high = sweep_interval(world, q, joint, poses_of)
            # the sweep stops at the last valid mrad: the exact interval lies within one step outside it
            assert brute_low - 2e-3 <= low[0] <= brute_low + 2e-3, (q.tolist(), joint)
            assert brute_high - 2e-3 <= high[0] <= brute_high + 2e-3, (q.tolist(), joint)


@pytest.mark.parametrize("seed", [11, 12, 13])
@pytest.mark.parametrize("transfer", [False, True], ids=["transit", "transfer"])
def test_the_broad_phase_never_changes_an_interval(seed, transfer):
    """The free intervals skip obstacles whose bounding circle is out of the moving pieces' reach: on
    cluttered random worlds they are bit for bit those computed with every obstacle placed, and the
    broad phase did skip obstacles (else this test would prove nothing)."""
    from dataclasses import replace

    from clew_ros.planar import kernel
    from clew_ros.planar.collision import packed_world

    world, rng = random_world(seed, joints=4, obstacles=40, width=0.02, limit=3.0, self_collision=True)
    packed = packed_world(world)
    groups = packed.obstacle_groups
    assert len(groups) == 40
    # boxes of 2 km around the origin: bounding circles nothing lies beyond, every obstacle is placed
    everything = replace(packed, obstacle_boxes=np.tile([-1e3, -1e3, 1e3, 1e3], (40, 1)))
    q = rng.uniform(world.robot.joint_lower, world.robot.joint_upper, (400, 4))
    poses = (
        np.tile([0.12, 0.0, 0.3], (400, 1)) if transfer else rng.uniform((-2.0, -2.0, -3.0), (2.0, 2.0, 3.0), (400, 3))
    )
    skipped = 0
    for joint in range(4):
        fast = kernel.intervals(packed, q, joint, transfer, poses, 1e-3)
        full = kernel.intervals(everything, q, joint, transfer, poses, 1e-3)
        assert np.array_equal(fast[0], full[0]), joint
        assert np.array_equal(fast[1], full[1]), joint
        pivots = joint_positions(world.robot, q)[:, joint]
        distance = np.linalg.norm(groups[None, :, 2:4] - pivots[:, None], axis=2) - groups[None, :, 4]
        # beyond the whole arm plus the carried object (0.12 m offset, radius under 0.15 m) and clearances:
        # obstacles the broad phase certainly left out
        skipped += int((distance > world.robot.reach + 0.5).sum())
    assert skipped > 0


def test_a_contact_is_skipped_only_if_it_would_change_neither_nearest_contact():
    """The free intervals skip the exact angle of a contact that lies between the nearest contacts
    found each way (:func:`kernel.contacts._cannot_improve`): the pseudo-angle it compares grows with the angle,
    and a skipped contact, had it been kept, leaves both nearest contacts as they were; contacts next to
    a bound (within rounding of it) are never skipped."""
    from clew_ros.planar.kernel.contacts import _cannot_improve, _contact, _nearest, _pseudo_angle, _reset

    angles = np.linspace(0.0, 2.0 * np.pi, 4001)[:-1]
    pseudo = np.array([_pseudo_angle(np.cos(a), np.sin(a)) for a in angles])
    assert np.all(np.diff(pseudo) > 0.0)
    assert pseudo[0] >= 0.0
    assert pseudo[-1] < 4.0

    rng = np.random.default_rng(5)
    best, kept = np.empty(4), np.empty(4)
    skipped = 0
    for _ in range(3000):
        _reset(best)
        for phi in rng.uniform(-7.0, 7.0, rng.integers(0, 4)):
            _nearest(phi, best)
        near = best[:2][np.isfinite(best[:2])]
        candidates = np.concatenate(
            [rng.uniform(-7.0, 7.0, 8), (near + rng.choice([-1e-10, 0.0, 1e-10], (3, len(near)))).ravel()]
        )
        for phi in candidates:
            scale = rng.uniform(0.1, 3.0)
            if _cannot_improve(scale * np.cos(phi), scale * np.sin(phi), best):
                skipped += 1
                kept[:] = best
                _nearest(phi, kept)
                assert kept[0] == best[0], (phi, best)
                assert kept[1] == best[1], (phi, best)
                assert np.all(np.abs(phi - near[:, None] - 2.0 * np.pi * np.arange(-2, 3)) > 1e-9)
    assert skipped > 1000
    # through the kernel's own path: a contact at c seen from a point p (dot and cross, the turn's sign)
    for _ in range(3000):
        _reset(best)
        for phi in rng.uniform(-7.0, 7.0, rng.integers(1, 4)):
            _nearest(phi, best)
        theta, turn = rng.uniform(-np.pi, np.pi), rng.choice([-1.0, 1.0])
        near = best[:2][np.isfinite(best[:2])]
        for phi in np.concatenate([rng.uniform(-7.0, 7.0, 4), near + rng.choice([-1e-10, 1e-10], len(near))]):
            p = rng.uniform(0.1, 2.0) * np.array([np.cos(theta), np.sin(theta)])
            c = rng.uniform(0.1, 2.0) * np.array([np.cos(theta + turn * phi), np.sin(theta + turn * phi)])
            exact = best.copy()
            # math.atan2, the C library's, as the compiled kernel calls it: numpy's own SIMD arctan2 (AVX-512)
            # can differ from it in the last bit
            _nearest(turn * (math.atan2(c[1], c[0]) - math.atan2(p[1], p[0])), exact)
            _contact(p[0], p[1], c[0], c[1], np.nan, turn, best)
            assert best[0] == exact[0], (phi, turn)
            assert best[1] == exact[1], (phi, turn)


@pytest.mark.parametrize("case", CASES[:4], ids=[f"seed{c[0]}" for c in CASES[:4]])
def test_the_clearance_is_kept_along_every_interval(case):
    """With clearance ``m`` every angle of the interval is valid for the arm widened by ``m`` (half on
    each side: links against obstacles, the object and the bounds keep ``m / 2``, links against each
    other ``m``, both widened), from any start that keeps more than
    ``1.5 m`` (closer, a pair is only kept from getting closer than it starts)."""
    seed, joints, obstacles, width, limit, self_collision = case
    margin = 0.03
    world, rng = random_world(
        seed, joints=joints, obstacles=obstacles, width=width, limit=limit, self_collision=self_collision
    )
    wide, _ = random_world(
        seed,
        joints=joints,
        obstacles=obstacles,
        width=width + 0.99 * margin,
        limit=limit,
        self_collision=self_collision,
    )
    wider, _ = random_world(
        seed,
        joints=joints,
        obstacles=obstacles,
        width=width + 2 * 1.6 * margin,
        limit=limit,
        self_collision=self_collision,
    )
    pose = world.object.initial
    poses_of = lambda qs: np.broadcast_to(pose, (len(qs), 3))  # noqa: E731
    qs = valid_configurations(wider, rng, 4, poses_of)
    assert len(qs) == 4
    for q in qs:
        for joint in range(joints):
            low, high = free_intervals(world, q[None], joint, object_poses=pose[None], margin_m=margin)
            angles = np.linspace(low[0], high[0], 2001)
            moved = np.repeat(q[None], len(angles), axis=0)
            moved[:, joint] += angles
            assert is_valid(wide, moved, poses_of(moved)).all()


@pytest.mark.parametrize("mode", ["transit", "transfer"])
def test_a_decoded_population_is_valid_at_the_checking_step(mode):
    world, rng = random_world(11, joints=4, obstacles=6, width=0.03, limit=4.0, self_collision=True)
    rel = np.array([0.2, 0.0, 0.5])
    if mode == "transit":
        poses_of = lambda qs: np.broadcast_to(world.object.initial, (len(qs), 3))  # noqa: E731
        kwargs = {"object_poses": world.object.initial[None]}
    else:
        poses_of = lambda qs: compose(tip_poses(world.robot, qs), rel)  # noqa: E731
        kwargs = {"grasp_rel": rel[None]}
    starts = valid_configurations(world, rng, 8, poses_of)
    genes = rng.normal(0.0, 3.0, (len(starts), 3, 4))
    paths = run_manhattan(world, starts, genes, margin_m=1e-3, **kwargs)
    moved = 0
    for waypoints in paths.waypoints:
        for a, b in itertools.pairwise(waypoints):
            steps = max(1, int(np.ceil(np.abs(b - a).max() / 0.002)))
            qs = a + np.linspace(0, 1, steps + 1)[:, None] * (b - a)
            assert is_valid(world, qs, poses_of(qs)).all()
            assert np.all(qs >= world.robot.joint_lower)
            assert np.all(qs <= world.robot.joint_upper)
            moved += np.abs(b - a).max() > 1e-6
    assert moved > 30


def test_huge_batches_split_and_stop_between_calls():
    """A world whose batch exceeds one call's work is decoded in pieces; a stop between pieces leaves
    every path where it got to (a prefix of the full decode)."""
    world, rng = random_world(12, joints=3, obstacles=40, width=0.02, limit=3.0, self_collision=True)
    pose = world.object.initial[None]
    starts = valid_configurations(world, rng, 1, lambda qs: np.broadcast_to(pose, (len(qs), 3)))
    genes = rng.normal(0.0, 2.0, (3000, 2, 3))
    full = run_manhattan(world, starts[0], genes, object_poses=pose)
    asked = []

    def stop_after_three() -> bool:
        asked.append(1)
        return len(asked) > 3

    cut = run_manhattan(world, starts[0], genes, object_poses=pose, should_stop=stop_after_three)
    assert len(asked) > 3  # split into several calls
    same = np.all(np.isclose(cut.waypoints, full.waypoints), axis=2)  # (B, columns)
    assert same[:, 1].any()
    assert not same.all()
    for row, waypoints in zip(same, cut.waypoints, strict=True):
        first_diff = np.flatnonzero(~row)
        if len(first_diff):  # after the stop the path stays put
            assert np.allclose(waypoints[first_diff[0] :], waypoints[first_diff[0] - 1])


def test_the_cache_falls_back_to_a_user_directory_when_the_package_is_read_only(tmp_path):
    """An installed package directory may be read-only (a system install): the kernels then cache
    in a per-user directory, and a second process loads them from there."""
    if shutil.which("unshare") is None or os.geteuid() != 0:
        pytest.skip("needs unshare and root to mount the package read-only")
    package = tmp_path / "site" / "clew_ros"
    shutil.copytree(ROOT / "clew_ros", package, ignore=shutil.ignore_patterns("__pycache__"))
    home = tmp_path / "home"
    home.mkdir()
    script = textwrap.dedent(f"""
        mount --bind {package} {package} && mount -o remount,bind,ro {package} || exit 77
        touch {package}/probe 2>/dev/null && exit 78
        for i in 1 2; do {sys.executable} -c '
        import clew_ros.planar.kernel as k; from clew_ros.planar.kernel import decoding; k.warm_up()
        print(k.__file__, sum(decoding._decode.stats.cache_hits.values()))' || exit 1; done
    """)
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
    env.update(HOME=str(home), PYTHONPATH=str(package.parent), XDG_CACHE_HOME=str(home / ".cache"))
    done = subprocess.run(
        ["unshare", "-m", "--propagation", "private", "sh", "-c", script],
        env=env,
        cwd=home,
        capture_output=True,
        text=True,
        timeout=600,
    )
    if done.returncode in (77, 78):
        pytest.skip("cannot mount the package read-only here")
    assert done.returncode == 0, done.stderr[-2000:]
    lines = done.stdout.split("\n")
    assert all(line.startswith(str(package)) for line in lines if line), done.stdout
    assert not list(package.rglob("*.nbi"))  # nothing was written next to the package
    cached = list(home.rglob("*.nbi"))
    assert any(path.parent.name.startswith("kernel_") for path in cached), [str(p) for p in cached]  # kernel/*.py
    first, second = (int(line.split()[-1]) for line in lines if line)
    assert first == 0
    assert second > 0


@pytest.mark.parametrize("case", CASES, ids=[f"seed{c[0]}_{c[1]}joints" for c in CASES])
def test_the_compiled_first_pass_never_changes_the_validity_test(case):
    """``is_valid`` (compiled first pass, shapely for the doubtful) agrees with shapely alone on random
    configurations and object poses, and on configurations that touch: turned to the very end of
    their free interval (1e-6 rad short of contact) and past it by 1e-9 rad."""
    seed, joints, obstacles, width, limit, self_collision = case
    world, rng = random_world(
        seed, joints=joints, obstacles=obstacles, width=width, limit=limit, self_collision=self_collision
    )
    q = rng.uniform(world.robot.joint_lower, world.robot.joint_upper, (3000, joints))
    poses = rng.uniform((-2.4, -2.4, -np.pi), (2.4, 2.4, np.pi), (3000, 3))
    poses[::2] = compose(tip_poses(world.robot, q[::2]), np.array([0.12, 0.0, 0.3]))  # carried
    fast = is_valid(world, q, poses)
    assert np.array_equal(fast, exactly_valid(world, q, poses))
    assert fast.sum() > 30  # the fast path had valid configurations to clear
    touching = []
    starts = q[fast][:40]
    for start, pose in zip(starts, poses[fast][:40], strict=True):
        for joint in range(joints):
            low, high = free_intervals(world, start[None], joint, object_poses=pose[None], margin_m=0.0)
            for end, push in ((high[0], 1e-6 + 1e-9), (low[0], -1e-6 - 1e-9), (high[0], 0.0)):
                moved = start.copy()
                moved[joint] += end + push
                touching.append((moved, pose))
    q_touch = np.array([t[0] for t in touching])
    pose_touch = np.array([t[1] for t in touching])
    fast = is_valid(world, q_touch, pose_touch)
    assert np.array_equal(fast, exactly_valid(world, q_touch, pose_touch))
    assert (~fast).any()  # some of them really touch


def test_the_same_seed_gives_the_same_plan_on_one_thread_and_on_all():
    """``planner.threads`` spreads a population over threads; every individual is decoded alone, so
    the plan is the same whatever the number of threads."""
    from clew_ros.core.plan import Plan
    from clew_ros.core.settings import PlannerSettings
    from clew_ros.planar.kernel import available_threads
    from clew_ros.planar.space import plan
    from clew_ros.planar.world import load_world

    assert available_threads() >= 1
    world = load_world(ROOT / "config" / "arm3_regrasp.yaml")
    documents = []
    for threads in (1, 0, 3):
        result = plan(world, PlannerSettings(seed=2, time_limit=60.0, threads=threads))
        assert result.success, result.message
        document = Plan.from_result(world, result).to_dict()
        document["stats"].pop("time_s")
        documents.append(Plan.from_dict(document).to_json())
    assert documents[0] == documents[1] == documents[2]


@pytest.mark.parametrize("mode", ["transit", "transfer"])
def test_a_start_within_the_clearance_of_a_bound_never_crosses_it(mode):
    """A point that starts between ``bound - inset - margin`` and ``bound - inset`` is kept from
    getting closer (not pushed out): the interval must not turn it through the bound."""
    rng = np.random.default_rng(4)
    world = world_from_parameters(
        {
            "world": {
                "name": "near_bound",
                "bounds": [-2.0, -2.0, 1.0, 2.0],
                "robot": {
                    "base": [0.0, 0.0],
                    "link_lengths": [0.6, 0.4],
                    "link_width": 0.02,
                    "joint_lower": [-3.0, -3.0],
                    "joint_upper": [3.0, 3.0],
                    "initial": [0.0, 0.5],
                },
                "obstacle_names": [],
                "obstacles": {},
                "object": {
                    "polygon": [-0.05, -0.05, 0.05, -0.05, 0.05, 0.05, -0.05, 0.05],
                    "initial": [-1.5, 1.5, 0.0],
                    "goal": [-1.5, 1.5, 0.0],
                    "grasps": [0.05, 0.0],
                },
            }
        }
    )
    margin = 1e-3
    rel = np.array([0.05, 0.0, 0.0])
    if mode == "transit":  # the straight arm's tip: x within the last mm before the bound inset by r
        kwargs = {"object_poses": world.object.initial[None]}
        poses_of = lambda qs: np.broadcast_to(world.object.initial, (len(qs), 3))  # noqa: E731
        nearest = lambda qs: joint_positions(world.robot, qs)[:, -1, 0]  # noqa: E731
        band = (0.99 - margin, 0.99)
    else:  # the carried object's vertices: the largest x within the last mm before the bound
        kwargs = {"grasp_rel": rel[None]}
        poses_of = lambda qs: compose(tip_poses(world.robot, qs), rel)  # noqa: E731
        nearest = lambda qs: transform_points(poses_of(qs), world.object.polygon)[..., 0].max(axis=1)  # noqa: E731
        band = (1.0 - margin, 1.0)
    q = np.zeros((200_000, 2))
    q[:, 0] = rng.uniform(-1.2, 0.0, len(q))
    q = q[(nearest(q) > band[0]) & (nearest(q) < band[1])][:20]
    checked = 0
    for start in q:
        if not is_valid(world, start[None], poses_of(start[None]))[0]:
            continue
        checked += 1
        low, high = free_intervals(world, start[None], 0, margin_m=margin, **kwargs)
        angles = np.linspace(low[0], high[0], 4001)
        moved = np.repeat(start[None], len(angles), axis=0)
        moved[:, 0] += angles
        assert is_valid(world, moved, poses_of(moved)).all(), (start.tolist(), low[0], high[0])
    assert checked >= 10


@pytest.mark.parametrize("mode", ["transit", "transfer"])
def test_one_pose_shared_by_a_batch_gives_the_intervals_of_the_pose_repeated(mode):
    world, rng = random_world(7, joints=4, obstacles=6, width=0.03, limit=3.0, self_collision=True)
    rest = world.object.initial[None]
    held = np.array([[float(np.abs(world.object.polygon).max()) + 0.05, 0.0, 0.7]])  # ahead of the tip
    poses_of = (
        (lambda q: np.repeat(rest, len(q), axis=0))
        if mode == "transit"
        else (lambda q: compose(tip_poses(world.robot, q), held))
    )
    q = valid_configurations(world, rng, 40, poses_of)
    assert len(q) >= 10
    key, pose = ("object_poses", rest) if mode == "transit" else ("grasp_rel", held)
    for joint in range(world.robot.dof):
        shared = free_intervals(world, q, joint, **{key: pose})
        repeated = free_intervals(world, q, joint, **{key: np.repeat(pose, len(q), axis=0)})
        np.testing.assert_array_equal(shared[0], repeated[0])
        np.testing.assert_array_equal(shared[1], repeated[1])


def test_warm_up_compiles_every_kernel_the_python_entry_points_call() -> None:
    """In a fresh process (the kernels compiled or loaded from the cache), after :func:`kernel.warm_up` every
    compiled function an entry point calls has a compiled version (the core's pruning too), and planning with
    the improvement (moves checked, RRT-Connect's rounds, both modes; on 3 joints the lattice's searches)
    compiles no other: no plan waits for the compiler (a read-only array is another type to numba: the
    lattice's lower limits once were, and a 3-joint world's first improvement waited about 2 s for them)."""
    code = textwrap.dedent("""
        import importlib
        import clew_ros.planar.kernel as k
        from clew_ros.planar.space import plan
        from clew_ros.core.settings import PlannerSettings
        from clew_ros.planar.world import load_world
        k.warm_up()
        entry = ["decoding._decode", "free_intervals._intervals", "validity._clearly_valid", "moves._moves_clear",
                 "rrt_connect._connect_rounds", "kinematics._solve_point", "kinematics._chain",
                 "prune._pruned", "free_intervals._bounce_all", "moves._screen", "path_shortcuts._shortcuts",
                 "lattice.lattice_search", "lattice.lattice_costs", "lattice.lattice_repair", "lattice.release_totals"]
        def compiled(name):
            module, function = name.split(".")
            package = "clew_ros.core.improve." if module == "prune" else "clew_ros.planar.kernel."
            return getattr(importlib.import_module(package + module), function)
        counts = {name: len(compiled(name).signatures) for name in entry}
        print(" ".join(name for name in entry if not counts[name]))
        plan(load_world("config/single_transfer.yaml"), PlannerSettings(seed=0, improve_time=0.4))
        plan(load_world("config/arm3_regrasp.yaml"), PlannerSettings(seed=0, improve_time=0.5))
        print(" ".join(name for name in entry if len(compiled(name).signatures) != counts[name]))
    """)
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=600, check=True, cwd=ROOT
    )
    not_compiled, compiled_again = (done.stdout + "\n").split("\n")[:2]
    assert not_compiled.split() == []
    assert compiled_again.split() == []
