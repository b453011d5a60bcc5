#!/usr/bin/python3
"""What a frame right after every light was dimmed cost beyond a warm frame, in warm frames, per
scene and preset: a bench/quality run (`dimmed_ms` against `wall_ms`) against the same method's rows
of a frame_changes.csv run (bench/frame_changes.py: `dimmed_ms` against `warm_ms`).

    bench/dimmed_frames.py QUALITY_CSV FRAME_CHANGES_CSV METHOD [RUN]

RUN picks frame_changes.csv's run (default 2, the first with dimmed frames)."""
import csv
import statistics
import sys


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    quality_csv, changes_csv, method = sys.argv[1:4]
    run = sys.argv[4] if len(sys.argv) > 4 else "2"
    before = {(r["scene"], r["preset"]): r for r in csv.DictReader(open(changes_csv))
              if r["method"] == method and r["run"] == run and r["dimmed_ms"]}
    now_values, before_values = [], []
    print("| scene | preset | now | before |")
    print("|---|---|---|---|")
    for r in csv.DictReader(open(quality_csv)):
        if r["method"] != method or not r["dimmed_ms"]:
            continue
        now = (float(r["dimmed_ms"]) - float(r["wall_ms"])) / float(r["wall_ms"])
        now_values.append(now)
        old = before.get((r["scene"], r["preset"]))
        old_text = ""
        if old:
            was = (float(old["dimmed_ms"]) - float(old["warm_ms"])) / float(old["warm_ms"])
            before_values.append(was)
            old_text = f"{was:.2f}"
        print(f"| {r['scene']} | {r['preset']} | {now:.2f} | {old_text} |")
    for name, values in (("now", now_values), ("before", before_values)):
        if values:
            print(f"{name}: {min(values):.2f} to {max(values):.2f}, median {statistics.median(values):.2f}, "
                  f"{sum(abs(v) > 0.1 for v in values)} of {len(values)} beyond 0.1 either way")


if __name__ == "__main__":
    main()
