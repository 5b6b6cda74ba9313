"""Job functions for ``clew_batch``'s fault tests: :func:`clew_ros.batch.worker.run_job` wrapped so that
chosen seeds fail the way a worker can fail. They run in the batch's worker processes (the tests pass
them as ``job_function``); nothing of them is in the package.

- seed 1: the worker process dies at once (``os._exit(3)``), every attempt;
- seed 2: the job raises ``RuntimeError('injected fault')``, every attempt;
- seed 3: the worker dies on the first attempt only (a marker file in ``$CLEW_TEST_FAULT_DIR``
  remembers it), then plans normally;
- seed 4: the job hangs (never returns);
- any other seed: planned normally.

:func:`unrecordable_job` plans normally, but its recording fails in the worker (``--record``).
"""

from __future__ import annotations

import os
import time
from pathlib import Path

from clew_ros.batch.worker import JobOutcome, JobSpec, run_job

__all__ = ["FAULT_DIR_VARIABLE", "faulty_job", "unrecordable_job"]

FAULT_DIR_VARIABLE = "CLEW_TEST_FAULT_DIR"


def faulty_job(spec: JobSpec) -> JobOutcome:
    """:func:`run_job`, or the fault of ``spec.seed`` (see the module)."""
    if spec.seed == 1:
        os._exit(3)
    if spec.seed == 2:
        raise RuntimeError("injected fault")
    if spec.seed == 3:
        marker = Path(os.environ[FAULT_DIR_VARIABLE], f"{spec.key.replace('/', '_')}.crashed")
        if not marker.exists():
            marker.touch()
            os._exit(3)
    if spec.seed == 4:
        while True:
            time.sleep(60)
    return run_job(spec)


def unrecordable_job(spec: JobSpec) -> JobOutcome:
    """:func:`run_job` in a worker where recording a run raises, as a broken message builder would."""
    from clew_ros.batch import recording

    def broken(*_args: object, **_kwargs: object) -> dict[str, bytes]:
        raise RuntimeError("injected recording fault")

    recording.recording_files = broken
    return run_job(spec)
