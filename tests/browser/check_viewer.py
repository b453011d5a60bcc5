#!/usr/bin/env python3
"""The viewer page in headless Chromium against a real daemon: the page opens the Cornell box's
stream, and its screenshot shows the frame the daemon renders for the page's view.

With --budget, the page's controls then plan the stream: method "auto" takes a budget (a frame
time of 100 ms), the frames carry their plan and the panel shows it, a target error added plans for
both limits and both stay shown, the frame time removed plans for the error alone, and removing the
budget keeps the plan's method and preset: the screenshot is then the daemon's frame of that method and preset.

Drives Chromium over the DevTools protocol (a WebSocket; the few lines of client it needs are
here, standard library only). The screenshot's image area is compared with a one-off render of the
page's own camera over TCP: PNG frames, drawn 1:1, so the bound is exactness up to the browser's
8-bit compositing (we allow 1 level in a channel, none in the mean beyond 0.05 levels).

usage: check_viewer.py BOUNCED CHROMIUM [--budget]
"""

from __future__ import annotations

import base64
import json
import os
import shutil
import socket
import struct
import subprocess
import sys
import tempfile
import time
import urllib.request
import zlib

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "client", "python"))
from bounce import Client  # noqa: E402

SIZE = 256


def fail(message: str) -> None:
    print(f"FAIL: {message}", file=sys.stderr)
    sys.exit(1)


def wait_for_file(path: str, lines: int, seconds: float) -> list[str]:
    deadline = time.time() + seconds
    while time.time() < deadline:
        if os.path.exists(path):
            content = open(path).read().split()
            if len(content) >= lines:
                return content
        time.sleep(0.05)
    fail(f"{path} did not appear within {seconds} s")
    return []


class DevTools:
    """A minimal WebSocket client (RFC 6455, client frames masked) for one DevTools target."""

    def __init__(self, url: str):
        assert url.startswith("ws://")
        host_port, path = url[5:].split("/", 1)
        host, port = host_port.split(":")
        self.sock = socket.create_connection((host, int(port)), timeout=60)
        key = base64.b64encode(os.urandom(16)).decode()
        self.sock.sendall((f"GET /{path} HTTP/1.1\r\nHost: {host_port}\r\nUpgrade: websocket\r\n"
                           f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n").encode())
        response = b""
        while b"\r\n\r\n" not in response:
            response += self.sock.recv(4096)
        if b" 101 " not in response.split(b"\r\n", 1)[0]:
            fail(f"DevTools handshake refused: {response[:200]!r}")
        self.buffer = response.split(b"\r\n\r\n", 1)[1]
        self.next_id = 0

    def _recv_exact(self, n: int) -> bytes:
        while len(self.buffer) < n:
            chunk = self.sock.recv(1 << 20)
            if not chunk:
                fail("DevTools closed the connection")
            self.buffer += chunk
        out, self.buffer = self.buffer[:n], self.buffer[n:]
        return out

    def _send_text(self, text: str) -> None:
        payload = text.encode()
        header = bytes([0x81])
        if len(payload) < 126:
            header += bytes([0x80 | len(payload)])
        elif len(payload) < 65536:
            header += bytes([0x80 | 126]) + struct.pack(">H", len(payload))
        else:
            header += bytes([0x80 | 127]) + struct.pack(">Q", len(payload))
        mask = os.urandom(4)
        self.sock.sendall(header + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(payload)))

    def _recv_message(self) -> dict:
        data = b""
        while True:
            first, second = self._recv_exact(2)
            length = second & 0x7F
            if length == 126:
                length = struct.unpack(">H", self._recv_exact(2))[0]
            elif length == 127:
                length = struct.unpack(">Q", self._recv_exact(8))[0]
            data += self._recv_exact(length)
            if first & 0x80:
                return json.loads(data)

    def call(self, method: str, **params) -> dict:
        self.next_id += 1
        self._send_text(json.dumps({"id": self.next_id, "method": method, "params": params}))
        while True:
            message = self._recv_message()
            if message.get("id") == self.next_id:
                if "error" in message:
                    fail(f"{method}: {message['error']}")
                return message["result"]

    def evaluate(self, expression: str):
        result = self.call("Runtime.evaluate", expression=expression, returnByValue=True)
        return result["result"].get("value")


def decode_png(data: bytes) -> tuple[int, int, int, bytes]:
    """8-bit RGB or RGBA PNG, non-interlaced: (width, height, channels, rows)."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, width = 8, b"", 0
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        chunk = data[pos + 8:pos + 8 + length]
        pos += 12 + length
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", chunk)
            if depth != 8 or colour not in (2, 6) or interlace:
                fail(f"unexpected PNG: depth {depth} colour {colour} interlace {interlace}")
            channels = 3 if colour == 2 else 4
        elif kind == b"IDAT":
            idat += chunk
    raw = zlib.decompress(idat)
    stride = width * channels
    out = bytearray(height * stride)
    previous = bytearray(stride)
    for y in range(height):
        kind = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            left = line[x - channels] if x >= channels else 0
            up = previous[x]
            up_left = previous[x - channels] if x >= channels else 0
            if kind == 1:
                line[x] = (line[x] + left) & 0xFF
            elif kind == 2:
                line[x] = (line[x] + up) & 0xFF
            elif kind == 3:
                line[x] = (line[x] + (left + up) // 2) & 0xFF
            elif kind == 4:
                p = left + up - up_left
                pa, pb, pc = abs(p - left), abs(p - up), abs(p - up_left)
                predictor = left if pa <= pb and pa <= pc else (up if pb <= pc else up_left)
                line[x] = (line[x] + predictor) & 0xFF
        out[y * stride:(y + 1) * stride] = line
        previous = line
    return width, height, channels, bytes(out)


def page_state(tools: DevTools) -> dict:
    return json.loads(tools.evaluate("JSON.stringify(document.body.dataset)") or "{}")


def wait_for_final(tools: DevTools, after_frames: int, seconds: float, what: str, plan: bool | None = None) -> dict:
    """The page's state once it shows a final frame, past `after_frames` frames, with a plan (True),
    without one (False) or either (None)."""
    deadline = time.time() + seconds
    state = {}
    while time.time() < deadline:
        state = page_state(tools)
        if state.get("error"):
            fail(f"{what}: the page shows an error: {state}")
        has_plan = bool(state.get("planMethod"))
        if (state.get("final") == "true" and int(state.get("frames", "0")) > after_frames
                and (plan is None or has_plan == plan)):
            return state
        time.sleep(0.2)
    fail(f"{what}: no final frame within {seconds} s: {state}")
    return state


def compare_with_daemon(tools: DevTools, tcp_port: int, work: str, name: str, **request) -> None:
    """The screenshot of the page's image against the daemon's frame of the page's camera (PNG, 1:1)."""
    camera = json.loads(tools.evaluate(
        "JSON.stringify({position: cameraPosition(orbit), look_at: orbit.target, fov_deg: orbit.fov})"))
    box = json.loads(tools.evaluate("JSON.stringify(document.getElementById('view').getBoundingClientRect())"))
    if (box["x"], box["y"], box["width"], box["height"]) != (0, 0, SIZE, SIZE):
        fail(f"the image is not at the page's corner at {SIZE}x{SIZE}: {box}")
    shot = base64.b64decode(tools.call("Page.captureScreenshot", format="png",
                                       clip={"x": 0, "y": 0, "width": SIZE, "height": SIZE, "scale": 1})["data"])
    open(os.path.join(os.environ.get("BOUNCE_ARTIFACTS", work), name), "wb").write(shot)
    width, height, channels, pixels = decode_png(shot)
    if (width, height) != (SIZE, SIZE):
        fail(f"screenshot is {width}x{height}")

    with Client(f"127.0.0.1:{tcp_port}") as client:
        frame, _ = client.render("cornell", width=SIZE, height=SIZE, format="png", camera=camera, **request)
    fw, fh, fc, expected = decode_png(frame)
    total, worst, off = 0, 0, 0
    for i in range(SIZE * SIZE):
        for c in range(3):
            d = abs(pixels[i * channels + c] - expected[i * fc + c])
            total += d
            worst = max(worst, d)
            off += d > 1
    mean = total / (SIZE * SIZE * 3)
    print(json.dumps({"camera": camera, "request": request, "mean_abs_diff": mean, "max_abs_diff": worst,
                      "values_off_by_more_than_1": off}))
    if mean > 0.05 or off > 0:
        fail(f"the screenshot is not the daemon's frame {request}: mean |diff| {mean:.3f}, "
             f"{off} values off by more than 1")


def check_budget(tools: DevTools, tcp_port: int, work: str, methods: list[str]) -> None:
    """Method auto through the page's controls, then the budget removed."""
    frames = int(page_state(tools)["frames"])
    tools.evaluate("(() => { const m = document.getElementById('method'); m.value = 'auto';"
                   " m.dispatchEvent(new Event('change')); })()")
    # The first budget calibrates the device's cost model (the daemon's smallest calibration).
    state = wait_for_final(tools, frames, 180, "method auto", plan=True)
    plan = json.loads(tools.evaluate("JSON.stringify(lastPlan)"))
    controls = json.loads(tools.evaluate(
        "JSON.stringify({ms: $('budget-ms').value, error: $('budget-error').value,"
        " preset_disabled: $('preset').disabled, shown: $('st-plan').textContent, why: $('st-plan').title})"))
    print(json.dumps({"plan": plan, "controls": controls}))
    if controls["ms"] != "100" or controls["error"] != "" or not controls["preset_disabled"]:
        fail(f"method auto did not take a frame time of 100 ms with the preset left to the plan: {controls}")
    if plan["method"] not in methods or state["planMethod"] != plan["method"]:
        fail(f"the plan's method is not one the daemon offers: {plan}")
    if plan["meets_budget"] and plan["predicted_ms"] > 100.0:
        fail(f"a plan said to meet 100 ms predicts {plan['predicted_ms']} ms")
    if not controls["shown"].startswith(f"{plan['method']} {plan['preset']}") or controls["why"] != plan["why"]:
        fail(f"the panel does not show the plan: {controls}")

    def set_limit(field: str, value: str) -> None:
        tools.evaluate(f"(() => {{ const f = $('{field}'); f.value = '{value}';"
                       " f.dispatchEvent(new Event('change')); })()")

    # A target error as well: the plan is for both, and both fields keep their limit.
    frames = int(state["frames"])
    set_limit("budget-error", "0.5")
    state = wait_for_final(tools, frames, 180, "a frame time and a target error", plan=True)
    plan = json.loads(tools.evaluate("JSON.stringify(lastPlan)"))
    both = json.loads(tools.evaluate("JSON.stringify({ms: $('budget-ms').value, error: $('budget-error').value,"
                                     " budget: view.budget})"))
    print(json.dumps({"plan for 100 ms and relMSE 0.5": plan, "controls": both}))
    if both != {"ms": "100", "error": "0.5", "budget": {"max_ms": 100, "max_error": 0.5}}:
        fail(f"the controls do not show both limits of the budget: {both}")
    if "relMSE 0.5" not in plan["why"] or "100 ms" not in plan["why"]:
        fail(f"the stream did not plan for both 100 ms and relMSE 0.5: {plan['why']}")

    # The frame time emptied: the target error alone (a merge patch nulls the limit that went).
    frames = int(state["frames"])
    set_limit("budget-ms", "")
    state = wait_for_final(tools, frames, 180, "a target error", plan=True)
    plan = json.loads(tools.evaluate("JSON.stringify(lastPlan)"))
    print(json.dumps({"plan for relMSE 0.5": plan}))
    if "relMSE 0.5" not in plan["why"] or "100 ms" in plan["why"]:
        fail(f"the stream did not plan for relMSE 0.5 alone: {plan['why']}")
    if plan["meets_budget"] and plan["promised_error"] > 0.5:
        fail(f"a plan said to meet relMSE 0.5 promises {plan['promised_error']}")
    if plan["promised_error"] < plan["predicted_error"]:
        fail(f"a plan promises {plan['promised_error']}, under its estimate {plan['predicted_error']}")

    # Without the budget the stream keeps the plan's method and preset (its planned knobs go).
    frames = int(state["frames"])
    set_limit("budget-error", "")
    wait_for_final(tools, frames, 180, "budget removed", plan=False)
    kept = json.loads(tools.evaluate("JSON.stringify({method: $('method').value, preset: $('preset').value,"
                                     " preset_disabled: $('preset').disabled})"))
    if kept != {"method": plan["method"], "preset": plan["preset"], "preset_disabled": False}:
        fail(f"removing the budget did not keep the plan's method and preset: {kept}, plan {plan}")
    compare_with_daemon(tools, tcp_port, work, "viewer-after-budget.png", method=plan["method"], preset=plan["preset"])


def main() -> None:
    if len(sys.argv) not in (3, 4) or (len(sys.argv) == 4 and sys.argv[3] != "--budget"):
        fail(__doc__)
    bounced, chromium = sys.argv[1], sys.argv[2]
    budget = len(sys.argv) == 4
    if shutil.which(chromium) is None:
        fail(f"no {chromium}: scripts/install-deps installs Debian's chromium")
    work = tempfile.mkdtemp(prefix="bounce-viewer-")
    port_file = os.path.join(work, "ports")
    flags = ["--listen", "127.0.0.1:0", "--http-listen", "127.0.0.1:0", "--port-file", port_file, "--log-level", "warn"]
    if budget:
        # The cost model a budget needs, calibrated at its smallest and kept in this run's folder.
        flags += ["--cache-dir", os.path.join(work, "cache"), "--calibration-size", "16",
                  "--calibration-change-frames", "1"]
    daemon = subprocess.Popen([bounced, *flags])
    browser = None
    try:
        tcp_port, http_port = (int(p) for p in wait_for_file(port_file, 2, 60))
        url = f"http://127.0.0.1:{http_port}/?scene=cornell&format=png&refine=0&width={SIZE}&height={SIZE}"
        browser = subprocess.Popen([chromium, "--headless=new", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                                    "--no-first-run", "--remote-debugging-port=0", f"--user-data-dir={work}/profile",
                                    "--window-size=900,700", "--force-device-scale-factor=1", url],
                                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        active = wait_for_file(os.path.join(work, "profile", "DevToolsActivePort"), 1, 60)
        targets = json.load(urllib.request.urlopen(f"http://127.0.0.1:{active[0]}/json/list"))
        page = next(t for t in targets if t["type"] == "page")
        tools = DevTools(page["webSocketDebuggerUrl"])

        wait_for_final(tools, 0, 120, "the page's first stream")
        compare_with_daemon(tools, tcp_port, work, "viewer-screenshot.png")
        if budget:
            with Client(f"127.0.0.1:{tcp_port}") as client:
                methods = list(client.hello()["methods"])
            check_budget(tools, tcp_port, work, methods)
            print("PASS: the viewer plans its stream for a budget and keeps the plan when the budget goes")
            return
        print("PASS: the viewer shows the Cornell box as the daemon renders it")
    finally:
        if browser:
            browser.terminate()
            browser.wait(timeout=30)
        daemon.terminate()
        daemon.wait(timeout=30)
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
