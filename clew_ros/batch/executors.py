"""Where jobs run: a local pool of worker processes (:class:`LocalPool`, the default) or Ray
(:class:`RayExecutor`: a local Ray on 127.0.0.1, or an existing cluster).

Both take :class:`~clew_ros.batch.worker.JobSpec` values with :meth:`submit`
and hand back :class:`Finished` ones from :meth:`wait`: the job's outcome, or
why there is none (the job function raised, its worker process died, or it
ran past ``spec.timeout_s`` and was stopped). A failed job never stops the
others. The driver keeps at most :attr:`capacity` jobs submitted: a killed
driver loses those and no more.

The local pool is a few ``multiprocessing`` processes (spawn context), one
job at a time each, fed through a pipe per worker rather than a
``concurrent.futures.ProcessPoolExecutor``: a pool executor cannot stop one
job that hangs, and when one of its workers dies it fails every job in
flight, so the job that killed it cannot be told from the others. Here a
dead or stopped worker costs only its own job, and a new worker takes its
place.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
import socket
import time
from collections import deque
from dataclasses import dataclass
from multiprocessing.connection import Connection, wait
from multiprocessing.process import BaseProcess
from pathlib import Path
from typing import Any, Protocol

import clew_ros
from clew_ros.batch.errors import ExecutorError, ExecutorUnavailableError
from clew_ros.batch.worker import JobFunction, JobOutcome, JobSpec, run_job, run_prepared, serve

__all__ = [
    "RAY_INSTALL_HINT",
    "Executor",
    "Finished",
    "LocalPool",
    "RayExecutor",
    "default_workers",
    "network_interfaces_up",
]

RAY_INSTALL_HINT = "pip install 'clew_ros[batch]' (or pip install 'ray>=2.9')"
#: Workers in a row that die before they are ready: the pool gives up (ExecutorError).
MAX_START_FAILURES = 3


_IFF_UP = 0x1
_IFF_LOOPBACK = 0x8
_SIOCGIFFLAGS = 0x8913  # Linux: read an interface's flags (struct ifreq: 16-byte name, then the flags)


def network_interfaces_up() -> list[str]:
    """The network interfaces of this process's network namespace, other than loopback, that are up;
    inside a private network namespace with only loopback up (``unshare --net``), none.

    Asked of the kernel (``if_nameindex``, ``SIOCGIFFLAGS``), not of ``/sys/class/net``, which shows the
    namespace it was mounted in. An interface whose flags cannot be read counts as up: when in doubt,
    there is a network.
    """
    import fcntl
    import struct

    up = []
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        for _, name in socket.if_nameindex():
            try:
                request = struct.pack("16s16x", name.encode()[:15])
                flags = struct.unpack_from("H", fcntl.ioctl(probe.fileno(), _SIOCGIFFLAGS, request), 16)[0]
            except OSError:
                flags = _IFF_UP
            if flags & _IFF_UP and not flags & _IFF_LOOPBACK:
                up.append(name)
    return up


@dataclass(frozen=True)
class Finished:
    """A job that left its executor: ``outcome``, or ``failure`` saying why there is none."""

    spec: JobSpec
    outcome: JobOutcome | None = None
    failure: str | None = None


class Executor(Protocol):
    """What the driver needs of an executor."""

    @property
    def capacity(self) -> int:
        """How many jobs may be submitted and not yet finished (after :meth:`start`)."""

    @property
    def description(self) -> str:
        """What runs the jobs, for the command's output."""

    def start(self) -> None:
        """Start the workers (or connect)."""

    def submit(self, spec: JobSpec) -> None:
        """Run ``spec`` when a worker is free."""

    def wait(self, timeout_s: float) -> list[Finished]:
        """The jobs finished within ``timeout_s`` (s; returns as soon as there is one)."""

    def close(self) -> None:
        """Stop every worker; jobs still running are dropped."""


def default_workers() -> int:
    """The cores this process may use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def _exit_reason(exitcode: int | None) -> str:
    if exitcode is None:
        return "it did not exit"
    if exitcode < 0:
        try:
            return f"killed by {signal.Signals(-exitcode).name}"
        except ValueError:
            return f"killed by signal {-exitcode}"
    return f"exit code {exitcode}"


@dataclass
class _Worker:
    process: BaseProcess
    connection: Connection
    ready: bool = False
    spec: JobSpec | None = None
    started: float = 0.0


class LocalPool:
    """``workers`` worker processes on this machine (spawn context), each running ``job_function``
    (:func:`~clew_ros.batch.worker.run_job`) on one job at a time."""

    def __init__(self, workers: int, *, job_function: JobFunction = run_job) -> None:
        if workers < 1:
            raise ValueError(f"workers: expected at least 1, got {workers}")
        self.workers = workers
        self.job_function = job_function
        self._context = multiprocessing.get_context("spawn")
        self._pool: list[_Worker] = []
        self._queue: deque[JobSpec] = deque()
        self._start_failures = 0

    @property
    def capacity(self) -> int:
        return self.workers

    @property
    def description(self) -> str:
        return f"local pool of {self.workers} process{'es' if self.workers > 1 else ''}"

    def start(self) -> None:
        from clew_ros.planar.kernel import warm_up

        warm_up()  # compiled here first (or loaded): the workers then load numba's cache instead of compiling
        for _ in range(self.workers):
            self._start_worker()

    def submit(self, spec: JobSpec) -> None:
        self._queue.append(spec)
        self._dispatch()

    def wait(self, timeout_s: float) -> list[Finished]:
        finished: list[Finished] = []
        self._dispatch()
        now = time.monotonic()
        deadlines = [w.started + w.spec.timeout_s for w in self._pool if w.spec is not None]
        timeout = max(0.0, min([timeout_s, *(d - now for d in deadlines)]))
        handles: list[Any] = [w.connection for w in self._pool] + [w.process.sentinel for w in self._pool]
        ready = set(wait(handles, timeout)) if handles else set()
        if not handles:
            time.sleep(timeout)
        for worker in list(self._pool):
            if worker.connection in ready or worker.process.sentinel in ready:
                finished.extend(self._read(worker))
        now = time.monotonic()
        for worker in list(self._pool):
            if worker.spec is not None and now >= worker.started + worker.spec.timeout_s:
                spec = worker.spec
                worker.process.kill()
                self._remove(worker)
                failure = f"timed out: no result {spec.timeout_s:g} s after it started (time limit + grace); stopped"
                finished.append(Finished(spec, failure=failure))
        self._dispatch()
        return finished

    def close(self) -> None:
        # a worker holds nothing worth a clean exit (its results are sent as they come), and an idle one
        # told to stop still takes seconds to tear the interpreter down: SIGTERM the idle, SIGKILL the busy
        for worker in self._pool:
            if worker.spec is None:
                worker.process.terminate()
            else:
                worker.process.kill()
        for worker in list(self._pool):
            worker.process.join(5.0)
            if worker.process.exitcode is None:
                worker.process.kill()
                worker.process.join(5.0)
            self._remove(worker)
        self._queue.clear()

    # -- the workers ------------------------------------------------------------------------------------

    def _start_worker(self) -> None:
        ours, theirs = self._context.Pipe(duplex=True)
        process = self._context.Process(
            target=serve, args=(theirs, self.job_function), name="clew_batch worker", daemon=True
        )
        process.start()
        theirs.close()  # only the worker holds its end: its death reads as end of file here
        self._pool.append(_Worker(process, ours))

    def _remove(self, worker: _Worker) -> None:
        self._pool.remove(worker)
        worker.connection.close()
        worker.process.join(1.0)

    def _dispatch(self) -> None:
        """Give queued jobs to idle workers; start workers to replace those gone."""
        for worker in self._pool:
            if not self._queue:
                break
            if worker.ready and worker.spec is None:
                spec = self._queue.popleft()
                try:
                    worker.connection.send(spec)
                except OSError:  # the worker just died; its death is read next; the job was not at fault
                    self._queue.appendleft(spec)
                    continue
                worker.spec, worker.started = spec, time.monotonic()
        while self._queue and len(self._pool) < self.workers:
            self._start_worker()

    def _read(self, worker: _Worker) -> list[Finished]:
        """Every message ``worker`` sent; its death when it is gone."""
        finished = []
        try:
            while worker.connection.poll():
                kind, value = worker.connection.recv()
                if kind == "ready":
                    worker.ready = True
                    self._start_failures = 0
                elif worker.spec is not None:
                    spec, worker.spec = worker.spec, None
                    if kind == "done":
                        finished.append(Finished(spec, outcome=value))
                    else:
                        finished.append(Finished(spec, failure=f"the job raised {value}"))
            if worker.process.is_alive():
                return finished
        except (EOFError, OSError):
            pass
        worker.process.join(1.0)
        reason = _exit_reason(worker.process.exitcode)
        if worker.spec is not None:
            finished.append(Finished(worker.spec, failure=f"the worker process died while planning ({reason})"))
        elif not worker.ready:
            self._start_failures += 1
        self._remove(worker)
        if self._start_failures >= MAX_START_FAILURES:
            raise ExecutorError(
                f"{self._start_failures} worker processes in a row died as they started ({reason}); "
                "see the errors above"
            )
        return finished


class RayExecutor:
    """Jobs as Ray tasks: on a local Ray started here (``address`` ``None``: node address 127.0.0.1,
    ``jobs`` CPUs, no dashboard, no usage statistics) or on the cluster at ``address``.

    On a cluster every node needs this package installed (the same version); a local Ray's workers
    import it from where this process does. :class:`ExecutorUnavailableError` when Ray is not
    installed or the cluster cannot be reached.
    """

    def __init__(self, address: str | None, jobs: int | None, *, job_function: JobFunction = run_job) -> None:
        try:
            import ray
        except ImportError:
            raise ExecutorUnavailableError(f"--ray needs Ray, which is not installed: {RAY_INSTALL_HINT}") from None
        self._ray = ray
        self.address = address
        self.jobs = jobs
        self.job_function = job_function
        self._capacity = jobs or 1
        self._task: Any = None
        self._running: dict[Any, tuple[JobSpec, float]] = {}

    @property
    def capacity(self) -> int:
        return self._capacity

    @property
    def description(self) -> str:
        where = "a local Ray on 127.0.0.1" if self.address is None else f"the Ray cluster at {self.address}"
        return f"{where} ({self._capacity} jobs at a time)"

    def start(self) -> None:
        ray = self._ray
        if self.address is None:
            os.environ["RAY_USAGE_STATS_ENABLED"] = "0"
            # Ray runs its workers at nice 15 by default (its worker_niceness setting): planning is this
            # command's whole work, so its workers get their fair share of a busy machine, as the pool's do
            os.environ.setdefault("RAY_worker_niceness", "0")
            # the local workers import clew_ros from where this process does
            package_root = str(Path(clew_ros.__file__).resolve().parents[1])
            os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [package_root, os.environ.get("PYTHONPATH")]))
            ray.init(
                address="local",
                num_cpus=self.jobs or default_workers(),
                include_dashboard=False,
                _node_ip_address="127.0.0.1",
                configure_logging=False,
                log_to_driver=False,
            )
        else:
            try:
                ray.init(address=self.address, configure_logging=False, log_to_driver=False)
            except (ConnectionError, RuntimeError, ValueError) as error:
                raise ExecutorUnavailableError(
                    f"--ray {self.address}: cannot connect to a Ray cluster ({error})"
                ) from None
        self._capacity = self.jobs or max(1, int(ray.cluster_resources().get("CPU", 1)))
        self._task = ray.remote(num_cpus=1, max_retries=0)(run_prepared)

    def submit(self, spec: JobSpec) -> None:
        reference = self._task.remote(self.job_function, spec)
        self._running[reference] = (spec, time.monotonic())

    def wait(self, timeout_s: float) -> list[Finished]:
        ray = self._ray
        if not self._running:
            time.sleep(timeout_s)
            return []
        now = time.monotonic()
        timeout = max(0.0, min([timeout_s, *(t + s.timeout_s - now for s, t in self._running.values())]))
        references = list(self._running)
        ready, rest = ray.wait(references, num_returns=1, timeout=timeout)
        if ready and rest:
            more, _ = ray.wait(rest, num_returns=len(rest), timeout=0)
            ready += more
        finished = [self._collect(reference) for reference in ready]
        now = time.monotonic()
        for reference, (spec, submitted) in list(self._running.items()):
            if now >= submitted + spec.timeout_s:
                ray.cancel(reference, force=True)
                del self._running[reference]
                failure = (
                    f"timed out: no result {spec.timeout_s:g} s after it was submitted (time limit + grace); stopped"
                )
                finished.append(Finished(spec, failure=failure))
        return finished

    def _collect(self, reference: Any) -> Finished:
        ray = self._ray
        spec, _ = self._running.pop(reference)
        try:
            return Finished(spec, outcome=ray.get(reference))
        except ray.exceptions.RayTaskError as error:
            cause = error.cause
            return Finished(spec, failure=f"the job raised {type(cause).__name__}: {cause}")
        except ray.exceptions.WorkerCrashedError:
            return Finished(spec, failure="the worker process died while planning")
        except ray.exceptions.RayError as error:
            return Finished(spec, failure=f"Ray lost the job: {str(error).splitlines()[0]}")

    def close(self) -> None:
        ray = self._ray
        for reference in self._running:
            with contextlib.suppress(Exception):
                ray.cancel(reference, force=True)
        self._running.clear()
        if ray.is_initialized():
            ray.shutdown()
