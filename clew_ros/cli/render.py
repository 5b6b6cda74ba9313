"""``clew_render``: draw a world, a plan or a recorded run as PNG, GIF or SVG.

    clew_render INPUT -o OUT.{png,gif,svg} [--world WORLD.yaml] [--size PX] [--view AZ,EL[,DIST]] [--frames F.json]

INPUT is a recording (run directory or ``.mcap``), a plan file (``clew-plan/1``
JSON, needs ``--world``) or a world parameter file alone. A recording holds
its world (``~/world_yaml``); ``--world`` replaces it. PNG: the world, the
landmark tree, the tip's path and the arm at fading poses along the plan; GIF:
the plan animated, holding at every grasp and ungrasp; SVG: the PNG's picture
as vector graphics. A spatial world (``world.kind: spatial``) is drawn in 3-D
as PNG or GIF, seen from ``--view`` (azimuth and elevation in degrees, distance
in metres; default: from the front right, framing the scene): alone, the arm
at its start with the goal ghosted; with a plan (INPUT) or ``--frames`` (a plan
or a frames file), the arm along the frames. A recording of a spatial run is
drawn the same way along its plan, rebuilt from ``~/trajectory`` and the
``succeeded`` event (the world: the recording's ``~/world_yaml``, the robot from
``~/robot_description`` and the meshes of ``~/world_markers``; ``--world``
replaces it: :mod:`clew_ros.render.spatial.recording`). No path named inside a
recording is opened; the files named here are read only when they are regular
files within their size caps. Exit 0: written; 2: invalid input (one line on
stderr).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from clew_ros.cli.oneline import one_line

if TYPE_CHECKING:
    from clew_ros.render.spatial import View3D
    from clew_ros.spatial.world import SpatialWorld

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
    parser.add_argument(
        "--view",
        metavar="AZ,EL[,DIST]",
        help="spatial worlds: the camera's azimuth, elevation (degrees) and distance (m; default: framing the scene)",
    )
    parser.add_argument(
        "--frames",
        metavar="FRAMES.json",
        help="spatial worlds: a plan file or a frames file ({joints, object_poses, held}) to draw along",
    )
    return parser


def _is_recording(path: Path) -> bool:
    return path.suffix == ".mcap" or (
        path.is_dir() and (any(path.glob("*.mcap")) or (path / "metadata.yaml").is_file())
    )


def _view_joined(argv: list[str]) -> list[str]:
    """``--view -50,28`` as ``--view=-50,28``: argparse would take a value starting with ``-`` for an option."""
    out: list[str] = []
    for arg in argv:
        if out and out[-1] == "--view" and len(arg) > 1 and arg[0] == "-" and arg[1] in "0123456789.":
            out[-1] = f"--view={arg}"
        else:
            out.append(arg)
    return out


def _os_reason(error: OSError, output: Path) -> str:
    """What an ``OSError`` means to the user: the output it could not write, or the file it could not read,
    with the system's reason (never ``None``)."""
    reason = error.strerror or str(error) or type(error).__name__
    if error.filename is not None and Path(str(error.filename)) != output:
        return f"cannot read {error.filename}: {reason}"
    return f"cannot write {output}: {reason}"


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(_view_joined(list(sys.argv[1:] if argv is None else argv)))
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
        if _spatial(source, args, output, size):
            print(f"clew_render: wrote {output}")
            return EXIT_OK
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
        print(one_line(f"clew_render: {_os_reason(error, output)}"), file=sys.stderr)
        return EXIT_INVALID
    print(f"clew_render: wrote {output}")
    return EXIT_OK


def _spatial(source: Path, args: argparse.Namespace, output: Path, size: int) -> bool:
    """Draw a spatial world (INPUT or ``--world`` says ``world.kind: spatial``, or INPUT is a recording of a
    spatial run) and say so; ``False`` for a planar world, which takes neither ``--view`` nor ``--frames``."""
    from clew_ros.render import RenderError
    from clew_ros.render.spatial.frames import is_spatial_world_file

    candidate = Path(args.world) if args.world else source if source.suffix.lower() in (".yaml", ".yml") else None
    world_file = None
    if candidate is not None and candidate.is_file() and is_spatial_world_file(candidate):
        world_file = candidate
    if _is_recording(source) and (world_file is not None or args.world is None):
        if _render_spatial_recording(source, world_file, args, output, size):
            return True
    elif _is_recording(source) and _recorded_spatial(source):
        raise RenderError(f"--world: {args.world} is a planar world; the recording is of a spatial run")
    elif world_file is not None:
        _render_spatial(world_file, source, args, output, size)
        return True
    for flag, value in (("--view", args.view), ("--frames", args.frames)):
        if value is not None:
            raise RenderError(f"{flag}: only for spatial worlds (world.kind: spatial)")
    return False


def _recorded_spatial(source: Path) -> bool:
    from clew_ros.render.spatial.recording import is_spatial_recording

    return is_spatial_recording(source)


def _view(args: argparse.Namespace, size: int, world: SpatialWorld | None) -> View3D:
    """``--view`` over the default; without it, the default turned to the side from which the robot and its
    goal are seen in ``world`` (:func:`~clew_ros.render.spatial.open_side.open_side_view`)."""
    from clew_ros.render.spatial import View3D, parse_view
    from clew_ros.render.spatial.open_side import open_side_view

    base = View3D(width=size, height=round(size * 0.75))
    if args.view is not None:
        return parse_view(args.view, base)
    return base if world is None else open_side_view(world, base)


def _spatial_output(output: Path) -> None:
    from clew_ros.render import RenderError

    if output.suffix.lower() == ".svg":
        raise RenderError("--output: a spatial world is drawn as .png or .gif, not .svg")


def _render_spatial_recording(
    source: Path, world_file: Path | None, args: argparse.Namespace, output: Path, size: int
) -> bool:
    """A recorded spatial run drawn along its plan (the world: the recording's, or ``world_file``);
    ``False`` when the recording is of a planar run."""
    from clew_ros.render import RenderError
    from clew_ros.render.spatial import draw_spatial_frames, write_spatial_gif
    from clew_ros.render.spatial.frames import load_spatial_world
    from clew_ros.render.spatial.recording import spatial_recording

    run = spatial_recording(source, load_spatial_world(world_file) if world_file is not None else None)
    if run is None:
        return False
    if args.frames is not None:
        raise RenderError("--frames: a recording holds its plan; give either a recording or --frames")
    _spatial_output(output)
    view, frames = _view(args, size, run.world), run.frames
    if output.suffix.lower() == ".gif":
        write_spatial_gif(
            output, run.world, frames.joints, frames.object_poses, view, held=frames.held, title=frames.title
        )
    else:
        picture = draw_spatial_frames(
            run.world, frames.joints, frames.object_poses, view, held=frames.held, title=frames.title
        )
        picture.save(output, format="PNG", optimize=True)
    return True


def _render_spatial(world_file: Path, source: Path, args: argparse.Namespace, output: Path, size: int) -> None:
    """A spatial world drawn: alone (INPUT the world) or along a plan (INPUT, with ``--world``) or ``--frames``."""
    from clew_ros.render import RenderError
    from clew_ros.render.spatial import draw_spatial_frames, draw_spatial_world, write_spatial_gif
    from clew_ros.render.spatial.frames import load_spatial_world, read_frames

    _spatial_output(output)
    _view(args, size, None)  # a bad --view is refused before the world is read
    frames_file = Path(args.frames) if args.frames else source if source != world_file else None
    if args.frames and source != world_file:
        raise RenderError("--frames: give the frames either as INPUT (with --world) or with --frames, not both")
    if frames_file is not None and not frames_file.is_file():
        why = "is not a regular file (a device, a pipe or a folder)" if frames_file.exists() else "does not exist"
        raise RenderError(f"--frames: {frames_file} {why}")
    world = load_spatial_world(world_file)
    view = _view(args, size, world)
    if frames_file is None:
        if output.suffix.lower() == ".gif":
            write_spatial_gif(output, world, world.initial, None, view, title=f"{world.name}: the start")
        else:
            draw_spatial_world(world, view).save(output, format="PNG", optimize=True)
        return
    frames = read_frames(frames_file, world)
    if output.suffix.lower() == ".gif":
        write_spatial_gif(output, world, frames.joints, frames.object_poses, view, held=frames.held, title=frames.title)
    else:
        draw_spatial_frames(world, frames.joints, frames.object_poses, view, held=frames.held, title=frames.title).save(
            output, format="PNG", optimize=True
        )


if __name__ == "__main__":
    raise SystemExit(main())
