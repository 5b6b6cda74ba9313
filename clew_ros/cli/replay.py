"""``clew_replay``: publish a recorded run again, with its timing, under ``/replay``.

    clew_replay RECORDING [--rate R] [--loop] [--prefix P | --live-topics] [--include-goal]
                [--delay S] [--wait-for-subscribers S] [--topics T...] [--dry-run]

RECORDING is a run directory (``<record dir>/<run id>/``) or its ``.mcap``
file; a recording cut short (writer killed) plays up to its last complete
chunk. Every recorded topic ``/T`` is published as ``/replay/T`` (another
prefix with ``--prefix``), so a replay never reaches a running planner or the
controllers that follow it; ``--live-topics`` publishes on the recorded names
themselves. The ``goal_pose`` topic (a recorded goal would start a real plan)
is left out unless ``--include-goal``. Each topic has the QoS it was offered
with: the latched topics (trajectory, landmarks, world markers, world YAML)
transient-local. Messages go out as recorded (the CDR bytes, with their
original header stamps, each checked first to decode with its recorded
schema), spaced as recorded divided by ``--rate``. ``--dry-run`` reads and
checks the recording and says what would be played, publishing nothing.
Exit 0 at the end (never with ``--loop``) and on Ctrl-C or SIGTERM; 2 for an
unreadable recording or bad options (one line on stderr).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

from clew_ros.cli.oneline import one_line

EXIT_OK = 0
EXIT_INVALID = 2
_TICK_S = 0.05  # longest sleep: how fast Ctrl-C and SIGTERM are noticed
_MAX_LATCHED_DEPTH = 1000
#: Where topics are published unless --prefix or --live-topics says otherwise.
DEFAULT_PREFIX = "/replay"
#: The recorded topic that starts a plan when published (``~/goal_pose``): never replayed unless asked.
GOAL_TOPIC = "goal_pose"


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="clew_replay",
        description=f"Publish a recorded clew_planner run again, under {DEFAULT_PREFIX} unless --live-topics.",
        epilog="Exit 0: played (or stopped); 2: unreadable recording or bad options.",
    )
    parser.add_argument("recording", metavar="RECORDING", help="run directory or .mcap file")
    parser.add_argument(
        "--rate", type=float, default=1.0, metavar="R", help="playback speed factor (2: twice as fast; default 1)"
    )
    parser.add_argument("--loop", action="store_true", help="start again at the end, until stopped")
    parser.add_argument(
        "--prefix",
        default=None,
        metavar="P",
        help=f"publish /T as P/T (default {DEFAULT_PREFIX}: {DEFAULT_PREFIX}/clew_planner/status)",
    )
    parser.add_argument(
        "--live-topics",
        action="store_true",
        help="publish on the recorded names themselves (what a running planner and its controllers listen to)",
    )
    parser.add_argument(
        "--include-goal",
        action="store_true",
        help=f"also play the recorded {GOAL_TOPIC} (left out by default: it starts a plan)",
    )
    parser.add_argument(
        "--delay",
        type=float,
        default=0.5,
        metavar="S",
        help="seconds to wait after creating the publishers (discovery), default 0.5",
    )
    parser.add_argument(
        "--wait-for-subscribers",
        type=float,
        default=0.0,
        metavar="S",
        help="before playing, wait up to S seconds until every topic has a subscriber",
    )
    parser.add_argument("--topics", nargs="+", metavar="T", help="play only these (recorded) topics")
    parser.add_argument(
        "--dry-run", action="store_true", help="read and check the recording, say what would be played, publish nothing"
    )
    return parser


def _remap(prefix: str, topic: str) -> str:
    prefix = prefix.rstrip("/")
    if prefix and not prefix.startswith("/"):
        prefix = "/" + prefix
    return prefix + topic


def _qos(info, count: int):
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    offered = info.offered_qos_profiles[0] if info.offered_qos_profiles else {}
    reliability = (
        ReliabilityPolicy.BEST_EFFORT
        if str(offered.get("reliability")).lower() == "best_effort"
        else ReliabilityPolicy.RELIABLE
    )
    depth = offered.get("depth")
    if isinstance(depth, bool) or not isinstance(depth, int) or not 0 < depth <= _MAX_LATCHED_DEPTH:
        depth = 10  # what the file says is not a depth a publisher can take
    if info.transient_local:
        # every latched message of the run reaches a late subscriber, as it did from the node
        return QoSProfile(
            history=HistoryPolicy.KEEP_LAST,
            depth=max(depth, min(count, _MAX_LATCHED_DEPTH)),
            reliability=reliability,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=max(depth, 1),
        reliability=reliability,
        durability=DurabilityPolicy.VOLATILE,
    )


class _InvalidInputError(Exception):
    """A command-line value or the recording is unusable: the message goes to stderr, exit 2."""


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        _check_arguments(args)
        recording, messages, classes = _load(args)
        targets = _targets(args.prefix, classes)
    except _InvalidInputError as error:
        print(one_line(f"clew_replay: {error}"), file=sys.stderr)
        return EXIT_INVALID
    if not recording.complete:
        why = f" ({recording.problem})" if recording.problem else ""
        print(
            f"clew_replay: {recording.mcap_path} was cut short{why}; playing its {len(messages)} readable messages",
            file=sys.stderr,
        )
    if args.dry_run:
        topics = ", ".join(f"{name} -> {targets[name]}" for name in sorted(targets))
        print(f"clew_replay: would play {len(messages)} messages: {topics}")
        return EXIT_OK

    import rclpy
    from rclpy.executors import ExternalShutdownException

    rclpy.init()
    node = None
    try:
        node = rclpy.create_node("clew_replay")
        publishers = _publishers(node, targets, recording.topics, classes, messages)
        _play_all(args, messages, publishers)
    except _InvalidInputError as error:
        print(one_line(f"clew_replay: {error}"), file=sys.stderr)
        return EXIT_INVALID
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return EXIT_OK


def _check_arguments(args: argparse.Namespace) -> None:
    if args.live_topics and args.prefix is not None:
        raise _InvalidInputError("--live-topics and --prefix: give one of them (--live-topics means no prefix)")
    args.prefix = "" if args.live_topics else (DEFAULT_PREFIX if args.prefix is None else args.prefix)
    if not args.live_topics and not args.prefix.strip("/"):
        raise _InvalidInputError(
            f"--prefix: expected a namespace such as {DEFAULT_PREFIX}, got {args.prefix!r} "
            "(--live-topics plays on the recorded names)"
        )
    if not args.include_goal and any(_is_goal(topic) for topic in args.topics or ()):
        raise _InvalidInputError(f"--topics: playing {GOAL_TOPIC} starts a plan; add --include-goal to play it")
    if not args.rate > 0:
        raise _InvalidInputError(f"--rate: expected a number > 0, got {args.rate}")
    if args.delay < 0 or args.wait_for_subscribers < 0:
        raise _InvalidInputError("--delay and --wait-for-subscribers: expected seconds >= 0")


def _load(args: argparse.Namespace) -> tuple[Any, list[Any], dict[str, Any]]:
    """The recording, the messages to play (in log time order) and each topic's message class."""
    from clew_ros.recording import Recording, RecordingError
    from clew_ros.recording.msgdefs import message_class

    try:
        recording = Recording(Path(args.recording))
        topics = recording.topics
        unknown = sorted(set(args.topics or ()) - set(topics))
        if unknown:
            raise RecordingError(
                f"{args.recording} has no topic {', '.join(unknown)}; it has {', '.join(sorted(topics))}"
            )
        messages = [m for m in recording.messages(args.topics) if args.include_goal or not _is_goal(m.topic)]
        classes = {}
        skipped = []
        for name in sorted({m.topic for m in messages}):
            try:
                classes[name] = message_class(topics[name].type_name)
            except RecordingError as error:
                if args.topics:  # asked for by name: say why it cannot be played
                    raise
                skipped.append(f"not playing {name}: {error}")  # e.g. /tf without tf2_msgs (PyPI wheels)
        messages = [m for m in messages if m.topic in classes]
        if not messages:
            raise RecordingError(f"{args.recording} holds no messages to play{''.join(f'; {s}' for s in skipped)}")
        for line in skipped:  # play the rest
            print(one_line(f"clew_replay: {line}"), file=sys.stderr)
        for name in classes:
            recording.decoded(name)  # every message played decodes with its recorded schema
    except RecordingError as error:
        raise _InvalidInputError(str(error)) from None
    return recording, messages, classes


def _is_goal(topic: str) -> bool:
    return topic.rstrip("/").rsplit("/", 1)[-1] == GOAL_TOPIC


def _targets(prefix: str, classes: dict[str, Any]) -> dict[str, str]:
    """Where each played topic is published: its recorded name under ``prefix``, checked to be a topic name."""
    from rclpy.validate_full_topic_name import validate_full_topic_name

    targets = {}
    for name in classes:
        target = _remap(prefix, name)
        try:
            validate_full_topic_name(target)
        except Exception as error:  # noqa: BLE001 - rclpy raises its own InvalidTopicNameException
            raise _InvalidInputError(
                f"the recorded topic {name!r:.80} under prefix {prefix!r:.80} is not a valid topic name "
                f"({str(error).splitlines()[0]})"
            ) from None
        targets[name] = target
    return targets


def _publishers(
    node: Any, targets: dict[str, str], topics: dict[str, Any], classes: dict[str, Any], messages: list[Any]
) -> dict[str, Any]:
    """One publisher per played topic, on its target name, with the QoS the topic was recorded with."""
    counts = {name: sum(m.topic == name for m in messages) for name in classes}
    return {
        name: node.create_publisher(cls, targets[name], _qos(topics[name], counts[name]))
        for name, cls in classes.items()
    }


def _play_all(args: argparse.Namespace, messages: list[Any], publishers: dict[str, Any]) -> None:
    """Wait as asked, play (looping if asked), then let reliable readers take the last messages."""
    import rclpy
    from rclpy.duration import Duration

    duration_s = (messages[-1].log_time_ns - messages[0].log_time_ns) / 1e9 / args.rate
    print(
        f"clew_replay: {len(messages)} messages on {len(publishers)} topics, {duration_s:.2f} s at rate "
        f"{args.rate:g}{' (looping)' if args.loop else ''}",
        flush=True,
    )
    if not _wait(args.delay):
        return
    deadline = time.monotonic() + args.wait_for_subscribers
    while rclpy.ok() and time.monotonic() < deadline:
        if all(p.get_subscription_count() > 0 for p in publishers.values()):
            break
        time.sleep(_TICK_S)
    while rclpy.ok() and _play(messages, publishers, args.rate) and args.loop:
        pass
    for publisher in publishers.values():
        if rclpy.ok():
            publisher.wait_for_all_acked(Duration(seconds=1.0))


def _wait(seconds: float) -> bool:
    """Sleep ``seconds`` in short ticks; False when ROS was shut down (Ctrl-C, SIGTERM)."""
    import rclpy

    deadline = time.monotonic() + seconds
    while rclpy.ok():
        remaining = deadline - time.monotonic()
        if remaining <= 0:
            return True
        time.sleep(min(remaining, _TICK_S))
    return False


def _play(messages, publishers, rate: float) -> bool:
    """Publish every message at its recorded offset / ``rate``; False when interrupted."""
    import rclpy

    start = time.monotonic()
    first_ns = messages[0].log_time_ns
    for message in messages:
        if not _wait(start + (message.log_time_ns - first_ns) / 1e9 / rate - time.monotonic()):
            return False
        if not rclpy.ok():
            return False
        publishers[message.topic].publish(message.data)
    return True


if __name__ == "__main__":
    raise SystemExit(main())
