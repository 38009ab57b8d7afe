#!/bin/sh
# Time to the first frame of an animation page, measured inside the page:
# `performance.now()` (ms since navigation started) when the first frame
# has been rendered, which the page writes to <body data-first-frame-ms>;
# read here from headless Debian chromium's `--dump-dom` (software WebGL).
# Includes reading and parsing the file, three.js, building the scene and
# the first render; not the browser's own start-up.
#   tests/browser/first_frame.sh PAGE.html [RUNS]     (default 3 runs)
set -eu
page=$(realpath "$1")
runs=${2:-3}
command -v chromium >/dev/null 2>&1 || { echo "chromium is missing (tests/browser/animate.sh installs it)"; exit 1; }
size=$(stat -c %s "$page")
k=0
while [ "$k" -lt "$runs" ]; do
    k=$((k + 1))
    d=$(mktemp -d)
    ms=$(timeout 300 chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
        --disable-background-networking --disable-component-update --disable-sync \
        --enable-unsafe-swiftshader --user-data-dir="$d" --window-size=800,600 \
        --dump-dom "file://$page" 2>/dev/null | grep -o 'data-first-frame-ms="[0-9.]*"' | grep -o '[0-9.][0-9.]*' || true)
    rm -rf "$d"
    [ -n "$ms" ] || { echo "$page: no first frame (the page failed?)"; exit 1; }
    echo "$page ($size bytes): first frame at $ms ms"
done
