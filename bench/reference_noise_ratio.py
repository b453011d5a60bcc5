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
make a frame's statistic a draw of its own (bench/reference_noise's section in docs/benchmarks.md).

Then the noise scale the planner reads off a pair of one seed's frames (calibrate_noise), per pair of
sample counts, weighed by the larger frame's own values and by its neighbourhoods' medians (image::Weight),
against the scale the truth reads (the fall of the two frames' relMSE against it, over the same
statistic), put in the frames' own terms (times the analysis' statistic over its own frame, over
its statistic against every bounce, as the pair's relMSE is against the larger frame): the mean over
bounce counts 1 to 8 and seeds, and the least and the most."""
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


    print()
    print("Noise scales of a pair of one seed's frames, per pair of sample counts (mean [least, most]):")
    print()
    print("| scene | samples | image::compare | neighbourhoods' medians | the truth |")
    print("|---|---|---|---|---|")
    pairs = defaultdict(lambda: defaultdict(list))
    for row in rows:
        if not row.get("pair_spp") or row["scene"] == "glossy_gallery" or row["bounces"] == "0":
            continue
        key = (row["scene"], int(row["pair_spp"]), int(row["spp"]))
        pairs[key]["compare"].append(float(row["pair_scale"]))
        pairs[key]["smoothed"].append(float(row["pair_scale_smoothed"]))
        own_terms = float(row["analysis_own"]) / float(row["analysis_whole"])
        pairs[key]["truth"].append(float(row["truth_scale"]) * own_terms)
    for (scene, fewer, more), scales in sorted(pairs.items()):
        cells = [f"{mean(v):.2f} [{min(v):.2f}, {max(v):.2f}]" for v in (scales["compare"], scales["smoothed"], scales["truth"])]
        print(f"| {scene} | {fewer} against {more} | {cells[0]} | {cells[1]} | {cells[2]} |")


if __name__ == "__main__":
    main()
