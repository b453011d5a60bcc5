"""Shared by the tests: a real bounced on an ephemeral loopback port, a scripted fake daemon for
the framing tests, small scenes, and readers for the image headers the tests check."""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path

HERE = Path(__file__).resolve().parent
PYTHON_ROOT = HERE.parent                     # client/python: what PYTHONPATH names
REPO = PYTHON_ROOT.parent.parent
GLTF_DATA = REPO / "tests" / "data" / "gltf"

sys.path.insert(0, str(PYTHON_ROOT))  # the tests run from any directory

from bounce import protocol  # noqa: E402


def bounced_path() -> str:
    """The daemon under test, from $BOUNCED; a clear failure when it is not set."""
    path = os.environ.get("BOUNCED")
    if not path:
        raise RuntimeError("set BOUNCED to the bounced binary to run the integration tests "
                           "(e.g. BOUNCED=build/server/bounced)")
    if not os.access(path, os.X_OK):
        raise RuntimeError(f"BOUNCED={path} is not an executable file")
    return path


def cli_env(**extra: str) -> dict[str, str]:
    """The environment for `python3 -m bounce`: this checkout's package, no inherited defaults."""
    env = {k: v for k, v in os.environ.items() if k not in ("BOUNCE_CONNECT", "BOUNCE_TOKEN_FILE")}
    env["PYTHONPATH"] = str(PYTHON_ROOT)
    env.update(extra)
    return env


def run_cli(*args: str, env: dict[str, str] | None = None, timeout: float = 60) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "bounce", *args], capture_output=True,
                          env=env or cli_env(), timeout=timeout)


class Daemon:
    """bounced with --listen 127.0.0.1:0 and a port file, as tests/integration/daemon_process.cpp
    runs it; the port file holds the protocol port on its first line."""

    def __init__(self, *extra: str, scene_root: Path | None = None, startup_timeout: float = 60.0):
        self.directory = Path(tempfile.mkdtemp(prefix="bounced-pytest-"))
        port_file = self.directory / "port"
        args = [bounced_path(), "--listen", "127.0.0.1:0", "--port-file", str(port_file), "--log-level", "warn"]
        if scene_root is not None:
            args += ["--scene-root", str(scene_root)]
        args += list(extra)
        self._log = open(self.directory / "log.txt", "wb")
        self.process = subprocess.Popen(args, stdout=self._log, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + startup_timeout
        while True:
            if self.process.poll() is not None:
                raise RuntimeError(f"bounced exited during startup with status {self.process.returncode}: "
                                   f"{self.log()}")
            try:
                self.port = int(port_file.read_text().split()[0])
                break
            except (OSError, IndexError, ValueError):
                pass
            if time.monotonic() > deadline:
                self.stop()
                raise RuntimeError(f"bounced did not listen within {startup_timeout} s")
            time.sleep(0.02)
        self.host = "127.0.0.1"

    @property
    def key(self) -> str:
        """The daemon's rendezvous key, "127.0.0.1:PORT"."""
        return f"{self.host}:{self.port}"

    def log(self) -> str:
        return (self.directory / "log.txt").read_text(errors="replace")[-4000:]

    def kill(self) -> None:
        """SIGKILL: the daemon gets no chance to clean up, as when a machine goes away."""
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait()

    def stop(self) -> int:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(20)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self._log.close()
        shutil.rmtree(self.directory, ignore_errors=True)
        return self.process.returncode

    def __enter__(self) -> "Daemon":
        return self

    def __exit__(self, *exc_info) -> None:
        self.stop()


def free_port() -> int:
    """A loopback port nothing listens on (bound, then released)."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def scene_root_with_gltf() -> Path:
    """A temporary --scene-root holding textured.gltf (one object, "card"; images as data: URIs)."""
    root = Path(tempfile.mkdtemp(prefix="bounce-scenes-"))
    shutil.copy(GLTF_DATA / "textured.gltf", root / "textured.gltf")
    return root


def make_glb(object_name: str = "box", light_name: str = "lamp") -> bytes:
    """A small binary glTF: a unit cube named `object_name` lit by a point light `light_name`.

    tests/data holds only hostile .glb files (external URIs, which an upload may not use), so the
    upload tests build their own.
    """
    corners = [(x, y, z) for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)]
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    indices = [i for a, b, c, d in faces for i in (a, b, c, a, c, d)]
    positions = struct.pack(f"<{3 * len(corners)}f", *(v for corner in corners for v in corner))
    index_bytes = struct.pack(f"<{len(indices)}H", *indices)
    index_bytes += b"\x00" * (-len(index_bytes) % 4)
    binary = positions + index_bytes
    document = {
        "asset": {"version": "2.0", "generator": "bounce python tests"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "name": light_name, "color": [1.0, 1.0, 1.0], "intensity": 20.0}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"name": object_name, "mesh": 0},
                  {"name": f"{light_name}_node", "translation": [0.5, 3.0, 2.0],
                   "extensions": {"KHR_lights_punctual": {"light": 0}}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0],
                                                "metallicFactor": 0.0, "roughnessFactor": 0.8}}],
        "buffers": [{"byteLength": len(binary)}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(positions), "target": 34962},
                        {"buffer": 0, "byteOffset": len(positions), "byteLength": 2 * len(indices),
                         "target": 34963}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": len(corners), "type": "VEC3",
                       "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0]},
                      {"bufferView": 1, "componentType": 5123, "count": len(indices), "type": "SCALAR"}],
    }
    text = json.dumps(document, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    chunks = struct.pack("<I4s", len(text), b"JSON") + text + struct.pack("<I4s", len(binary), b"BIN\x00") + binary
    return struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks


# -- image headers ---------------------------------------------------------------------------------

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def png_size(data: bytes) -> tuple[int, int]:
    """(width, height) from a PNG's IHDR; AssertionError when it is not a PNG."""
    assert data[:8] == PNG_SIGNATURE, f"not a PNG: {data[:8]!r}"
    length, kind = struct.unpack(">I4s", data[8:16])
    assert kind == b"IHDR" and length == 13, f"first chunk is {kind!r}, not IHDR"
    return struct.unpack(">II", data[16:24])


def exr_size(data: bytes) -> tuple[int, int]:
    """(width, height) from an OpenEXR header's dataWindow; AssertionError when it is not EXR."""
    assert data[:4] == b"\x76\x2f\x31\x01", f"not an OpenEXR file: {data[:4]!r}"
    at = 8  # magic, then the version and flags
    while data[at] != 0:
        name_end = data.index(b"\x00", at)
        type_end = data.index(b"\x00", name_end + 1)
        name = data[at:name_end]
        (size,) = struct.unpack("<i", data[type_end + 1:type_end + 5])
        value = data[type_end + 5:type_end + 5 + size]
        if name == b"dataWindow":
            x_min, y_min, x_max, y_max = struct.unpack("<4i", value)
            return x_max - x_min + 1, y_max - y_min + 1
        at = type_end + 5 + size
    raise AssertionError("EXR header has no dataWindow")


# -- a scripted fake daemon ------------------------------------------------------------------------

class FakeDaemon:
    """A one-connection TCP server on 127.0.0.1 that runs `script(conn)` in a thread, for testing
    how the client reads frames without a real daemon."""

    def __init__(self, script: Callable[["FakeConnection"], None]):
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port = self.listener.getsockname()[1]
        self.error: BaseException | None = None
        self.thread = threading.Thread(target=self._serve, args=(script,), daemon=True)
        self.thread.start()

    def _serve(self, script: Callable[["FakeConnection"], None]) -> None:
        try:
            sock, _ = self.listener.accept()
            with sock:
                sock.settimeout(10)
                script(FakeConnection(sock))
        except BaseException as error:  # reported by close()
            self.error = error

    def close(self) -> None:
        self.thread.join(10)
        self.listener.close()
        if self.error is not None:
            raise self.error

    def __enter__(self) -> "FakeDaemon":
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()


class FakeConnection:
    def __init__(self, sock: socket.socket):
        self.sock = sock

    def read(self) -> protocol.Message:
        header = protocol.decode_header(self._exact(protocol.HEADER_SIZE), protocol.Limits())
        body = protocol.decode_body(self._exact(header.json_length))
        return protocol.Message(header.type, header.request_id, body, self._exact(header.attachment_length))

    def _exact(self, count: int) -> bytes:
        data = b""
        while len(data) < count:
            chunk = self.sock.recv(count - len(data))
            if not chunk:
                raise EOFError("client closed the connection")
            data += chunk
        return data

    def send(self, kind: int | str, request_id: int, body: dict | None = None, attachment: bytes = b"") -> None:
        self.sock.sendall(protocol.encode(protocol.message_type(kind), request_id, body, attachment))

    def send_raw(self, data: bytes) -> None:
        self.sock.sendall(data)

    def greet(self, limits: dict | None = None) -> None:
        """Answers the client's hello as bounced would."""
        hello = self.read()
        assert hello.name == "hello", hello
        self.send("hello", hello.request_id, {
            "server": "fake/0", "protocol": 1, "renderer": "none",
            "limits": limits or {"max_json_bytes": 1 << 20, "max_attachment_bytes": 1 << 20,
                                 "max_in_flight": 8, "max_pixels": 1 << 24},
            "heartbeat_ms": 15000, "methods": ["direct"]})
