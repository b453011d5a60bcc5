"""`python3 -m bounce` and the turntable example against a real bounced."""

import json
import shutil
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

import support

daemon: support.Daemon
scene_root: Path
work: Path


def setUpModule():
    global daemon, scene_root, work
    scene_root = support.scene_root_with_gltf()
    work = Path(tempfile.mkdtemp(prefix="bounce-cli-"))
    daemon = support.Daemon(scene_root=scene_root)


def tearDownModule():
    daemon.stop()
    shutil.rmtree(scene_root, ignore_errors=True)
    shutil.rmtree(work, ignore_errors=True)


def bounce(*args: str, env=None) -> subprocess.CompletedProcess:
    return support.run_cli("--connect", daemon.key, *args, env=env)


class Cli(unittest.TestCase):
    def test_render_writes_a_frame_and_prints_its_stats(self):
        out = work / "frame.png"
        result = bounce("render", "--scene", "cornell", "--method", "direct", "--size", "32x32",
                        "--set", "shadow_map_size=256", "--tone", "reinhard", "--exposure", "-0.5", "-o", str(out))
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertEqual(support.png_size(out.read_bytes()), (32, 32))
        stats = json.loads(result.stdout)
        self.assertEqual((stats["width"], stats["knobs"]["shadow_map_size"]), (32, 256))

    def test_render_to_stdout_and_exr(self):
        result = bounce("render", "--scene", "cornell", "--size", "16x8", "-o", "-")
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertEqual(support.png_size(result.stdout), (16, 8))
        self.assertEqual(json.loads(result.stderr)["format"], "png")
        out = work / "frame.exr"
        result = bounce("render", "--scene", "cornell", "--size", "8x8", "-o", str(out))
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertEqual(support.exr_size(out.read_bytes()), (8, 8))

    def test_scene_commands(self):
        glb = work / "cube.glb"
        glb.write_bytes(support.make_glb())
        result = bounce("upload", str(glb), "--name", "cli_cube")
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertEqual(json.loads(result.stdout)["objects"], 1)
        result = bounce("load", "textured.gltf", "--name", "cli_textured")
        self.assertEqual(result.returncode, 0, result.stderr)
        result = bounce("move", "--scene", "cli_cube", "--object", "box", "--translate", "-0.5,0,0",
                        "--rotate-deg", "0,45,0", "--scale", "0.5")
        self.assertEqual(result.returncode, 0, result.stderr)
        first = json.loads(result.stdout)["scene_version"]
        result = bounce("light", "--scene", "cli_cube", "--light", "lamp", "--type", "spot",
                        "--position", "0,2,2", "--direction", "0,-1,-1", "--color", "1,0.5,0.5", "--intensity", "3")
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertEqual(json.loads(result.stdout)["scene_version"], first + 1)
        result = bounce("list")
        names = [scene["name"] for scene in json.loads(result.stdout)["scenes"]]
        self.assertTrue({"cornell", "cli_cube", "cli_textured"} <= set(names), names)
        result = bounce("describe", "--scene", "cli_cube")
        self.assertEqual(json.loads(result.stdout)["lights"][0]["type"], "spot")
        result = bounce("stats")
        self.assertIn("gpu_memory", json.loads(result.stdout))

    def test_environment_defaults(self):
        result = support.run_cli("list", env=support.cli_env(BOUNCE_CONNECT=daemon.key))
        self.assertEqual(result.returncode, 0, result.stderr)

    def test_exit_codes(self):
        self.assertEqual(support.run_cli("--version").returncode, 0)
        self.assertEqual(support.run_cli("render", "--help").returncode, 0)
        unknown = bounce("render", "--scene", "cornell", "--bogus", "1", "-o", str(work / "x.png"))
        self.assertEqual(unknown.returncode, 2)
        self.assertIn(b"--bogus", unknown.stderr)
        self.assertEqual(bounce("list", "--scene", "cornell").returncode, 2)  # list takes no options
        refused = support.run_cli("--connect", f"127.0.0.1:{support.free_port()}", "list")
        self.assertEqual(refused.returncode, 3, refused.stderr)
        missing = bounce("render", "--scene", "no_such_scene", "--size", "8x8", "-o", str(work / "x.png"))
        self.assertEqual(missing.returncode, 1)
        self.assertIn(b"not_found", missing.stderr)
        self.assertFalse((work / "x.png").exists())
        bad_method = bounce("render", "--scene", "cornell", "--method", "nope", "-o", str(work / "x.png"))
        self.assertEqual(bad_method.returncode, 1)
        self.assertIn(b"bad_request", bad_method.stderr)

    def test_turntable_example_runs(self):
        out = work / "turntable"
        result = subprocess.run(
            [sys.executable, str(support.PYTHON_ROOT / "examples" / "turntable.py"), "--connect", daemon.key,
             "--scene", "cornell", "--views", "3", "--size", "24x16", "--out-dir", str(out)],
            capture_output=True, env=support.cli_env(), timeout=60)
        self.assertEqual(result.returncode, 0, result.stderr)
        frames = sorted(out.glob("cornell_*.png"))
        self.assertEqual(len(frames), 3)
        self.assertEqual({support.png_size(frame.read_bytes()) for frame in frames}, {(24, 16)})
        self.assertEqual(len({frame.read_bytes() for frame in frames}), 3, "the views should differ")


if __name__ == "__main__":
    unittest.main()
