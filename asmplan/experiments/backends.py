"""Where tasks run: in this process, in a local process pool, or on a Ray cluster.

Every backend takes a list of :class:`~asmplan.experiments.tasks.TaskSpec` and yields
``(spec, outcome)`` pairs in completion order, the outcome being the
:class:`~asmplan.experiments.tasks.TaskResult` or the exception the task raised. A task's
result depends on its spec only, so all backends give the same results for the same seeds.

Ray is optional (``pip install 'asmplan[cluster]'``) and imported only when used.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import signal
import sys
import threading
import time
from collections.abc import Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass
from multiprocessing import get_context
from pathlib import Path

from asmplan.experiments.tasks import TaskResult, TaskSpec, run_task

Outcome = TaskResult | BaseException
THREAD_ENV = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS")


PARENT_POLL_S = 0.5
"""How often a pool worker checks that the process that started it is still there."""
_PR_SET_PDEATHSIG = 1


def _init_pool_worker(parent: int) -> None:
    # Every core runs a task of its own: keep the numerical libraries to one thread each.
    for name in THREAD_ENV:
        os.environ[name] = "1"
    die_with_parent(parent)


def die_with_parent(parent: int) -> None:
    """End this process as soon as ``parent`` (the pid that started it) is gone.

    On Linux the kernel kills it when the parent dies (``prctl(PR_SET_PDEATHSIG)``), at
    once, even in the middle of a task; everywhere a daemon thread also polls the parent
    pid (a process whose parent died is re-parented) every :data:`PARENT_POLL_S` seconds.
    Without this, a worker of a killed ``asmplan experiment`` waits forever for its next
    task: it holds the write end of the task queue itself, so the queue never closes.
    """
    if sys.platform.startswith("linux"):
        # Without prctl (no libc symbol) the thread below suffices.
        with contextlib.suppress(OSError, AttributeError):
            ctypes.CDLL(None).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)
    if os.getppid() != parent:  # the parent died before the death signal was set
        os._exit(1)

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(PARENT_POLL_S)
        os._exit(1)

    threading.Thread(target=watch, name="watch-parent", daemon=True).start()


@dataclass(frozen=True)
class SerialBackend:
    """Run the tasks one after another in this process (``--workers 1``)."""

    name: str = "serial"

    def run(self, specs: Sequence[TaskSpec]) -> Iterator[tuple[TaskSpec, Outcome]]:
        """Yield ``(spec, result or exception)`` for each task, in order."""
        for spec in specs:
            try:
                yield spec, run_task(spec)
            except Exception as exc:  # reported by the runner, the sweep goes on
                yield spec, exc


@dataclass(frozen=True)
class LocalBackend:
    """A pool of ``workers`` processes on this machine (default: one per core).

    The pool uses the ``spawn`` start method, so workers never inherit threads (torch,
    Ray, tqdm) from the parent. Workers die with this process (:func:`die_with_parent`);
    when the sweep is interrupted (Ctrl-C, SIGTERM through the command line, or the
    caller stops iterating) the running tasks are terminated and the queued ones dropped.
    """

    workers: int | None = None
    name: str = "local"

    def run(self, specs: Sequence[TaskSpec]) -> Iterator[tuple[TaskSpec, Outcome]]:
        """Yield ``(spec, result or exception)`` as tasks finish."""
        if not specs:
            return
        workers = min(self.workers or os.cpu_count() or 1, len(specs))
        pool = ProcessPoolExecutor(
            max_workers=workers,
            mp_context=get_context("spawn"),
            initializer=_init_pool_worker,
            initargs=(os.getpid(),),
        )
        finished = False
        try:
            pending: dict[Future, TaskSpec] = {pool.submit(run_task, s): s for s in specs}
            while pending:
                done, _ = wait(pending, return_when=FIRST_COMPLETED)
                for future in done:
                    spec = pending.pop(future)
                    exc = future.exception()
                    yield spec, (exc if exc is not None else future.result())
            finished = True
        finally:
            if not finished:  # interrupted: stop the running tasks too, not only the queue
                for process in list((pool._processes or {}).values()):  # no public API (3.11)
                    process.terminate()
            pool.shutdown(wait=True, cancel_futures=True)


@dataclass(frozen=True)
class RayBackend:
    """Run the tasks as Ray tasks (one CPU each).

    Attributes
    ----------
    address : str
        ``"auto"`` (a cluster started with ``ray start`` on this machine), ``"host:port"``
        (a remote cluster; the local ``cad``, ``asp``, ``arl`` and ``asmplan`` packages are
        shipped to it with ``runtime_env={"py_modules": ...}`` so every node runs this
        code), or ``"local"``
        (a private Ray instance on this machine, shut down afterwards). When this process
        is already connected to Ray (``ray.is_initialized()``), that connection is used.
    workers : int, optional
        Maximum tasks in flight (default: all; Ray schedules them on the free CPUs).
    """

    address: str = "auto"
    workers: int | None = None
    name: str = "ray"

    def run(self, specs: Sequence[TaskSpec]) -> Iterator[tuple[TaskSpec, Outcome]]:
        """Yield ``(spec, result or exception)`` as tasks finish."""
        if not specs:
            return
        ray = import_ray()
        started = connect_ray(ray, self.address, self.workers)
        pending: dict = {}
        try:
            remote = ray.remote(num_cpus=1)(run_task)
            queue = list(specs)
            limit = self.workers or len(queue)
            while queue or pending:
                while queue and len(pending) < limit:
                    spec = queue.pop(0)
                    pending[remote.remote(spec)] = spec
                ready, _ = ray.wait(list(pending), num_returns=1)
                for ref in ready:
                    spec = pending.pop(ref)
                    try:
                        yield spec, ray.get(ref)
                    except Exception as exc:  # RayTaskError wraps the task's exception
                        yield spec, exc
        finally:
            for ref in pending:  # interrupted: do not leave queued tasks on the cluster
                ray.cancel(ref)
            if started:
                ray.shutdown()


def import_ray():
    """Import Ray, or raise ``ValueError`` saying how to install it."""
    try:
        import ray
    except ImportError:
        raise ValueError(
            "the ray backend needs Ray: pip install 'asmplan[cluster]' (or use --backend local)"
        ) from None
    return ray


def connect_ray(ray, address: str, workers: int | None = None) -> bool:
    """Connect to (or start) Ray unless already connected; return whether we connected."""
    if ray.is_initialized():
        return False
    quiet = {"include_dashboard": False, "log_to_driver": False}
    if address == "local":
        ray.init(num_cpus=workers or os.cpu_count(), **quiet)
        return True
    runtime_env = None if address == "auto" else {"py_modules": _project_modules()}
    try:
        ray.init(address=address, runtime_env=runtime_env, log_to_driver=False)
    except ConnectionError as exc:
        raise ValueError(
            f"no Ray cluster at --address {address} ({str(exc).splitlines()[0]}); "
            "start one with `ray start --head`, or use --address local"
        ) from None
    return True


def _project_modules() -> list[str]:
    """The project's packages, shipped to a remote cluster so every node runs this code."""
    import arl
    import asmplan
    import asp
    import cad

    return [str(Path(m.__file__).parent) for m in (cad, asp, arl, asmplan)]


BACKENDS = ("local", "ray")
"""Where tasks run: a local process pool (serial with one worker) or a Ray cluster."""


def make_backend(name: str, *, workers: int | None = None, address: str = "auto"):
    """The backend called ``name``: ``"local"`` (a pool, or serial with one worker) or ``"ray"``."""
    if workers is not None and workers < 1:
        raise ValueError(f"workers: expected a positive integer, got {workers}")
    if name == "local":
        return SerialBackend() if workers == 1 else LocalBackend(workers)
    if name == "ray":
        import_ray()
        return RayBackend(address=address, workers=workers)
    raise ValueError(f"backend: expected local or ray, got {name!r}")
