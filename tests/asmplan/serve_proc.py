"""``asmplan serve`` as a process of its own (for kills, full disks, busy ports)."""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import threading
import time

from tests.asmplan.server import free_port

CLI = [sys.executable, "-c", "import sys; from asmplan.cli import main; main(sys.argv[1:])"]


def serve_args(*args, port: int | None = None) -> list[str]:
    return [*CLI, "serve", *map(str, args), "--port", str(port or free_port())]


@contextlib.contextmanager
def serving(args: list[str], *, prefix: list[str] = (), env: dict | None = None, timeout=60):
    """Start ``prefix + args`` (an ``asmplan serve`` command line); yield ``(url, process,
    lines)`` once it says where it serves (``lines``: its stderr so far, growing); kill it
    on exit."""
    port = args[args.index("--port") + 1]
    proc = subprocess.Popen(
        [*prefix, *args],
        stderr=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        text=True,
        env={**os.environ, **(env or {})},
    )
    lines: list[str] = []
    ready = threading.Event()

    def read():
        for line in proc.stderr:
            lines.append(line.rstrip("\n"))
            if line.startswith("serving "):
                ready.set()
        ready.set()

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    try:
        if not ready.wait(timeout) or proc.poll() is not None:
            time.sleep(0.2)
            raise RuntimeError(f"asmplan serve did not start: {lines}")
        yield f"http://127.0.0.1:{port}", proc, lines
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.wait(timeout=20)
        reader.join(timeout=5)
