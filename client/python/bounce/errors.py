"""Exceptions of the Bounce client.

Every exception the package raises on purpose derives from BounceError, so a caller can catch
them all at once; the three kinds below tell apart what went wrong:

- ServerError: the daemon answered the request with an `error` reply (docs/protocol.md, "Errors").
- ConnectionFailed (also a built-in ConnectionError): the daemon could not be reached, or the
  connection broke while a reply was awaited.
- ProtocolError: the daemon sent something that is not protocol v1, or a frame past the limits;
  the connection is closed, since its framing can no longer be trusted.
"""

from __future__ import annotations

# Error codes the protocol marks as retryable: the same request may succeed later, unchanged.
RETRYABLE_CODES = frozenset({"busy", "timeout", "shutting_down"})


class BounceError(Exception):
    """Base of every error this package raises."""


class ServerError(BounceError):
    """An `error` reply: the daemon refused or could not finish the request.

    Attributes:
        code: the protocol's error code, e.g. "not_found" or "busy".
        message: the daemon's explanation.
        field: the request field at fault, when the daemon names one (else None).
        retryable: whether sending the same request again later may succeed.
        request_type: the wire name of the request that failed, e.g. "render".
    """

    def __init__(self, code: str, message: str, field: str | None = None, retryable: bool = False,
                 request_type: str | None = None):
        super().__init__(f"{code}: {message}")
        self.code = code
        self.message = message
        self.field = field
        self.retryable = retryable
        self.request_type = request_type

    @classmethod
    def from_body(cls, body: dict, request_type: str | None = None) -> "ServerError":
        """Builds the exception from an `error` reply's JSON body, tolerating missing fields."""
        code = body.get("code")
        code = code if isinstance(code, str) and code else "internal"
        message = body.get("message")
        message = message if isinstance(message, str) else "error"
        field = body.get("field")
        field = field if isinstance(field, str) else None
        retryable = body.get("retryable")
        # The daemon always says; should it not, fall back to the protocol's table.
        retryable = retryable if isinstance(retryable, bool) else code in RETRYABLE_CODES
        return cls(code, message, field, retryable, request_type)


class ConnectionFailed(BounceError, ConnectionError):
    """The daemon could not be reached, or the connection broke before the reply came.

    Attributes:
        endpoint: "host:port" of the daemon concerned, when known.
    """

    def __init__(self, message: str, endpoint: str | None = None):
        super().__init__(message)
        self.endpoint = endpoint

    def __str__(self) -> str:
        return self.args[0] if self.args else "connection failed"


class ConnectTimeout(ConnectionFailed, TimeoutError):
    """No connection could be established in time (a host that drops packets, say)."""


class ReplyTimeout(ConnectionFailed, TimeoutError):
    """The connection was established but the daemon sent nothing for the client's `timeout`.

    The daemon pings a client that waits on a long request (every `heartbeat_ms`), so this means
    the daemon or the network stalled, not merely that a render is slow.
    """


class ProtocolError(BounceError):
    """The daemon sent bytes that are not a valid protocol v1 frame, or a frame past the limits."""
