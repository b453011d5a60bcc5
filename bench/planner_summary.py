#!/usr/bin/python3
"""The figures a closing note quotes from one or more runs of bench/planner, read off planner.csv.

    bench/planner_summary.py [PLANNER_CSV ...]   (default bench/results/planner.csv)

Per run: budgets that hold and target errors met, per pass; the slowest time-budget frame per pass
in multiples of T and how many passed 1.2 T; reference plans' measured relMSE over predicted, per
scene (plans of no bounces left out: their error is the analysis' stopped error alone); the time the
target-error requests of passes 1 and 2 took in all; and how much a comparator's second timing
differs from its first (5th, 50th and 95th percentile), the frame-to-frame noise of one plan."""
import csv
import re
import sys
from collections import defaultdict


def percentile(values, q):
    ordered = sorted(values)
    return ordered[round(q * (len(ordered) - 1))]


def summarise(path):
    rows = list(csv.DictReader(open(path)))
    print(f"## {path}")
    for run_pass in sorted({r["pass"] for r in rows}):
        in_pass = [r for r in rows if r["pass"] == run_pass]
        targets = [r for r in in_pass if "relMSE" in r["budget"]]
        times = []
        for r in in_pass:
            budget = re.search(r"≤ (\d+) ms", r["budget"])
            if budget:
                times.append(float(r["measured_ms"]) / float(budget.group(1)))
        held = sum(r["holds"] == "true" for r in in_pass)
        met = sum(r["met"] == "true" for r in targets)
        slowest = f"{max(times):.2f} T, {sum(t > 1.2 for t in times)} over 1.2 T" if times else "none"
        print(f"pass {run_pass}: {held} of {len(in_pass)} hold; targets met {met} of {len(targets)}; "
              f"slowest time-budget frame {slowest}")
    ratios = defaultdict(list)
    for r in rows:
        if r["plan"].startswith("reference") and "bounces=0" not in r["plan"] and float(r["predicted_rel_mse"]) > 0:
            ratios[r["scene"]].append(float(r["measured_rel_mse"]) / float(r["predicted_rel_mse"]))
    for scene, values in sorted(ratios.items()):
        print(f"reference plans, measured over predicted relMSE, {scene}: {min(values):.2f} to {max(values):.2f}")
    total = sum(float(r["measured_ms"]) for r in rows if "relMSE" in r["budget"] and r["pass"] in ("1", "2"))
    print(f"target-error requests of passes 1 and 2: {total / 1000:.1f} s in all")
    again = []
    for r in rows:
        try:
            first, second = float(r["fixed_ms"]), float(r["fixed_ms_again"])
        except (KeyError, ValueError):
            continue
        if first > 5 and second > 5:
            again.append(second / first)
    if again:
        print(f"a comparator's second timing over its first ({len(again)} frames over 5 ms): "
              f"{percentile(again, 0.05):.2f} / {percentile(again, 0.5):.2f} / {percentile(again, 0.95):.2f}")


def main():
    for path in sys.argv[1:] or ["bench/results/planner.csv"]:
        summarise(path)


if __name__ == "__main__":
    main()
