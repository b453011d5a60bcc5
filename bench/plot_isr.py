#!/usr/bin/python3
"""Plots bench/isr's CSVs: isr_fig9.csv (error against the eye-space depth threshold,
one curve per normal threshold; the paper's Fig. 9) and isr_fig13.csv (error against the VPL-tree
threshold tau, one curve per max_depth; the paper's Fig. 13), into isr_fig9.png and isr_fig13.png
in the same folder. Usage: plot_isr.py [RESULTS_DIR] (default bench/results)."""
import csv
import sys
from collections import defaultdict
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def numeric_rows(path: Path, key: str):
    """The CSV's rows whose `key` column is a number (the baseline row is not)."""
    rows = []
    for row in csv.DictReader(open(path)):
        try:
            float(row[key])
        except ValueError:
            continue
        rows.append(row)
    return rows


def plot_fig9(results: Path) -> None:
    rows = numeric_rows(results / "isr_fig9.csv", "normal_threshold")
    curves = defaultdict(list)
    for row in rows:
        curves[float(row["normal_threshold"])].append(
            (float(row["depth_threshold"]), float(row["rel_rmse_pct"]), float(row["fragments_fraction"])))
    figure, (error_axis, fragment_axis) = plt.subplots(1, 2, figsize=(11, 4.2))
    for normal, points in sorted(curves.items()):
        points.sort()
        label = f"normal threshold {normal:g}" + (" (depth only)" if normal >= 2 else "")
        error_axis.plot([p[0] for p in points], [p[1] for p in points], marker="o", label=label)
        fragment_axis.plot([p[0] for p in points], [p[2] for p in points], marker="o", label=label)
    thresholds = sorted({p[0] for points in curves.values() for p in points})
    for axis in (error_axis, fragment_axis):
        # The threshold sweep starts at 0: linear near 0, logarithmic above.
        axis.set_xscale("symlog", linthresh=0.005)
        axis.set_xticks(thresholds)
        axis.set_xticklabels([f"{t:g}" for t in thresholds], rotation=45, fontsize=8)
        axis.minorticks_off()
        axis.set_xlabel("depth threshold (relative depth span)")
        axis.grid(True, which="both", alpha=0.3)
        axis.legend()
    error_axis.set_ylabel("RMSE, % of the baseline's mean")
    error_axis.set_title("isr: error vs depth threshold (cf. paper Fig. 9)")
    fragment_axis.set_ylabel("multiresolution fragments / pixels")
    fragment_axis.set_title("fragments that gather")
    figure.tight_layout()
    figure.savefig(results / "isr_fig9.png", dpi=110)


def plot_fig13(results: Path) -> None:
    rows = numeric_rows(results / "isr_fig13.csv", "max_depth")
    curves = defaultdict(list)
    for row in rows:
        curves[int(row["max_depth"])].append(
            (float(row["tau"]), float(row["rel_rmse_pct"]), float(row["vpls_per_fragment_mean"])))
    figure, (error_axis, vpl_axis) = plt.subplots(1, 2, figsize=(11, 4.2))
    for max_depth, points in sorted(curves.items()):
        points.sort()
        positive = [p for p in points if p[0] > 0]
        line, = error_axis.plot([p[0] for p in positive], [p[1] for p in positive], marker="o",
                                label=f"max_depth {max_depth}")
        vpl_axis.plot([p[0] for p in positive], [p[2] for p in positive], marker="o", color=line.get_color(),
                      label=f"max_depth {max_depth}")
        # tau 0 (every patch opened to the finest level) cannot sit on a log axis: a dashed level.
        for tau, error, vpls in points:
            if tau == 0:
                error_axis.axhline(error, color=line.get_color(), linestyle="--", linewidth=0.8, alpha=0.7)
                vpl_axis.axhline(vpls, color=line.get_color(), linestyle="--", linewidth=0.8, alpha=0.7)
    error_axis.set_xscale("log")
    error_axis.set_xlabel("tau (dashed: tau 0)")
    error_axis.set_ylabel("RMSE, % of the baseline's mean")
    error_axis.set_title("isr: error vs tau (cf. paper Fig. 13)")
    vpl_axis.set_xscale("log")
    vpl_axis.set_yscale("log")
    vpl_axis.set_xlabel("tau (dashed: tau 0)")
    vpl_axis.set_ylabel("VPLs gathered per fragment (mean)")
    vpl_axis.set_title("VPLs per fragment")
    # Room above the curves for the legend.
    error_axis.set_ylim(bottom=0, top=1.3 * max(p[1] for points in curves.values() for p in points))
    error_axis.legend(loc="upper left", ncol=2, fontsize=8)
    vpl_axis.legend()
    for axis in (error_axis, vpl_axis):
        axis.grid(True, which="both", alpha=0.3)
    figure.tight_layout()
    figure.savefig(results / "isr_fig13.png", dpi=110)


def main(results: Path) -> None:
    plot_fig9(results)
    plot_fig13(results)


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "bench/results"))
