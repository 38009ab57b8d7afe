#!/bin/sh
# Follows README.md's "Use eom in your own crate" verbatim in an empty
# directory: each block marked `<!-- newcomer:DIR/FILE -->` is written to
# DIR/FILE with `/path/to/eom` replaced by this checkout, the model is
# copied, and both crates (macro and build.rs) are built and run. Reuses
# the workspace's target directory (CARGO_TARGET_DIR) so that it takes
# seconds once the workspace is built.
set -eu
repo=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$repo/target}"
awk -v out="$work" -v repo="$repo" '
    /^<!-- newcomer:.* -->$/ { file = $2; sub(/^newcomer:/, "", file); next }
    file != "" && /^```/ && !inside { inside = 1; path = out "/" file; system("mkdir -p \"$(dirname \"" path "\")\""); printf "" > path; next }
    inside && /^```$/ { inside = 0; close(path); file = ""; next }
    inside { gsub("/path/to/eom", repo); print >> path }
' "$repo/README.md"
for kind in macro build; do
    test -f "$work/$kind/Cargo.toml" || { echo "newcomer: no $kind/Cargo.toml block in README.md" >&2; exit 1; }
    mkdir -p "$work/$kind/models"
    cp "$repo/models/pendulum.ron" "$work/$kind/models/"
    out=$(cd "$work/$kind" && cargo run -q 2>&1) || { echo "$out" >&2; exit 1; }
    echo "$kind: $out"
    case "$out" in
        *"t = 1: theta = "*) ;;
        *) echo "newcomer: unexpected output of the $kind crate" >&2; exit 1 ;;
    esac
done
# Without eom-sim in its Cargo.toml, the macro says what to add instead of
# rustc's bare "could not find `eom_sim`".
mkdir -p "$work/missing"
cp -r "$work/macro/src" "$work/macro/models" "$work/missing/"
grep -v '^eom-sim' "$work/macro/Cargo.toml" > "$work/missing/Cargo.toml"
if out=$(cd "$work/missing" && cargo build -q 2>&1); then
    echo "newcomer: a crate without eom-sim built" >&2; exit 1
fi
case "$out" in
    *"uses the \`eom-sim\` runtime"*"add \`eom-sim = "*) echo "missing eom-sim: the macro says what to add" ;;
    *) echo "$out" >&2; echo "newcomer: no helpful error without eom-sim" >&2; exit 1 ;;
esac
