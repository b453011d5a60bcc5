"""Rendezvous (highest-random-weight) hashing of scenes onto daemons.

Each daemon is known by its key, its numeric address "ip:port" ("[addr]:port" for IPv6). A scene
belongs to the key of highest weight(key, scene); a tie goes to the lexicographically smaller
key. When a daemon goes away only its own scenes move, each to the key that ranked second for it.

The C++ client computes the same function, so both must agree bit for bit:

    h = FNV-1a 64 (offset basis 0xcbf29ce484222325, prime 0x100000001b3) over
        UTF-8(key) + b"\\x00" + UTF-8(scene)
    weight = splitmix64 finalizer of h (all arithmetic mod 2**64)
"""

from __future__ import annotations

from collections.abc import Iterable

_MASK = 0xFFFFFFFFFFFFFFFF
FNV_OFFSET_BASIS = 0xCBF29CE484222325
FNV_PRIME = 0x100000001B3


def fnv1a64(data: bytes) -> int:
    """64-bit FNV-1a of `data`."""
    h = FNV_OFFSET_BASIS
    for byte in data:
        h = ((h ^ byte) * FNV_PRIME) & _MASK
    return h


def splitmix64_finalize(z: int) -> int:
    """The output mix of splitmix64: spreads every input bit over the whole word."""
    z &= _MASK
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & _MASK
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & _MASK
    return z ^ (z >> 31)


def weight(key: str, scene: str) -> int:
    """The weight of endpoint `key` for `scene`, an unsigned 64-bit integer."""
    # The 0x00 separator keeps ("ab", "c") and ("a", "bc") apart.
    return splitmix64_finalize(fnv1a64(key.encode("utf-8") + b"\x00" + scene.encode("utf-8")))


def rank(keys: Iterable[str], scene: str) -> list[str]:
    """`keys` in failover order for `scene`: descending weight, ties to the smaller key."""
    return sorted(set(keys), key=lambda key: (-weight(key, scene), key))


def owner(keys: Iterable[str], scene: str) -> str:
    """The key `scene` belongs to; ValueError when there are no keys."""
    ranked = rank(keys, scene)
    if not ranked:
        raise ValueError("no endpoints to choose from")
    return ranked[0]
