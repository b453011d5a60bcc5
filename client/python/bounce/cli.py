"""`python3 -m bounce`: the command-line client, with the commands and flags of client/main.cpp.

Exit codes: 0 success, 2 usage error, 3 connection failure, 4 retryable daemon error (busy,
timeout, or any error the daemon marks retryable), 1 any other failure.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import os
import re
import sys
from collections.abc import Callable
from typing import Any

from . import __version__
from .client import Client, parse_endpoints, read_token_file
from .errors import ConnectionFailed, ProtocolError, ServerError
from .router import Router

EXIT_OK, EXIT_FAILURE, EXIT_USAGE, EXIT_CONNECTION, EXIT_RETRYABLE = 0, 1, 2, 3, 4

COMMANDS = """commands:
  render  --scene S [--method M] [--preset P] [--set KNOB=VALUE ...] [--size WxH]
          [--exposure E] [--tone none|reinhard|aces] [--camera NAME]
          [--budget-ms T] [--target-error E] -o OUT.(png|jpg|exr)|-   (a budget plans method auto)
  bake    --scene S [--method cssm] [--preset P] [--set KNOB=VALUE ...]   (progress on stderr)
  watch   --scene S [--method M] [--preset P] [--size WxH] [--format jpeg|png|webp]
          [--budget-ms T] [--target-error E] [--frames N] [--until-final] -o DIR
          (a stream's frames, one JSON line each; a budget plans its first two rungs)
  load    PATH --name S          (PATH under the daemon's --scene-root)
  upload  FILE.glb --name S      (sends the file)
  move    --scene S --object O [--translate X,Y,Z] [--rotate-deg RX,RY,RZ] [--scale K]
  light   --scene S --light L [--type point|spot|directional] [--position X,Y,Z]
          [--direction X,Y,Z] [--color R,G,B] [--intensity I]
  describe --scene S [--analyze] | list | stats

--connect and --token-file default to $BOUNCE_CONNECT and $BOUNCE_TOKEN_FILE, then 127.0.0.1:7878.
With several endpoints (--connect a:7878,b:7878) each scene goes to its daemon by rendezvous
hashing, and list and stats ask every daemon.
exit codes: 0 success, 2 usage error, 3 connection failure, 4 retryable daemon error, 1 other"""


class UsageError(Exception):
    """A command line that cannot be run as given (exit 2)."""


# -- parsing ---------------------------------------------------------------------------------------

def _number(text: str, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise UsageError(f"{what}: '{text}' is not a number") from None
    if not math.isfinite(value):
        raise UsageError(f"{what}: '{text}' is not a finite number")
    return value


def _numbers(text: str, count: int, what: str) -> list[float]:
    values = [_number(part, what) for part in text.split(",")]
    if len(values) != count:
        raise UsageError(f"{what} expects {count} comma-separated numbers")
    return values


def _size(text: str) -> tuple[int, int]:
    match = re.fullmatch(r"(\d+)x(\d+)", text)
    if not match:
        raise UsageError(f"--size expects WxH, got '{text}'")
    return int(match[1]), int(match[2])


def _format_of(path: str) -> str:
    if path == "-":
        return "png"
    extension = os.path.splitext(path)[1].lower().lstrip(".")
    if extension in ("png", "exr"):
        return extension
    if extension in ("jpg", "jpeg"):
        return "jpeg"
    raise UsageError(f"-o must end in .png, .jpg or .exr (or be - for PNG on stdout), got '{path}'")


class _Parser:
    """Builds the argparse parsers and remembers which options take a value."""

    def __init__(self) -> None:
        self.value_options: set[str] = set()
        self.root = argparse.ArgumentParser(
            prog="bounce", description="Command-line client of bounced (Python).", epilog=COMMANDS,
            formatter_class=argparse.RawDescriptionHelpFormatter, allow_abbrev=False)
        self.option(self.root, "--connect", metavar="HOST:PORT[,HOST:PORT...]",
                    default=os.environ.get("BOUNCE_CONNECT") or "127.0.0.1:7878")
        self.option(self.root, "--token-file", metavar="F", default=os.environ.get("BOUNCE_TOKEN_FILE") or None)
        self.root.add_argument("--version", action="version", version=f"bounce {__version__}")
        commands = self.root.add_subparsers(dest="command", metavar="COMMAND", required=True)

        def command(name: str, help: str) -> argparse.ArgumentParser:
            return commands.add_parser(name, help=help, allow_abbrev=False)

        def frame_options(parser: argparse.ArgumentParser) -> None:
            self.option(parser, "--scene", required=True)
            self.option(parser, "--method")
            self.option(parser, "--preset")
            self.option(parser, "--set", action="append", default=[], metavar="KNOB=VALUE", dest="knobs")
            self.option(parser, "--size", metavar="WxH")
            self.option(parser, "--exposure", metavar="E")
            self.option(parser, "--tone", choices=("none", "reinhard", "aces"))

        def budget_options(parser):
            self.option(parser, "--budget-ms", metavar="T")
            self.option(parser, "--target-error", metavar="E")

        render = command("render", "render one frame to a file")
        frame_options(render)
        self.option(render, "--camera", metavar="NAME")
        budget_options(render)
        self.option(render, "-o", dest="out", required=True, metavar="OUT.(png|jpg|exr)|-")
        frame_options(command("bake", "build a method's precomputed structures"))
        watch = command("watch", "stream a view: each frame to DIR, one JSON line per frame")
        frame_options(watch)
        budget_options(watch)
        self.option(watch, "--format", choices=("jpeg", "jpg", "png", "webp"), default="jpeg")
        self.option(watch, "--frames", metavar="N")
        watch.add_argument("--until-final", action="store_true")
        self.option(watch, "-o", dest="out", required=True, metavar="DIR")
        for name, help in (("load", "load a scene file under the daemon's --scene-root"),
                           ("upload", "send a .glb and load it")):
            parser = command(name, help)
            parser.add_argument("path", metavar="PATH" if name == "load" else "FILE.glb")
            self.option(parser, "--name", required=True, metavar="S")
        move = command("move", "set an object's transform")
        self.option(move, "--scene", required=True)
        self.option(move, "--object", required=True)
        self.option(move, "--translate", metavar="X,Y,Z")
        self.option(move, "--rotate-deg", metavar="RX,RY,RZ")
        self.option(move, "--scale", metavar="K")
        light = command("light", "create or update a light")
        self.option(light, "--scene", required=True)
        self.option(light, "--light", required=True)
        self.option(light, "--type", choices=("point", "spot", "directional"))
        self.option(light, "--position", metavar="X,Y,Z")
        self.option(light, "--direction", metavar="X,Y,Z")
        self.option(light, "--color", metavar="R,G,B")
        self.option(light, "--intensity", metavar="I")
        described = command("describe", "describe a scene")
        self.option(described, "--scene", required=True)
        described.add_argument("--analyze", action="store_true",
                               help="add the scene analysis: light by bounce, thin walls, indirect visibility")
        command("list", "list the scenes (of every daemon)")
        command("stats", "the daemon's counters (of every daemon)")

    def option(self, parser: argparse.ArgumentParser, *names: str, **kwargs: Any) -> None:
        self.value_options.update(names)
        parser.add_argument(*names, **kwargs)

    def parse(self, argv: list[str]) -> argparse.Namespace:
        return self.root.parse_args(self.attach_values(argv))

    def attach_values(self, argv: list[str]) -> list[str]:
        """Joins each option with the word after it, so that a value starting with '-'
        (--translate -1,0,0) is taken as the value, as the C++ client does, not as an option."""
        words: list[str] = []
        i = 0
        while i < len(argv):
            word = argv[i]
            if word in self.value_options and i + 1 < len(argv) and argv[i + 1].startswith("-") \
                    and argv[i + 1] != "-":
                value = argv[i + 1]
                words.append(f"{word}={value}" if word.startswith("--") else word + value)
                i += 2
                continue
            words.append(word)
            i += 1
        return words


# -- commands --------------------------------------------------------------------------------------

def _dump(value: Any, pretty: bool = False) -> str:
    # Sorted keys, as the C++ client prints (its JSON objects are ordered maps).
    if pretty:
        return json.dumps(value, indent=2, sort_keys=True)
    return json.dumps(value, separators=(",", ":"), sort_keys=True)


def _knobs(pairs: list[str]) -> dict[str, float]:
    knobs: dict[str, float] = {}
    for pair in pairs:
        name, equals, value = pair.partition("=")
        if not equals or not name:
            raise UsageError(f"--set expects KNOB=VALUE, got '{pair}'")
        knobs[name] = _number(value, "--set")
    return knobs


def _add_budget(fields: dict[str, Any], args: argparse.Namespace) -> None:
    """--budget-ms and --target-error as the request's `budget` (the daemon then plans the method
    too, unless --method names one)."""
    budget = {}
    if args.budget_ms is not None:
        budget["max_ms"] = _number(args.budget_ms, "--budget-ms")
    if args.target_error is not None:
        budget["max_error"] = _number(args.target_error, "--target-error")
    if budget:
        fields["budget"] = budget


def _frame_fields(args: argparse.Namespace) -> dict[str, Any]:
    width, height = _size(args.size) if args.size else (None, None)
    return {"method": args.method, "preset": args.preset, "knobs": _knobs(args.knobs) or None,
            "width": width, "height": height,
            "exposure": None if args.exposure is None else _number(args.exposure, "--exposure"),
            "tone": args.tone}


def _write_file(path: str, data: bytes) -> None:
    """Writes through a temporary file, so a reader never sees half a frame."""
    temporary = f"{path}.tmp-{os.getpid()}"
    try:
        with open(temporary, "wb") as file:
            file.write(data)
        os.replace(temporary, path)
    except OSError:
        try:
            os.unlink(temporary)
        except OSError:
            pass
        raise


def _count(text: str, what: str) -> int:
    if not text.isdigit() or int(text) < 1:
        raise UsageError(f"{what} expects a whole number of 1 or more, got '{text}'")
    return int(text)


def _progress(event: dict[str, Any]) -> None:
    fraction = event.get("fraction", 0.0)
    percent = int(100.0 * fraction) if isinstance(fraction, (int, float)) else 0
    print(f"bake: {event.get('stage', '')} {percent}%", file=sys.stderr, flush=True)


def _run(args: argparse.Namespace) -> int:
    # Every argument is checked before connecting: a typo costs no connection and exits 2.
    try:
        endpoints = parse_endpoints(args.connect)
    except ValueError as error:
        raise UsageError(f"--connect: {error}") from None
    token = None
    if args.token_file:
        try:
            token = read_token_file(args.token_file)
        except OSError as error:
            raise UsageError(str(error)) from None
    action = _prepare(args)
    routed = len(endpoints) > 1
    # A Router sends each scene to its daemon; a single endpoint needs only a Client.
    target: Client | Router = Router(endpoints, token) if routed else Client(*endpoints[0], token=token)
    with target:
        code = action(target, routed)
    return EXIT_OK if code is None else code


# Runs a command on a Client or Router; returns its exit code, or None for success.
Action = Callable[[Any, bool], int | None]


def _prepare(args: argparse.Namespace) -> Action:
    """Checks and converts the command's arguments; returns what runs it on a Client or Router."""
    command = args.command
    if command == "render":
        fmt = _format_of(args.out)
        fields = _frame_fields(args)
        _add_budget(fields, args)

        def render(target, routed):
            image, stats = target.render(args.scene, format=fmt, camera=args.camera, **fields)
            if args.out == "-":
                sys.stdout.buffer.write(image)
                sys.stdout.buffer.flush()
                print(_dump(stats), file=sys.stderr)  # stdout carries the image
            else:
                _write_file(args.out, image)
                print(_dump(stats))
        return render
    if command == "bake":
        fields = _frame_fields(args)
        # Taken for parity with render, as the C++ client does; a bake draws no frame.
        for unused in ("width", "height", "exposure", "tone"):
            fields.pop(unused)
        fields["method"] = fields["method"] or "cssm"
        return lambda target, routed: print(_dump(target.bake(args.scene, on_progress=_progress, **fields)))
    if command == "watch":
        return _prepare_watch(args)
    if command == "load":
        return lambda target, routed: print(_dump(target.load(args.path, args.name)))
    if command == "upload":
        try:
            with open(args.path, "rb") as file:
                glb = file.read()
        except OSError as error:
            raise UsageError(f"cannot read {args.path}: {error.strerror}") from None
        return lambda target, routed: print(_dump(target.upload(glb, args.name)))
    if command == "move":
        transform = {
            "translation": None if args.translate is None else _numbers(args.translate, 3, "--translate"),
            "rotation_deg": None if args.rotate_deg is None else _numbers(args.rotate_deg, 3, "--rotate-deg"),
            "scale": None if args.scale is None else _number(args.scale, "--scale")}
        return lambda target, routed: print(_dump(target.move(args.scene, args.object, **transform)))
    if command == "light":
        def vector(text: str | None, what: str) -> list[float] | None:
            return None if text is None else _numbers(text, 3, what)

        light = {"type": args.type, "position": vector(args.position, "--position"),
                 "direction": vector(args.direction, "--direction"), "color": vector(args.color, "--color"),
                 "intensity": None if args.intensity is None else _number(args.intensity, "--intensity")}
        return lambda target, routed: print(_dump(target.light(args.scene, args.light, **light)))
    if command == "describe":
        return lambda target, routed: print(_dump(target.describe(args.scene, analyze=args.analyze), pretty=True))

    def survey(target, routed):
        """list and stats: one daemon's answer, or every daemon's keyed by endpoint."""
        if not routed:
            print(_dump({"scenes": target.list()} if command == "list" else target.stats(), pretty=True))
            return
        answers = target.list() if command == "list" else target.stats()
        report = {key: ({"error": "unreachable"} if answer is None
                        else {"scenes": answer} if command == "list" else answer)
                  for key, answer in answers.items()}
        print(_dump(report, pretty=True))
        if all(answer is None for answer in answers.values()):
            raise ConnectionFailed("no daemon reachable: " + ", ".join(answers))
    return survey


def _prepare_watch(args: argparse.Namespace) -> Action:
    """watch: starts a stream, saves each frame as DIR/frame-NNNNNN.EXT and prints a JSON line for
    it, then stops the stream after --frames frames or the first final one (else it runs until
    interrupted)."""
    fields = _frame_fields(args)
    _add_budget(fields, args)
    fmt = "jpeg" if args.format == "jpg" else args.format
    extension = "jpg" if fmt == "jpeg" else fmt
    frames = None if args.frames is None else _count(args.frames, "--frames")

    def watch(target, routed):
        # A stream lives on one connection: the scene's daemon's.
        client = target.client(target.owner(args.scene)) if routed else target
        os.makedirs(args.out, exist_ok=True)
        stream = client.stream_start(args.scene, format=fmt, **fields)
        saved = 0
        while frames is None or saved < frames:
            try:
                image, body = client.next_frame()
            except ServerError as error:
                # The stream's frame failed and the stream ended: refused, whatever the code.
                print(f"bounce: {error.code}: {error.message}", file=sys.stderr)
                return EXIT_FAILURE
            path = os.path.join(args.out, f"frame-{saved:06d}.{extension}")
            _write_file(path, image)
            info = body.get("stream", {})
            print(_dump({"file": path, "scene_version": body.get("scene_version"), "rung": info.get("rung"),
                         "stage": info.get("stage"), "final": info.get("final"), "width": body.get("width"),
                         "height": body.get("height"),
                         "total_ms": body.get("timings_ms", {}).get("total")}), flush=True)
            saved += 1
            if args.until_final and info.get("final"):
                break
        client.stream_stop(stream)
        return None
    return watch


def main(argv: list[str] | None = None) -> int:
    parser = _Parser()
    argv = sys.argv[1:] if argv is None else argv
    try:
        args = parser.parse(argv)  # exits 2 on a usage error, 0 for --help and --version
    except SystemExit as exit:
        return EXIT_OK if exit.code is None else exit.code if isinstance(exit.code, int) else EXIT_USAGE
    # Failovers and reloads are worth a line on stderr; the rest of the log stays quiet.
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("bounce: %(message)s"))
    logger = logging.getLogger("bounce")
    logger.addHandler(handler)
    logger.setLevel(logging.WARNING)
    try:
        return _run(args)
    except UsageError as error:
        print(f"bounce: {error}", file=sys.stderr)
        return EXIT_USAGE
    except ServerError as error:
        print(f"bounce: {error.code}: {error.message}", file=sys.stderr)
        return EXIT_RETRYABLE if error.retryable or error.code in ("busy", "timeout", "shutting_down") else EXIT_FAILURE
    except ConnectionFailed as error:
        print(f"bounce: {error}", file=sys.stderr)
        return EXIT_CONNECTION
    except (ProtocolError, OSError, ValueError) as error:
        print(f"bounce: {error}", file=sys.stderr)
        return EXIT_FAILURE
    except KeyboardInterrupt:
        return 130
    finally:
        logger.removeHandler(handler)
