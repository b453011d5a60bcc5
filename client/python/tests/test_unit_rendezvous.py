"""Rendezvous hashing: the weight vectors the C++ client must reproduce, and the routing rules."""

import ctypes
import unittest

import support  # noqa: F401  (puts the package on sys.path)
from bounce import rendezvous
from bounce.router import resolve_endpoints

# weight(key, scene) for the vectors the C++ client is checked against (hex, 64-bit).
VECTORS = [
    ("127.0.0.1:7878", "cornell", 0xDAD35017D9228FD2),
    ("[::1]:7878", "cornell", 0x0E3B98BA5962E6A9),
    ("10.0.0.2:7878", "atrium", 0x9D0E179C8BFEEFD2),
]


def straightforward_weight(key: str, scene: str) -> int:
    """The specification written out again with C-style unsigned 64-bit arithmetic (ctypes
    wraps on overflow), independent of the package's masking."""
    u64 = ctypes.c_uint64
    h = u64(0xCBF29CE484222325)
    for byte in key.encode("utf-8") + bytes([0]) + scene.encode("utf-8"):
        h = u64(h.value ^ byte)
        h = u64(h.value * 0x100000001B3)
    z = h
    z = u64((z.value ^ (z.value >> 30)) * 0xBF58476D1CE4E5B9)
    z = u64((z.value ^ (z.value >> 27)) * 0x94D049BB133111EB)
    return u64(z.value ^ (z.value >> 31)).value


class WeightVectors(unittest.TestCase):
    def test_vectors(self):
        for key, scene, expected in VECTORS:
            with self.subTest(key=key, scene=scene):
                self.assertEqual(rendezvous.weight(key, scene), expected,
                                 f"weight({key!r}, {scene!r}) = {rendezvous.weight(key, scene):#018x}")

    def test_vectors_match_a_straightforward_computation(self):
        for key, scene, expected in VECTORS:
            with self.subTest(key=key, scene=scene):
                self.assertEqual(straightforward_weight(key, scene), expected)

    def test_agrees_with_the_straightforward_computation_elsewhere(self):
        for key in ("127.0.0.1:1", "[fe80::1]:7878", "10.1.2.3:65535", "ünïcode:1"):
            for scene in ("", "a", "cornell", "scène/ü", "x" * 300):
                self.assertEqual(rendezvous.weight(key, scene), straightforward_weight(key, scene))

    def test_fnv1a_known_values(self):
        # Published FNV-1a 64 test vectors.
        self.assertEqual(rendezvous.fnv1a64(b""), 0xCBF29CE484222325)
        self.assertEqual(rendezvous.fnv1a64(b"a"), 0xAF63DC4C8601EC8C)
        self.assertEqual(rendezvous.fnv1a64(b"foobar"), 0x85944171F73967E8)

    def test_the_separator_keeps_key_and_scene_apart(self):
        self.assertNotEqual(rendezvous.weight("ab", "c"), rendezvous.weight("a", "bc"))


class Ranking(unittest.TestCase):
    KEYS = [f"10.0.0.{i}:7878" for i in range(1, 6)]

    def test_rank_is_descending_weight(self):
        for scene in ("cornell", "atrium", "sponza"):
            ranked = rendezvous.rank(self.KEYS, scene)
            weights = [rendezvous.weight(key, scene) for key in ranked]
            self.assertEqual(weights, sorted(weights, reverse=True))
            self.assertEqual(rendezvous.owner(self.KEYS, scene), ranked[0])

    def test_ties_go_to_the_smaller_key(self):
        original = rendezvous.weight
        rendezvous.weight = lambda key, scene: 7  # every key ties
        try:
            self.assertEqual(rendezvous.rank(["b:1", "a:1", "c:1"], "s"), ["a:1", "b:1", "c:1"])
        finally:
            rendezvous.weight = original

    def test_removing_a_key_moves_only_its_scenes_to_their_second_choice(self):
        scenes = [f"scene-{i}" for i in range(300)]
        before = {scene: rendezvous.rank(self.KEYS, scene) for scene in scenes}
        gone = self.KEYS[2]
        remaining = [key for key in self.KEYS if key != gone]
        for scene in scenes:
            after = rendezvous.owner(remaining, scene)
            expected = before[scene][1] if before[scene][0] == gone else before[scene][0]
            self.assertEqual(after, expected, scene)
        # And the keys share the scenes roughly evenly.
        counts = [sum(1 for s in scenes if before[s][0] == key) for key in self.KEYS]
        self.assertTrue(all(30 <= count <= 90 for count in counts), counts)

    def test_no_keys(self):
        with self.assertRaises(ValueError):
            rendezvous.owner([], "cornell")


class Endpoints(unittest.TestCase):
    def test_keys_are_numeric_addresses_without_duplicates(self):
        endpoints = resolve_endpoints("127.0.0.1:7878, [::1]:7878,127.0.0.1:7878,[0:0::1]:7879")
        self.assertEqual(list(endpoints), ["127.0.0.1:7878", "[::1]:7878", "[::1]:7879"])
        self.assertEqual(endpoints["[::1]:7878"], ("::1", 7878))

    def test_a_name_becomes_one_endpoint_per_address(self):
        endpoints = resolve_endpoints(["localhost:7878"])
        self.assertGreaterEqual(len(endpoints), 1)
        for key in endpoints:
            self.assertTrue(key in ("127.0.0.1:7878", "[::1]:7878") or key.endswith(":7878"), key)
            self.assertFalse(key.startswith("localhost"))

    def test_pairs_are_accepted(self):
        self.assertEqual(list(resolve_endpoints([("127.0.0.1", 1), "127.0.0.2:2"])), ["127.0.0.1:1", "127.0.0.2:2"])

    def test_bad_specs(self):
        from bounce import parse_endpoint
        for bad in ("", "host", "host:0", "host:70000", "host:x", "::1:7878", "[::1"):
            with self.subTest(spec=bad), self.assertRaises(ValueError):
                parse_endpoint(bad)
        self.assertEqual(parse_endpoint("[::1]:7878"), ("::1", 7878))
        self.assertEqual(parse_endpoint("example.org:1"), ("example.org", 1))


if __name__ == "__main__":
    unittest.main()
