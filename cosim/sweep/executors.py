"""Where the cases of a sweep run: in this process, on a local process pool or on a Dask cluster.

Every executor takes a module-level (picklable) function and tasks ``(key, args)`` and yields a
:class:`Completed` per task as tasks finish, in completion order. ``error`` is a plain message
(``TypeName: text``) when the task did not return: an exception that escaped the function, a
worker process that died, a Dask ``KilledWorker``. Nothing else escapes: no
``BrokenProcessPool``, no remote tracebacks.

The process pool keeps at most ``jobs`` tasks in flight. When a worker process dies (killed,
out of memory, a crash in a compiled library) every task then in flight is lost: each is queued
again once and rerun *alone*, so a task that kills its worker again is the culprit and is
reported as failed, while the innocent ones finish normally.
"""
from __future__ import annotations

import multiprocessing
import signal
import sys
import threading
import uuid
from collections import deque
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Iterator, List, Optional, Sequence, Tuple

from cosim.errors import ExecutorUnavailable
from cosim.interrupts import ignore_in_worker

Task = Tuple[str, Sequence[Any]]

DASK_INSTALL_HINT = "pip install -e \".[dask]\" (or: pip install \"dask[distributed]\" h5netcdf)"


@dataclass
class Completed:
    key: str
    result: Any = None
    error: Optional[str] = None


def message(exc: BaseException) -> str:
    """A plain, picklable description of an exception (no traceback objects)."""
    text = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


class Serial:
    """Run the tasks one after the other in this process (``--jobs 1``)."""

    def __init__(self) -> None:
        self.running = 0
        self.description = "in this process"

    def run(self, fn: Callable, tasks: Iterable[Task]) -> Iterator[Completed]:
        """Each task in turn; Ctrl-C raises KeyboardInterrupt here even when it arrived inside
        compiled code that wraps it into an error of its own (exudyn's user functions turn it into
        a ModelError, and the case reported it as failed with its traceback in the sweep's
        report): a case during which Ctrl-C came stays pending and runs again on resuming."""
        received: List[int] = []

        def handler(signum, frame):
            received.append(signum)
            raise KeyboardInterrupt
        main = threading.current_thread() is threading.main_thread()    # signals reach the main thread only
        previous = signal.signal(signal.SIGINT, handler) if main else None
        try:
            for key, args in tasks:
                self.running = 1
                try:
                    done = Completed(key, fn(*args))
                except Exception as exc:                   # noqa: BLE001 -- reported, the sweep goes on
                    done = Completed(key, None, message(exc))
                if received:                               # the case ended by the interrupt: pending
                    raise KeyboardInterrupt
                self.running = 0
                yield done
        finally:
            if main:
                signal.signal(signal.SIGINT, previous)


def _context():
    # fork: workers start in milliseconds with everything imported (spawn would re-import numpy,
    # exudyn and matplotlib in every worker); the sweep's parent holds no threads.
    return multiprocessing.get_context("fork" if sys.platform.startswith("linux") else "spawn")


class Pool:
    """A local process pool of ``jobs`` workers (``--jobs N``, the default executor)."""

    LOST = ("the worker process died while running this case alone (killed, or crashed: out of "
            "memory, a signal, a fault in a compiled library)")

    def __init__(self, jobs: int) -> None:
        self.jobs = jobs
        self.running = 0
        self.description = f"on a pool of {jobs} processes"

    def run(self, fn: Callable, tasks: Iterable[Task]) -> Iterator[Completed]:
        queue = deque(tasks)
        suspects = set()                       # in flight when a worker died: rerun alone
        while queue:
            pool = ProcessPoolExecutor(max_workers=min(self.jobs, len(queue)), mp_context=_context(),
                                       initializer=ignore_in_worker)
            inflight = {}
            clean = False
            try:
                lost = []
                while (queue or inflight) and not lost:
                    while queue and len(inflight) < self.jobs:
                        key, args = queue[0]
                        alone = key in suspects
                        if inflight and (alone or any(k in suspects for k, _ in inflight.values())):
                            break
                        queue.popleft()
                        inflight[pool.submit(fn, *args)] = (key, args)
                    self.running = len(inflight)
                    done, _ = wait(list(inflight), return_when=FIRST_COMPLETED)
                    for fut in done:
                        key, args = inflight.pop(fut)
                        self.running = len(inflight)
                        try:
                            result = fut.result()
                        except BrokenProcessPool:
                            lost.append((key, args))
                            continue
                        except Exception as exc:       # noqa: BLE001 -- e.g. an unpicklable result
                            yield Completed(key, None, message(exc))
                            continue
                        yield Completed(key, result)
                if lost:
                    # the pool is broken: every future still in flight fails at once
                    wait(list(inflight))
                    for fut, (key, args) in list(inflight.items()):
                        try:
                            result = fut.result()
                        except Exception:              # noqa: BLE001 -- BrokenProcessPool
                            lost.append((key, args))
                        else:
                            yield Completed(key, result)
                    inflight.clear()
                    for key, args in reversed(lost):
                        if key in suspects:
                            yield Completed(key, None, self.LOST)
                        else:
                            suspects.add(key)
                            queue.appendleft((key, args))
                clean = True
            finally:
                self.running = 0
                if not clean:                          # Ctrl-C or the consumer stopped: stop now
                    for proc in list(getattr(pool, "_processes", {}).values()):
                        proc.terminate()
                    pool.shutdown(wait=False, cancel_futures=True)
                else:
                    pool.shutdown(wait=True)


#: how long a --scheduler address may take to accept a connection [s] (--connect-timeout)
CONNECT_TIMEOUT_S = 5.0


class Dask:
    """Dask distributed: a ``LocalCluster`` of ``jobs`` single-threaded worker processes, or an
    existing cluster at ``scheduler`` (its workers need pneumorail installed and the output
    folder on a shared file system)."""

    def __init__(self, jobs: int, scheduler: Optional[str] = None, connect_timeout_s: float = CONNECT_TIMEOUT_S) -> None:
        try:
            import distributed  # noqa: F401
        except ImportError:
            raise ExecutorUnavailable(f"{'--scheduler' if scheduler else '--dask'} needs Dask distributed, which is "
                                      f"not installed: {DASK_INSTALL_HINT}") from None
        self.jobs, self.scheduler = jobs, scheduler
        self.connect_timeout_s = connect_timeout_s
        self._client = None
        if scheduler:
            # connected now, before the sweep announces itself or creates anything
            reachable(scheduler, connect_timeout_s)
            from distributed import Client
            try:
                self._client = Client(scheduler, timeout=f"{connect_timeout_s}s")
            except Exception as exc:                   # noqa: BLE001 -- not a scheduler at that address
                raise ExecutorUnavailable(f"--scheduler {scheduler}: no Dask scheduler answered there "
                                          f"({message(exc)})") from None
        self.running = 0
        self.description = (f"on the Dask cluster at {scheduler}" if scheduler else
                            f"on a Dask LocalCluster of {jobs} worker processes")

    def run(self, fn: Callable, tasks: Iterable[Task]) -> Iterator[Completed]:
        import logging

        from distributed import Client, LocalCluster, as_completed
        tasks = list(tasks)
        if not tasks:
            return
        cluster = None
        if self._client is not None:
            client = self._client
        else:
            cluster = LocalCluster(n_workers=self.jobs, threads_per_worker=1, processes=True,
                                   dashboard_address=None, silence_logs=logging.ERROR)
            client = Client(cluster)
        try:
            slots = max(1, sum(client.nthreads().values()))
            tag = uuid.uuid4().hex[:8]
            futures = {client.submit(fn, *args, key=f"pneumorail-case-{key}-{tag}", pure=False): key
                       for key, args in tasks}
            remaining = len(futures)
            self.running = min(slots, remaining)
            for fut in as_completed(futures):
                key = futures[fut]
                remaining -= 1
                self.running = min(slots, remaining)
                try:
                    result = fut.result()
                except Exception as exc:               # noqa: BLE001 -- KilledWorker, a remote error
                    yield Completed(key, None, message(exc))
                else:
                    yield Completed(key, result)
        finally:
            self.running = 0
            client.close()
            if cluster is not None:
                cluster.close()


def reachable(address: str, timeout_s: float) -> None:
    """Refuse a scheduler address that does not answer a TCP connection within ``timeout_s``,
    before the sweep announces itself or creates anything (Dask's own connect timeout is 30 s)."""
    import socket
    from urllib.parse import urlsplit
    parts = urlsplit(address if "://" in address else f"tcp://{address}")
    try:
        host, port = parts.hostname, parts.port
    except ValueError:
        host, port = None, None
    if not host or not port:
        raise ExecutorUnavailable(f"--scheduler {address}: expected an address like tcp://host:8786")
    try:
        with socket.create_connection((host, port), timeout=timeout_s):
            pass
    except OSError as exc:
        reason = "no answer" if isinstance(exc, TimeoutError) else (exc.strerror or type(exc).__name__)
        raise ExecutorUnavailable(f"--scheduler {address}: cannot connect within {timeout_s:g} s ({reason}); is the "
                                  f"scheduler running and reachable from here?") from None


def make_executor(jobs: int, dask: bool = False, scheduler: Optional[str] = None,
                  connect_timeout_s: float = CONNECT_TIMEOUT_S):
    if dask or scheduler:
        return Dask(jobs, scheduler, connect_timeout_s)
    return Serial() if jobs == 1 else Pool(jobs)
