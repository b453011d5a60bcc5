"""The Client against a real bounced (BOUNCED names the binary): hello, frames, mutations,
uploads, loads by path, errors, and a connection the daemon closed while it was idle."""

import shutil
import tempfile
import time
import unittest
from pathlib import Path

import support
from bounce import Client, ConnectionFailed, ServerError

daemon: support.Daemon
scene_root: Path


def setUpModule():
    global daemon, scene_root
    scene_root = support.scene_root_with_gltf()
    # A short heartbeat: the daemon pings while a frame is awaited, and closes idle connections soon.
    daemon = support.Daemon("--heartbeat-ms", "100", scene_root=scene_root)


def tearDownModule():
    daemon.stop()
    shutil.rmtree(scene_root, ignore_errors=True)


class ClientAgainstDaemon(unittest.TestCase):
    def setUp(self):
        self.client = Client("127.0.0.1", daemon.port, timeout=30)

    def tearDown(self):
        self.client.close()

    def test_hello(self):
        info = self.client.info
        self.assertTrue(info["server"].startswith("bounced/"), info)
        self.assertEqual(info["protocol"], 1)
        self.assertIn("direct", info["methods"])
        self.assertEqual(info["limits"]["max_json_bytes"], self.client.limits.max_json_bytes)
        self.assertEqual(info["limits"]["max_attachment_bytes"], self.client.limits.max_attachment_bytes)
        self.assertEqual(self.client.hello()["protocol"], 1)
        self.client.ping()

    def test_render_png(self):
        image, stats = self.client.render("cornell", method="direct", width=32, height=24)
        self.assertEqual(image[:8], support.PNG_SIGNATURE)
        self.assertEqual(support.png_size(image), (32, 24))
        self.assertEqual((stats["width"], stats["height"], stats["format"], stats["method"]), (32, 24, "png", "direct"))
        self.assertIn("total", stats["timings_ms"])

    def test_render_exr_and_jpeg(self):
        image, stats = self.client.render("cornell", method="direct", width=16, height=20, format="exr",
                                          knobs={"shadow_map_size": 256})
        self.assertEqual(support.exr_size(image), (16, 20))
        self.assertEqual(stats["knobs"]["shadow_map_size"], 256)
        image, stats = self.client.render("cornell", width=16, height=16, format="jpeg", exposure=1.0, tone="reinhard")
        self.assertEqual(image[:2], b"\xff\xd8")
        self.assertEqual(stats["format"], "jpeg")

    def test_mutations_count_scene_versions(self):
        self.client.load_builtin("cornell", "versions")
        try:
            first = self.client.move("versions", "short_block", translation=[0.05, 0.0, 0.1])["scene_version"]
            second = self.client.move("versions", "tall_block", rotation_deg=[0, 15, 0], scale=1.1)["scene_version"]
            third = self.client.light("versions", "ceiling_light", intensity=0.5, color=[1, 0.9, 0.8])["scene_version"]
            fourth = self.client.light("versions", "fill", type="point", position=[0.3, 0.3, 0.1],
                                       intensity=0.2)["scene_version"]
            fifth = self.client.camera("versions", position=[0.278, 0.273, -0.9], look_at=[0.278, 0.273, 0.0],
                                       fov_deg=45)["scene_version"]
            sixth = self.client.remove_light("versions", "fill")["scene_version"]
            self.assertEqual([first, second, third, fourth, fifth, sixth],
                             list(range(first, first + 6)))
            image, stats = self.client.render("versions", width=16, height=16, min_scene_version=sixth)
            self.assertEqual(stats["scene_version"], sixth)
            described = self.client.describe("versions")
            short_block = next(o for o in described["objects"] if o["name"] == "short_block")
            self.assertAlmostEqual(short_block["transform"][12], 0.1855 + 0.05, places=4)
            self.assertEqual([light["name"] for light in described["lights"]], ["ceiling_light"])
            self.assertEqual(described["cameras"][0]["fov_deg"], 45)
        finally:
            self.client.unload("versions")

    def test_upload_render_unload(self):
        reply = self.client.upload(support.make_glb("cube"), "uploaded")
        self.assertEqual(reply["objects"], 1)
        self.assertIn("uploaded", [scene["name"] for scene in self.client.list()])
        self.assertEqual([o["name"] for o in self.client.describe("uploaded")["objects"]], ["cube"])
        image, _ = self.client.render("uploaded", width=24, height=24)
        self.assertEqual(support.png_size(image), (24, 24))
        self.client.unload("uploaded")
        with self.assertRaises(ServerError) as caught:
            self.client.render("uploaded", width=8, height=8)
        self.assertEqual((caught.exception.code, caught.exception.field), ("not_found", "scene"))

    def test_upload_from_a_path(self):
        with tempfile.NamedTemporaryFile(suffix=".glb") as file:
            file.write(support.make_glb())
            file.flush()
            self.assertEqual(self.client.upload(file.name, "from_path")["triangles"], 12)
        self.client.unload("from_path")

    def test_load_by_path_inside_the_scene_root(self):
        reply = self.client.load("textured.gltf", "textured")
        self.assertEqual(reply["objects"], 1)
        image, _ = self.client.render("textured", width=16, height=16)
        self.assertEqual(support.png_size(image), (16, 16))
        self.client.unload("textured")
        with self.assertRaises(ServerError) as caught:
            self.client.load("../etc/passwd", "escape")
        self.assertEqual((caught.exception.code, caught.exception.field), ("bad_request", "path"))

    def test_errors_carry_code_message_field(self):
        with self.assertRaises(ServerError) as caught:
            self.client.render("no_such_scene", width=8, height=8)
        error = caught.exception
        self.assertEqual((error.code, error.field, error.retryable), ("not_found", "scene", False))
        self.assertIn("no_such_scene", error.message)
        with self.assertRaises(ServerError) as caught:
            self.client.render("cornell", method="no_such_method", width=8, height=8)
        self.assertEqual(caught.exception.code, "bad_request")
        self.assertIn("no_such_method", caught.exception.message)
        with self.assertRaises(ServerError) as caught:
            self.client.move("cornell", "short_block", scale=1e9)
        self.assertEqual((caught.exception.code, caught.exception.field), ("bad_request", "scale"))
        with self.assertRaises(ServerError) as caught:
            self.client.request(99)
        self.assertEqual(caught.exception.code, "unsupported")
        # The connection stays usable after every refusal.
        self.assertEqual(self.client.stats()["queue_depth"], 0)

    def test_bake_reports_progress(self):
        progress = []
        reply = self.client.bake("cornell", preset="draft", on_progress=progress.append)
        self.assertEqual(reply["method"], "cssm")
        self.assertTrue(progress, "no progress events")
        self.assertEqual(progress[-1]["fraction"], 1.0)

    def test_a_stream_refines_follows_its_camera_and_stops(self):
        view = {"position": [0.278, 0.273, -0.8], "look_at": [0.278, 0.273, 0.0], "fov_deg": 39.3}
        stream = self.client.stream_start("cornell", method="direct", width=32, height=32, format="png",
                                          camera=view, refine=False)
        draft, draft_body = self.client.next_frame(timeout=30)
        still, still_body = self.client.next_frame(timeout=30)
        self.assertEqual(support.png_size(draft), (16, 16))  # interactive_scale 0.5 by default
        self.assertEqual((draft_body["stream"]["id"], draft_body["stream"]["rung"]), (stream, 0))
        self.assertEqual((still_body["stream"]["rung"], still_body["stream"]["final"]), (1, True))
        # The still rung is the one-off frame of the same view, to the byte.
        one_off, _ = self.client.render("cornell", method="direct", width=32, height=32, camera=view)
        self.assertEqual(still, one_off)
        self.assertIsNone(self.client.next_frame(timeout=0.3))  # a still view sends nothing more

        moved = {"position": [0.1, 0.273, -0.8]}  # merged into the view: look_at and fov stay
        version = self.client.stream_update(stream, camera=moved)
        while True:
            image, body = self.client.next_frame(timeout=30)
            if body["stream"]["view_version"] >= version and body["stream"]["final"]:
                break
        one_off, _ = self.client.render("cornell", method="direct", width=32, height=32,
                                        camera={**view, **moved})
        self.assertEqual(image, one_off)
        self.assertNotEqual(image, still)

        stopped = self.client.stream_stop(stream)
        self.assertEqual(stopped["stream"], stream)
        self.assertGreaterEqual(stopped["frames"], 4)
        with self.assertRaises(ServerError) as caught:
            self.client.stream_update(stream, width=64)
        self.assertEqual((caught.exception.code, caught.exception.field), ("not_found", "stream"))

    def test_describe_with_the_scene_analysis(self):
        plain = self.client.describe("cornell")
        self.assertNotIn("analysis", plain)
        analysis = self.client.describe("cornell", analyze=True)["analysis"]
        bounces = analysis["bounces"]
        self.assertAlmostEqual(sum(bounces["share"]) + bounces["tail"], 1.0, places=9)
        # An open-fronted box of albedo about 0.6 keeps more than a tenth of its light past bounce 1.
        self.assertGreaterEqual(bounces["needed"]["0.02"], bounces["needed"]["0.1"])
        self.assertGreater(bounces["needed"]["0.1"], 1)
        self.assertEqual(set(analysis["thin_walls"]["presets"]), {"draft", "low", "medium", "high", "ultra"})
        self.assertFalse(any(p["leaks"] for p in analysis["thin_walls"]["presets"].values()))
        self.assertFalse(analysis["indirect_visibility"]["isr_unsuitable"])
        with self.assertRaises(ServerError) as caught:
            self.client.request("scene.describe", {"name": "cornell", "analyze": "yes"})
        self.assertEqual((caught.exception.code, caught.exception.field), ("bad_request", "analyze"))

    def test_generic_request(self):
        reply = self.client.request("scene.list")
        self.assertEqual(reply.name, "ok")
        self.assertIn("cornell", [scene["name"] for scene in reply.body["scenes"]])
        self.assertEqual(self.client.request("ping").name, "pong")

    def test_a_connection_the_daemon_closed_while_idle_is_reopened(self):
        before = self.client._sock
        time.sleep(0.6)  # past three heartbeats of 100 ms: the daemon hangs up
        self.assertTrue(self.client.list())
        self.assertIsNot(self.client._sock, before)

    def test_context_manager_closes(self):
        with Client(f"127.0.0.1:{daemon.port}") as client:
            client.ping()
        self.assertFalse(client.connected)
        with self.assertRaises(ConnectionFailed):
            client.ping()

    def test_a_refused_connection(self):
        with self.assertRaises(ConnectionFailed) as caught:
            Client("127.0.0.1", support.free_port())
        self.assertIsInstance(caught.exception, ConnectionError)


class Token(unittest.TestCase):
    def test_a_daemon_with_a_token(self):
        directory = Path(tempfile.mkdtemp(prefix="bounce-token-"))
        try:
            (directory / "token").write_text("s3cret-token-0123456789 \r\n")
            with support.Daemon("--token-file", str(directory / "token")) as guarded:
                with self.assertRaises(ServerError) as caught:
                    Client("127.0.0.1", guarded.port)
                self.assertEqual(caught.exception.code, "unauthorized")
                with Client("127.0.0.1", guarded.port, token="s3cret-token-0123456789") as client:
                    self.assertTrue(client.list())
                result = support.run_cli("--connect", guarded.key, "--token-file", str(directory / "token"), "list")
                self.assertEqual(result.returncode, 0, result.stderr)
                result = support.run_cli("--connect", guarded.key, "list")
                self.assertEqual(result.returncode, 1, result.stderr)
                self.assertIn(b"unauthorized", result.stderr)
        finally:
            shutil.rmtree(directory, ignore_errors=True)


if __name__ == "__main__":
    unittest.main()
