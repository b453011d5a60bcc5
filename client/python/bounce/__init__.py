"""Python client of bounced, the Bounce render daemon (protocol v1, docs/protocol.md).

    from bounce import Client
    with Client("127.0.0.1", 7878) as client:
        png, stats = client.render("cornell", width=256, height=256)

Router spreads scenes over several daemons by rendezvous hashing; `python3 -m bounce` is the
command-line client. Standard library only.
"""

import logging as _logging

__version__ = "0.1.0"  # the project's version (CMakeLists.txt), as `bounce --version` reports it

from .client import Client, format_endpoint, parse_endpoint, parse_endpoints, read_token_file  # noqa: E402
from .errors import (BounceError, ConnectionFailed, ConnectTimeout, ProtocolError, ReplyTimeout,  # noqa: E402
                     ServerError)
from .protocol import Limits, Message  # noqa: E402
from .rendezvous import owner, rank, weight  # noqa: E402
from .router import Router, resolve_endpoints  # noqa: E402

# A library logs; the application decides where it goes (the CLI sends warnings to stderr).
_logging.getLogger("bounce").addHandler(_logging.NullHandler())

__all__ = [
    "BounceError", "Client", "ConnectTimeout", "ConnectionFailed", "Limits", "Message", "ProtocolError",
    "ReplyTimeout", "Router", "ServerError", "format_endpoint", "owner", "parse_endpoint", "parse_endpoints",
    "rank", "read_token_file", "resolve_endpoints", "weight", "__version__",
]
