"""Issue 43 item 1: the Meshcat viewer of ``drakedeburr show`` (and of every report replay)
listens on 127.0.0.1 only unless ``--host`` says otherwise, and the log names the address
actually bound.

The listening sockets are read from the kernel (``/proc/<pid>/fd`` -> socket inodes ->
``/proc/net/tcp``, ``/proc/net/tcp6``; proc(5)), not from what drakedeburr says: an address
of 0.0.0.0 or :: (every interface) or any address other than loopback fails the test.
"""

from __future__ import annotations

import os
import signal
import socket
import struct
import subprocess
import sys
import time
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent

pytestmark = pytest.mark.skipif(not Path("/proc/net/tcp").exists(), reason="needs Linux /proc")


def _address(hex_addr: str) -> tuple[str, int]:
    """A /proc/net/tcp{,6} local address (``0100007F:1B58``) -> (address text, port)."""
    host, port = hex_addr.split(":")
    raw = bytes.fromhex(host)
    if len(raw) == 4:  # one little-endian 32-bit word
        return socket.inet_ntop(socket.AF_INET, raw[::-1]), int(port, 16)
    words = struct.unpack("<4I", raw)  # four host-order 32-bit words
    return socket.inet_ntop(socket.AF_INET6, struct.pack(">4I", *words)), int(port, 16)


def listening(pid: int) -> list[tuple[str, int]]:
    """(address, port) of every TCP socket process ``pid`` holds in the LISTEN state."""
    inodes = set()
    for fd in os.listdir(f"/proc/{pid}/fd"):
        try:
            link = os.readlink(f"/proc/{pid}/fd/{fd}")
        except OSError:
            continue
        if link.startswith("socket:["):
            inodes.add(link[8:-1])
    out = []
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        if not os.path.exists(table):
            continue
        for line in Path(table).read_text().splitlines()[1:]:
            f = line.split()
            if f[3] == "0A" and f[9] in inodes:  # 0A: TCP_LISTEN
                out.append(_address(f[1]))
    return out


def _show(tmp_path: Path, *extra: str) -> tuple[subprocess.Popen, list[str]]:
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    proc = subprocess.Popen([sys.executable, "-m", "drakedeburr", "show", "h5_straight", *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            cwd=tmp_path, env=env)
    lines = []
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        line = proc.stdout.readline()  # "hub ...: open URL (Ctrl-C to quit)" once published
        if not line:
            break
        lines.append(line)
        if "Ctrl-C" in line:
            return proc, lines
    proc.kill()
    pytest.fail(f"show did not start: {lines} {proc.communicate()}")


def _stop(proc: subprocess.Popen) -> str:
    proc.send_signal(signal.SIGINT)
    try:
        _, err = proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        _, err = proc.communicate()
    return err


def test_show_listens_on_loopback_only_and_says_where(tmp_path):
    proc, out = _show(tmp_path)
    try:
        socks = listening(proc.pid)
    finally:
        err = _stop(proc)
    assert socks, "no listening socket found"
    assert all(addr == "127.0.0.1" for addr, _ in socks), socks
    port = socks[0][1]
    # the log and the printed address are the ones bound
    assert f"Meshcat listening on 127.0.0.1 port {port}" in err, err
    assert f"http://127.0.0.1:{port}" in "".join(out)


def test_show_host_option_exposes_the_viewer(tmp_path):
    """``--host '*'`` is the one way to listen on every interface (and the socket check
    above sees it: it is not a test that cannot fail)."""
    proc, _ = _show(tmp_path, "--host", "*")
    try:
        socks = listening(proc.pid)
    finally:
        err = _stop(proc)
    assert any(addr in ("0.0.0.0", "::") for addr, _ in socks), socks
    assert "Meshcat listening on * port" in err


def test_report_replay_meshcat_binds_loopback():
    """The replay Meshcat a report's HTML is drawn with (verify, plan --html) also listens on
    127.0.0.1 only."""
    from drakedeburr.viz.scene import get_meshcat

    meshcat = get_meshcat(new=True)
    try:
        socks = [s for s in listening(os.getpid()) if s[1] == meshcat.port()]
        assert socks and all(addr == "127.0.0.1" for addr, _ in socks), socks
    finally:
        del meshcat
        import gc

        gc.collect()


def test_bad_host_is_one_line(capsys):
    from drakedeburr.cli import main

    code = main(["show", "h5_straight", "--host", "a b;rm"])
    err = capsys.readouterr().err
    assert code == 2 and "--host" in err and err.count("\n") == 1, err
