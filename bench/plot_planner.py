#!/usr/bin/python3
"""Plots bench/planner's results: per scene, relMSE against time of every fixed plan (one colour a
method), their Pareto front (no plan both faster and more accurate), and the frames the planner
planned for each budget, pass 1, pass 2, the relit passes (time budgets right after a light
change, frames rendered as they come: after the same budget's frame, then after another budget's)
and the moved-camera pass (time budgets of the view right after a frame from a camera moved aside),
labelled by their budget."""
import csv
import os
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def pareto(points):
    front, best = [], float("inf")
    for ms, error in sorted(points):
        if error < best:
            front.append((ms, error))
            best = error
    return front


def main(results: str) -> None:
    fixed = list(csv.DictReader(open(os.path.join(results, "planner_fixed.csv"))))
    planned = list(csv.DictReader(open(os.path.join(results, "planner.csv"))))
    scenes = list(dict.fromkeys(row["scene"] for row in fixed))
    columns = min(3, len(scenes))
    rows = (len(scenes) + columns - 1) // columns
    figure, axes = plt.subplots(rows, columns, figsize=(6 * columns, 4.8 * rows), squeeze=False)
    for axis in axes.flat[len(scenes):]:
        axis.set_visible(False)
    for axis, scene in zip(axes.flat, scenes):
        by_method = defaultdict(list)
        for row in fixed:
            if row["scene"] == scene and float(row["measured_rel_mse"]) > 0:
                by_method[row["plan"].split()[0]].append((float(row["measured_ms"]), float(row["measured_rel_mse"])))
        for method, points in sorted(by_method.items()):
            axis.scatter([p[0] for p in points], [p[1] for p in points], s=18, label=method, alpha=0.7)
        front = pareto([p for points in by_method.values() for p in points])
        axis.step([p[0] for p in front], [p[1] for p in front], where="post", color="grey", linewidth=1,
                  label="fixed plans' Pareto front")
        for row in planned:
            if row["scene"] != scene or float(row["measured_rel_mse"]) <= 0:
                continue
            marker = ("x" if row["pass"] == "1" else "v" if "another budget" in row["budget"]
                      else "^" if "relit" in row["budget"] else "s" if "camera moved" in row["budget"] else "+")
            colour = "black" if row["holds"] == "true" else "red"
            x, y = float(row["measured_ms"]), float(row["measured_rel_mse"])
            axis.scatter([x], [y], marker=marker, s=60, color=colour, linewidths=1.5)
            axis.annotate(f'{row["budget"]} ({row["pass"]})', (x, y), textcoords="offset points", xytext=(4, -8),
                          fontsize=6, color=colour)
        axis.scatter([], [], marker="x", color="black", label="planned, pass 1 (red: does not hold)")
        axis.scatter([], [], marker="+", color="black", label="planned, pass 2")
        axis.scatter([], [], marker="^", color="black", label="planned right after a light change")
        axis.scatter([], [], marker="v", color="black", label="the same, after another budget's frame")
        axis.scatter([], [], marker="s", color="black", label="planned right after the camera moved")
        axis.set_xscale("log")
        axis.set_yscale("log")
        axis.set_xlabel("render time (ms)")
        axis.set_ylabel("relMSE against the reference")
        axis.set_title(scene)
        axis.grid(True, which="both", alpha=0.3)
        axis.legend(fontsize=7)
    figure.tight_layout()
    figure.savefig(os.path.join(results, "planner.png"), dpi=100)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "bench/results")
