#!/usr/bin/env python3
"""Table of run_image_size.sh results (run_corpus.sh's results.tsv with one
configuration per working resolution, labelled by its longest side or
"full"): per case and size, accuracy90 and normal error (also as a ratio to
the full-resolution run) and the time; then per size the worst case of the
ratios and the slowest run.

  python3 benchmark/refine/image_size_table.py OUT_DIR/results.tsv
"""
import sys

from corpus_table import read_results


def main(path):
    rows, sizes = read_results(path)
    full = {n: r for n, l, r, _, _ in rows if l == "full"}
    print("| case | working size | faces | accuracy90 | / full | normal_deg | / full | "
          "completeness % | s | MB |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    worst = {}
    for name, label, r, secs, mb in rows:
        f = full.get(name)
        acc = r["accuracy90"] / f["accuracy90"] if f else float("nan")
        nrm = r["normal_deg"] / f["normal_deg"] if f else float("nan")
        shown = "Poisson input" if label == "input" else label
        print(f"| {name} | {shown} | {r['faces']} | {r['accuracy90']:.4f} | {acc:.3f} | "
              f"{r['normal_deg']:.2f} | {nrm:.3f} | {r['completeness']:.2f} | "
              f"{'' if label == 'input' else f'{secs:.0f}'} | {'' if label == 'input' else mb} |")
        if label == "input" or not f:
            continue
        w = worst.setdefault(label, {"acc": (0, ""), "nrm": (0, ""), "secs": (0, ""), "mb": 0})
        for key, value in (("acc", acc), ("nrm", nrm), ("secs", secs)):
            if value > w[key][0]:
                w[key] = (value, name)
        w["mb"] = max(w["mb"], mb)
    print()
    print("| working size | worst accuracy90 / full | worst normal_deg / full | slowest s | "
          "most MB |")
    print("|---|---|---|---|---|")
    for label in sizes:
        if label in worst:
            w = worst[label]
            print(f"| {label} | {w['acc'][0]:.3f} ({w['acc'][1]}) | {w['nrm'][0]:.3f} "
                  f"({w['nrm'][1]}) | {w['secs'][0]:.0f} ({w['secs'][1]}) | {w['mb']} |")


if __name__ == "__main__":
    main(sys.argv[1])
