"""A TCP server on loopback that records what connects to it: what a sandboxed program must
not reach."""
from __future__ import annotations

import socket
import threading
from contextlib import contextmanager
from typing import Iterator


@contextmanager
def listening() -> Iterator[tuple[int, list[bytes]]]:
    """(its port, the first bytes of every connection it accepted while the block ran)."""
    heard: list[bytes] = []
    stop = threading.Event()
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen(8)
        server.settimeout(0.1)

        def listen() -> None:
            while not stop.is_set():
                try:
                    conn, _ = server.accept()
                except OSError:
                    continue
                with conn:
                    conn.settimeout(5)
                    heard.append(conn.recv(100))

        listener = threading.Thread(target=listen)
        listener.start()
        try:
            yield server.getsockname()[1], heard
        finally:
            stop.set()
            listener.join()
