"""The Router's bookkeeping without daemons: ownership with endpoints down, and the mutation log
it replays after a failover."""

import unittest

import support
from bounce import ConnectionFailed, Router, rendezvous
from bounce.router import _Edits


class Ownership(unittest.TestCase):
    def test_a_down_endpoint_hands_its_scenes_to_their_second_choice(self):
        keys = ["127.0.0.1:7001", "127.0.0.1:7002", "127.0.0.1:7003"]
        router = Router(keys)
        self.assertEqual(router.endpoints, keys)
        for scene in ("a", "b", "c", "d", "e"):
            self.assertEqual(router.owner(scene), rendezvous.owner(keys, scene))
        gone = router.owner("a")
        router.mark_down(gone)
        self.assertEqual(router.owner("a"), rendezvous.rank(keys, "a")[1])
        router.refresh()
        self.assertEqual(router.owner("a"), gone)
        for key in keys:
            router.mark_down(key)
        with self.assertRaises(ConnectionFailed):
            router.owner("a")

    def test_unreachable_owners_are_marked_down_on_the_way(self):
        ports = [support.free_port() for _ in range(2)]
        with Router([("127.0.0.1", port) for port in ports], connect_timeout=2) as router:
            with self.assertRaises(ConnectionFailed):
                router.render("cornell")
            self.assertEqual(router.down, set(router.endpoints))
            self.assertEqual(router.list(), {key: None for key in router.endpoints})

    def test_a_request_needs_a_scene_to_route_by(self):
        with self.assertRaises(ValueError):
            Router("127.0.0.1:1").request("stats")


class EditLog(unittest.TestCase):
    def test_transforms_keep_the_last_per_object(self):
        edits = _Edits()
        edits.record("object.set_transform", {"scene": "s", "object": "a", "translation": [1, 0, 0]})
        edits.record("object.set_transform", {"scene": "s", "object": "b", "scale": 2.0})
        edits.record("object.set_transform", {"scene": "s", "object": "a", "rotation_deg": [0, 90, 0]})
        self.assertEqual(edits.replay(), [
            ("object.set_transform", {"scene": "s", "object": "b", "scale": 2.0}),
            ("object.set_transform", {"scene": "s", "object": "a", "rotation_deg": [0, 90, 0]})])

    def test_light_sets_merge_and_a_remove_supersedes(self):
        edits = _Edits()
        edits.record("light.set", {"scene": "s", "light": "l", "intensity": 1.0})
        edits.record("light.set", {"scene": "s", "light": "l", "color": [1, 0, 0]})
        self.assertEqual(edits.replay(), [("light.set", {"scene": "s", "light": "l", "intensity": 1.0,
                                                         "color": [1, 0, 0]})])
        edits.record("light.remove", {"scene": "s", "light": "l"})
        edits.record("light.set", {"scene": "s", "light": "l", "type": "spot"})
        self.assertEqual(edits.replay(), [("light.remove", {"scene": "s", "light": "l"}),
                                          ("light.set", {"scene": "s", "light": "l", "type": "spot"})])

    def test_full_camera_views_replace_each_other(self):
        edits = _Edits()
        edits.record("camera.set", {"scene": "s", "fov_deg": 30.0})
        for x in range(50):  # a turntable
            edits.record("camera.set", {"scene": "s", "position": [x, 0, 0], "look_at": [0, 0, 0]})
        self.assertEqual(edits.replay(), [("camera.set", {"scene": "s", "fov_deg": 30.0, "position": [49, 0, 0],
                                                          "look_at": [0, 0, 0]})])
        edits.record("camera.set", {"scene": "s", "camera": "top"})
        edits.record("camera.set", {"scene": "s", "position": [0, 1, 0], "look_at": [0, 0, 0]})
        self.assertEqual(len(edits.replay()), 3)  # a named camera is kept in order


if __name__ == "__main__":
    unittest.main()
