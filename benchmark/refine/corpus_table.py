#!/usr/bin/env python3
"""Table of run_corpus.sh results: one row per case and configuration, with
ratios to the Poisson input and the floors of the generalisation issue, then
the worst case of every column per configuration. Where the evaluator gave
them (since the twenty-eighth session), the median and the 90th percentile of
the normal error are given too, as ratios to the input's: the floor is on the
mean, and the mean of a refined surface is held up by its worst tenth.

  python3 benchmark/refine/corpus_table.py OUT_DIR/results.tsv
"""
import json
import sys

ACC_FLOOR, NORMAL_FLOOR, COMPLETENESS_DROP = 0.6, 0.7, 1.0


def read_results(path):
    """run_corpus.sh's results.tsv: rows (case, label, result dict, seconds,
    MB), and the labels other than "input" in their order of appearance."""
    rows = []
    with open(path) as f:
        for line in f:
            name, label, js, secs, mb = line.rstrip("\n").split("\t")
            rows.append((name, label, json.loads(js), float(secs), int(mb)))
    labels = []
    for _, label, _, _, _ in rows:
        if label != "input" and label not in labels:
            labels.append(label)
    return rows, labels


def angle_ratio(r, i, key):
    """r[key] / i[key] as text, blank where either evaluation lacks the key."""
    if key not in r or key not in i or i[key] <= 0:
        return ""
    return f"{r[key] / i[key]:.3f}"


def main(path):
    rows, labels = read_results(path)
    inputs = {name: r for name, label, r, _, _ in rows if label == "input"}
    print("| case | mesh | faces | accuracy90 | x input | normal_deg | x input | "
          "median x input | p90 x input | completeness % | - input | chamfer | s | MB | floors |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    worst = {}
    for name, label, r, secs, mb in rows:
        i = inputs[name]
        if label == "input":
            print(f"| {name} | Poisson input | {r['faces']} | {r['accuracy90']:.4f} | | "
                  f"{r['normal_deg']:.2f} | | | | {r['completeness']:.2f} | | {r['chamfer']:.4f} | | | |")
            continue
        acc = r["accuracy90"] / i["accuracy90"]
        nrm = r["normal_deg"] / i["normal_deg"]
        drop = i["completeness"] - r["completeness"]
        ok = acc <= ACC_FLOOR and nrm <= NORMAL_FLOOR and drop <= COMPLETENESS_DROP
        print(f"| {name} | {label} | {r['faces']} | {r['accuracy90']:.4f} | {acc:.3f} | "
              f"{r['normal_deg']:.2f} | {nrm:.3f} | {angle_ratio(r, i, 'normal_deg_median')} | "
              f"{angle_ratio(r, i, 'normal_deg_p90')} | {r['completeness']:.2f} | {-drop:+.2f} | "
              f"{r['chamfer']:.4f} | {secs:.0f} | {mb} | {'met' if ok else 'NOT met'} |")
        w = worst.setdefault(label, {"acc": (0, ""), "nrm": (0, ""), "drop": (-1e9, ""),
                                     "secs": (0, ""), "mb": (0, ""), "met": 0, "n": 0})
        for key, value in (("acc", acc), ("nrm", nrm), ("drop", drop), ("secs", secs), ("mb", mb)):
            if value > w[key][0]:
                w[key] = (value, name)
        w["met"] += ok
        w["n"] += 1
    print()
    print("| worst case | accuracy90 x input | normal_deg x input | completeness - input | "
          "s | MB | cases meeting all floors |")
    print("|---|---|---|---|---|---|---|")
    for label in labels:
        w = worst[label]
        print(f"| {label} | {w['acc'][0]:.3f} ({w['acc'][1]}) | {w['nrm'][0]:.3f} ({w['nrm'][1]}) | "
              f"{-w['drop'][0]:+.2f} ({w['drop'][1]}) | {w['secs'][0]:.0f} ({w['secs'][1]}) | "
              f"{w['mb'][0]} ({w['mb'][1]}) | {w['met']}/{w['n']} |")
    # The defaults against the baseline, per case (the issue: never worse by > 5 %).
    if "defaults" in labels and "zncc+laplacian" in labels:
        by = {(n, l): r for n, l, r, _, _ in rows}
        worst_acc = worst_nrm = (0, "")
        beyond = []
        for name in inputs:
            d, b = by.get((name, "defaults")), by.get((name, "zncc+laplacian"))
            if d is None or b is None:
                continue
            worst_acc = max(worst_acc, (d["accuracy90"] / b["accuracy90"], name))
            worst_nrm = max(worst_nrm, (d["normal_deg"] / b["normal_deg"], name))
            for key in ("accuracy90", "normal_deg"):
                if d[key] > 1.05 * b[key]:
                    beyond.append(f"{name} {key} {d[key] / b[key]:.3f}")
        print()
        print(f"defaults / zncc+laplacian, worst case: accuracy90 {worst_acc[0]:.3f} "
              f"({worst_acc[1]}), normal_deg {worst_nrm[0]:.3f} ({worst_nrm[1]}); "
              f"bound 1.05; beyond it: {', '.join(beyond) if beyond else 'none'}")


if __name__ == "__main__":
    main(sys.argv[1])
