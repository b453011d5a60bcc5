#!/usr/bin/python3
"""The figures a closing note quotes from one or more runs of bench/planner, read off planner.csv.

    bench/planner_summary.py [PLANNER_CSV ...]   (default bench/results/planner.csv)
    bench/planner_summary.py --against OLD_CSV [NEW_CSV]

With --against, the time-budget frames that were the reference in both runs (paired by pass, scene
and budget): the new run's relMSE over the old's (median, and how many under 0.95 and over 1.05),
and each run's median and slowest frame in multiples of T; where both runs have their fixed plans'
file beside them (NAME_fixed.csv), each scene's median time of the same fixed plans, new over old.
`git show REV:bench/results/planner.csv > OLD_CSV` gives an earlier run.

Per run: budgets that hold and target errors met, per pass; the slowest time-budget frame per pass
in multiples of T and how many passed 1.2 T; reference plans' measured relMSE over predicted, per
scene (plans of no bounces left out: their error is the analysis' stopped error alone); the GPU
plans of pass 1 whose measured relMSE exceeded their prediction (a first-sight promise broken); the time the
target-error requests of passes 1 and 2 took in all; and how much a comparator's second timing
differs from its first (5th, 50th and 95th percentile), the frame-to-frame noise of one plan."""
import csv
import os
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
    # At first sight a GPU plan's predicted error is its prior's promise: those it did not keep.
    first_gpu = [r for r in rows if r["pass"] == "1" and not r["plan"].startswith("reference")]
    broken = [r for r in first_gpu if float(r["measured_rel_mse"]) > float(r["predicted_rel_mse"])]
    print(f"GPU plans of pass 1 measured over their predicted relMSE: {len(broken)} of {len(first_gpu)}" +
          "".join(f"; {r['scene']} {r['budget']}, {r['plan']}: {float(r['predicted_rel_mse']):.4f} predicted, "
                  f"{float(r['measured_rel_mse']):.4f} measured" for r in broken))
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


def budget_ms(row):
    budget = re.search(r"≤ (\d+) ms", row["budget"])
    return float(budget.group(1)) if budget else None


def compare(old_path, new_path):
    key = lambda r: (r["pass"], r["scene"], r["budget"])
    old = {key(r): r for r in csv.DictReader(open(old_path))}
    pairs = [(old[key(r)], r) for r in csv.DictReader(open(new_path))
             if budget_ms(r) and key(r) in old and r["plan"].startswith("reference")
             and old[key(r)]["plan"].startswith("reference")]
    if not pairs:
        print("no time-budget frames were the reference in both runs")
        return
    errors = [float(n["measured_rel_mse"]) / float(o["measured_rel_mse"]) for o, n in pairs]
    print(f"## {new_path} against {old_path}: {len(pairs)} time-budget frames the reference in both")
    print(f"relMSE, new over old: median {percentile(errors, 0.5):.2f}; {sum(e < 0.95 for e in errors)} under 0.95, "
          f"{sum(e > 1.05 for e in errors)} over 1.05")
    for name, run in (("old", 0), ("new", 1)):
        times = [float(p[run]["measured_ms"]) / budget_ms(p[run]) for p in pairs]
        print(f"{name}: median {percentile(times, 0.5):.2f} T, slowest {max(times):.2f} T")
    # The fixed plans' times beside each run (bench/planner writes NAME_fixed.csv beside NAME.csv, or
    # planner_fixed.csv beside planner.csv): how much faster or slower the machine ran the same plans.
    fixed = [re.sub(r"\.csv$", "_fixed.csv", path) for path in (old_path, new_path)]
    if not all(os.path.exists(path) for path in fixed):
        return
    old_ms, new_ms = ({(r["scene"], r["plan"]): float(r["measured_ms"]) for r in csv.DictReader(open(path))}
                      for path in fixed)
    for scene in sorted({scene for scene, _ in new_ms}):
        line = []
        for kind, is_kind in (("GPU plans", lambda plan: not plan.startswith("reference")),
                              ("references", lambda plan: plan.startswith("reference")),
                              ("isr draft", lambda plan: plan == "isr draft")):
            ratios = [new_ms[k] / old_ms[k] for k in new_ms if k in old_ms and k[0] == scene and is_kind(k[1])]
            if ratios:
                line.append(f"{kind} {percentile(ratios, 0.5):.2f}")
        print(f"fixed plans' time, new over old (median), {scene}: " + ", ".join(line))


def main():
    if sys.argv[1:2] == ["--against"]:
        compare(sys.argv[2], sys.argv[3] if len(sys.argv) > 3 else "bench/results/planner.csv")
        return
    for path in sys.argv[1:] or ["bench/results/planner.csv"]:
        summarise(path)


if __name__ == "__main__":
    main()
