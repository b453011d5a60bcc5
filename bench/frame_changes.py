#!/usr/bin/python3
"""What a frame that redoes work costs beyond a warm one, from a bench/quality run (its relit_ms,
cold_ms and their shadow_maps pass, and dimmed_ms): per scene, method and preset, as multiples of the
warm frame (wall_ms), in all and less the shadow maps, and for a change of the lights' power alone;
then, per method and preset, the largest over the scenes, which the planner takes as its bound
before a scene measured its own (renderer/planning/bench_bounds.cpp, kMostChangeCost).

    bench/frame_changes.py OUT_CSV QUALITY_CSV...

Several runs are taken together (single frames right after a change vary by a third from run to
run): every row is kept, with its run's number, and the bounds are the largest over all of them. A
run without dimmed_ms has no light-power figure."""
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


def main(out: str, qualities: list) -> None:
    most = defaultdict(lambda: [0.0, 0.0, 0.0, 0.0, 0.0])
    with open(out, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["run", "scene", "method", "preset", "warm_ms", "relit_ms", "relit_shadow_ms", "cold_ms",
                         "cold_shadow_ms", "dimmed_ms", "lights", "lights_besides_maps", "knobs", "knobs_besides_maps",
                         "light_power"])
        for run, quality in enumerate(qualities, start=1):
            for r in csv.DictReader(open(quality)):
                if float(r.get("relit_ms") or 0) <= 0:
                    continue
                warm = float(r["wall_ms"])
                relit, relit_maps = float(r["relit_ms"]), float(r["relit_shadow_ms"])
                cold, cold_maps = float(r["cold_ms"]), float(r["cold_shadow_ms"])
                dimmed = float(r["dimmed_ms"]) if r.get("dimmed_ms") else None
                ratios = [max(0.0, (relit - warm) / warm), max(0.0, (relit - relit_maps - warm) / warm),
                          max(0.0, (cold - warm) / warm), max(0.0, (cold - cold_maps - warm) / warm),
                          max(0.0, (dimmed - warm) / warm) if dimmed is not None else 0.0]
                writer.writerow([run, r["scene"], r["method"], r["preset"], f"{warm:.2f}", f"{relit:.2f}",
                                 f"{relit_maps:.2f}", f"{cold:.2f}", f"{cold_maps:.2f}",
                                 f"{dimmed:.2f}" if dimmed is not None else ""] +
                                [f"{x:.3f}" for x in ratios[:4]] + [f"{ratios[4]:.3f}" if dimmed is not None else ""])
                key = (r["method"], r["preset"])
                most[key] = [max(a, b) for a, b in zip(most[key], ratios)]
    print("largest over the scenes and runs: lights, lights besides maps, knobs, knobs besides maps, light power")
    for (method, preset), values in sorted(most.items(), key=lambda kv: (kv[0][0], PRESETS.index(kv[0][1]))):
        print(f'    {{"{method}", "{preset}", ' + ", ".join(rounded_up(v) for v in values) + "},")


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit("usage: bench/frame_changes.py OUT_CSV QUALITY_CSV...")
    main(sys.argv[1], sys.argv[2:])
