"""``clew_plan WORLD.yaml --output PLAN.json [--seed N] [--time-limit S]``: plan offline, no ROS needed.

Exit 0: a plan was found; 1: no plan (the file is still written with
``success: false``); 2: invalid input, with a message naming the parameter.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from clew_ros.core.clew import Progress, plan
from clew_ros.core.errors import ParameterError
from clew_ros.core.plan import dumps_plan, plan_to_dict, validate_plan
from clew_ros.core.settings import PlannerSettings
from clew_ros.core.world import read_parameter_file, world_from_parameters


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="clew_plan", description=__doc__.split("\n\n")[0])
    parser.add_argument("world", type=Path, help="ROS 2 parameter file holding world.* (and planner.*)")
    parser.add_argument("--output", "-o", type=Path, required=True, help="plan file to write (clew-plan/1 JSON)")
    parser.add_argument("--seed", type=int, default=None, help="overrides planner.seed")
    parser.add_argument("--time-limit", type=float, default=None, help="overrides planner.time_limit (s)")
    parser.add_argument("--quiet", "-q", action="store_true", help="no progress line on stderr")
    return parser


class _ProgressLine:
    """One updating line on stderr, shown once a run has lasted a second."""

    def __init__(self, enabled: bool) -> None:
        self.enabled = enabled
        self.shown = False

    def __call__(self, progress: Progress) -> None:
        if not self.enabled or progress.elapsed < 1.0:
            return
        self.shown = True
        end = "\r" if sys.stderr.isatty() else "\n"
        print(f"clew_plan: {progress.elapsed:6.1f} s  landmarks {progress.landmarks:3d}  "
              f"best goal distance {progress.best_distance:.4f} m", end=end, file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.shown and sys.stderr.isatty():
            print(file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        parameters = read_parameter_file(args.world)
        world = world_from_parameters(parameters)
        settings = PlannerSettings.from_parameters(parameters, seed=args.seed, time_limit=args.time_limit)
    except ParameterError as error:
        print(f"clew_plan: invalid input: {error}", file=sys.stderr)
        return 2
    progress = _ProgressLine(not args.quiet)
    started = time.monotonic()
    result = plan(world, settings, progress=progress)
    progress.close()
    document = plan_to_dict(world, result)
    if result.success:
        problems = validate_plan(world, document)
        if problems:  # a bug: never hand out a plan that fails the validator
            document = plan_to_dict(world, result)
            document.update(success=False, code="INTERNAL_ERROR", segments=[], final_object_pose=None,
                            message="internal error: the plan failed validation: " + "; ".join(problems[:3]))
    try:
        args.output.parent.mkdir(parents=True, exist_ok=True)
        args.output.write_text(dumps_plan(document))
    except OSError as error:
        print(f"clew_plan: cannot write --output {args.output}: {error.strerror}", file=sys.stderr)
        return 2
    elapsed = time.monotonic() - started
    outcome = document["code"]
    print(f"clew_plan: {outcome}: {document['message'].splitlines()[0]} ({elapsed:.2f} s, "
          f"{len(result.tree)} landmarks) -> {args.output}", file=sys.stderr)
    return 0 if document["success"] else 1


if __name__ == "__main__":
    raise SystemExit(main())
