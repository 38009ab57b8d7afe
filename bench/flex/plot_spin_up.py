#!/usr/bin/env python3
"""SVG plot of the spin-up tip deflection (bench/results/spin_up.csv, written by
`SPIN_UP_CSV=$PWD/bench/results/spin_up.csv cargo test -p eom-gen --test all flex_spin_up::`).
Usage: python3 bench/flex/plot_spin_up.py bench/results/spin_up.csv bench/results/spin_up.svg"""
import csv
import sys

rows = list(csv.DictReader(open(sys.argv[1])))
W, H, ML, MR, MT, MB = 760, 420, 70, 20, 30, 50
T0, T1, Y0, Y1 = 0.0, 30.0, -1.0, 0.4


def px(t, y):
    return (ML + (t - T0) / (T1 - T0) * (W - ML - MR),
            MT + (Y1 - y) / (Y1 - Y0) * (H - MT - MB))


def line(key, colour, dash=""):
    pts = []
    for r in rows:
        t, y = float(r["t"]), float(r[key])
        if not (Y0 <= y <= Y1):
            break
        pts.append("%.1f,%.1f" % px(t, y))
    return '<polyline fill="none" stroke="%s" stroke-width="1.6" %s points="%s"/>' % (
        colour, dash, " ".join(pts))


out = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" font-family="sans-serif" font-size="12">' % (W, H),
       '<rect width="100%" height="100%" fill="white"/>']
for y in [-1.0, -0.8, -0.6, -0.4, -0.2, 0.0, 0.2, 0.4]:
    a, b = px(T0, y), px(T1, y)
    out.append('<line x1="%.1f" y1="%.1f" x2="%.1f" y2="%.1f" stroke="#ddd"/>' % (a[0], a[1], b[0], b[1]))
    out.append('<text x="%.1f" y="%.1f" text-anchor="end">%.1f</text>' % (a[0] - 6, a[1] + 4, y))
for t in range(0, 31, 5):
    a, b = px(t, Y0), px(t, Y1)
    out.append('<line x1="%.1f" y1="%.1f" x2="%.1f" y2="%.1f" stroke="#ddd"/>' % (a[0], a[1], b[0], b[1]))
    out.append('<text x="%.1f" y="%.1f" text-anchor="middle">%d</text>' % (a[0], a[1] + 16, t))
out.append('<text x="%d" y="%d" text-anchor="middle">t (s)</text>' % ((W + ML) / 2, H - 10))
out.append('<text x="16" y="%d" transform="rotate(-90 16 %d)" text-anchor="middle">tip deflection u_y(L) in the rotating frame (m)</text>' % (H / 2, H / 2))
out.append(line("quasi_static", "#999", 'stroke-dasharray="5,4"'))
out.append(line("tip_linear", "#d62728"))
out.append(line("tip_stiffening", "#1f77b4"))
out.append('<text x="%d" y="20" text-anchor="middle">Spin-up of a flexible beam (0 → 6 rad/s in 15 s; L = 10 m, EI = 1.4e4 N m²)</text>' % ((W + ML) / 2))
legend = [("#1f77b4", "FFR with geometric stiffening"), ("#d62728", "linear FFR (diverges past Ω = ω₁ at 8.5 s; clipped at −1 m)"),
          ("#999", "quasi-static lag under the hub's acceleration")]
for k, (c, label) in enumerate(legend):
    y = H - MB - 70 + 18 * k
    out.append('<line x1="%d" y1="%d" x2="%d" y2="%d" stroke="%s" stroke-width="2"/>' % (ML + 330, y, ML + 360, y, c))
    out.append('<text x="%d" y="%d">%s</text>' % (ML + 366, y + 4, label))
out.append('</svg>')
open(sys.argv[2], "w").write("\n".join(out) + "\n")
