#!/usr/bin/python3
"""Whether each method's presets err less as they cost more, on every bench scene: read off the
ladder.csv files bench/quality writes beside its quality.csv.

    bench/preset_ladder.py [--markdown] [LADDER_CSV ...]
        (default bench/results/ladder.csv bench/results/corpus/ladder.csv)

A ladder row holds one preset against one cheaper preset of the same bounce count on one scene:
their own errors (relMSE against the reference at those bounces) and the standard deviation that
the reference's noise gives their difference (image::rel_mse_difference_noise). A preset's error
rises there where its error exceeds the cheaper one's by more than two of those deviations: the
frames', not the reference's draw. Per method and preset: the scenes where it rises over a cheaper
preset (the cheaper preset whose error it exceeds by the largest share, and by how much), and on how
many scenes the method's ladder holds: on all, and leaving out the pairs where the scene analysis
finds walls thinner than either preset's voxels (vct; `thin_walls`), presets the planner never
plans on that scene. Presets are in their ladder's order (draft to
ultra), which is their cost's on the bench (docs/benchmarks.md)."""
import csv
import sys
from collections import defaultdict

ORDER = ["draft", "low", "medium", "high", "ultra"]
DEFAULT = ["bench/results/ladder.csv", "bench/results/corpus/ladder.csv"]


def read(paths):
    rows = []
    for path in paths:
        try:
            rows += list(csv.DictReader(open(path)))
        except OSError as error:
            sys.exit(f"preset_ladder: {error}")
    return rows


def rises(rows):
    """method -> preset -> scene -> (cheaper, difference, share, deviations) of its largest rise."""
    out = defaultdict(lambda: defaultdict(dict))
    scenes = defaultdict(set)
    for r in rows:
        scenes[r["method"]].add(r["scene"])
        difference, noise = float(r["difference"]), float(r["noise"])
        if not difference > 2.0 * noise:  # within the noise, or not measured (NaN)
            continue
        cheaper_error = float(r["cheaper_rel_mse_same_bounces"])
        share = difference / cheaper_error if cheaper_error > 0 else float("inf")
        deviations = difference / noise if noise > 0 else float("inf")
        thin_walls = r.get("thin_walls", "0") == "1"
        held = out[r["method"]][r["preset"]].get(r["scene"])
        # A rise between presets the planner may plan outranks one it rules out.
        if held is None or (not thin_walls, share) > (not held[4], held[2]):
            out[r["method"]][r["preset"]][r["scene"]] = (r["cheaper"], difference, share, deviations, thin_walls)
    return out, scenes


def sigmas(deviations):
    # Past a thousand the count says only that the reference has next to no noise there (direct
    # light from point lights through pixel centres has none: its variance is float rounding).
    return f"{deviations:.0f} sigma" if deviations < 1000 else "over 1000 sigma"


def main(argv):
    markdown = "--markdown" in argv
    paths = [a for a in argv if a != "--markdown"] or DEFAULT
    found, scenes = rises(read(paths))
    if markdown:
        print("| method | preset | scenes where its own error rises over a cheaper preset's (by more than "
              "twice the reference's noise) |")
        print("|---|---|---|")
    for method in sorted(scenes):
        total = len(scenes[method])
        failing = {s for preset in found[method].values() for s in preset}
        planned = {s for preset in found[method].values() for s, rise in preset.items() if not rise[4]}
        summary = f"the ladder holds on {total - len(failing)} of {total} scenes"
        if planned != failing:
            summary += f", on {total - len(planned)} leaving out presets ruled out by thin walls"
        if not markdown:
            print(f"{method}: {summary}")
        for preset in ORDER[1:]:
            where = found[method].get(preset, {})
            text = ", ".join(f"{scene} (over {cheaper} by {share:.0%}, "
                             f"{sigmas(deviations)}"
                             f"{'; thin walls' if thin_walls else ''})"
                             for scene, (cheaper, _, share, deviations, thin_walls) in sorted(where.items()))
            if markdown:
                print(f"| {method} | {preset} | {text or 'none'} |")
            elif text:
                print(f"  {preset}: {text}")
        if markdown:
            print(f"| {method} | (all) | {summary} |")


if __name__ == "__main__":
    main(sys.argv[1:])
