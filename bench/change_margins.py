#!/usr/bin/python3
"""How far the device's calibration of what changes redo (ChangeCost, measured on the Cornell box)
fell short of what the bench corpus's frames redid, per method and change: the margin the planner
adds, in warm frames at 128x128 of the scene (renderer/planning/bench_bounds.cpp, kChangeMargin).

    bench/change_margins.py FRAME_CHANGES_CSV COST_MODEL_JSON

FRAME_CHANGES_CSV is bench/frame_changes.py's output (every corpus scene, method and preset, one row
a run); COST_MODEL_JSON the cost model calibrated on the same machine (the daemon's or the bench's
cache folder, cost-model/). Each row's time beyond its warm frame, less its shadow maps (a scene
prices those from its own timings), is set against the calibration's multiple times the scene's warm
frame at the calibration's size (the warm frame at 128x128 scaled by the device's line between the
two sizes). Preset switches leave out draft, whose first frame in the bench also compiled its
method's shaders, which a daemon does once.

Then each row's time as a multiple of the calibration's price of it (the scale planner.cpp's
scene_scale_of_calibration learns from a scene's frames of a method's other presets), per method and
change, and per scene for switches; rows whose price is under a twentieth of their warm frame are
left out, as the planner leaves them out.

Last, how far a move of the lights falls short of its price when the scene has no such frame yet:
priced as the planner prices it, the calibration scaled by the scene's switches (the median, at least
1), against the calibration plus the margin above."""
import csv
import json
import math
import sys
from collections import defaultdict


def main(frame_changes: str, cost_model: str) -> None:
    model = json.load(open(cost_model))
    lines = {(l["method"], l["preset"]): l for l in model["lines"]}
    changes = {(c["method"], c["preset"]): c for c in model["changes"]}
    at = lambda line, pixels: line["fixed_ms"] + line["per_megapixel_ms"] * pixels * 1e-6
    scales, scene_scales = defaultdict(list), defaultdict(list)
    short = defaultdict(list)  # (method, change) -> (shortfall in warm frames, preset, scene, run)
    # Each row with its preset's calibrated figures, its warm frame, and that frame at the calibration's size.
    frames = []
    for r in csv.DictReader(open(frame_changes)):
        key = (r["method"], r["preset"])
        line, cost = lines[key], changes[key]
        warm = float(r["warm_ms"])
        frames.append((r, cost, warm, warm * at(line, cost["pixels"]) / at(line, 128 * 128)))
    for r, cost, warm, warm_there in frames:
        measured = {"lights": float(r["relit_ms"]) - float(r["relit_shadow_ms"]) - warm,
                    "knobs": float(r["cold_ms"]) - float(r["cold_shadow_ms"]) - warm}
        predicted = {"lights": cost["lights"], "knobs": max(cost["lights"], cost["rebuild"])}
        if r["dimmed_ms"]:
            measured["light_power"] = float(r["dimmed_ms"]) - warm
            predicted["light_power"] = cost["light_power"]
        for change, ms in measured.items():
            if change == "knobs" and r["preset"] == "draft":
                continue
            priced = predicted[change] * warm_there
            if priced >= 0.05 * warm:
                scales[(r["method"], change)].append((max(0.0, ms) / priced, r["preset"]))
                if change == "knobs":
                    scene_scales[(r["method"], r["scene"])].append((max(0.0, ms) / priced, r["preset"]))
            short[(r["method"], change)].append(((max(0.0, ms) - predicted[change] * warm_there) / warm,
                                                 r["preset"], r["scene"], r["run"]))
    print("largest shortfall, in warm frames at 128x128 (preset, scene, run); then the table, rounded up to 0.1")
    margins = defaultdict(dict)
    for (method, change), rows in sorted(short.items()):
        worst = max(rows)
        print(f"  {method:7} {change:12} {worst[0]:6.2f}  ({worst[1]}, {worst[2]}, run {worst[3]})")
        margins[method][change] = max(0.0, math.ceil(worst[0] * 10 - 1e-9) / 10)
    for method, m in margins.items():
        # A switch redoes the lights' work too: never under their margin.
        knobs = max(m.get("knobs", 0.0), m.get("lights", 0.0))
        print(f'    {{"{method}", {m.get("lights", 0.0):.1f}, {knobs:.1f}, {m.get("light_power", 0.0):.1f}}},')
    print("measured / the calibration's price, besides maps: smallest, median, largest (rows)")
    for key, rows in sorted(scales.items()):
        values = sorted(v for v, _ in rows)
        print(f"  {key[0]:7} {key[1]:12} {values[0]:6.2f} {values[len(values) // 2]:6.2f} {values[-1]:6.2f}  ({len(values)})")
    print("switches, per scene: preset initial and scale")
    for (method, scene), rows in sorted(scene_scales.items()):
        print(f"  {method:7} {scene:15} " + " ".join(f"{preset[0]}:{value:.1f}" for value, preset in rows))
    # A move of the lights priced as the planner prices it before the scene has a frame of one: the
    # calibration scaled by the median of the scene's switches (of its run), at least 1, besides the
    # maps; against the calibration plus the margin these frames measure (the most they fell short by).
    switch_scale = defaultdict(list)
    for r, cost, warm, warm_there in frames:
        priced = max(cost["lights"], cost["rebuild"]) * warm_there
        if r["preset"] != "draft" and priced >= 0.05 * warm:
            ms = float(r["cold_ms"]) - float(r["cold_shadow_ms"]) - warm
            switch_scale[(r["method"], r["scene"], r["run"])].append(max(0.0, ms) / priced)
    shortfalls = defaultdict(lambda: ([], []))
    for r, cost, warm, warm_there in frames:
        figure = cost["lights"] * warm_there
        ms = float(r["relit_ms"]) - float(r["relit_shadow_ms"]) - warm
        found = switch_scale.get((r["method"], r["scene"], r["run"]))
        scale = max(1.0, sorted(found)[len(found) // 2]) if found else 1.0
        scaled, with_margin = shortfalls[r["method"]]
        scaled.append((ms - scale * figure) / warm)
        with_margin.append((ms - figure - margins[r["method"]]["lights"] * warm) / warm)
    print("moves of the lights, in warm frames at 128x128: how far the price fell short, median and largest, "
          "and how many by over 0.2; scaled as the scene's switches, then plus the margin above")
    for method, (scaled, with_margin) in sorted(shortfalls.items()):
        scaled, with_margin = sorted(scaled), sorted(with_margin)
        print(f"  {method:7} scaled {scaled[len(scaled) // 2]:6.2f} {scaled[-1]:6.2f} "
              f"({sum(v > 0.2 for v in scaled)} of {len(scaled)});  margin {with_margin[len(with_margin) // 2]:6.2f} "
              f"{with_margin[-1]:6.2f} ({sum(v > 0.2 for v in with_margin)} of {len(with_margin)})")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: bench/change_margins.py FRAME_CHANGES_CSV COST_MODEL_JSON")
    main(sys.argv[1], sys.argv[2])
