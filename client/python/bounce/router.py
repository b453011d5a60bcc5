"""Scene affinity across several daemons.

A Router spreads scenes over daemons by rendezvous hashing (bounce.rendezvous): every request
about scene S goes to the daemon that owns S, so S is loaded, resident and mutated on one daemon
only. A host name that resolves to several addresses (a Kubernetes headless Service, say) counts
as one daemon per address.

The router remembers how each scene it loaded came to be (the path, the uploaded bytes or the
built-in name) and the mutations it sent since (transforms, lights, camera). When S's owner can no
longer be reached, the owner is marked down, S goes to the next daemon in its failover order, is
loaded there from its source, its mutations are replayed, and the request is sent again. When
the owner answers `not_found` for S (it restarted, say), S is reloaded there the same way.
"""

from __future__ import annotations

import dataclasses
import logging
import os
import socket
from collections.abc import Callable, Iterable, Mapping
from typing import Any, TypeVar

from . import rendezvous
from .client import (Client, ProgressCallback, _glb_bytes, camera_body, format_endpoint, light_body,
                     load_body, parse_endpoints, render_body, transform_body)
from .errors import ConnectionFailed, ReplyTimeout, ServerError
from .protocol import Message

__all__ = ["Router", "resolve_endpoints"]

log = logging.getLogger("bounce")

T = TypeVar("T")


def resolve_endpoints(spec: str | Iterable[str | tuple[str, int]]) -> dict[str, tuple[str, int]]:
    """Resolves "a:7878,b:7878" (or a list) to {key: (address, port)}, one entry per address.

    The key is the numeric address, "ip:port" or "[ipv6]:port", the name rendezvous hashing knows a
    daemon by. A name with IPv4 addresses gives those only (a dual-stack host is one daemon, and
    "localhost" must not add a [::1] the daemon does not listen on); IPv6 when it has no IPv4.
    Duplicates are removed; the order is that of the spec, then of the resolver.
    Raises ConnectionFailed for a name that does not resolve.
    """
    endpoints: dict[str, tuple[str, int]] = {}
    for host, port in parse_endpoints(spec):
        try:
            infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
        except socket.gaierror as error:
            raise ConnectionFailed(f"cannot resolve {host}: {error.strerror}", format_endpoint(host, port)) from None
        families = {info[0] for info in infos}
        family_wanted = socket.AF_INET if socket.AF_INET in families else socket.AF_INET6
        for family, _, _, _, sockaddr in infos:
            if family != family_wanted:
                continue
            address, resolved_port = sockaddr[0], sockaddr[1]
            key = f"[{address}]:{resolved_port}" if family == socket.AF_INET6 else f"{address}:{resolved_port}"
            endpoints.setdefault(key, (address, resolved_port))
    return endpoints


@dataclasses.dataclass(frozen=True)
class _Source:
    """How a scene was loaded: the scene.load body and the uploaded bytes, if any."""

    body: dict[str, Any]
    attachment: bytes = b""


class _Edits:
    """The mutations sent to one scene since it was loaded, kept short enough to replay.

    Transforms are absolute (relative to the loaded scene), so only each object's last one counts;
    consecutive light.sets of one light merge; a light.remove supersedes what came before it. The
    camera's changes are kept in order, except that a full view (position with look_at or
    orientation) replaces an unnamed view before it. Changes to different objects, lights and the
    camera commute, so replaying them grouped gives the same scene.
    """

    def __init__(self) -> None:
        self.transforms: dict[str, dict[str, Any]] = {}
        self.lights: dict[str, list[tuple[str, dict[str, Any]]]] = {}
        self.camera: list[dict[str, Any]] = []

    def record(self, kind: str, body: dict[str, Any]) -> None:
        if kind == "object.set_transform":
            self.transforms.pop(body["object"], None)
            self.transforms[body["object"]] = body
        elif kind == "light.set":
            ops = self.lights.setdefault(body["light"], [])
            if ops and ops[-1][0] == "light.set":
                ops[-1] = ("light.set", {**ops[-1][1], **body})
            else:
                ops.append(("light.set", body))
        elif kind == "light.remove":
            self.lights[body["light"]] = [("light.remove", body)]
        elif kind == "camera.set":
            full_view = "camera" not in body and "position" in body and ("look_at" in body or "orientation" in body)
            if full_view and self.camera and "camera" not in self.camera[-1]:
                previous = self.camera.pop()
                # Only the field of view survives a full view from the one before.
                body = {**({"fov_deg": previous["fov_deg"]} if "fov_deg" in previous else {}), **body}
            self.camera.append(body)

    def replay(self) -> list[tuple[str, dict[str, Any]]]:
        ops: list[tuple[str, dict[str, Any]]] = [("camera.set", body) for body in self.camera]
        for light_ops in self.lights.values():
            ops.extend(light_ops)
        ops.extend(("object.set_transform", body) for body in self.transforms.values())
        return ops


class Router:
    """Routes scene requests to the daemon that owns the scene (rendezvous hashing).

    Router(endpoints, token=None): `endpoints` is "a:7878,b:7878" or a list of "HOST:PORT"
    strings or (host, port) pairs; each name may resolve to several addresses, each one daemon.
    It offers the Client's scene methods, routed by scene name; list() and stats() ask every
    daemon. Not thread-safe: use one Router per thread.

    An endpoint stays marked down once it could not be reached, until refresh() resolves the
    names again.
    """

    def __init__(self, endpoints: str | Iterable[str | tuple[str, int]], token: str | None = None,
                 timeout: float | None = 60.0, *, connect_timeout: float | None = 5.0):
        self._spec = endpoints if isinstance(endpoints, str) else list(endpoints)
        self.token = token
        self.timeout = timeout
        self.connect_timeout = connect_timeout
        self._endpoints: dict[str, tuple[str, int]] = resolve_endpoints(self._spec)
        self._down: set[str] = set()
        self._clients: dict[str, Client] = {}
        self._sources: dict[str, _Source] = {}
        self._edits: dict[str, _Edits] = {}
        self._placed: dict[str, str] = {}  # scene -> key of the daemon it was last loaded on

    # -- endpoints -------------------------------------------------------------------------------

    @property
    def endpoints(self) -> list[str]:
        """Every endpoint's key, down or not."""
        return list(self._endpoints)

    @property
    def down(self) -> set[str]:
        """Keys of the endpoints marked down."""
        return set(self._down)

    def ranking(self, scene: str) -> list[str]:
        """The live endpoints in `scene`'s failover order, its owner first."""
        return rendezvous.rank((key for key in self._endpoints if key not in self._down), scene)

    def owner(self, scene: str) -> str:
        """The key of the live endpoint that owns `scene`; ConnectionFailed when none is live."""
        ranking = self.ranking(scene)
        if not ranking:
            raise ConnectionFailed(f"no daemon left for scene '{scene}': all of {self.endpoints} are down")
        return ranking[0]

    def client(self, key: str) -> Client:
        """The connection to one endpoint (opened on first use); ConnectionFailed when unreachable."""
        client = self._clients.get(key)
        if client is None:
            address, port = self._endpoints[key]
            client = Client(address, port, self.token, self.timeout, connect_timeout=self.connect_timeout)
            self._clients[key] = client
        return client

    def mark_down(self, key: str, reason: object = "") -> None:
        """Stops routing to `key`; its scenes go to the next endpoint in their failover order."""
        if key not in self._down:
            log.warning("%s is down%s; its scenes move to the next daemon", key,
                        f" ({reason})" if reason else "")
        self._down.add(key)
        self._drop_client(key)

    def refresh(self) -> None:
        """Resolves the endpoint names again and forgets every down mark (daemons came back, or a
        Service's addresses changed). Scenes whose owner changes are reloaded on next use."""
        endpoints = resolve_endpoints(self._spec)
        for key in set(self._clients) - set(endpoints):
            self._drop_client(key)
        self._endpoints = endpoints
        self._down.clear()

    def _drop_client(self, key: str) -> None:
        client = self._clients.pop(key, None)
        if client is not None:
            client.close()

    def close(self) -> None:
        for key in list(self._clients):
            self._drop_client(key)

    def __enter__(self) -> "Router":
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"<bounce.Router {self.endpoints} down={sorted(self._down)}>"

    # -- routing ---------------------------------------------------------------------------------

    def _connect_owner(self, scene: str) -> tuple[str, Client]:
        """The first endpoint of `scene`'s failover order that accepts a connection; those that
        do not are marked down on the way."""
        last: ConnectionFailed | None = None
        for key in self.ranking(scene):
            try:
                return key, self.client(key)
            except ConnectionFailed as error:
                self.mark_down(key, error)
                last = error
        raise ConnectionFailed(f"no daemon reachable for scene '{scene}'"
                               + (f"; last: {last}" if last else f": all of {self.endpoints} are down"))

    def _place(self, scene: str, key: str, client: Client) -> None:
        """Loads `scene` from its source on `key` and replays its mutations, unless it is there."""
        source = self._sources.get(scene)
        if source is None or self._placed.get(scene) == key:
            return
        log.info("loading scene '%s' on %s from its source", scene, key)
        client.request("scene.load", source.body, source.attachment)
        for kind, body in self._edits.get(scene, _Edits()).replay():
            try:
                client.request(kind, body)
            except ServerError as error:
                # Replaying what once succeeded can only fail where the source itself changed.
                log.warning("replaying %s on scene '%s' failed: %s", kind, scene, error)
        # Only now: a connection lost mid-replay leaves the scene to be loaded again.
        self._placed[scene] = key

    def _route(self, scene: str, send: Callable[[str, Client], T], *, place: bool = True,
               reload_missing: bool = True) -> T:
        """Runs send(key, client) on `scene`'s owner, with one retry after a failover or reload."""
        retried = False
        while True:
            key, client = self._connect_owner(scene)
            try:
                if place:
                    self._place(scene, key, client)
                return send(key, client)
            except ServerError as error:
                if retried:
                    raise
                if error.code == "shutting_down":
                    self.mark_down(key, "shutting down")
                elif (reload_missing and error.code == "not_found" and error.field in ("scene", "name")
                      and scene in self._sources):
                    log.info("%s lost scene '%s'; reloading it", key, scene)
                    self._placed.pop(scene, None)
                else:
                    raise
            except ReplyTimeout:
                raise  # the daemon may still be working on it: not a reason to move the scene
            except ConnectionFailed:
                # The next round connects afresh: a daemon that is only gone from this connection
                # answers again; one that is gone for good is marked down and the scene moves.
                self._drop_client(key)
                if retried:
                    raise
            retried = True

    def _mutate(self, scene: str, kind: str, body: dict[str, Any]) -> dict[str, Any]:
        reply = self._route(scene, lambda key, client: client.request(kind, body).body)
        if scene in self._sources:
            self._edits.setdefault(scene, _Edits()).record(kind, body)
        return reply

    def _load(self, name: str, source: _Source) -> dict[str, Any]:
        def send(key: str, client: Client) -> dict[str, Any]:
            reply = client.request("scene.load", source.body, source.attachment).body
            # A fresh load: the scene's state is its source again, with nothing to replay.
            self._sources[name] = source
            self._edits[name] = _Edits()
            self._placed[name] = key
            return reply

        return self._route(name, send, place=False, reload_missing=False)

    # -- requests --------------------------------------------------------------------------------

    def request(self, kind: int | str, body: Mapping[str, Any] | None = None,
                attachment: bytes | bytearray | memoryview = b"", on_progress: ProgressCallback | None = None,
                *, scene: str | None = None) -> Message:
        """Sends one request to the owner of `scene` (by default the body's "scene", else its
        "name") and returns the reply. Scenes loaded this way are not remembered for failover."""
        body = dict(body or {})
        scene = scene if scene is not None else body.get("scene", body.get("name"))
        if not isinstance(scene, str):
            raise ValueError("the request names no scene to route by; use Router.client(key) for one daemon")
        return self._route(scene, lambda key, client: client.request(kind, body, attachment, on_progress))

    def load(self, path: str | os.PathLike, name: str, dynamic: Iterable[str] | None = None) -> dict[str, Any]:
        """Loads `path` (under the owner's --scene-root) as `name` on the daemon that owns `name`."""
        return self._load(name, _Source(load_body(name, path=path, dynamic=dynamic)))

    def upload(self, glb: bytes | bytearray | memoryview | str | os.PathLike, name: str,
               dynamic: Iterable[str] | None = None) -> dict[str, Any]:
        """Uploads a .glb to the daemon that owns `name`; the bytes are kept for failover."""
        return self._load(name, _Source(load_body(name, dynamic=dynamic), _glb_bytes(glb)))

    def load_builtin(self, builtin: str, name: str, dynamic: Iterable[str] | None = None) -> dict[str, Any]:
        return self._load(name, _Source(load_body(name, builtin=builtin, dynamic=dynamic)))

    def unload(self, name: str) -> dict[str, Any]:
        """Unloads `name` from its owner and forgets its source, even when the owner had lost it."""
        try:
            return self._route(name, lambda key, client: client.unload(name), place=False, reload_missing=False)
        finally:
            for memory in (self._sources, self._edits, self._placed):
                memory.pop(name, None)

    def list(self) -> dict[str, list[dict[str, Any]] | None]:
        """Every daemon's scenes, keyed by endpoint; None for one that is down."""
        return self._each(lambda client: client.list())

    def stats(self) -> dict[str, dict[str, Any] | None]:
        """Every daemon's stats, keyed by endpoint; None for one that is down."""
        return self._each(lambda client: client.stats())

    def _each(self, ask: Callable[[Client], T]) -> dict[str, T | None]:
        answers: dict[str, T | None] = {}
        for key in self._endpoints:
            answers[key] = None
            if key in self._down:
                continue
            for attempt in range(2):
                try:
                    client = self.client(key)
                except ConnectionFailed as error:
                    self.mark_down(key, error)
                    break
                try:
                    answers[key] = ask(client)
                    break
                except ReplyTimeout:
                    raise
                except ConnectionFailed:
                    # A broken connection is not a dead daemon: the next round connects afresh.
                    self._drop_client(key)
                    if attempt:
                        raise
        return answers

    def describe(self, scene: str) -> dict[str, Any]:
        return self._route(scene, lambda key, client: client.describe(scene))

    def move(self, scene: str, object: str, translation: Iterable[float] | None = None,
             rotation_deg: Iterable[float] | None = None, scale: float | None = None,
             matrix: Iterable[float] | None = None) -> dict[str, Any]:
        return self._mutate(scene, "object.set_transform",
                            transform_body(scene, object, translation, rotation_deg, scale, matrix))

    def light(self, scene: str, light: str, type: str | None = None,
              position: Iterable[float] | None = None, direction: Iterable[float] | None = None,
              color: Iterable[float] | None = None, intensity: float | None = None,
              inner_cone_deg: float | None = None, outer_cone_deg: float | None = None) -> dict[str, Any]:
        return self._mutate(scene, "light.set", light_body(scene, light, type, position, direction, color,
                                                           intensity, inner_cone_deg, outer_cone_deg))

    def remove_light(self, scene: str, light: str) -> dict[str, Any]:
        return self._mutate(scene, "light.remove", {"scene": scene, "light": light})

    def camera(self, scene: str, position: Iterable[float] | None = None,
               look_at: Iterable[float] | None = None, orientation: Iterable[float] | None = None,
               fov_deg: float | None = None, name: str | None = None) -> dict[str, Any]:
        return self._mutate(scene, "camera.set", camera_body(scene, position, look_at, orientation, fov_deg, name))

    def render(self, scene: str, method: str | None = None, preset: str | None = None,
               knobs: Mapping[str, float] | None = None, width: int | None = None,
               height: int | None = None, format: str = "png", exposure: float | None = None,
               tone: str | None = None, camera: str | None = None, *, jpeg_quality: int | None = None,
               exr_half: bool | None = None, min_scene_version: int | None = None,
               timeout_ms: int | None = None, budget: Mapping[str, float] | None = None,
               on_progress: ProgressCallback | None = None) -> tuple[bytes, dict[str, Any]]:
        """As Client.render, on the scene's owner. After a failover the scene's version restarts
        from its reload, so a `min_scene_version` from before may no longer hold."""
        body = render_body(scene, method=method, preset=preset, knobs=knobs, width=width, height=height,
                           format=format, exposure=exposure, tone=tone, camera=camera,
                           jpeg_quality=jpeg_quality, exr_half=exr_half,
                           min_scene_version=min_scene_version, timeout_ms=timeout_ms, budget=budget)
        reply = self._route(scene, lambda key, client: client.request("render", body, on_progress=on_progress))
        return reply.attachment, reply.body

    def bake(self, scene: str, method: str = "cssm", preset: str | None = None,
             knobs: Mapping[str, float] | None = None, *, timeout_ms: int | None = None,
             on_progress: ProgressCallback | None = None) -> dict[str, Any]:
        body = render_body(scene, method=method, preset=preset, knobs=knobs, format=None, timeout_ms=timeout_ms)
        return self._route(scene, lambda key, client: client.request("bake", body, on_progress=on_progress).body)
