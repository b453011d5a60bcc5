#!/usr/bin/env python3
"""Whether a method's presets err less as they cost more once each preset's error is taken over
nearby placements of its samples, not at one: reads a CSV of scene, method, preset, knob, value,
rel_mse_same_bounces (one row per frame, each preset at its own value of the knob and at values
near it, as bench/quality --preset P --knob K=V writes them) and prints, per scene and preset, the
mean, the spread (min to max) and the standard deviation over the values, then the ladder on the
means: a preset rises where its mean exceeds a cheaper preset's by more than twice the standard
error of their difference (each mean's standard deviation over sqrt(n)).

usage: placement_ladder.py FILE [--markdown]
       placement_ladder.py --collect KNOB OUT VALUE=QUALITY_CSV ...   (appends each run's rows to OUT)
"""
import csv
import math
import os
import statistics
import sys
from collections import defaultdict

ORDER = ["draft", "low", "medium", "high", "ultra"]


def collect(knob: str, out: str, runs: list[str]) -> int:
    """Appends the rows of bench/quality runs, each made with --knob KNOB=VALUE, to OUT."""
    new = not os.path.exists(out)
    with open(out, "a", newline="") as f:
        writer = csv.writer(f)
        if new:
            writer.writerow(["scene", "method", "preset", "knob", "value", "rel_mse_same_bounces", "wall_ms"])
        for run in runs:
            value, sep, path = run.partition("=")
            if not sep:
                print(f"placement_ladder: {run!r} is not VALUE=QUALITY_CSV", file=sys.stderr)
                return 2
            float(value)  # a number, or the traceback says which
            with open(path) as q:
                for row in csv.DictReader(q):
                    writer.writerow([row["scene"], row["method"], row["preset"], knob, value,
                                     row["rel_mse_same_bounces"], row["wall_ms"]])
    return 0


def main() -> int:
    args = sys.argv[1:]
    if args[:1] == ["--collect"]:
        if len(args) < 4:
            print(__doc__, file=sys.stderr)
            return 2
        return collect(args[1], args[2], args[3:])
    markdown = "--markdown" in args
    files = [a for a in args if a != "--markdown"]
    if len(files) != 1:
        print(__doc__, file=sys.stderr)
        return 2
    errors = defaultdict(list)  # (method, scene, preset) -> [(value, relMSE)]
    with open(files[0]) as f:
        for row in csv.DictReader(f):
            errors[(row["method"], row["scene"], row["preset"])].append(
                (float(row["value"]), float(row["rel_mse_same_bounces"])))
    knobs = defaultdict(set)  # a method's placements are of one knob: pooling two would mean nothing
    with open(files[0]) as f:
        for row in csv.DictReader(f):
            knobs[row["method"]].add(row["knob"])
    for method, names in knobs.items():
        if len(names) > 1:
            print(f"placement_ladder: {method}'s rows vary {sorted(names)}; one knob per method", file=sys.stderr)
            return 2
    share = lambda x, y: f"{x / y:.0%}" if y > 0 else "n/a"  # a black frame's relMSE can be 0
    stats = {}
    for key, frames in errors.items():
        values = [e for _, e in frames]
        sd = statistics.stdev(values) if len(values) > 1 else 0.0
        stats[key] = (statistics.mean(values), min(values), max(values), sd, len(values))
    methods = sorted({m for m, _, _ in stats})
    for method in methods:
        scenes = sorted({s for m, s, _ in stats if m == method})
        if markdown:
            if len(methods) > 1:
                print(f"\n{method}:\n")
            print(f"| scene | " + " | ".join(p for p in ORDER) + " |")
            print("|---|" + "---|" * len(ORDER))
        else:
            print(f"{method}: mean relMSE over placements (min-max, sd/mean)")
        for scene in scenes:
            cells = []
            for preset in ORDER:
                s = stats.get((method, scene, preset))
                cells.append("" if s is None else f"{s[0]:.4f} ({s[1]:.4f}-{s[2]:.4f}, {share(s[3], s[0])})")
            print(f"| {scene} | " + " | ".join(cells) + " |" if markdown else f"  {scene}: " + "; ".join(
                f"{p} {c}" for p, c in zip(ORDER, cells)))
        holds = 0
        for scene in scenes:
            rises = []
            for k, preset in enumerate(ORDER):
                a = stats.get((method, scene, preset))
                if a is None:
                    continue
                for cheaper in ORDER[:k]:
                    b = stats.get((method, scene, cheaper))
                    if b is None:
                        continue
                    se = math.sqrt(a[3] ** 2 / a[4] + b[3] ** 2 / b[4])
                    if a[0] - b[0] > 2 * se:
                        by = f"{a[0] / b[0] - 1:.0%}" if b[0] > 0 else f"{a[0]:.4f} (over none)"
                        rises.append(f"{preset} over {cheaper} by {by}" + (f" ({(a[0] - b[0]) / se:.1f} se)" if se > 0 else ""))
            if rises:
                print(f"{'- ' if markdown else '  '}{method} on {scene}: " + ", ".join(rises))
            else:
                holds += 1
        print(f"{'- ' if markdown else ''}{method}: the ladder of means holds on {holds} of {len(scenes)} scenes")
    return 0


if __name__ == "__main__":
    sys.exit(main())
