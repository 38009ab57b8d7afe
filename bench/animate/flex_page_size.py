#!/usr/bin/env python3
"""Page size of flexible bodies in an animation page (`eom-gen animate`):
the page as written (per frame each flexible body's k elastic coordinates,
its stations' mode shapes once) against the alternatives of sending every
station's (or only every finite-element node's) world position per frame (3 numbers per station per frame, 6
decimals as the poses), computed from the page's own data: the positions
are the page's `R (p + S q_f) + r` at every frame.
Usage: flex_page_size.py PAGE.html"""
import json
import sys


def number(x):
    """Rust's animate::number: 6 decimals, trailing zeros dropped."""
    s = f"{x:.6f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def turn(q, v):
    x, y, z, w = q
    c = (y * v[2] - z * v[1], z * v[0] - x * v[2], x * v[1] - y * v[0])
    cc = (y * c[2] - z * c[1], z * c[0] - x * c[2], x * c[1] - y * c[0])
    return [v[i] + 2 * w * c[i] + 2 * cc[i] for i in range(3)]


def main(path):
    page = open(path, encoding="utf-8").read()
    tag = 'type="application/json">'
    start = page.index(tag) + len(tag)
    end = page.index("</script>", start)
    data = json.loads(page[start:end].replace("<\\/", "</"))
    flex, ff, poses = data["flex"], data["flexFrames"], data["poses"]
    frames = len(poses)
    modal_frames = len(json.dumps(ff, separators=(",", ":")))
    shapes = sum(len(json.dumps(f["s"], separators=(",", ":"))) for f in flex)
    positions, nodes_only = [], []
    for k in range(frames):
        row, nrow = [], []
        for f in flex:
            o, kk = 7 * f["body"], f["k"]
            r, q = poses[k][o:o + 3], poses[k][o + 3:o + 7]
            qf = ff[k][f["at"]:f["at"] + kk]
            for j in range(len(f["p"]) // 3):
                local = [f["p"][3 * j + a] + sum(f["s"][3 * kk * j + a * kk + m] * qf[m] for m in range(kk))
                         for a in range(3)]
                xyz = [number(r[a] + v) for a, v in enumerate(turn(q, local))]
                row.extend(xyz)
                if j in f["nodes"]:
                    nrow.extend(xyz)
        positions.append("[" + ",".join(row) + "]")
        nodes_only.append("[" + ",".join(nrow) + "]")
    alt_frames = len("[" + ",".join(positions) + "]")
    node_frames = len("[" + ",".join(nodes_only) + "]")
    size = len(page.encode("utf-8"))
    stations = sum(len(f["p"]) // 3 for f in flex)
    alt = size - modal_frames - shapes + alt_frames
    print(f"{path}: {frames} frames, {len(flex)} flexible bod(ies), {stations} stations, "
          f"k = {[f['k'] for f in flex]}")
    print(f"  page as written (elastic coordinates per frame): {size} B "
          f"(flexFrames {modal_frames} B, shapes {shapes} B)")
    print(f"  stations' positions per frame instead: {alt} B (their frames {alt_frames} B), "
          f"{alt / size:.2f}x")
    alt_nodes = size - modal_frames - shapes + node_frames
    print(f"  the nodes' positions per frame instead (straight between nodes): {alt_nodes} B "
          f"(their frames {node_frames} B), {alt_nodes / size:.2f}x")


if __name__ == "__main__":
    main(sys.argv[1])
