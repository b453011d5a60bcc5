#!/usr/bin/python3
"""Which of a scene's reference frames should set the planner's noise ratio at a bounce count
(SceneMeasurements::record_noise), read off bench/reference_noise's table.

    bench/reference_noise_ratio.py [bench/results/corpus/reference_noise.csv]

A reference frame's own noise statistic, over the analysis' at its bounce count, is the ratio the
planner multiplies the analysis' statistic by to predict a reference plan's noise. The planner sees
the frames it renders: on the bench, 4-sample drafts and 64-sample frames among them. Per scene and
bounce count, the prediction (the analysis' stopped error plus the ratio times its statistic against
every bounce, over the samples) is set against the frames' relMSE against the truth, at 16, 64 and
256 samples, with the ratio of either rule:

  - largest: the largest the 4- and 64-sample frames read (the rule before);
  - most samples: the 64-sample frames' (the rule now).

Without the noise scale that pairs of frames measure (comparisons.cpp, calibrate_noise): the scale
takes out what the luminance statistic and relMSE's channels part by (the foliage's coloured light,
about a half), and is the same for either rule. The glossy gallery is left out: its rare bright paths
make a frame's statistic a draw of its own (bench/reference_noise's section in docs/benchmarks.md)."""
import csv
import sys
from collections import defaultdict

SEEN_SPP = (4, 64)  # the frames the planner sees of a scene on the bench
PREDICTED_SPP = (16, 64, 256)


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else "bench/results/corpus/reference_noise.csv"
    rows = list(csv.DictReader(open(path)))
    frames = defaultdict(list)
    for row in rows:
        frames[(row["scene"], int(row["bounces"]), int(row["spp"]))].append(row)

    def mean(values):
        return sum(values) / len(values)

    def per_sample(scene, bounces, spp, column):
        return mean([float(r[column]) * spp for r in frames[(scene, bounces, spp)]])

    by_scene = defaultdict(lambda: {"largest": [], "most samples": []})
    print("| scene | bounces | samples | relMSE | largest | most samples |")
    print("|---|---|---|---|---|---|")
    for (scene, bounces, spp), kept in sorted(frames.items()):
        if bounces == 0 or spp not in PREDICTED_SPP or scene == "glossy_gallery":
            continue
        first = kept[0]
        first_spp = int(first["spp"])
        analysis_own = float(first["analysis_own"]) * first_spp
        analysis_whole = float(first["analysis_whole"]) * first_spp
        stopped = float(first["analysis_stopped"])
        if not all((scene, bounces, seen) in frames for seen in SEEN_SPP) or analysis_own <= 0.0:
            continue
        ratios = {seen: per_sample(scene, bounces, seen, "own_statistic") / analysis_own for seen in SEEN_SPP}
        rules = {"largest": max(ratios.values()), "most samples": ratios[max(SEEN_SPP)]}
        measured = mean([float(r["rel_mse"]) for r in kept])
        cells = []
        for rule, ratio in rules.items():
            predicted = stopped + ratio * analysis_whole / spp
            by_scene[scene][rule].append(predicted / measured)
            cells.append(f"{predicted:.4f} ({predicted / measured:.2f})")
        print(f"| {scene} | {bounces} | {spp} | {measured:.4f} | {cells[0]} | {cells[1]} |")
    print()
    print("Predicted over measured, per scene (the least to the most):")
    print()
    print("| scene | largest | most samples |")
    print("|---|---|---|")
    for scene, rules in sorted(by_scene.items()):
        spans = [f"{min(v):.2f} to {max(v):.2f}" for v in rules.values()]
        print(f"| {scene} | {spans[0]} | {spans[1]} |")


if __name__ == "__main__":
    main()
