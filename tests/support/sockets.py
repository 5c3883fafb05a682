"""Addresses where no Dask scheduler answers: a local TCP server that accepts and sends garbage or nothing."""

from __future__ import annotations

import contextlib
import socket
import threading
from typing import Iterator

#: what the services a --scheduler address may reach by mistake send first: an SSH server's greeting, read by Dask
#: as a frame length, is an allocation of 2.8 EiB; 0xff bytes are a length beyond numpy's dimensions
SSH_GREETING = b"SSH-2.0-OpenSSH_9.2p1 Debian-2\r\n"
GARBAGE = b"\xff" * 64


@contextlib.contextmanager
def not_a_scheduler(greeting: bytes = b"") -> Iterator[str]:
    """``tcp://127.0.0.1:<port>`` of a server that accepts every connection, sends ``greeting`` (nothing: it stays
    silent) and then neither reads nor closes it, until the block ends."""
    server = socket.create_server(("127.0.0.1", 0))
    server.settimeout(0.1)  # so that the thread sees the end of the block
    stop = threading.Event()
    accepted: list[socket.socket] = []

    def serve() -> None:
        while not stop.is_set():
            try:
                connection, _ = server.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            accepted.append(connection)
            if greeting:
                with contextlib.suppress(OSError):
                    connection.sendall(greeting)

    thread = threading.Thread(target=serve, name="not a Dask scheduler", daemon=True)
    thread.start()
    try:
        yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    finally:
        stop.set()
        thread.join()
        for connection in accepted:
            connection.close()
        server.close()
