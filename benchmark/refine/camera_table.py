#!/usr/bin/env python3
"""Markdown tables from run_cameras.sh's results.tsv (case, level, config,
json, datum-aligned json, seconds, MiB per row). Per row: accuracy90 and
normal error of the mesh, their ratios to the same case's run with exact
cameras and no camera refinement (the issue's reference), and the cameras'
RMS reprojection displacement from the truth; each as it is and after the
datum alignment (mesh_evaluator --align_cameras). Then, per error level and
configuration, the worst case over the cases."""
import json
import sys
from collections import defaultdict


def main(path):
    rows = []
    with open(path) as f:
        for line in f:
            parts = line.rstrip("\n").split("\t")
            if len(parts) != 7:
                continue
            case, level, config, blob, aligned, secs, mib = parts
            rows.append((case, level, config, json.loads(blob), json.loads(aligned),
                         float(secs), int(mib)))
    reference = {r[0]: r[3] for r in rows if r[1] == "exact" and r[2] == "none"}
    none_time = {(r[0], r[1]): r[5] for r in rows if r[2] == "none"}

    print("| case | camera error | run | accuracy90 | / exact-camera run | aligned | normal "
          "error | aligned | cameras vs truth, RMS (worst image) px | aligned | time s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    worst = defaultdict(lambda: defaultdict(float))
    order = []
    for case, level, config, m, a, secs, mib in rows:
        ref = reference.get(case)
        nan = float("nan")
        ratio = m["accuracy90"] / ref["accuracy90"] if ref else nan
        aratio = a["accuracy90"] / ref["accuracy90"] if ref else nan
        nratio = m["normal_deg"] / ref["normal_deg"] if ref else nan
        anratio = a["normal_deg"] / ref["normal_deg"] if ref else nan
        time = f"{secs:.0f}" if config != "input" else ""
        print(f"| {case} | {level} | {config} | {m['accuracy90']:.4f} | {ratio:.3f} | "
              f"{aratio:.3f} | {m['normal_deg']:.2f}° | {a['normal_deg']:.2f}° | "
              f"{m['camera_rms_px']:.3f} ({m['camera_max_rms_px']:.3f}) | "
              f"{a['camera_rms_px']:.3f} ({a['camera_max_rms_px']:.3f}) | {time} |")
        key = (level, config)
        if key not in worst:
            order.append(key)
        w = worst[key]
        w["cases"] += 1
        for name, value in (("accuracy", ratio), ("aligned_accuracy", aratio),
                            ("normal", nratio), ("aligned_normal", anratio),
                            ("cameras", m["camera_rms_px"]),
                            ("aligned_cameras", a["camera_rms_px"])):
            # A ratio without the case's exact-camera run (LEVELS without
            # "exact") is nan and makes the worst case nan too.
            w[name] = value if value != value else max(w[name], value)
        if config not in ("input", "none") and (case, level) in none_time:
            w["time_ratio"] = max(w["time_ratio"], secs / none_time[(case, level)])
    print()
    print("Worst case over the cases (aligned: mesh and cameras carried into the true world by "
          "the similarity that best aligns the cameras with the true ones):")
    print()
    print("| camera error | run | cases | accuracy90 / exact-camera run | aligned | normal "
          "error / exact-camera run | aligned | cameras vs truth, RMS px | aligned | time / "
          "no refinement |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for level, config in order:
        w = worst[(level, config)]
        t = f"{w['time_ratio']:.2f}" if w["time_ratio"] else ""
        print(f"| {level} | {config} | {int(w['cases'])} | {w['accuracy']:.3f} | "
              f"{w['aligned_accuracy']:.3f} | {w['normal']:.3f} | {w['aligned_normal']:.3f} | "
              f"{w['cameras']:.3f} | {w['aligned_cameras']:.3f} | {t} |")


if __name__ == "__main__":
    main(sys.argv[1])
