"""The wire format and how the client reads replies, against a scripted fake daemon (no GL)."""

import contextlib
import io
import struct
import time
import tempfile
import unittest

import support
from bounce import Client, ConnectionFailed, ProtocolError, ServerError, protocol
from bounce.cli import main


def cli_main(argv):
    """The CLI's exit code, its output kept off the test log."""
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        return main(argv)


class Frames(unittest.TestCase):
    def test_header_layout(self):
        frame = protocol.encode(protocol.message_type("render"), 0x0102030405060708, {"scene": "a"}, b"xyz")
        self.assertEqual(frame[:4], b"BNCE")
        magic, version, kind, request_id, json_length, attachment_length = struct.unpack("<4sHHQII", frame[:24])
        self.assertEqual((version, kind, request_id), (1, 24, 0x0102030405060708))
        self.assertEqual(frame[24:24 + json_length], b'{"scene":"a"}')
        self.assertEqual(frame[24 + json_length:], b"xyz")
        self.assertEqual(attachment_length, 3)

    def test_an_empty_body_has_length_zero_and_reads_as_an_object(self):
        frame = protocol.encode(protocol.PING, 1)
        self.assertEqual(len(frame), protocol.HEADER_SIZE)
        header = protocol.decode_header(frame, protocol.Limits())
        self.assertEqual((header.json_length, header.attachment_length), (0, 0))
        self.assertEqual(protocol.decode_body(b""), {})

    def test_limits_are_checked_from_the_header(self):
        header = struct.pack("<4sHHQII", b"BNCE", 1, 2, 9, 2_000_000, 0)
        with self.assertRaises(protocol.FrameError) as caught:
            protocol.decode_header(header, protocol.Limits(max_json_bytes=1 << 20))
        self.assertEqual(caught.exception.request_id, 9)
        with self.assertRaises(protocol.FrameError):
            protocol.decode_header(struct.pack("<4sHHQII", b"BNCX", 1, 2, 9, 0, 0), protocol.Limits())
        with self.assertRaises(protocol.FrameError):
            protocol.decode_header(struct.pack("<4sHHQII", b"BNCE", 2, 2, 9, 0, 0), protocol.Limits())

    def test_bodies_must_be_objects_and_numbers_finite(self):
        for bad in (b"[1]", b"{", b"\xff"):
            with self.assertRaises(protocol.FrameError):
                protocol.decode_body(bad)
        with self.assertRaises(ValueError):
            protocol.encode_body({"exposure": float("nan")})

    def test_non_ascii_is_sent_as_utf8(self):
        self.assertEqual(protocol.encode_body({"name": "scène"}), '{"name":"scène"}'.encode())


class ClientReads(unittest.TestCase):
    def test_pings_are_answered_and_progress_reported_while_waiting(self):
        def script(conn):
            conn.greet()
            request = conn.read()
            assert request.name == "bake" and request.body["scene"] == "s", request
            conn.send("ping", 0)
            pong = conn.read()
            assert pong.name == "pong" and pong.request_id == 0, pong
            conn.send("progress", request.request_id, {"fraction": 0.5, "stage": "maps"})
            conn.send("ok", request.request_id + 100, {"late": True})  # another request's reply
            conn.send("ok", request.request_id, {"bake_ms": 1.0})

        progress = []
        with support.FakeDaemon(script) as fake, Client("127.0.0.1", fake.port) as client:
            self.assertEqual(client.info["server"], "fake/0")
            self.assertEqual(client.bake("s", on_progress=progress.append), {"bake_ms": 1.0})
        self.assertEqual(progress, [{"fraction": 0.5, "stage": "maps"}])

    def test_a_ping_that_came_while_idle_is_answered_before_the_next_request(self):
        def script(conn):
            conn.greet()
            conn.send("ping", 0)
            pong = conn.read()
            assert pong.name == "pong", pong
            request = conn.read()
            conn.send("ok", request.request_id, {"queue_depth": 0})

        with support.FakeDaemon(script) as fake, Client("127.0.0.1", fake.port, timeout=5) as client:
            time.sleep(0.2)  # the ping arrives while the client waits on nothing
            started = time.monotonic()
            self.assertEqual(client.stats(), {"queue_depth": 0})
            self.assertLess(time.monotonic() - started, 2.0)

    def test_error_replies_raise_server_error(self):
        def script(conn):
            conn.greet()
            request = conn.read()
            conn.send("error", request.request_id, {"code": "bad_request", "message": "field 'width' is 0",
                                                    "field": "width", "retryable": False})
            request = conn.read()
            conn.send("error", request.request_id, {"code": "busy", "message": "queue full", "retryable": True})

        with support.FakeDaemon(script) as fake, Client("127.0.0.1", fake.port) as client:
            with self.assertRaises(ServerError) as caught:
                client.render("s", width=0)
            error = caught.exception
            self.assertEqual((error.code, error.field, error.retryable, error.request_type),
                             ("bad_request", "width", False, "render"))
            self.assertIn("width", error.message)
            with self.assertRaises(ServerError) as caught:
                client.stats()
            self.assertTrue(caught.exception.retryable)

    def test_a_reply_past_the_announced_limits_is_refused_before_it_is_read(self):
        def script(conn):
            conn.greet(limits={"max_json_bytes": 4096, "max_attachment_bytes": 1000})
            request = conn.read()
            # Announces 3 GiB of attachment and sends none of it.
            conn.send_raw(struct.pack("<4sHHQII", b"BNCE", 1, 4, request.request_id, 0, 3 << 30))

        with support.FakeDaemon(script) as fake, Client("127.0.0.1", fake.port) as client:
            with self.assertRaises(ProtocolError) as caught:
                client.render("s")
            self.assertIn("exceeds the limit of 1000", str(caught.exception))
            self.assertFalse(client.connected)

    def test_a_wrong_magic_closes_the_connection(self):
        def script(conn):
            conn.greet()
            conn.read()
            conn.send_raw(b"HTTP/1.1 400 Bad Request\r\n\r\n")

        with support.FakeDaemon(script) as fake, Client("127.0.0.1", fake.port) as client:
            with self.assertRaises(ProtocolError):
                client.stats()
            self.assertFalse(client.connected)

    def test_a_connection_closed_mid_request_is_a_connection_failure(self):
        def script(conn):
            conn.greet()
            conn.read()

        with support.FakeDaemon(script) as fake, Client("127.0.0.1", fake.port) as client:
            with self.assertRaises(ConnectionFailed) as caught:
                client.stats()
            self.assertIsInstance(caught.exception, ConnectionError)

    def test_the_token_goes_in_hello(self):
        def script(conn):
            hello = conn.read()
            assert hello.body == {"client": "bounce-python/0.1.0", "protocol": 1, "token": "s3cret"}, hello.body
            conn.send("error", hello.request_id, {"code": "unauthorized", "message": "no", "field": "token",
                                                  "retryable": False})

        with support.FakeDaemon(script) as fake:
            with self.assertRaises(ServerError) as caught:
                Client("127.0.0.1", fake.port, token="s3cret")
            self.assertEqual(caught.exception.code, "unauthorized")

    def test_an_oversized_upload_is_refused_before_sending(self):
        def script(conn):
            conn.greet(limits={"max_json_bytes": 4096, "max_attachment_bytes": 10})

        with support.FakeDaemon(script) as fake, Client("127.0.0.1", fake.port) as client:
            with self.assertRaises(ValueError):
                client.upload(b"x" * 11, "big")


class CliExitCodes(unittest.TestCase):
    def _exit_code_for(self, error_body):
        def script(conn):
            conn.greet()
            request = conn.read()
            conn.send("error", request.request_id, error_body)

        with support.FakeDaemon(script) as fake:
            return cli_main(["--connect", f"127.0.0.1:{fake.port}", "stats"])

    def test_retryable_errors_exit_4_and_others_1(self):
        self.assertEqual(self._exit_code_for({"code": "busy", "message": "queue full", "retryable": True}), 4)
        self.assertEqual(self._exit_code_for({"code": "timeout", "message": "late"}), 4)
        self.assertEqual(self._exit_code_for({"code": "shutting_down", "message": "bye", "retryable": True}), 4)
        self.assertEqual(self._exit_code_for({"code": "not_found", "message": "no", "retryable": False}), 1)

    def test_usage_errors_exit_2(self):
        self.assertEqual(cli_main(["render", "--scene", "s", "-o", "x.gif"]), 2)
        self.assertEqual(cli_main(["render", "--scene", "s", "--presett", "high", "-o", "x.png"]), 2)
        self.assertEqual(cli_main(["render", "--scene", "s", "--pre", "high", "-o", "x.png"]), 2)  # no abbreviations
        self.assertEqual(cli_main(["move", "--scene", "s", "--object", "o", "--translate", "1,2"]), 2)
        self.assertEqual(cli_main(["--connect", "nonsense", "list"]), 2)
        self.assertEqual(cli_main([]), 2)

    def test_a_value_may_start_with_a_dash(self):
        def script(conn):
            conn.greet()
            request = conn.read()
            assert request.body["translation"] == [-1.0, 0.0, 0.5], request.body
            conn.send("ok", request.request_id, {"scene_version": 1})

        with support.FakeDaemon(script) as fake:
            self.assertEqual(cli_main(["--connect", f"127.0.0.1:{fake.port}", "move", "--scene", "s",
                                       "--object", "o", "--translate", "-1,0,0.5"]), 0)


if __name__ == "__main__":
    unittest.main()


class Budgets(unittest.TestCase):
    def test_the_cli_sends_a_budget_as_method_auto(self):
        seen = []

        def script(conn):
            conn.greet()
            request = conn.read()
            seen.append(request.body)
            conn.send("error", request.request_id, {"code": "not_found", "message": "no scene", "retryable": False})

        with support.FakeDaemon(script) as fake:
            cli_main(["--connect", f"127.0.0.1:{fake.port}", "render", "--scene", "s", "--budget-ms", "50",
                      "--target-error", "0.05", "-o", "x.png"])
        self.assertEqual(seen[0]["budget"], {"max_ms": 50.0, "max_error": 0.05})
        self.assertEqual(seen[0]["method"], "auto")

    def test_watch_starts_a_stream_with_its_budget(self):
        seen = []

        def script(conn):
            conn.greet()
            request = conn.read()
            seen.append((request.type, request.body))
            conn.send("error", request.request_id, {"code": "not_found", "message": "no scene", "retryable": False})

        with support.FakeDaemon(script) as fake, tempfile.TemporaryDirectory() as out:
            cli_main(["--connect", f"127.0.0.1:{fake.port}", "watch", "--scene", "s", "--target-error", "0.05",
                      "--frames", "1", "-o", out])
        self.assertEqual(seen[0][1]["budget"], {"max_error": 0.05})
        self.assertEqual(seen[0][1]["method"], "auto")

    def test_a_named_method_with_a_budget_is_kept(self):
        from bounce.client import render_body
        body = render_body("s", method="vct", budget={"max_error": 0.1})
        self.assertEqual((body["method"], body["budget"]), ("vct", {"max_error": 0.1}))
        self.assertEqual(cli_main(["render", "--scene", "s", "--budget-ms", "fast", "-o", "x.png"]), 2)
