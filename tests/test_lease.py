"""The run lease: a task writes into the results directory only while the run that started it
is alive (rotorid.lease), checked on this machine by the run's process and elsewhere by the
lease file's renewal."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

import attrs
import pytest
from rotorid import lease as leases
from rotorid.errors import OrphanedRunError
from rotorid.executors import run_tasks
from rotorid.io import atomic_write
from rotorid.lease import Lease, hold_lease, writing_for


def ended_process() -> int:
    """The pid of a process that has ended (and been reaped)."""
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


def test_a_task_of_a_live_run_writes_and_the_lease_file_lives_as_long_as_the_run(tmp_path):
    with hold_lease(tmp_path) as lease:
        assert lease.path.parent == tmp_path and lease.path.is_file()
        with writing_for(lease):
            atomic_write(tmp_path / "step.json", "{}")
    assert (tmp_path / "step.json").read_text() == "{}"
    assert not lease.path.exists()


@pytest.mark.parametrize("ended", ["process gone", "pid reused"])
def test_a_task_of_an_ended_run_on_this_machine_writes_nothing(tmp_path, ended):
    with hold_lease(tmp_path) as live:
        pass
    if ended == "process gone":
        dead = attrs.evolve(live, pid=ended_process(), started=None)
    else:       # this process's pid, but not its start time: another process got the pid
        dead = attrs.evolve(live, started=live.started + 1)
    assert not dead.owner_alive()
    with writing_for(dead), pytest.raises(OrphanedRunError, match="has ended"):
        atomic_write(tmp_path / "step.json", "{}")
    assert not any(tmp_path.iterdir())         # neither the file nor a temporary one


def test_on_another_machine_the_run_is_alive_while_its_lease_file_is_renewed(tmp_path):
    path = tmp_path / f"{leases.PREFIX}x"
    elsewhere = Lease(path, "another-host/another-boot", os.getpid(), None)
    assert not elsewhere.owner_alive()                        # no lease file
    path.touch()
    assert elsewhere.owner_alive()
    late = time.time() - leases.TIMEOUT - 1.0
    os.utime(path, (late, late))
    assert not elsewhere.owner_alive()                        # not renewed in time


def test_the_run_renews_its_lease_and_removes_those_of_killed_runs(tmp_path, monkeypatch):
    monkeypatch.setattr(leases, "RENEWAL", 0.01)
    killed = tmp_path / f"{leases.PREFIX}killed"
    killed.touch()
    late = time.time() - leases.TIMEOUT - 1.0
    os.utime(killed, (late, late))
    with hold_lease(tmp_path) as lease:
        assert not killed.exists()
        os.utime(lease.path, (late, late))
        deadline = time.monotonic() + 5.0
        while lease.path.stat().st_mtime == late and time.monotonic() < deadline:
            time.sleep(0.01)
        assert time.time() - lease.path.stat().st_mtime < leases.TIMEOUT


def test_run_tasks_hands_the_lease_to_every_task(tmp_path):
    with hold_lease(tmp_path) as live:
        pass
    dead = attrs.evolve(live, pid=ended_process(), started=None)
    tasks = {"a": ((tmp_path / "a.json", "{}"), {})}
    with ThreadPoolExecutor(1) as pool:
        results, failures = run_tasks(atomic_write, tasks, pool, lease=dead)
        assert results == {} and "OrphanedRunError" in failures["a"]
        results, failures = run_tasks(atomic_write, tasks, pool, lease=live)
    assert failures == {} and (tmp_path / "a.json").is_file()
