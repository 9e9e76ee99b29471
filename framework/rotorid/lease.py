"""A run's lease on its results directory: tasks in other processes write only while the run
that started them is alive.

A run that hands tasks to other processes (a process pool, a Dask cluster) holds a lease on
its results directory while they run (:func:`hold_lease`): the hidden file
``OUT/.rotorid-lease-<token>``, whose modification time the run renews every
:data:`RENEWAL` s, and the identity of the run's process (machine, pid, start time). Each task
runs under the lease (:func:`writing_for`); before each of its writes into the directory
(every :func:`rotorid.io.atomic_write`, the removal of old resume points)
:func:`check_owner_alive` raises :class:`~rotorid.errors.OrphanedRunError` when the run has
ended, which ends the task before it writes (the refusal is also logged as a warning on the
``rotorid.lease`` logger, for the worker's log). The run counts as ended

* on the run's own machine: when its process is gone (a reused pid does not count: the start
  time must match), at once;
* on another machine: when the lease file is gone or was not renewed for :data:`TIMEOUT` s
  (it must be on a file system both machines share, and their clocks must agree to a few
  seconds).

Outside :func:`writing_for` (serial runs, the run's own process) nothing is checked.
"""

from __future__ import annotations

import contextlib
import contextvars
import logging
import os
import socket
import threading
import time
import uuid
from collections.abc import Iterator
from pathlib import Path

import attrs

from rotorid.errors import OrphanedRunError

#: Seconds between renewals of the lease file by the run's process.
RENEWAL = 1.0
#: Seconds without renewal after which a task on another machine takes the run as ended.
TIMEOUT = 10.0
#: Name prefix of lease files in a results directory.
PREFIX = ".rotorid-lease-"


def _machine() -> str:
    """This machine: its host name and, where the system tells it, its boot id (containers on
    one kernel share the boot id but not the host name)."""
    try:
        boot = Path("/proc/sys/kernel/random/boot_id").read_text().strip()
    except OSError:
        boot = ""
    return f"{socket.gethostname()}/{boot}"


def _process_state(pid: int) -> tuple[str, int] | None:
    """(state letter, start time in clock ticks since boot) of process ``pid`` from
    ``/proc``, or ``None`` where the system has no ``/proc``."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except FileNotFoundError:
        return ("X", -1) if Path("/proc/self").exists() else None
    except OSError:
        return None
    fields = stat[stat.rindex(")") + 2:].split()    # after "pid (command) "
    return fields[0], int(fields[19])


def process_alive(pid: int, started: int | None = None) -> bool:
    """Whether process ``pid`` runs (not a zombie) and, when ``started`` is known, is the one
    that started at that time."""
    state = _process_state(pid)
    if state is None:                       # no /proc: ask the kernel about the pid only
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return False
        except PermissionError:             # alive, owned by someone else
            pass
        return True
    letter, start = state
    return letter not in ("Z", "X") and (started is None or start == started)


@attrs.frozen
class Lease:
    """What a task needs to tell whether the run that started it is alive.

    Attributes:
        path: the lease file, in the run's results directory.
        machine: the run's machine (host name and boot id).
        pid: the run's process id.
        started: its start time in clock ticks since boot (``None`` without ``/proc``).
    """

    path: Path
    machine: str
    pid: int
    started: int | None

    def owner_alive(self) -> bool:
        """Whether the run is alive, seen from this process (see the module docstring)."""
        if self.machine == _machine():
            return process_alive(self.pid, self.started)
        try:
            age = time.time() - self.path.stat().st_mtime
        except OSError:
            return False
        return age <= TIMEOUT


def _stale(directory: Path) -> Iterator[Path]:
    """Lease files in ``directory`` not renewed for :data:`TIMEOUT` s (left by killed runs)."""
    for path in directory.glob(f"{PREFIX}*"):
        with contextlib.suppress(OSError):
            if time.time() - path.stat().st_mtime > TIMEOUT:
                yield path


@contextlib.contextmanager
def hold_lease(directory: str | os.PathLike) -> Iterator[Lease]:
    """This process's lease on ``directory`` (which must exist) while the block runs: the
    lease file is created, renewed every :data:`RENEWAL` s from a background thread and
    removed at the end; lease files of killed runs are removed first."""
    directory = Path(directory)
    for stale in _stale(directory):
        stale.unlink(missing_ok=True)
    path = directory / f"{PREFIX}{uuid.uuid4().hex}"
    path.touch()
    state = _process_state(os.getpid())
    lease = Lease(path, _machine(), os.getpid(), None if state is None else state[1])
    stop = threading.Event()

    def renew():
        while not stop.wait(RENEWAL):
            with contextlib.suppress(OSError):   # a removed directory: tasks elsewhere stop
                os.utime(path)

    renewal = threading.Thread(target=renew, name="rotorid-lease", daemon=True)
    renewal.start()
    try:
        yield lease
    finally:
        stop.set()
        renewal.join()
        path.unlink(missing_ok=True)


_current: contextvars.ContextVar[Lease | None] = contextvars.ContextVar("rotorid_lease",
                                                                        default=None)


@contextlib.contextmanager
def writing_for(lease: Lease | None) -> Iterator[None]:
    """Check every write in this block against ``lease`` (``None``: no check)."""
    token = _current.set(lease)
    try:
        yield
    finally:
        _current.reset(token)


def check_owner_alive(target: str | os.PathLike) -> None:
    """Before writing ``target``: :class:`~rotorid.errors.OrphanedRunError` when this code runs
    for a run (:func:`writing_for`) that has ended."""
    lease = _current.get()
    if lease is None or lease.owner_alive():
        return
    message = (f"not writing {target}: the run that started this task (process {lease.pid} on "
               f"{lease.machine.partition('/')[0]}) has ended; its results directory is left "
               f"as it was (rerun with --resume to continue)")
    # nobody collects the task's error any more: the worker's log tells why it stopped
    logging.getLogger("rotorid.lease").warning(message)
    raise OrphanedRunError(message)
