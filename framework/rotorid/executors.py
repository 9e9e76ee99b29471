"""Where independent work runs: in this process, in a local process pool, or on a Dask cluster.

A study's cases and a Monte Carlo's runs are independent tasks. They are submitted through the
:class:`concurrent.futures.Executor` interface (module-level task functions, picklable
arguments), so any executor runs them:

* ``None``: one after the other in this process;
* ``"process"``: a local :class:`~concurrent.futures.ProcessPoolExecutor`, one worker per core
  (at most one per task), shut down afterwards; a worker ends itself within
  :data:`PARENT_CHECK_INTERVAL` s when the process that started the pool dies;
* any :class:`~concurrent.futures.Executor`, e.g. a Dask cluster's
  ``dask.distributed.Client("tcp://HOST:8786").get_executor()``.

Tasks that write into a results directory run under the caller's lease on it
(:mod:`rotorid.lease`, ``run_tasks(..., lease=...)``): once the caller has died, a task still
running (on a Dask worker, which outlives it) refuses its next write and ends.

The numerical hot paths run with one BLAS thread, so a task computes the same bytes whichever
executor runs it (on the same platform and library versions). A task that fails, or whose
worker dies, is reported by name; the other tasks still finish and are returned.
"""

from __future__ import annotations

import contextlib
import logging
import os
import threading
import time
from collections.abc import Callable, Hashable, Iterator, Mapping
from concurrent.futures import Executor, ProcessPoolExecutor

from rotorid.errors import PluginError, StudyError
from rotorid.lease import Lease, process_alive, writing_for
from rotorid.progress import Countdown

#: Executor names accepted by the commands (``--executor``).
KINDS = ("serial", "process", "dask")
#: Seconds to wait for a Dask scheduler before giving up.
CONNECT_TIMEOUT = 10.0

_log = logging.getLogger("rotorid.executors")


def cpu_count() -> int:
    """Cores this process may use (its CPU affinity where the platform tells it)."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)


def check_executor(executor) -> None:
    """Reject anything that is not ``None``, ``"process"`` or an Executor, saying what is."""
    if executor is None or executor == "process" or isinstance(executor, Executor):
        return
    hint = (" (for Dask pass Client(address).get_executor())" if executor in KINDS
            else "")
    raise PluginError(f"executor must be None, 'process' or a concurrent.futures.Executor, "
                      f"got {executor!r}{hint}")


Task = tuple[tuple, Mapping]


def run_tasks(function: Callable, tasks: Mapping[Hashable, Task], executor=None,
              label: Callable[[Hashable], str] = str,
              lease: Lease | None = None) -> tuple[dict, dict]:
    """Run ``function(*args, **kwargs)`` for every task; results and failures by task key.

    Args:
        function: a module-level function (it is pickled to the workers).
        tasks: key → ``(args, kwargs)``; results come back in this order.
        executor: ``None``, ``"process"`` (a single task then runs in this process) or an
            Executor (see the module docstring).
        label: names a task in failure messages, e.g. ``lambda k: f"case {k}"``.
        lease: the caller's lease on the directory the tasks write into
            (:func:`rotorid.lease.hold_lease`); tasks in other processes then write only
            while the caller is alive.

    Returns:
        ``(results, failures)``: key → return value for the tasks that finished, key → one
        line naming the task and the error for those that raised or whose worker died.
    """
    check_executor(executor)
    if executor == "process" and len(tasks) <= 1:
        executor = None                          # a pool would only add start-up time
    if executor == "process":
        with ProcessPoolExecutor(max_workers=max(1, min(len(tasks), cpu_count())),
                                 initializer=_stop_with, initargs=(os.getpid(),)) as pool:
            return run_tasks(function, tasks, pool, label, lease)
    if executor is None:
        futures = {key: _Deferred(function, args, kwargs) for key, (args, kwargs) in tasks.items()}
    else:
        futures = {key: executor.submit(_under_lease, lease, function, *args, **kwargs)
                   for key, (args, kwargs) in tasks.items()}
    return _collect(futures, label)


def _under_lease(lease: Lease | None, function: Callable, *args, **kwargs):
    """``function(*args, **kwargs)`` with every write checked against ``lease`` (a task)."""
    with writing_for(lease):
        return function(*args, **kwargs)


#: Seconds between a pool worker's checks that the process which started it is alive.
PARENT_CHECK_INTERVAL = 0.2


def _stop_with(parent: int) -> None:
    """Pool worker initializer: end this worker at once when ``parent`` (the process that
    started the pool) has died or this worker was handed to another parent, so that an
    orphaned worker never goes on writing results into the output directory."""
    started_by = os.getppid()

    def watch():
        while True:
            time.sleep(PARENT_CHECK_INTERVAL)
            if not process_alive(parent) or os.getppid() != started_by:
                os._exit(1)

    threading.Thread(target=watch, name="rotorid-parent-watch", daemon=True).start()


class _Deferred:
    """A task run in this process when its result is asked for (serial execution)."""

    def __init__(self, function, args, kwargs):
        self.call = lambda: function(*args, **kwargs)

    def result(self):
        return self.call()


def _collect(futures: Mapping, label) -> tuple[dict, dict]:
    """Wait for every task in order; with several, log each one's end and the time left."""
    results, failures = {}, {}
    countdown = Countdown(len(futures))
    for key, future in futures.items():
        try:
            results[key] = future.result()
        except Exception as error:  # one task's failure must not lose the others
            detail = str(error) if isinstance(error, StudyError) else (
                f"{type(error).__name__}: {error}")
            failures[key] = f"{label(key)}: {detail}"
        if len(futures) > 1:
            _log.info("%s %s %s", label(key), "failed" if key in failures else "done",
                      countdown.step())
    return results, failures


def failure_error(what: str, results: Mapping, failures: Mapping, where: str,
                  label=None) -> StudyError:
    """One error naming every failed task and the finished ones, which it carries along.
    With the tasks' ``label`` (the one :func:`run_tasks` was given) tasks that failed for the
    same reason are named once with it: ``case a, case b: DataError: …``."""
    finished = ", ".join(str(k) for k in results) or "none"
    reasons: dict[str, list[str]] = {}
    for key, message in failures.items():
        name = "" if label is None else label(key)
        if name and message.startswith(f"{name}: "):
            reasons.setdefault(message[len(name) + 2:], []).append(name)
        else:
            reasons.setdefault(message, [])
    told = "; ".join(f"{', '.join(names)}: {reason}" if names else reason
                     for reason, names in reasons.items())
    return StudyError(f"{len(failures)} of {len(results) + len(failures)} {what} failed: "
                      + told + f" (finished: {finished}; their results are in {where})",
                      results=results, failures=failures)


def connect_dask(address: str, timeout: float = CONNECT_TIMEOUT):
    """A ``dask.distributed.Client`` connected to the scheduler at ``address``."""
    try:
        from dask.distributed import Client
    except ImportError:
        raise PluginError("the Dask executor needs dask.distributed: "
                          "pip install 'rotorid[dask]'") from None
    try:
        return Client(address, timeout=timeout)
    except (OSError, TimeoutError, ValueError) as error:
        raise PluginError(f"cannot reach the Dask scheduler at {address!r} within "
                          f"{timeout:.0f} s ({type(error).__name__}: {error}); check the "
                          f"address, or start a scheduler with `dask scheduler` and workers "
                          f"with `dask worker {address}`") from None


@contextlib.contextmanager
def open_executor(kind: str, scheduler: str | None = None) -> Iterator:
    """The executor of a command's ``--executor``/``--scheduler`` options, closed on exit."""
    if kind not in KINDS:
        raise PluginError(f"unknown executor {kind!r}; choose from {', '.join(KINDS)}")
    if kind != "dask":
        if scheduler:
            raise PluginError(f"--scheduler only applies to --executor dask, not {kind}")
        yield None if kind == "serial" else "process"
        return
    if not scheduler:
        raise PluginError("--executor dask needs --scheduler tcp://HOST:PORT (the address a "
                          "`dask scheduler` prints)")
    client = connect_dask(scheduler)
    try:
        yield client.get_executor()
    finally:
        client.close()
