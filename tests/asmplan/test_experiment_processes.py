"""`asmplan experiment` as real processes: pool workers die with a killed parent."""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

from tests.conftest import REPO

pytestmark = pytest.mark.skipif(not Path("/proc").is_dir(), reason="reads /proc")


def _processes() -> list[tuple[int, str, int, int]]:
    """(pid, state, parent pid, process group) of every process."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            state, ppid, pgid = stat.read_text().rsplit(")", 1)[1].split()[:3]
        except (OSError, ValueError):
            continue
        found.append((int(stat.parent.name), state, int(ppid), int(pgid)))
    return found


def _children(pid: int) -> set[int]:
    """Pids of the live processes whose parent is ``pid``."""
    return {p for p, state, ppid, _ in _processes() if ppid == pid and state != "Z"}


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state != "Z"  # a zombie has exited (nobody reaped it yet)


def _poll(condition, timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.2)
    return condition()


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM], ids=["SIGKILL", "SIGTERM"])
def test_pool_workers_die_with_the_parent(tmp_path, sig):
    # Two long tasks (the paper's ARL configuration) on two pool workers.
    argv = "experiment table4 --trials 2 --solver arl --config paper --workers 2 --no-progress"
    parent = subprocess.Popen(
        [sys.executable, "-c", "from asmplan.cli import main; main()", *argv.split()]
        + ["--output", str(tmp_path)],
        env={**os.environ, "PYTHONPATH": str(REPO)},
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    workers: set[int] = set()
    try:

        def two_workers() -> bool:
            workers.update(_children(parent.pid))
            return len(workers) >= 2

        assert _poll(two_workers, 60), "the pool never started"
        time.sleep(1.0)  # let the workers get into their tasks
        parent.send_signal(sig)
        parent.wait(timeout=30)
        assert _poll(lambda: not any(_alive(p) for p in workers), 20), "workers outlived it"
        if sig == signal.SIGTERM:
            assert parent.returncode != 0  # interrupted like Ctrl-C, not a success
            assert b"Traceback" not in parent.stderr.read()
    finally:
        parent.kill()
        parent.wait()
        for pid in workers:
            if _alive(pid):  # only after a failure
                os.kill(pid, signal.SIGKILL)


# ------------------------------------------------------------------ a two-node Ray cluster


def _free_ports(n: int) -> list[int]:
    sockets = [socket.socket() for _ in range(n)]
    try:
        for s in sockets:
            s.bind(("127.0.0.1", 0))
        return [s.getsockname()[1] for s in sockets]
    finally:
        for s in sockets:
            s.close()


def _group(pgid: int) -> set[int]:
    """Live processes of process group ``pgid``."""
    return {p for p, state, _, group in _processes() if group == pgid and state != "Z"}


def _ray_start(args: list[str], env: dict, cwd: Path) -> int:
    """Run ``ray start ARGS`` in a new process group; return the group (its daemons stay
    in it), or skip the test with ray's last line of output."""
    ray_cli = Path(sys.executable).with_name("ray")
    if not ray_cli.is_file():
        pytest.skip("the ray command is not installed")
    start = subprocess.Popen(
        [str(ray_cli), "start", "--disable-usage-stats", "--num-cpus=1", *args],
        env=env,
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        start_new_session=True,
    )
    try:
        output, _ = start.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        start.kill()
        output = b"ray start timed out"
    if start.returncode != 0:
        _stop_group(start.pid)
        lines = output.decode(errors="replace").strip().splitlines() or ["no output"]
        pytest.skip(f"ray could not start: {lines[-1][:200]}")
    return start.pid


def _stop_group(pgid: int, grace: float = 3.0) -> None:
    """What ``ray stop`` does (SIGTERM, then SIGKILL after a grace period), for our own
    processes only: ``ray stop`` would stop every Ray instance on the machine."""
    for sig, wait in ((signal.SIGTERM, grace), (signal.SIGKILL, 5.0)):
        if not _group(pgid):
            return
        with contextlib.suppress(ProcessLookupError):
            os.killpg(pgid, sig)
        _poll(lambda: not _group(pgid), wait)


def test_ray_cluster_of_two_nodes_by_address(tmp_path, monkeypatch):
    ray = pytest.importorskip("ray")
    from asmplan.experiments.runner import run_experiment

    if ray.is_initialized():
        pytest.skip("this process is already connected to Ray")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "RAY_ADDRESS")}
    env["RAY_USAGE_STATS_ENABLED"] = "0"
    env["RAY_AUTH_MODE"] = "disabled"  # a private test cluster on 127.0.0.1, no token
    monkeypatch.setenv("RAY_AUTH_MODE", "disabled")  # and this process, its driver
    session = tempfile.mkdtemp(prefix="ray", dir="/tmp")  # sockets: paths under 108 bytes
    port, client, dashboard, *node_ports = _free_ports(3 + 2 * 6)
    head_args = [
        "--head",
        "--node-ip-address=127.0.0.1",
        f"--port={port}",
        "--include-dashboard=false",
        f"--temp-dir={session}",
        f"--ray-client-server-port={client}",
        f"--dashboard-port={dashboard}",
    ]

    def own_ports(ports: list[int]) -> list[str]:
        names = ("node-manager", "object-manager", "dashboard-agent-listen")
        names += ("dashboard-agent-grpc", "runtime-env-agent")
        return [f"--{name}-port={p}" for name, p in zip(names, ports, strict=False)] + [
            f"--metrics-export-port={ports[-1]}"
        ]

    groups = []
    try:
        groups.append(_ray_start(head_args + own_ports(node_ports[:6]), env, tmp_path))
        worker_args = [f"--address=127.0.0.1:{port}", "--node-ip-address=127.0.0.1"]
        groups.append(_ray_start(worker_args + own_ports(node_ports[6:]), env, tmp_path))
        options = dict(trials=2, solver="exact", n_games=200, progress=False)
        on_ray = run_experiment(
            "table4", tmp_path / "ray-run", backend="ray", address=f"127.0.0.1:{port}", **options
        )
        local = run_experiment("table4", tmp_path / "local-run", workers=1, **options)
        assert on_ray.ran == 2
        assert [r.comparable() for r in on_ray.rows] == [r.comparable() for r in local.rows]
    finally:
        if ray.is_initialized():
            ray.shutdown()
        for pgid in reversed(groups):  # the worker node first, then the head
            _stop_group(pgid)
        shutil.rmtree(session, ignore_errors=True)
    assert not any(_group(pgid) for pgid in groups), "ray processes left behind"
