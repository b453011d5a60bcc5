#!/usr/bin/python3
"""What further bounces cost a warm frame: bench/quality at each bounce count of cssm (1, 2, 8) and
vct (1, 2), on every corpus scene and the Cornell box, each preset's time against its time at one
bounce. The planner prices bounce counts a scene has not measured by the largest ratio here
(renderer/planning/bench_bounds.cpp, kMostBounceCost), and expects them at the median (kTypicalBounceCost).

usage: bench/bounce_cost.py [--runs DIR] [--out FILE]
  --runs DIR  where each run's output goes, DIR/<scene>-<method>-<bounces>/ (default /tmp/bounce_cost);
              runs already there are read, not run again
  --out FILE  the table (default bench/results/bounce_cost.csv)
Takes about half an hour on two cores."""
import csv
import os
import statistics
import subprocess
import sys
from collections import defaultdict

SCENES = ["furnished_room", "atrium", "outdoor", "glossy_gallery", "foliage", "cornell"]
COUNTS = {"cssm": [1, 2, 8], "vct": [1, 2]}
QUALITY = "build/bench/bounce_bench_quality"


def run(runs: str, scene: str, method: str, bounces: int) -> str:
    folder = os.path.join(runs, f"{scene}-{method}-{bounces}")
    table = os.path.join(folder, "quality.csv")
    if not os.path.exists(table):
        # A one-sample reference: only the times are read here.
        command = [QUALITY, "--method", method, "--knob", f"bounces={bounces}", "--reference-spp", "1",
                   "--reference-bounces", "1", "--repeats", "3", "--out", folder,
                   "--markdown", os.path.join(folder, "quality.md")]
        command += ["--scene", scene] if scene == "cornell" else ["--corpus", "--scene", scene]
        print(" ".join(command), file=sys.stderr)
        subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    return table


def main(runs: str, out: str) -> None:
    warm = defaultdict(dict)  # (scene, method, preset) -> bounces -> ms
    for scene in SCENES:
        for method, counts in COUNTS.items():
            for bounces in counts:
                for row in csv.DictReader(open(run(runs, scene, method, bounces))):
                    if row["method"] == method:
                        warm[(row["scene"], method, row["preset"])][int(row["bounces"])] = float(row["wall_ms"])
    ratios = defaultdict(list)
    with open(out, "w", newline="") as file:
        table = csv.writer(file)
        table.writerow(["scene", "method", "preset", "bounces", "warm_ms", "one_bounce_ms", "ratio"])
        for (scene, method, preset), by_count in sorted(warm.items()):
            for bounces, ms in sorted(by_count.items()):
                if bounces == 1 or 1 not in by_count:
                    continue
                ratio = ms / by_count[1]
                ratios[(method, preset)].append(ratio)
                table.writerow([scene, method, preset, bounces, f"{ms:.1f}", f"{by_count[1]:.1f}", f"{ratio:.2f}"])
    print(f"wrote {out}; per preset, the largest ratio and the median:")
    for (method, preset), values in sorted(ratios.items()):
        print(f"  {method} {preset}: {max(values):.2f}, {statistics.median(values):.2f}")


if __name__ == "__main__":
    arguments = sys.argv[1:]
    options = {"--runs": "/tmp/bounce_cost", "--out": "bench/results/bounce_cost.csv"}
    while arguments:
        name = arguments.pop(0)
        if name not in options or not arguments:
            sys.exit(__doc__)
        options[name] = arguments.pop(0)
    main(options["--runs"], options["--out"])
