#!/usr/bin/python3
"""Plots bench/quality's CSV: relMSE against wall time, log-log, one panel per scene and one
curve per method (points labelled by preset or, for the reference, by samples per pixel)."""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(csv_path: str, png_path: str) -> None:
    rows = list(csv.DictReader(open(csv_path)))
    scenes = sorted({row["scene"] for row in rows})
    figure, axes = plt.subplots(1, len(scenes), figsize=(5.5 * len(scenes), 4.5), squeeze=False)
    for axis, scene in zip(axes[0], scenes):
        curves = defaultdict(list)
        for row in rows:
            if row["scene"] == scene and float(row["rel_mse"]) > 0:
                curves[row["method"]].append((float(row["wall_ms"]), float(row["rel_mse"]), row["preset"]))
        for method, points in sorted(curves.items()):
            points.sort()
            axis.plot([p[0] for p in points], [p[1] for p in points], marker="o", label=method)
            for x, y, label in points:
                axis.annotate(label, (x, y), textcoords="offset points", xytext=(4, 4), fontsize=7)
        axis.set_xscale("log")
        axis.set_yscale("log")
        axis.set_xlabel("wall time per frame (ms)")
        axis.set_ylabel("relMSE against the reference")
        axis.set_title(scene)
        axis.grid(True, which="both", alpha=0.3)
        axis.legend()
    figure.tight_layout()
    figure.savefig(png_path, dpi=110)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
