#!/usr/bin/python3
"""What a frame that redoes work costs beyond a warm one, from a bench/quality run (its relit_ms,
cold_ms and their shadow_maps pass): per scene, method and preset, as multiples of the warm frame
(wall_ms), in all and less the shadow maps; then, per method and preset, the largest over the
scenes, which the planner takes as its bound before a scene measured its own (planner.cpp,
kMostChangeCost).

    bench/frame_changes.py QUALITY_CSV [OUT_CSV]

OUT_CSV defaults to bench/results/corpus/frame_changes.csv."""
import csv
import math
import sys
from collections import defaultdict

PRESETS = ["draft", "low", "medium", "high", "ultra"]


def rounded_up(x: float) -> str:
    """x to three significant digits, rounded up: the table holds bounds."""
    if x <= 0:
        return "0.0"
    step = 10.0 ** (math.floor(math.log10(x)) - 2)
    return f"{math.ceil(x / step - 1e-9) * step:.6g}"


def main(quality: str, out: str) -> None:
    rows = [r for r in csv.DictReader(open(quality)) if float(r.get("relit_ms") or 0) > 0]
    most = defaultdict(lambda: [0.0, 0.0, 0.0, 0.0])
    with open(out, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["scene", "method", "preset", "warm_ms", "relit_ms", "relit_shadow_ms", "cold_ms",
                         "cold_shadow_ms", "lights", "lights_besides_maps", "knobs", "knobs_besides_maps"])
        for r in rows:
            warm = float(r["wall_ms"])
            relit, relit_maps = float(r["relit_ms"]), float(r["relit_shadow_ms"])
            cold, cold_maps = float(r["cold_ms"]), float(r["cold_shadow_ms"])
            ratios = [max(0.0, (relit - warm) / warm), max(0.0, (relit - relit_maps - warm) / warm),
                      max(0.0, (cold - warm) / warm), max(0.0, (cold - cold_maps - warm) / warm)]
            writer.writerow([r["scene"], r["method"], r["preset"], f"{warm:.2f}", f"{relit:.2f}", f"{relit_maps:.2f}",
                             f"{cold:.2f}", f"{cold_maps:.2f}"] + [f"{x:.3f}" for x in ratios])
            key = (r["method"], r["preset"])
            most[key] = [max(a, b) for a, b in zip(most[key], ratios)]
    print("largest over the scenes: lights, lights besides maps, knobs, knobs besides maps")
    for (method, preset), values in sorted(most.items(), key=lambda kv: (kv[0][0], PRESETS.index(kv[0][1]))):
        print(f'    {{"{method}", "{preset}", ' + ", ".join(rounded_up(v) for v in values) + "},")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else "bench/results/corpus/frame_changes.csv")
