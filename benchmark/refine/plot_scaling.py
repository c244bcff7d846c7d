#!/usr/bin/env python3
"""Log-log plot of run_scaling.sh's table, as a standalone SVG (no plotting
library needed): seconds per iteration against pixels x views (faces held)
and against faces (image size held), each with its least-squares slope, for
the whole iteration and for the data term alone.

    python3 benchmark/refine/plot_scaling.py scaling.tsv scaling.svg
"""
import csv
import math
import sys


def fit(xs, ys):
    """Slope and intercept of log10(y) = a log10(x) + b."""
    lx = [math.log10(x) for x in xs]
    ly = [math.log10(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    sxx = sum((x - mx) ** 2 for x in lx)
    a = sum((x - mx) * (y - my) for x, y in zip(lx, ly)) / sxx
    return a, my - a * mx


def panel(rows, xkey, title, xlabel, x0, width=420, height=320):
    """One panel's SVG elements, placed at horizontal offset x0."""
    xs = [float(r[xkey]) for r in rows]
    series = [("seconds", "iteration", "#1f77b4"), ("data", "data term", "#d62728")]
    ys_all = [float(r[k]) for r in rows for k, _, _ in series]
    lx0, lx1 = math.floor(math.log10(min(xs)) * 2) / 2, math.ceil(math.log10(max(xs)) * 2) / 2
    ly0, ly1 = math.floor(math.log10(min(ys_all))), math.ceil(math.log10(max(ys_all)))
    left, top, pw, ph = x0 + 60, 40, width - 80, height - 90

    def px(x):
        return left + (math.log10(x) - lx0) / (lx1 - lx0) * pw

    def py(y):
        return top + ph - (math.log10(y) - ly0) / (ly1 - ly0) * ph

    out = [f'<text x="{left + pw / 2}" y="22" text-anchor="middle" font-size="14">{title}</text>',
           f'<rect x="{left}" y="{top}" width="{pw}" height="{ph}" fill="none" stroke="#000"/>']
    for e in range(int(ly0), int(ly1) + 1):
        y = py(10 ** e)
        out.append(f'<line x1="{left}" x2="{left + pw}" y1="{y}" y2="{y}" stroke="#ddd"/>')
        out.append(f'<text x="{left - 6}" y="{y + 4}" text-anchor="end" font-size="11">'
                   f'{10.0 ** e:g}</text>')
    e = math.ceil(lx0)
    while e <= lx1:
        x = px(10 ** e)
        out.append(f'<line x1="{x}" x2="{x}" y1="{top}" y2="{top + ph}" stroke="#ddd"/>')
        out.append(f'<text x="{x}" y="{top + ph + 16}" text-anchor="middle" font-size="11">'
                   f'1e{e}</text>')
        e += 1
    out.append(f'<text x="{left + pw / 2}" y="{top + ph + 36}" text-anchor="middle" '
               f'font-size="12">{xlabel}</text>')
    out.append(f'<text x="{x0 + 16}" y="{top + ph / 2}" font-size="12" text-anchor="middle" '
               f'transform="rotate(-90 {x0 + 16} {top + ph / 2})">seconds per iteration</text>')
    # Slope 1 through the largest run's iteration time, for reference.
    x_hi, y_hi = max(xs), float(max(rows, key=lambda r: float(r[xkey]))["seconds"])
    x_lo = max(min(xs), x_hi * 10 ** ly0 / y_hi)  # not below the plot
    out.append(f'<line x1="{px(x_lo)}" y1="{py(y_hi * x_lo / x_hi)}" x2="{px(x_hi)}" '
               f'y2="{py(y_hi)}" stroke="#888" stroke-dasharray="1 3"/>')
    out.append(f'<text x="{left + 8}" y="{top + 48}" font-size="12" fill="#888">'
               f'dotted: slope 1</text>')
    for k, (key, label, colour) in enumerate(series):
        ys = [float(r[key]) for r in rows]
        a, b = fit(xs, ys)
        lo, hi = min(xs), max(xs)
        out.append(f'<line x1="{px(lo)}" y1="{py(10 ** (a * math.log10(lo) + b))}" '
                   f'x2="{px(hi)}" y2="{py(10 ** (a * math.log10(hi) + b))}" '
                   f'stroke="{colour}" stroke-dasharray="4 3"/>')
        for x, y in zip(xs, ys):
            out.append(f'<circle cx="{px(x)}" cy="{py(y)}" r="3.5" fill="{colour}"/>')
        out.append(f'<text x="{left + 8}" y="{top + 16 + 16 * k}" font-size="12" '
                   f'fill="{colour}">{label}: slope {a:.2f}</text>')
    return out


def main():
    rows = list(csv.DictReader(open(sys.argv[1]), delimiter="\t"))
    pixels = [r for r in rows if r["sweep"] == "pixels"]
    faces = [r for r in rows if r["sweep"] == "faces"]
    body = panel(pixels, "pixels_x_views",
                 f"faces held at {pixels[0]['faces']}", "pixels x views", 0)
    body += panel(faces, "faces", f"{faces[0]['width']}x{faces[0]['height']} images, "
                  f"{faces[0]['views']} views", "faces", 420)
    with open(sys.argv[2], "w") as f:
        f.write('<svg xmlns="http://www.w3.org/2000/svg" width="840" height="320" '
                'font-family="sans-serif">\n<rect width="840" height="320" fill="#fff"/>\n')
        f.write("\n".join(body))
        f.write("\n</svg>\n")
    for name, sweep, key in (("pixels x views", pixels, "pixels_x_views"),
                             ("faces", faces, "faces")):
        xs = [float(r[key]) for r in sweep]
        print(f"slope against {name}: iteration {fit(xs, [float(r['seconds']) for r in sweep])[0]:.2f}, "
              f"data term {fit(xs, [float(r['data']) for r in sweep])[0]:.2f}")


if __name__ == "__main__":
    main()
