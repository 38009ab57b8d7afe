#!/usr/bin/env python3
"""Work-precision diagrams (log-log, CPU time against error) of eom and
Exudyn on the ANCF cases, one panel per case, from the CSV of the figures
in BENCHMARKS.md ("After the elastic kernels, SIMD lanes and a banded LU"),
measured by `cargo run --release -p eom-sim --example ancf_bench -- static |
pendulum N 2.5e-4` and `bench/peers/ancf_exudyn_cases.py` in one session.
Each point is one mesh (its element count written beside it).
Usage: python3 bench/peers/plot_ancf_wp.py bench/results/ancf_wp_plot.csv bench/results/ancf_wp.svg"""
import csv
import math
import sys

rows = list(csv.DictReader(open(sys.argv[1])))
cases = []
for r in rows:
    if r["case"] not in cases:
        cases.append(r["case"])
TITLES = {
    "pendulum_1s": "Falling ANCF pendulum (Berzeri–Shabana), 1 s, h = 2.5e-4 s",
    "static_cantilever": "Static cantilever (Gerstmayr–Irschik), 10 load steps",
}
COLOURS = {"eom": "#1f77b4", "Exudyn": "#d62728"}
PW, PH, ML, MR, MT, MB = 520, 380, 80, 20, 40, 55
W, H = PW * len(cases), PH
out = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" font-family="sans-serif" font-size="12">' % (W, H),
       '<rect width="100%" height="100%" fill="white"/>']
for k, case in enumerate(cases):
    pts = [r for r in rows if r["case"] == case]
    xs = [math.log10(float(r["end_error"])) for r in pts]
    ys = [math.log10(float(r["cpu_ms"])) for r in pts]
    x0, x1 = math.floor(min(xs)), math.ceil(max(xs))
    y0, y1 = math.floor(min(ys)), math.ceil(max(ys))
    ox = k * PW

    def px(x, y):
        return (ox + ML + (x1 - x) / (x1 - x0) * (PW - ML - MR),
                MT + (y1 - y) / (y1 - y0) * (PH - MT - MB))

    for e in range(x0, x1 + 1):
        a, b = px(e, y0), px(e, y1)
        out.append('<line x1="%.1f" y1="%.1f" x2="%.1f" y2="%.1f" stroke="#ddd"/>' % (a[0], a[1], b[0], b[1]))
        out.append('<text x="%.1f" y="%.1f" text-anchor="middle">1e%d</text>' % (a[0], a[1] + 16, e))
    for e in range(y0, y1 + 1):
        a, b = px(x0, e), px(x1, e)
        out.append('<line x1="%.1f" y1="%.1f" x2="%.1f" y2="%.1f" stroke="#ddd"/>' % (a[0], a[1], b[0], b[1]))
        out.append('<text x="%.1f" y="%.1f" text-anchor="end">1e%d</text>' % (b[0] - 4 if False else ox + ML - 6, a[1] + 4, e))
    out.append('<text x="%.1f" y="22" text-anchor="middle" font-weight="bold">%s</text>' % (ox + PW / 2, TITLES.get(case, case)))
    out.append('<text x="%.1f" y="%d" text-anchor="middle">tip error, m (smaller to the right)</text>' % (ox + (PW + ML) / 2, PH - 12))
    out.append('<text x="%.1f" y="%d" transform="rotate(-90 %.1f %d)" text-anchor="middle">CPU time, ms</text>' % (ox + 18, PH / 2, ox + 18, PH / 2))
    for j, tool in enumerate(["eom", "Exudyn"]):
        tp = sorted((r for r in pts if r["tool"] == tool), key=lambda r: -float(r["end_error"]))
        c = COLOURS[tool]
        line = " ".join("%.1f,%.1f" % px(math.log10(float(r["end_error"])), math.log10(float(r["cpu_ms"]))) for r in tp)
        out.append('<polyline fill="none" stroke="%s" stroke-width="1.8" points="%s"/>' % (c, line))
        for r in tp:
            x, y = px(math.log10(float(r["end_error"])), math.log10(float(r["cpu_ms"])))
            out.append('<circle cx="%.1f" cy="%.1f" r="3.5" fill="%s"/>' % (x, y, c))
            out.append('<text x="%.1f" y="%.1f" fill="%s" font-size="10">%s</text>' % (x + 5, y + (12 if tool == "eom" else -6), c, r["elements"]))
        lx, ly = ox + ML + 12, MT + 16 + 16 * j
        out.append('<line x1="%d" y1="%d" x2="%d" y2="%d" stroke="%s" stroke-width="2"/>' % (lx, ly - 4, lx + 20, ly - 4, c))
        out.append('<text x="%d" y="%d">%s</text>' % (lx + 26, ly, tool))
out.append("</svg>")
open(sys.argv[2], "w").write("\n".join(out) + "\n")
