"""Scene affinity over three real daemons: placement by rendezvous hashing, renders through the
router, and failover when a scene's daemon dies or forgets the scene."""

import json
import shutil
import unittest
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import support
from bounce import Client, Router, rendezvous

daemons: list[support.Daemon] = []
scene_root: Path

TINY = {"method": "direct", "width": 32, "height": 32}


def setUpModule():
    global daemons, scene_root
    scene_root = support.scene_root_with_gltf()
    with ThreadPoolExecutor(3) as pool:  # start them side by side
        daemons = list(pool.map(lambda _: support.Daemon(scene_root=scene_root), range(3)))


def tearDownModule():
    for daemon in daemons:
        daemon.stop()
    shutil.rmtree(scene_root, ignore_errors=True)


def two_scenes_each(keys: list[str]) -> list[str]:
    """Six scene names, two owned by each daemon: every daemon has scenes to lose or keep, whatever
    ephemeral ports the daemons got."""
    names, owned = [], {key: 0 for key in keys}
    for i in range(1000):
        name = f"scene-{i}"
        owner = rendezvous.owner(keys, name)
        if owned[owner] < 2:
            owned[owner] += 1
            names.append(name)
    assert len(names) == 6, owned
    return names


def scenes_on(daemon: support.Daemon) -> set[str]:
    with Client("127.0.0.1", daemon.port) as client:
        return {scene["name"] for scene in client.list()} - {"cornell"}  # cornell is built into every one


class RouterAcrossDaemons(unittest.TestCase):
    def test_placement_renders_and_failover(self):
        keys = [daemon.key for daemon in daemons]
        by_key = {daemon.key: daemon for daemon in daemons}
        router = Router(",".join(keys), timeout=30)
        self.addCleanup(router.close)
        self.assertEqual(sorted(router.endpoints), sorted(keys))

        names = two_scenes_each(keys)
        path_scenes, upload_scenes = names[0::2], names[1::2]  # each daemon gets one of each kind
        for name in path_scenes:
            self.assertEqual(router.load("textured.gltf", name)["objects"], 1)
        for name in upload_scenes:
            self.assertEqual(router.upload(support.make_glb(), name)["objects"], 1)

        # Each scene lives on exactly one daemon: the one the hash predicts.
        predicted = {name: rendezvous.owner(keys, name) for name in names}
        placed = {daemon.key: scenes_on(daemon) for daemon in daemons}
        for name, owner in predicted.items():
            holders = [key for key, names in placed.items() if name in names]
            self.assertEqual(holders, [owner], name)
        self.assertEqual({router.owner(name) for name in names}, set(keys))

        # The router's list asks every daemon.
        listed = router.list()
        self.assertEqual(set(listed), set(keys))
        for key, scenes in listed.items():
            self.assertEqual({s["name"] for s in scenes} - {"cornell"}, placed[key])

        for name in predicted:
            image, stats = router.render(name, **TINY)
            self.assertEqual(support.png_size(image), (32, 32), name)

        # A moved object survives the failover: the router replays what it sent since the load.
        victim = upload_scenes[1]
        router.move(victim, "box", translation=[0.25, 0.0, 0.0])
        first_owner = predicted[victim]
        second_owner = rendezvous.rank(keys, victim)[1]
        by_key[first_owner].kill()

        image, stats = router.render(victim, **TINY)
        self.assertEqual(support.png_size(image), (32, 32))
        self.assertEqual(router.down, {first_owner})
        self.assertEqual(router.owner(victim), second_owner)
        self.assertIn(victim, scenes_on(by_key[second_owner]))
        box = router.describe(victim)["objects"][0]
        self.assertAlmostEqual(box["transform"][12], 0.25, places=5)

        # Scenes of the other daemons did not move; those of the dead one move on first use.
        for name, owner in predicted.items():
            if owner != first_owner:
                self.assertEqual(router.owner(name), owner, name)
            image, _ = router.render(name, **TINY)
            self.assertEqual(support.png_size(image), (32, 32), name)
        listed = router.list()
        self.assertIsNone(listed[first_owner])

        # A daemon that forgets a scene (restarted, say) gets it again from its source.
        survivor = next(name for name, owner in predicted.items() if owner != first_owner)
        with Client("127.0.0.1", by_key[router.owner(survivor)].port) as direct:
            direct.unload(survivor)
        image, _ = router.render(survivor, **TINY)
        self.assertEqual(support.png_size(image), (32, 32))

        # The CLI routes the same way and lists every daemon, the dead one as unreachable.
        result = support.run_cli("--connect", ",".join(keys), "list")
        self.assertEqual(result.returncode, 0, result.stderr)
        report = json.loads(result.stdout)
        self.assertEqual(report[first_owner], {"error": "unreachable"})
        alive = [key for key in keys if key != first_owner]
        for key in alive:
            self.assertIn("scenes", report[key])
        out_name = next(name for name, owner in predicted.items() if owner != first_owner)
        result = support.run_cli("--connect", ",".join(keys), "render", "--scene", out_name, "--size", "8x8",
                                 "-o", "-")
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertEqual(support.png_size(result.stdout), (8, 8))


if __name__ == "__main__":
    unittest.main()
