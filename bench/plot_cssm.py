#!/usr/bin/env python3
"""Plots of bench/cssm: visibility disagreement per cube face size (Fig. 14 as a number) and error
against frame time per preset and bounce count. Usage: plot_cssm.py RESULTS_DIR"""
import csv
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def main():
    results = Path(sys.argv[1] if len(sys.argv) > 1 else "bench/results")
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4))

    visibility = rows(results / "cssm_fig14.csv")
    faces = [int(r["face"]) for r in visibility]
    for key, label in (("disagree_pcf1", "PCF 1"), ("disagree_pcf3", "PCF 3 (< 50% lit)")):
        left.plot(faces, [100.0 * int(r[key]) / int(r["pairs"]) for r in visibility], marker="o", label=label)
    left.set_xscale("log", base=2)
    left.set_xlabel("cube face size (pixels)")
    left.set_ylabel("answers unlike the exact ray query (%)")
    left.set_title("CSSM visibility vs Embree, Cornell box")
    left.legend()
    left.grid(True, alpha=0.3)

    error = rows(results / "cssm_error.csv")
    for bounces in sorted({r["bounces"] for r in error}):
        series = [r for r in error if r["bounces"] == bounces]
        right.plot([float(r["warm_ms"]) for r in series], [float(r["rel_mse"]) for r in series], marker="o",
                   label=f"n = {bounces}")
        for r in series:
            right.annotate(r["preset"], (float(r["warm_ms"]), float(r["rel_mse"])), fontsize=7)
    right.set_xscale("log")
    right.set_yscale("log")
    right.set_xlabel("warm frame (ms)")
    right.set_ylabel("relMSE against the reference, same bounces")
    right.set_title("cssm: error against time per preset")
    right.legend()
    right.grid(True, alpha=0.3)

    fig.tight_layout()
    fig.savefig(results / "cssm.png", dpi=120)
    print(f"wrote {results / 'cssm.png'}")


if __name__ == "__main__":
    main()
