#!/bin/sh
# The animation page in a real browser: installs Debian's chromium if
# missing, writes the page of a 2 s run of the double pendulum, opens it
# headless at t = 0 and t = 1 s (the page honours `#t=SECONDS`), requires
# no console error and no uncaught exception, and checks that both
# screenshots show the mechanism and differ (tests/browser/png_check.py).
#   tests/browser/animate.sh            (from the repository root)
# EOM_GEN=path/to/eom-gen uses that binary instead of `cargo run`.
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
here="$root/tests/browser"
if ! command -v chromium >/dev/null 2>&1; then
    echo "installing chromium (apt-get) ..."
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -q >/dev/null
    apt-get install -y -q chromium >/dev/null
fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
if [ -n "${EOM_GEN:-}" ]; then
    "$EOM_GEN" animate "$root/models/double_pendulum.ron" --t-end 2 -o "$out/run.html"
else
    (cd "$root" && cargo run -q -p eom-cli -- animate models/double_pendulum.ron --t-end 2 -o "$out/run.html")
fi
shot() { # shot T FILE: a screenshot at time T; the browser's log in FILE.log
    timeout 120 chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
        --disable-background-networking --disable-component-update --disable-sync \
        --enable-unsafe-swiftshader --user-data-dir="$(mktemp -d -p "$out")" \
        --enable-logging=stderr --v=0 --window-size=800,600 \
        --screenshot="$2" "file://$out/run.html#t=$1" 2>"$2.log" >/dev/null
    # Console lines of the page, less WebGL's performance notes.
    if grep 'CONSOLE' "$2.log" | grep -v 'GL Driver Message' | grep -q .; then
        echo "console messages of the page at t = $1:"
        grep 'CONSOLE' "$2.log" | grep -v 'GL Driver Message'
        exit 1
    fi
    test -s "$2" || { echo "no screenshot at t = $1"; cat "$2.log"; exit 1; }
}
shot 0 "$out/t0.png"
shot 1 "$out/t1.png"
python3 "$here/png_check.py" "$out/t0.png" "$out/t1.png"
if [ -n "${EOM_SHOTS:-}" ]; then cp "$out/t0.png" "$out/t1.png" "$EOM_SHOTS/"; fi
echo "animation page: drawn, moved, no console errors"
