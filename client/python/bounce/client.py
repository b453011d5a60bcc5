"""One blocking connection to bounced (the Python twin of client/client.cpp).

Every call sends one request and waits for its reply. While waiting, the daemon's pings are
answered, `progress` events go to the caller's callback and the events of the connection's streams
are queued for next_frame(); an `error` reply raises ServerError.
"""

from __future__ import annotations

import logging
import os
import select
import socket
import time
from collections import deque
from collections.abc import Callable, Iterable, Mapping
from typing import Any, NoReturn

from . import protocol
from .errors import BounceError, ConnectionFailed, ConnectTimeout, ProtocolError, ReplyTimeout, ServerError
from .protocol import Limits, Message

__all__ = ["Client", "parse_endpoint", "parse_endpoints", "read_token_file", "format_endpoint"]

log = logging.getLogger("bounce")

CLIENT_NAME = "bounce-python/0.1.0"
DEFAULT_PORT = 7878
# Read a body at most this much at a time: memory follows the bytes that really arrive, never a
# header's announcement alone.
_CHUNK = 1 << 20
# Before hello's limits are known, a reply may hold what a hello reply needs and no attachment.
_HELLO_LIMITS = Limits(max_json_bytes=1 << 20, max_attachment_bytes=0)
_STREAM_START = protocol.message_type("stream.start")

ProgressCallback = Callable[[dict[str, Any]], None]


def parse_endpoint(text: str, default_port: int | None = None) -> tuple[str, int]:
    """"HOST:PORT" (IPv6 as "[ADDR]:PORT") -> (host, port); ValueError naming the problem."""
    text = text.strip()
    if text.startswith("["):
        close = text.find("]")
        if close < 0:
            raise ValueError(f"expected [ADDR]:PORT, got '{text}'")
        host, rest = text[1:close], text[close + 1:]
        if rest and not rest.startswith(":"):
            raise ValueError(f"expected [ADDR]:PORT, got '{text}'")
        port_text = rest[1:] if rest else None
    else:
        host, colon, port_text = text.rpartition(":")
        if not colon:
            host, port_text = text, None
        elif ":" in host:
            raise ValueError(f"write an IPv6 address in brackets, [ADDR]:PORT, got '{text}'")
    if not host:
        raise ValueError(f"expected HOST:PORT, got '{text}'")
    if port_text is None:
        if default_port is None:
            raise ValueError(f"expected HOST:PORT, got '{text}'")
        return host, default_port
    if not port_text.isdigit() or not 0 < int(port_text) <= 65535:
        raise ValueError(f"'{port_text}' is not a port")
    return host, int(port_text)


def parse_endpoints(spec: str | Iterable[str | tuple[str, int]]) -> list[tuple[str, int]]:
    """"a:7878,b:7878" or a list of "HOST:PORT" strings or (host, port) pairs -> [(host, port)]."""
    items = spec.split(",") if isinstance(spec, str) else list(spec)
    endpoints = []
    for item in items:
        if isinstance(item, tuple):
            host, port = item
            endpoints.append((str(host), int(port)))
        elif item.strip():
            endpoints.append(parse_endpoint(item))
    if not endpoints:
        raise ValueError("no endpoint given")
    return endpoints


def format_endpoint(host: str, port: int) -> str:
    """"host:port", with an IPv6 address in brackets."""
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


def read_token_file(path: str | os.PathLike) -> str:
    """The shared token: the file's first line, trailing spaces and CR removed (as the C++ does)."""
    try:
        with open(path, encoding="utf-8") as file:
            line = file.readline()
    except OSError as error:
        raise OSError(f"cannot read token file {os.fspath(path)}: {error.strerror}") from None
    return line.rstrip("\n").rstrip("\r ")


def _numbers(value: Iterable[float], count: int, field: str) -> list[float]:
    numbers = [float(x) for x in value]
    if len(numbers) != count:
        raise ValueError(f"{field} expects {count} numbers, got {len(numbers)}")
    return numbers


def _glb_bytes(glb: bytes | bytearray | memoryview | str | os.PathLike) -> bytes:
    """The bytes of an upload: given as bytes, or as the path of a file to read."""
    if isinstance(glb, (bytes, bytearray, memoryview)):
        return bytes(glb)
    with open(glb, "rb") as file:
        return file.read()


def _put(body: dict[str, Any], field: str, value: Any) -> None:
    if value is not None:
        body[field] = value


def _camera_field(camera: str | Mapping[str, Any] | None) -> str | dict[str, Any] | None:
    """A request's `camera`: the name of a camera of the scene, or an inline view {"position",
    "look_at" or "orientation", "fov_deg"} whose vectors are checked here. A None inside a view is
    kept: in a stream.update it removes that field."""
    if camera is None or isinstance(camera, str):
        return camera
    view = dict(camera)
    for field, count in (("position", 3), ("look_at", 3), ("orientation", 4)):
        if view.get(field) is not None:
            view[field] = _numbers(view[field], count, f"camera.{field}")
    if view.get("fov_deg") is not None:
        view["fov_deg"] = float(view["fov_deg"])
    return view


def render_body(scene: str, *, method: str | None = None, preset: str | None = None,
                knobs: Mapping[str, float] | None = None, width: int | None = None,
                height: int | None = None, format: str | None = "png", exposure: float | None = None,
                tone: str | None = None, camera: str | Mapping[str, Any] | None = None,
                jpeg_quality: int | None = None,
                exr_half: bool | None = None, min_scene_version: int | None = None,
                timeout_ms: int | None = None, budget: Mapping[str, float] | None = None) -> dict[str, Any]:
    """The JSON body of a `render` (or, without the image fields, a `bake`); None fields are left
    out, so the daemon's defaults apply. `budget` ({"max_ms": T} and/or {"max_error": E}) lets the
    daemon plan the preset and knobs, and the method when it is "auto" (the default with a budget)."""
    body: dict[str, Any] = {"scene": scene}
    _put(body, "method", method)
    _put(body, "preset", preset)
    if knobs:
        body["knobs"] = {str(name): float(value) for name, value in knobs.items()}
    _put(body, "width", None if width is None else int(width))
    _put(body, "height", None if height is None else int(height))
    _put(body, "format", format)
    _put(body, "exposure", None if exposure is None else float(exposure))
    _put(body, "tone", tone)
    _put(body, "camera", _camera_field(camera))
    _put(body, "jpeg_quality", None if jpeg_quality is None else int(jpeg_quality))
    _put(body, "exr_half", None if exr_half is None else bool(exr_half))
    _put(body, "min_scene_version", None if min_scene_version is None else int(min_scene_version))
    _put(body, "timeout_ms", None if timeout_ms is None else int(timeout_ms))
    if budget is not None:
        body["budget"] = {str(name): float(value) for name, value in budget.items()}
        body.setdefault("method", "auto")
    return body


def stream_fields(*, refine: bool | None = None, reference_spp: int | None = None,
                  interactive_scale: float | None = None,
                  interactive_quality: int | None = None) -> dict[str, Any]:
    """The fields of a stream.start that a `render` lacks: its ladder's; None fields are left out."""
    body: dict[str, Any] = {}
    _put(body, "refine", None if refine is None else bool(refine))
    _put(body, "reference_spp", None if reference_spp is None else int(reference_spp))
    _put(body, "interactive_scale", None if interactive_scale is None else float(interactive_scale))
    _put(body, "interactive_quality", None if interactive_quality is None else int(interactive_quality))
    return body


def transform_body(scene: str, object: str, translation=None, rotation_deg=None, scale=None,
                   matrix=None) -> dict[str, Any]:
    body: dict[str, Any] = {"scene": scene, "object": object}
    _put(body, "translation", None if translation is None else _numbers(translation, 3, "translation"))
    _put(body, "rotation_deg", None if rotation_deg is None else _numbers(rotation_deg, 3, "rotation_deg"))
    _put(body, "scale", None if scale is None else float(scale))
    _put(body, "matrix", None if matrix is None else _numbers(matrix, 16, "matrix"))
    return body


def light_body(scene: str, light: str, type=None, position=None, direction=None, color=None,
               intensity=None, inner_cone_deg=None, outer_cone_deg=None) -> dict[str, Any]:
    body: dict[str, Any] = {"scene": scene, "light": light}
    _put(body, "type", type)
    _put(body, "position", None if position is None else _numbers(position, 3, "position"))
    _put(body, "direction", None if direction is None else _numbers(direction, 3, "direction"))
    _put(body, "color", None if color is None else _numbers(color, 3, "color"))
    _put(body, "intensity", None if intensity is None else float(intensity))
    _put(body, "inner_cone_deg", None if inner_cone_deg is None else float(inner_cone_deg))
    _put(body, "outer_cone_deg", None if outer_cone_deg is None else float(outer_cone_deg))
    return body


def camera_body(scene: str, position=None, look_at=None, orientation=None, fov_deg=None,
                name=None) -> dict[str, Any]:
    body: dict[str, Any] = {"scene": scene}
    _put(body, "camera", name)
    _put(body, "position", None if position is None else _numbers(position, 3, "position"))
    _put(body, "look_at", None if look_at is None else _numbers(look_at, 3, "look_at"))
    _put(body, "orientation", None if orientation is None else _numbers(orientation, 4, "orientation"))
    _put(body, "fov_deg", None if fov_deg is None else float(fov_deg))
    return body


def load_body(name: str, *, path: str | None = None, builtin: str | None = None,
              dynamic: Iterable[str] | None = None) -> dict[str, Any]:
    body: dict[str, Any] = {"name": name}
    _put(body, "path", None if path is None else os.fspath(path))
    _put(body, "builtin", builtin)
    _put(body, "dynamic", None if dynamic is None else [str(o) for o in dynamic])
    return body


class Client:
    """A connection to one bounced.

    Client(host, port=None, token=None, timeout=60.0) connects and says hello at once; `host` may
    also be "HOST:PORT" with `port` left out. `timeout` bounds each wait for the daemon's next
    bytes (the daemon pings a client that waits on a long request, so a slow render does not trip
    it); `connect_timeout` bounds establishing the connection.

    The connection is re-established on the next request after the daemon closed it (a daemon
    drops connections idle for three heartbeats). Not thread-safe: use one Client per thread.
    """

    def __init__(self, host: str = "127.0.0.1", port: int | None = None, token: str | None = None,
                 timeout: float | None = 60.0, *, connect_timeout: float | None = 10.0,
                 max_reply_json_bytes: int | None = None, max_reply_attachment_bytes: int | None = None):
        if port is None:
            host, port = parse_endpoint(host, DEFAULT_PORT)
        self.host = host
        self.port = int(port)
        self.token = token
        self.timeout = timeout
        self.connect_timeout = connect_timeout
        self._reply_limit_overrides = (max_reply_json_bytes, max_reply_attachment_bytes)
        self._limits = _HELLO_LIMITS
        self._sock: socket.socket | None = None
        self._closed = False
        self._next_id = 1  # 0 is what the daemon uses for its own pings and id-less errors
        self._streams: set[int] = set()  # ids of the streams running on this connection
        # Their frame and error events that came while a request waited, for next_frame().
        self._stream_events: deque[Message] = deque()
        self.info: dict[str, Any] = {}
        self._connect()

    # -- connection ------------------------------------------------------------------------------

    @property
    def endpoint(self) -> str:
        return format_endpoint(self.host, self.port)

    @property
    def connected(self) -> bool:
        return self._sock is not None

    @property
    def limits(self) -> Limits:
        """What a reply may hold: hello's announced limits unless overridden."""
        return self._limits

    def _connect(self) -> None:
        try:
            sock = socket.create_connection((self.host, self.port), timeout=self.connect_timeout)
        except socket.timeout:
            raise ConnectTimeout(f"cannot connect to {self.endpoint}: timed out", self.endpoint) from None
        except OSError as error:
            reason = error.strerror or str(error)
            raise ConnectionFailed(f"cannot connect to {self.endpoint}: {reason}", self.endpoint) from None
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        sock.settimeout(self.timeout)
        self._sock = sock
        self._limits = _HELLO_LIMITS
        body: dict[str, Any] = {"client": CLIENT_NAME, "protocol": protocol.PROTOCOL_VERSION}
        if self.token is not None:
            body["token"] = self.token
        try:
            self.info = self._exchange(protocol.HELLO, body).body
        except BaseException:
            self._drop()
            raise
        self._limits = self._announced_limits(self.info)

    def _announced_limits(self, info: dict[str, Any]) -> Limits:
        limits = info.get("limits") if isinstance(info.get("limits"), dict) else {}

        def announced(field: str, fallback: int) -> int:
            value = limits.get(field)
            return value if isinstance(value, int) and 0 <= value <= protocol.MAX_LENGTH else fallback

        json_override, attachment_override = self._reply_limit_overrides
        default = Limits()
        return Limits(
            max_json_bytes=json_override if json_override is not None
            else announced("max_json_bytes", default.max_json_bytes),
            max_attachment_bytes=attachment_override if attachment_override is not None
            else announced("max_attachment_bytes", default.max_attachment_bytes))

    def _drop(self) -> None:
        """Closes the socket; the next request connects again. Its streams end with it (events
        already queued are still delivered)."""
        self._streams.clear()
        if self._sock is not None:
            try:
                self._sock.close()
            finally:
                self._sock = None

    def close(self) -> None:
        """Closes the connection for good; later requests raise ConnectionFailed."""
        self._closed = True
        self._drop()

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "connected" if self.connected else "closed" if self._closed else "disconnected"
        return f"<bounce.Client {self.endpoint} {state}>"

    # -- frames ----------------------------------------------------------------------------------

    def _fail(self, error: Exception) -> NoReturn:
        """Drops the connection (its framing can no longer be trusted) and raises `error`."""
        self._drop()
        raise error

    def _send(self, data: bytes) -> None:
        assert self._sock is not None
        try:
            self._sock.sendall(data)
        except socket.timeout:
            self._fail(ReplyTimeout(f"{self.endpoint}: sending timed out", self.endpoint))
        except OSError as error:
            self._fail(ConnectionFailed(f"{self.endpoint}: send failed: {error.strerror or error}",
                                        self.endpoint))

    def _read_exact(self, count: int, what: str) -> bytes:
        assert self._sock is not None
        data = bytearray()
        while len(data) < count:
            try:
                chunk = self._sock.recv(min(count - len(data), _CHUNK))
            except socket.timeout:
                self._fail(ReplyTimeout(f"{self.endpoint}: no reply within {self.timeout} s", self.endpoint))
            except OSError as error:
                self._fail(ConnectionFailed(f"{self.endpoint}: connection lost: {error.strerror or error}",
                                            self.endpoint))
            if not chunk:
                where = "mid-frame" if data or what != "header" else "by the daemon"
                self._fail(ConnectionFailed(f"{self.endpoint}: connection closed {where}", self.endpoint))
            data += chunk
        return bytes(data)

    def _read_frame(self) -> Message:
        """The next frame, whatever it is; the header is checked before the body is read."""
        try:
            header = protocol.decode_header(self._read_exact(protocol.HEADER_SIZE, "header"), self._limits)
            body = protocol.decode_body(self._read_exact(header.json_length, "body"), header.request_id)
        except protocol.FrameError as error:
            self._fail(ProtocolError(f"{self.endpoint}: {error}"))
        attachment = self._read_exact(header.attachment_length, "attachment")
        if header.type == protocol.PING:
            self._send(protocol.encode(protocol.PONG, header.request_id))
        return Message(header.type, header.request_id, body, attachment)

    def _read_message(self) -> Message:
        """The next frame that is not a ping (pings are answered on the way)."""
        while True:
            message = self._read_frame()
            if message.type != protocol.PING:
                return message

    def _keep_stream_event(self, message: Message) -> bool:
        """Queues a `frame` or `error` event of a running stream for next_frame(); False for
        anything else."""
        if message.request_id not in self._streams or message.type not in (protocol.FRAME, protocol.ERROR):
            return False
        if message.type == protocol.ERROR:
            self._streams.discard(message.request_id)  # an error ends its stream: nothing follows
        self._stream_events.append(message)
        return True

    def _forget_stream(self, stream_id: int) -> None:
        self._streams.discard(stream_id)
        self._stream_events = deque(event for event in self._stream_events if event.request_id != stream_id)

    def _discard_stale(self) -> None:
        """Before a request: answers pings that arrived while idle, queues stream events, drops
        late replies to abandoned requests, and reconnects when the daemon closed the idle
        connection."""
        while self._sock is not None:
            try:
                readable, _, _ = select.select([self._sock], [], [], 0)
            except (OSError, ValueError):
                readable = [True]
            if not readable:
                return
            try:
                stale = self._read_frame()  # one frame only: after a ping there may be nothing more
            except ConnectionFailed:
                break  # closed while idle: not a failure of the next request
            if stale.type == protocol.ERROR and stale.request_id == 0:
                # An id-less error comes before the daemon closes the connection.
                self._drop()
            else:
                self._keep_stream_event(stale)
        if not self._closed:
            self._connect()

    def _exchange(self, kind: int, body: dict[str, Any] | None, attachment: bytes = b"",
                  on_progress: ProgressCallback | None = None) -> Message:
        request_id = self._next_id
        self._next_id += 1
        starts_stream = kind == _STREAM_START
        if starts_stream:
            self._streams.add(request_id)  # its events carry its id, and may come before its `ok`
        self._send(protocol.encode(kind, request_id, body, attachment))
        while True:
            reply = self._read_message()
            if reply.request_id != request_id:
                if reply.type == protocol.ERROR and reply.request_id == 0:
                    # The daemon could not tell which request broke the frame; it closes next.
                    self._drop()
                    raise ServerError.from_body(reply.body, protocol.message_name(kind))
                self._keep_stream_event(reply)  # else a late reply to an earlier, abandoned request
                continue
            if reply.type == protocol.PROGRESS:
                if on_progress is not None:
                    on_progress(reply.body)
                continue
            if starts_stream and reply.type == protocol.FRAME:
                self._keep_stream_event(reply)
                continue
            if reply.type == protocol.ERROR:
                self._streams.discard(request_id)
                raise ServerError.from_body(reply.body, protocol.message_name(kind))
            return reply

    # -- requests --------------------------------------------------------------------------------

    def request(self, kind: int | str, body: Mapping[str, Any] | None = None,
                attachment: bytes | bytearray | memoryview = b"",
                on_progress: ProgressCallback | None = None) -> Message:
        """Sends one request and returns its reply (`ok`, `frame`, `hello` or `pong`).

        `kind` is a wire name ("scene.load") or a type number. Raises ServerError for an `error`
        reply, ConnectionFailed when the daemon cannot be reached or the connection breaks, and
        ProtocolError for a reply that breaks the format or the limits. `progress` events of the
        request go to `on_progress(body)` when given.
        """
        if self._closed:
            raise ConnectionFailed(f"{self.endpoint}: the client is closed", self.endpoint)
        kind = protocol.message_type(kind)
        announced = self.info.get("limits", {}).get("max_attachment_bytes")
        if isinstance(announced, int) and len(attachment) > announced:
            # The daemon would refuse the frame and close the connection: say so before sending.
            raise ValueError(f"attachment of {len(attachment)} bytes exceeds the daemon's limit of "
                             f"{announced} (max_attachment_bytes)")
        if self._sock is None:
            self._connect()
        else:
            self._discard_stale()
        return self._exchange(kind, dict(body or {}), attachment, on_progress)

    def hello(self) -> dict[str, Any]:
        """Says hello again and returns the daemon's answer (server, renderer, limits, methods)."""
        body: dict[str, Any] = {"client": CLIENT_NAME, "protocol": protocol.PROTOCOL_VERSION}
        if self.token is not None:
            body["token"] = self.token
        self.info = self.request("hello", body).body
        self._limits = self._announced_limits(self.info)
        return self.info

    def ping(self) -> None:
        """A round trip; raises when the daemon does not answer."""
        self.request("ping")

    def load(self, path: str | os.PathLike, name: str, dynamic: Iterable[str] | None = None) -> dict[str, Any]:
        """Loads a .gltf/.glb at `path`, resolved inside the daemon's --scene-root, as `name`.

        `dynamic` names objects that will move (cssm bakes them apart). Returns the reply:
        {"scene", "scene_version", "warnings", ...}.
        """
        return self.request("scene.load", load_body(name, path=path, dynamic=dynamic)).body

    def upload(self, glb: bytes | bytearray | memoryview | str | os.PathLike, name: str,
               dynamic: Iterable[str] | None = None) -> dict[str, Any]:
        """Sends a .glb (its bytes, or the path of a local file) and loads it as `name`."""
        return self.request("scene.load", load_body(name, dynamic=dynamic), _glb_bytes(glb)).body

    def load_builtin(self, builtin: str, name: str, dynamic: Iterable[str] | None = None) -> dict[str, Any]:
        """Loads a built-in scene ("cornell", "cornell_blob") as `name`."""
        return self.request("scene.load", load_body(name, builtin=builtin, dynamic=dynamic)).body

    def unload(self, name: str) -> dict[str, Any]:
        return self.request("scene.unload", {"name": name}).body

    def list(self) -> list[dict[str, Any]]:
        """The daemon's scenes: [{"name", "objects", "triangles", "resident_bytes", "scene_version"}]."""
        return self.request("scene.list").body.get("scenes", [])

    def describe(self, scene: str, analyze: bool = False) -> dict[str, Any]:
        """Objects (bounds, transform), lights, cameras, materials and resident structures; with
        `analyze`, the scene analysis too (light by bounce, thin walls, indirect visibility)."""
        body: dict[str, Any] = {"name": scene}
        if analyze:
            body["analyze"] = True
        return self.request("scene.describe", body).body

    def move(self, scene: str, object: str, translation: Iterable[float] | None = None,
             rotation_deg: Iterable[float] | None = None, scale: float | None = None,
             matrix: Iterable[float] | None = None) -> dict[str, Any]:
        """Sets an object's transform: TRS about its origin, relative to how it was loaded
        (rotation applied X, then Y, then Z), or a column-major 4x4 `matrix`.
        Returns {"scene_version": N}."""
        return self.request("object.set_transform",
                            transform_body(scene, object, translation, rotation_deg, scale, matrix)).body

    def light(self, scene: str, light: str, type: str | None = None,
              position: Iterable[float] | None = None, direction: Iterable[float] | None = None,
              color: Iterable[float] | None = None, intensity: float | None = None,
              inner_cone_deg: float | None = None, outer_cone_deg: float | None = None) -> dict[str, Any]:
        """Creates or updates a light; fields left None keep their value. Returns {"scene_version": N}."""
        return self.request("light.set", light_body(scene, light, type, position, direction, color, intensity,
                                                    inner_cone_deg, outer_cone_deg)).body

    def remove_light(self, scene: str, light: str) -> dict[str, Any]:
        return self.request("light.remove", {"scene": scene, "light": light}).body

    def camera(self, scene: str, position: Iterable[float] | None = None,
               look_at: Iterable[float] | None = None, orientation: Iterable[float] | None = None,
               fov_deg: float | None = None, name: str | None = None) -> dict[str, Any]:
        """Sets the scene's current view (camera.set): `position` with `look_at` or `orientation`
        (quaternion xyzw) and `fov_deg`, or `name` to use a camera of the scene. This changes the
        view every client of the daemon renders by default. Returns {"scene_version": N}."""
        return self.request("camera.set", camera_body(scene, position, look_at, orientation, fov_deg, name)).body

    def render(self, scene: str, method: str | None = None, preset: str | None = None,
               knobs: Mapping[str, float] | None = None, width: int | None = None,
               height: int | None = None, format: str = "png", exposure: float | None = None,
               tone: str | None = None, camera: str | Mapping[str, Any] | None = None, *,
               jpeg_quality: int | None = None,
               exr_half: bool | None = None, min_scene_version: int | None = None,
               timeout_ms: int | None = None, budget: Mapping[str, float] | None = None,
               on_progress: ProgressCallback | None = None) -> tuple[bytes, dict[str, Any]]:
        """Renders one frame; returns (encoded image, stats). Fields left None take the daemon's
        defaults (method direct, preset medium, 512x512, exposure 0, tone aces). `camera` names a
        camera of the scene or is an inline view for this frame only, {"position", "look_at" or
        "orientation", "fov_deg"}. With `budget` the daemon plans the frame and the stats carry
        `plan` (docs/protocol.md, "Budgets"). `on_progress` receives the progress of a bake the
        frame needs first."""
        body = render_body(scene, method=method, preset=preset, knobs=knobs, width=width, height=height,
                           format=format, exposure=exposure, tone=tone, camera=camera,
                           jpeg_quality=jpeg_quality, exr_half=exr_half,
                           min_scene_version=min_scene_version, timeout_ms=timeout_ms, budget=budget)
        reply = self.request("render", body, on_progress=on_progress)
        return reply.attachment, reply.body

    def bake(self, scene: str, method: str = "cssm", preset: str | None = None,
             knobs: Mapping[str, float] | None = None, *, timeout_ms: int | None = None,
             on_progress: ProgressCallback | None = None) -> dict[str, Any]:
        """Builds a method's precomputed structures; `on_progress({"fraction", "stage"})` is called
        for each progress event. Returns {"bake_ms", "resident", "method_stats", ...}."""
        body = render_body(scene, method=method, preset=preset, knobs=knobs, format=None, timeout_ms=timeout_ms)
        return self.request("bake", body, on_progress=on_progress).body

    def stats(self) -> dict[str, Any]:
        """Frames rendered, errors by code, queue depth, resident bytes, GPU memory budget."""
        return self.request("stats").body

    # -- streams ---------------------------------------------------------------------------------

    def stream_start(self, scene: str, *, method: str | None = None, preset: str | None = None,
                     knobs: Mapping[str, float] | None = None, width: int | None = None,
                     height: int | None = None, format: str | None = None, exposure: float | None = None,
                     tone: str | None = None, camera: str | Mapping[str, Any] | None = None,
                     jpeg_quality: int | None = None, refine: bool | None = None, reference_spp: int | None = None,
                     interactive_scale: float | None = None, interactive_quality: int | None = None,
                     budget: Mapping[str, float] | None = None) -> int:
        """Starts a stream: a view the daemon renders again whenever the scene or the view changes,
        and refines while neither does (docs/protocol.md, "stream.start, stream.update,
        stream.stop"). Takes render's fields, `format` "jpeg" (the daemon's default), "png" or
        "webp", and the ladder's. With `budget` the interactive and still frames are planned for
        it. Returns the stream's id; next_frame() reads its frames."""
        body = render_body(scene, method=method, preset=preset, knobs=knobs, width=width, height=height,
                           format=format, exposure=exposure, tone=tone, camera=camera,
                           jpeg_quality=jpeg_quality, budget=budget)
        body.update(stream_fields(refine=refine, reference_spp=reference_spp,
                                  interactive_scale=interactive_scale, interactive_quality=interactive_quality))
        reply = self.request("stream.start", body)
        return int(reply.body.get("stream", reply.request_id))

    def stream_update(self, stream_id: int, **fields: Any) -> int:
        """Changes a stream's fields. `fields` is a JSON merge patch over them (RFC 7386): a value
        replaces the field's, a dict (an inline `camera`, `knobs`) is merged into it, and None
        removes the field. Returns the view version from which frames show the change."""
        body = dict(fields)
        if "camera" in body:
            body["camera"] = _camera_field(body["camera"])
        body["stream"] = int(stream_id)
        return int(self.request("stream.update", body).body["view_version"])

    def stream_stop(self, stream_id: int) -> dict[str, Any]:
        """Stops a stream; its frames still queued are dropped. Returns {"stream", "frames",
        "dropped_stale"}."""
        try:
            return self.request("stream.stop", {"stream": int(stream_id)}).body
        finally:
            self._forget_stream(int(stream_id))

    def next_frame(self, timeout: float | None = None) -> tuple[bytes, dict[str, Any]] | None:
        """The next `frame` event of this connection's streams: (encoded image, body), where
        body["stream"] gives its stream's id, rung, stage and whether it is `final`. Waits at most
        `timeout` seconds (None: until one comes; a still view sends none) and returns None when
        none came. Raises ServerError for a stream's `error` event: that stream has ended."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while not self._stream_events:
            if not self._streams:
                if self._sock is None:
                    raise ConnectionFailed(f"{self.endpoint}: the connection closed, and its streams with it",
                                           self.endpoint)
                raise BounceError("no stream is running on this connection: call stream_start() first")
            remaining = None if deadline is None else max(0.0, deadline - time.monotonic())
            # A still view is silent for as long as nothing changes: wait here, not in a read that
            # the client's `timeout` would end.
            try:
                readable, _, _ = select.select([self._sock], [], [], remaining)
            except (OSError, ValueError):
                readable = [True]  # let the read say what broke
            if not readable:
                return None
            message = self._read_frame()
            if message.type == protocol.ERROR and message.request_id == 0:
                self._drop()
                raise ServerError.from_body(message.body, "stream.start")
            self._keep_stream_event(message)  # else a ping, or a late reply to an abandoned request
        event = self._stream_events.popleft()
        if event.type == protocol.ERROR:
            raise ServerError.from_body(event.body, "stream.start")
        return event.attachment, event.body
