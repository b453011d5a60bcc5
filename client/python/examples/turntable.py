#!/usr/bin/env python3
"""Renders a turntable: N views of a scene from a camera orbiting its centre, one file per view.

    PYTHONPATH=client/python python3 client/python/examples/turntable.py \\
        --scene cornell --views 24 --size 256x256 --out-dir turntable/

A render request names a camera of the scene but cannot carry one inline, so each view moves the
scene's camera with camera.set (position and look_at), then renders. camera.set changes the view
every client of that daemon renders by default; the script puts the camera back when it is done.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # run from anywhere in the checkout

from bounce import BounceError, Client, Router, parse_endpoints, read_token_file  # noqa: E402


def scene_sphere(description: dict) -> tuple[list[float], float]:
    """Centre and radius of a sphere around every object's bounds."""
    objects = description.get("objects") or []
    if not objects:
        return [0.0, 0.0, 0.0], 1.0
    low = [min(o["bounds_min"][axis] for o in objects) for axis in range(3)]
    high = [max(o["bounds_max"][axis] for o in objects) for axis in range(3)]
    centre = [(a + b) / 2 for a, b in zip(low, high)]
    radius = math.dist(low, high) / 2
    return centre, max(radius, 1e-3)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    parser.add_argument("--connect", default=os.environ.get("BOUNCE_CONNECT") or "127.0.0.1:7878",
                        metavar="HOST:PORT[,HOST:PORT...]")
    parser.add_argument("--token-file", default=os.environ.get("BOUNCE_TOKEN_FILE") or None)
    parser.add_argument("--scene", required=True)
    parser.add_argument("--views", type=int, default=12, help="number of views around the orbit [12]")
    parser.add_argument("--size", default="256x256", metavar="WxH")
    parser.add_argument("--method", default="direct")
    parser.add_argument("--preset")
    parser.add_argument("--format", choices=("png", "jpeg", "exr"), default="png")
    parser.add_argument("--elevation-deg", type=float, default=20.0, help="camera height above the centre [20]")
    parser.add_argument("--fov-deg", type=float, default=40.0, help="vertical field of view [40]")
    parser.add_argument("--out-dir", type=Path, default=Path("turntable"))
    args = parser.parse_args()
    width, height = (int(n) for n in args.size.split("x"))
    if args.views < 1:
        parser.error("--views must be at least 1")

    token = read_token_file(args.token_file) if args.token_file else None
    endpoints = parse_endpoints(args.connect)
    # Several daemons: the Router sends the scene's requests to the daemon that owns it.
    target = Router(endpoints, token) if len(endpoints) > 1 else Client(*endpoints[0], token=token)
    args.out_dir.mkdir(parents=True, exist_ok=True)
    extension = {"png": "png", "jpeg": "jpg", "exr": "exr"}[args.format]

    with target:
        description = target.describe(args.scene)
        centre, radius = scene_sphere(description)
        # Far enough that the bounding sphere fits the vertical field of view.
        distance = radius / math.sin(math.radians(args.fov_deg) / 2)
        saved = (description.get("cameras") or [None])[0]
        elevation = math.radians(args.elevation_deg)
        try:
            for view in range(args.views):
                azimuth = 2 * math.pi * view / args.views
                eye = [centre[0] + distance * math.cos(elevation) * math.sin(azimuth),
                       centre[1] + distance * math.sin(elevation),
                       centre[2] + distance * math.cos(elevation) * math.cos(azimuth)]
                target.camera(args.scene, position=eye, look_at=centre, fov_deg=args.fov_deg)
                # Requests of one connection run in order: this render sees the camera just set.
                image, stats = target.render(args.scene, method=args.method, preset=args.preset,
                                             width=width, height=height, format=args.format)
                path = args.out_dir / f"{args.scene}_{view:03d}.{extension}"
                path.write_bytes(image)
                print(f"{path}  {stats['timings_ms']['total']:.1f} ms")
        finally:
            if saved is not None:  # put the scene's view back as it was
                position = saved["position"]
                look_at = [p + f for p, f in zip(position, saved["forward"])]
                target.camera(args.scene, position=position, look_at=look_at, fov_deg=saved["fov_deg"])
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except BounceError as error:
        print(f"turntable: {error}", file=sys.stderr)
        sys.exit(1)
