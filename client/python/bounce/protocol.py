"""The Bounce wire format, protocol version 1 (docs/protocol.md, "Frames").

A frame is a fixed 24-byte little-endian header, a UTF-8 JSON body (length 0 means `{}`) and an
optional binary attachment. This module only turns messages into bytes and back; it knows
nothing about sockets.
"""

from __future__ import annotations

import dataclasses
import json
import struct
from typing import Any

MAGIC = b"BNCE"
PROTOCOL_VERSION = 1
HEADER_SIZE = 24
# magic, version, type, request id, JSON length, attachment length.
_HEADER = struct.Struct("<4sHHQII")
assert _HEADER.size == HEADER_SIZE

MAX_LENGTH = 0xFFFFFFFF  # both lengths are 32-bit fields

# Message types (docs/protocol.md, "Message types"): wire name -> number.
MESSAGE_TYPES: dict[str, int] = {
    "hello": 1,
    "ok": 2,
    "error": 3,
    "frame": 4,
    "progress": 5,
    "ping": 6,
    "pong": 7,
    "cancel": 8,
    "scene.load": 16,
    "scene.unload": 17,
    "scene.list": 18,
    "scene.describe": 19,
    "object.set_transform": 20,
    "light.set": 21,
    "light.remove": 22,
    "camera.set": 23,
    "render": 24,
    "stream.start": 25,
    "stream.stop": 26,
    "bake": 27,
    "stats": 28,
    "stream.update": 29,
}
MESSAGE_NAMES: dict[int, str] = {number: name for name, number in MESSAGE_TYPES.items()}

HELLO, OK, ERROR, FRAME, PROGRESS, PING, PONG = (MESSAGE_TYPES[n] for n in (
    "hello", "ok", "error", "frame", "progress", "ping", "pong"))


def message_type(kind: int | str) -> int:
    """The type number of `kind`, given as a wire name ("scene.load") or a number."""
    if isinstance(kind, str):
        try:
            return MESSAGE_TYPES[kind]
        except KeyError:
            raise ValueError(f"unknown message type '{kind}'") from None
    if not 0 <= kind <= 0xFFFF:
        raise ValueError(f"message type {kind} does not fit 16 bits")
    return kind


def message_name(number: int) -> str:
    """The wire name of a type number, or "type N" for one the table lacks."""
    return MESSAGE_NAMES.get(number, f"type {number}")


@dataclasses.dataclass(frozen=True)
class Limits:
    """The largest JSON body and attachment a reader accepts, checked against the header."""

    max_json_bytes: int = 1 << 20
    max_attachment_bytes: int = 256 << 20


@dataclasses.dataclass
class Message:
    """One frame: its type number, request id, JSON body and attachment."""

    type: int
    request_id: int
    body: dict[str, Any] = dataclasses.field(default_factory=dict)
    attachment: bytes = b""

    @property
    def name(self) -> str:
        return message_name(self.type)


@dataclasses.dataclass(frozen=True)
class Header:
    type: int
    request_id: int
    json_length: int
    attachment_length: int


class FrameError(ValueError):
    """A frame that breaks the format or a limit; `request_id` is set when the header was read."""

    def __init__(self, message: str, request_id: int | None = None):
        super().__init__(message)
        self.request_id = request_id


def encode_body(body: dict[str, Any] | None) -> bytes:
    """The JSON bytes of a body: empty for an empty body, as the C++ encoder does.

    Non-finite numbers are refused here (ValueError): JSON has no NaN or infinity, and the daemon
    would answer bad_request anyway.
    """
    if not body:
        return b""
    if not isinstance(body, dict):
        raise TypeError(f"a message body must be a dict, not {type(body).__name__}")
    return json.dumps(body, ensure_ascii=False, separators=(",", ":"), allow_nan=False).encode("utf-8")


def encode(type: int, request_id: int, body: dict[str, Any] | None = None,
           attachment: bytes | bytearray | memoryview = b"") -> bytes:
    """One complete frame."""
    text = encode_body(body)
    if len(text) > MAX_LENGTH or len(attachment) > MAX_LENGTH:
        raise ValueError("a JSON body or attachment does not fit the 32-bit length field")
    header = _HEADER.pack(MAGIC, PROTOCOL_VERSION, type, request_id, len(text), len(attachment))
    return b"".join((header, text, attachment))


def decode_header(data: bytes, limits: Limits) -> Header:
    """Reads and checks a header before anything of the body is read or allocated.

    Raises FrameError for a wrong magic or version, or a length past `limits`.
    """
    if len(data) != HEADER_SIZE:
        raise FrameError(f"a header is {HEADER_SIZE} bytes, got {len(data)}")
    magic, version, type_, request_id, json_length, attachment_length = _HEADER.unpack(data)
    if magic != MAGIC:
        # Without the magic nothing else in these bytes can be trusted, the request id included.
        raise FrameError(f"bad magic {magic!r}, expected {MAGIC!r}")
    if version != PROTOCOL_VERSION:
        raise FrameError(f"protocol version {version} is not supported, this client speaks "
                         f"{PROTOCOL_VERSION}", request_id)
    if json_length > limits.max_json_bytes:
        raise FrameError(f"{message_name(type_)} JSON body of {json_length} bytes exceeds the limit of "
                         f"{limits.max_json_bytes}", request_id)
    if attachment_length > limits.max_attachment_bytes:
        raise FrameError(f"{message_name(type_)} attachment of {attachment_length} bytes exceeds the "
                         f"limit of {limits.max_attachment_bytes}", request_id)
    return Header(type_, request_id, json_length, attachment_length)


def decode_body(data: bytes, request_id: int | None = None) -> dict[str, Any]:
    """Parses a JSON body: empty bytes are {}; anything but one JSON object is a FrameError."""
    if not data:
        return {}
    try:
        body = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError) as error:
        raise FrameError(f"JSON body does not parse: {error}", request_id) from None
    if not isinstance(body, dict):
        raise FrameError(f"JSON body must be an object, not {type(body).__name__}", request_id)
    return body

