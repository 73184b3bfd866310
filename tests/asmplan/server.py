"""A real uvicorn server on 127.0.0.1 at a free port, in a thread (for the HTTP tests)."""

from __future__ import annotations

import contextlib
import socket
import threading
import time

import uvicorn

from asmplan.serve import create_app


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@contextlib.contextmanager
def running(plans: list[dict], state_dir, **kwargs):
    """Serve ``plans`` with sessions in ``state_dir``; yield the base URL; stop on exit."""
    port = free_port()
    app = create_app(plans, state_dir, **kwargs)
    server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port, log_level="error"))
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + 20
    while not server.started:
        if time.monotonic() > deadline or not thread.is_alive():
            raise RuntimeError("the test server did not start")
        time.sleep(0.02)
    try:
        yield f"http://127.0.0.1:{port}"
    finally:
        server.should_exit = True
        thread.join(timeout=10)
