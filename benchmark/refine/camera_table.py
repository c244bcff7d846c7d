#!/usr/bin/env python3
"""Markdown tables from run_cameras.sh's results.tsv (case, level, config,
json, seconds, MiB per row). Per row: accuracy90 and normal error of the
mesh, its ratio to the same case's run with exact cameras and no camera
refinement (the issue's reference), and the cameras' RMS reprojection
displacement from the truth. Then, per error level and configuration, the
worst case over the cases."""
import json
import sys
from collections import defaultdict


def main(path):
    rows = []
    with open(path) as f:
        for line in f:
            parts = line.rstrip("\n").split("\t")
            if len(parts) != 6:
                continue
            case, level, config, blob, secs, mib = parts
            rows.append((case, level, config, json.loads(blob), float(secs), int(mib)))
    reference = {r[0]: r[3] for r in rows if r[1] == "exact" and r[2] == "none"}
    none_time = {(r[0], r[1]): r[4] for r in rows if r[2] == "none"}

    print("| case | camera error | run | accuracy90 | / exact-camera run | normal error | "
          "completeness | cameras vs truth, RMS (worst image) px | time s |")
    print("|---|---|---|---|---|---|---|---|---|")
    worst = defaultdict(lambda: defaultdict(float))
    order = []
    for case, level, config, m, secs, mib in rows:
        ref = reference.get(case)
        ratio = m["accuracy90"] / ref["accuracy90"] if ref else float("nan")
        nratio = m["normal_deg"] / ref["normal_deg"] if ref else float("nan")
        time = f"{secs:.0f}" if config != "input" else ""
        print(f"| {case} | {level} | {config} | {m['accuracy90']:.4f} | {ratio:.3f} | "
              f"{m['normal_deg']:.2f}° | {m['completeness']:.2f} % | "
              f"{m['camera_rms_px']:.3f} ({m['camera_max_rms_px']:.3f}) | {time} |")
        key = (level, config)
        if key not in worst:
            order.append(key)
        w = worst[key]
        w["cases"] += 1
        w["accuracy_ratio"] = max(w["accuracy_ratio"], ratio)
        w["normal_ratio"] = max(w["normal_ratio"], nratio)
        w["camera_rms_px"] = max(w["camera_rms_px"], m["camera_rms_px"])
        if config not in ("input", "none") and (case, level) in none_time:
            w["time_ratio"] = max(w["time_ratio"], secs / none_time[(case, level)])
    print()
    print("| camera error | run | cases | worst accuracy90 / exact-camera run | worst normal "
          "error / exact-camera run | worst cameras vs truth, RMS px | worst time / no "
          "refinement |")
    print("|---|---|---|---|---|---|---|")
    for level, config in order:
        w = worst[(level, config)]
        t = f"{w['time_ratio']:.2f}" if w["time_ratio"] else ""
        print(f"| {level} | {config} | {int(w['cases'])} | {w['accuracy_ratio']:.3f} | "
              f"{w['normal_ratio']:.3f} | {w['camera_rms_px']:.3f} | {t} |")


if __name__ == "__main__":
    main(sys.argv[1])
