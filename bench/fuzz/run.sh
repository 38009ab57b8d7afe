#!/usr/bin/env bash
# Fuzzing (issue #14): the `cargo fuzz` targets of `fuzz/` — `ron_model`
# (RON model text → check → generation of small models), `scene` (scene
# text → check against the bundled models) and `urdf` (URDF text →
# conversion → check → generation of small models) — each run for a fixed
# time, one after the other, one libFuzzer process each (no `-jobs`, which
# would fork workers and log to `fuzz-N.log`), at low priority.
#
#   bash bench/fuzz/run.sh [SECONDS_PER_TARGET] [TARGET ...]
#        (default: 1800 seconds; ron_model scene urdf)
#
# Installs what it needs: cargo-fuzz (`cargo install`) and, for the URDF
# seeds, the PyPI package `example-robot-data` in a venv under /tmp (its
# URDFs are copied into the corpus at run time, never committed). Seeds:
# `models/*.ron`, `models/scenes/*.scene.ron`, `fuzz/seeds/` (`ron_model/`,
# `scene/`), the fixtures
# of `eom-gen/tests/fixtures`. Corpora grow in `fuzz/corpus/<target>`,
# crashes land in `fuzz/artifacts/<target>` (both ignored by git); the
# summary (executions, coverage, corpus, crashes) is printed and written to
# `bench/results/fuzz.md` (or `$EOM_FUZZ_OUT`), the logs to
# `target/fuzz-logs/`.
#
# Builds with debug assertions (integer overflow panics too) and without a
# sanitizer: eom-gen forbids unsafe code, and the point is panics, hangs
# (`-timeout`) and memory blow-ups (`-rss_limit_mb`). A finding is
# minimized with `cargo +nightly fuzz tmin -a -s none <target> <artifact>`
# (in `fuzz/`), fixed, and pinned in `eom-gen/tests/fuzz_findings.rs`.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
fuzz="$root/fuzz"
secs="${1:-1800}"
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(ron_model scene urdf)

# cargo-fuzz needs nightly features: the nightly toolchain if there is one,
# else stable with RUSTC_BOOTSTRAP=1.
if rustup toolchain list 2>/dev/null | grep -q '^nightly'; then
    cargo=(cargo +nightly)
else
    export RUSTC_BOOTSTRAP=1
    cargo=(cargo)
fi
if ! cargo fuzz --version >/dev/null 2>&1; then
    nice -n 10 cargo install --locked cargo-fuzz
fi

# Seeds.
venv="${EOM_FUZZ_VENV:-/tmp/eom-fuzz-venv}"
if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c 'import example_robot_data' 2>/dev/null; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install -q example-robot-data
fi
# The package installs its robots under <venv>/share/example-robot-data.
robots="$(find "$venv" -path '*example-robot-data*' -name '*.urdf' 2>/dev/null | sort)"
seed() { # seed TARGET FILE...
    local dir="$fuzz/corpus/$1"
    shift
    mkdir -p "$dir"
    for f in "$@"; do
        [ -f "$f" ] && cp "$f" "$dir/seed-$(md5sum <"$f" | cut -c1-8)-$(basename "$f")"
    done
    return 0
}
seed ron_model "$root"/models/*.ron "$fuzz"/seeds/ron_model/*.ron \
    "$root"/eom-gen/tests/fixtures/every_field.ron
seed scene "$root"/models/scenes/*.scene.ron "$fuzz"/seeds/scene/*.ron \
    "$root"/eom-gen/tests/fixtures/every_field.scene.ron
# shellcheck disable=SC2086
seed urdf "$root"/eom-gen/tests/fixtures/urdf/*.urdf $robots
nrobots=$(printf '%s\n' "$robots" | grep -c . || true)

export CARGO_BUILD_JOBS="${CARGO_BUILD_JOBS:-1}"
logs="$root/target/fuzz-logs"
mkdir -p "$logs" "$root/bench/results"
# The scene target copies the models into a temporary directory per
# process: here, removed at the end.
export TMPDIR="$root/target/fuzz-tmp/$$"
mkdir -p "$TMPDIR"
trap 'rm -rf "$TMPDIR"' EXIT
cd "$fuzz"
echo "building the fuzz targets…"
for t in "${targets[@]}"; do
    nice -n 10 "${cargo[@]}" fuzz build -a -s none "$t"
done

rows=()
for t in "${targets[@]}"; do
    log="$logs/$t.log"
    dict="$fuzz/dict/ron.dict"
    [ "$t" = urdf ] && dict="$fuzz/dict/urdf.dict"
    mkdir -p "$fuzz/artifacts/$t"
    before=$(find "$fuzz/artifacts/$t" -type f | wc -l)
    seeds=$(find "$fuzz/corpus/$t" -type f | wc -l)
    echo "fuzzing $t for ${secs}s ($seeds inputs in the corpus) → $log"
    start=$(date +%s)
    set +e
    nice -n 10 "${cargo[@]}" fuzz run -a -s none "$t" -- \
        -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 \
        -dict="$dict" -print_final_stats=1 >"$log" 2>&1
    rc=$?
    set -e
    ran=$(($(date +%s) - start))
    after=$(find "$fuzz/artifacts/$t" -type f | wc -l)
    execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | tail -1 | grep -o '[0-9]*$' || echo "?")
    last=$(grep -E '^#[0-9]+' "$log" | tail -1)
    cov=$(grep -o 'cov: [0-9]*' <<<"$last" | grep -o '[0-9]*' || echo "?")
    ft=$(grep -o 'ft: [0-9]*' <<<"$last" | grep -o '[0-9]*' || echo "?")
    corp=$(grep -o 'corp: [0-9]*' <<<"$last" | grep -o '[0-9]*' || echo "?")
    rss=$(grep -o 'stat::peak_rss_mb: *[0-9]*' "$log" | tail -1 | grep -o '[0-9]*$' || echo "?")
    crashes=$((after - before))
    status="ok"
    if [ "$rc" -ne 0 ] || [ "$crashes" -ne 0 ]; then
        status="FAILED (exit $rc; see $log and fuzz/artifacts/$t)"
    fi
    echo "  $t: ${ran}s, $execs executions, cov $cov, ft $ft, corpus $corp, $crashes new artifacts: $status"
    rows+=("| \`$t\` | $ran | $execs | $((execs / (ran > 0 ? ran : 1))) | $seeds | $corp | $cov | $ft | $rss | $crashes | $status |")
done

{
    echo "# Fuzzing: $(date -u +%Y-%m-%d) at $(git -C "$root" rev-parse --short HEAD)"
    echo
    echo "\`bash bench/fuzz/run.sh $secs ${targets[*]}\`; $("${cargo[@]}" --version 2>/dev/null),"
    echo "$(cargo fuzz --version 2>/dev/null), debug assertions, no sanitizer, one job,"
    echo "\`-timeout=10 -rss_limit_mb=2048\`; URDF seeds include $nrobots robots of \`example-robot-data\`."
    echo
    echo "| target | seconds | executions | exec/s | corpus files at start | corpus at end (units) | cov | ft | peak RSS MB | crashes | status |"
    echo "|---|---|---|---|---|---|---|---|---|---|---|"
    printf '%s\n' "${rows[@]}"
} | tee "${EOM_FUZZ_OUT:-$root/bench/results/fuzz.md}"
