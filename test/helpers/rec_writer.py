"""A RunRecorder in a process of its own, for the kill and disk-full tests.

python rec_writer.py loop DIR RUN_ID
    writes std_msgs/String {"n": 0, 1, 2, ...} on /clew_planner/events
    without end (small chunks); prints "ready" after the first message.
python rec_writer.py exit DIR RUN_ID
    writes ten messages and exits without calling close() (atexit closes).
python rec_writer.py fsize DIR RUN_ID LIMIT_BYTES
    limits the size of files this process writes (RLIMIT_FSIZE), writes
    until the recorder reports an error, closes, and prints one JSON line:
    {"error": ..., "raised": ..., "written": N, "dropped": N}.
"""

from __future__ import annotations

import json
import resource
import sys
import time

from std_msgs.msg import String

from clew_ros.recording import RunRecorder

TOPIC = "/clew_planner/events"
START_NS = 1_700_000_000_000_000_000


def loop(directory: str, run_id: str) -> int:
    recorder = RunRecorder(directory, run_id, chunk_size=4096, flush_period_s=0.2)
    n = 0
    while True:
        recorder.write(TOPIC, String(data=json.dumps({"n": n, "pad": "x" * 200})), START_NS + n * 1_000_000)
        if n == 0:
            print("ready", flush=True)
        n += 1
        time.sleep(0.0005)


def exit_without_close(directory: str, run_id: str) -> int:
    recorder = RunRecorder(directory, run_id)
    for n in range(10):
        recorder.write(TOPIC, String(data=str(n)), START_NS + n)
    return 0


def fsize(directory: str, run_id: str, limit: int) -> int:
    recorder = RunRecorder(directory, run_id, chunk_size=8192, flush_period_s=0.05)
    resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))  # SIGXFSZ is ignored by Python: EFBIG instead
    raised = None
    written = 0
    deadline = time.monotonic() + 20.0
    while recorder.error is None and time.monotonic() < deadline:
        try:
            recorder.write(TOPIC, String(data="y" * 2000), START_NS + written * 1_000_000)
        except Exception as error:  # noqa: BLE001 - the test asserts that this never happens
            raised = repr(error)
            break
        written += 1
        time.sleep(0.0005)
    try:
        for _ in range(10):  # writes after the failure are dropped quietly
            recorder.write(TOPIC, String(data="late"), START_NS)
        recorder.close()
        recorder.close()
    except Exception as error:  # noqa: BLE001 - reported to the test, which asserts none
        raised = raised or repr(error)
    print(
        json.dumps({"error": recorder.error, "raised": raised, "written": written, "dropped": recorder.dropped}),
        flush=True,
    )
    return 0


def main(argv: list[str]) -> int:
    if len(argv) >= 3 and argv[0] == "loop":
        return loop(argv[1], argv[2])
    if len(argv) == 3 and argv[0] == "exit":
        return exit_without_close(argv[1], argv[2])
    if len(argv) == 4 and argv[0] == "fsize":
        return fsize(argv[1], argv[2], int(argv[3]))
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
