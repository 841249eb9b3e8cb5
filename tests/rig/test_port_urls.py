"""The drivers run unchanged over pyserial URLs: socket:// (a serial server) and spy://."""

import socket
import threading

import pytest

from flowcurve.rig.encoder import CrossheadEncoder
from flowcurve.rig.furnace import Furnace


@pytest.fixture
def dcon_server():
    """A TCP 'serial server' with a DCON furnace module behind it (localhost only)."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(1)
    stop = threading.Event()

    def serve():
        conn, _ = server.accept()
        conn.settimeout(0.05)
        buf = b""
        with conn:
            while not stop.is_set():
                try:
                    data = conn.recv(64)
                except socket.timeout:
                    continue
                if not data:
                    break
                buf += data
                while b"\r" in buf:
                    frame, buf = buf.split(b"\r", 1)
                    reply = {b"#01": b">+0123.40\r", b"@01DO00": b"!\r", b"$01M": b"!017011\r",
                             b"$012": b"!010F0600\r"}.get(frame)
                    if reply:  # silent on anything else, like the module
                        conn.sendall(reply)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    yield f"socket://127.0.0.1:{server.getsockname()[1]}"
    stop.set()
    thread.join(timeout=2)
    server.close()


def test_furnace_over_socket_url(dcon_server):
    with Furnace(dcon_server, timeout_s=0.3) as furnace:
        assert furnace.temperature_C() == pytest.approx(123.4)
        assert furnace.module_name() == "7011"


def test_spy_url_logs_the_traffic(tmp_path):
    import flowcurve.rig.virtual.rig as virtual
    log = tmp_path / "spy.txt"
    with virtual.VirtualRig() as rig:
        with CrossheadEncoder(f"spy://{rig.ports['encoder']}?file={log}") as enc:
            assert enc.read_counts() == 0
    text = log.read_text()
    # the spy's hex dump: the command written, the reply read (in as many reads as it took)
    assert "TX   0000  23 30 32 30 0D" in text and "#020." in text
    assert "RX" in text and "00000000." in text
