"""``clew_render``: draw a world, a plan or a recorded run as PNG, GIF or SVG.

    clew_render INPUT -o OUT.{png,gif,svg} [--world WORLD.yaml] [--size PX]

INPUT is a recording (run directory or ``.mcap``), a plan file (``clew-plan/1``
JSON, needs ``--world``) or a world parameter file alone. A recording holds
its world (``~/world_yaml``); ``--world`` replaces it. PNG: the world, the
landmark tree, the tip's path and the arm at fading poses along the plan; GIF:
the plan animated, holding at every grasp and ungrasp; SVG: the PNG's picture
as vector graphics. Exit 0: written; 2: invalid input (message on stderr).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from clew_ros.cli.oneline import one_line

EXIT_OK = 0
EXIT_INVALID = 2
FORMATS = (".png", ".gif", ".svg")


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="clew_render", description=__doc__.split("\n\n")[0].split(": ", 1)[1])
    parser.add_argument("input", metavar="INPUT", help="recording directory or .mcap, plan JSON, or world YAML")
    parser.add_argument("-o", "--output", required=True, metavar="OUT", help="output file: .png, .gif or .svg")
    parser.add_argument("--world", metavar="WORLD.yaml", help="world parameter file (needed for a plan JSON)")
    parser.add_argument(
        "--size", type=int, default=None, metavar="PX", help="picture width in pixels (default 800; 600 for GIF)"
    )
    return parser


def _is_recording(path: Path) -> bool:
    return path.suffix == ".mcap" or (
        path.is_dir() and (any(path.glob("*.mcap")) or (path / "metadata.yaml").is_file())
    )


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    from clew_ros.render import RenderError, render_gif, render_png, render_svg
    from clew_ros.render.scene import (
        load_world_file,
        read_plan_file,
        scene_from_plan,
        scene_from_recording,
        scene_from_world,
    )

    source = Path(args.input)
    output = Path(args.output)
    suffix = output.suffix.lower()
    if suffix not in FORMATS:
        print(
            f"clew_render: --output: expected a file ending in {', '.join(FORMATS)}, got {output.name!r}",
            file=sys.stderr,
        )
        return EXIT_INVALID
    if args.size is not None and not 64 <= args.size <= 8192:
        print(f"clew_render: --size: expected 64 to 8192 pixels, got {args.size}", file=sys.stderr)
        return EXIT_INVALID
    size = args.size or (600 if suffix == ".gif" else 800)
    try:
        if not source.exists():
            raise RenderError(f"{source} does not exist")
        world = load_world_file(args.world) if args.world else None
        if _is_recording(source):
            scene = scene_from_recording(source, world)
        elif source.suffix.lower() == ".json":
            if world is None:
                raise RenderError(f"{source} is a plan: pass its world with --world WORLD.yaml")
            scene = scene_from_plan(world, read_plan_file(source))
        elif source.suffix.lower() in (".yaml", ".yml"):
            if world is not None:
                raise RenderError("give the world either as INPUT or with --world, not both")
            scene = scene_from_world(load_world_file(source))
        else:
            raise RenderError(f"{source}: expected a recording directory, an .mcap file, a plan .json or a world .yaml")
        render = {".png": render_png, ".gif": render_gif, ".svg": render_svg}[suffix]
        render(scene, output, size)
    except RenderError as error:
        print(one_line(f"clew_render: {error}"), file=sys.stderr)
        return EXIT_INVALID
    except OSError as error:
        print(f"clew_render: cannot write {output}: {error.strerror}", file=sys.stderr)
        return EXIT_INVALID
    print(f"clew_render: wrote {output}")
    return EXIT_OK


if __name__ == "__main__":
    raise SystemExit(main())
