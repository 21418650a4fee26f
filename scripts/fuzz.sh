#!/usr/bin/env bash
# Runs every cargo-fuzz target of fuzz/ for a bounded time, installing cargo-fuzz first if
# it is missing. Needs a nightly toolchain (libFuzzer with the address sanitizer); without one
# it says so and exits 0.
#
#   scripts/fuzz.sh                  # every target, 60 s each
#   FUZZ_SECONDS=600 scripts/fuzz.sh # longer
#   scripts/fuzz.sh map_file board_json
#
# A crash stops the script with a non-zero exit; the input that crashed is kept under
# fuzz/artifacts/<target>/ (reproduce with `cargo +nightly fuzz run <target> <file>`). The
# corpora grown under fuzz/corpus/ are not committed; the seeds are (fuzz/seeds/).
set -euo pipefail
cd "$(dirname "$0")/.."

seconds="${FUZZ_SECONDS:-60}"
cargo_fuzz_version="0.13.2"

if ! rustup toolchain list 2>/dev/null | grep -q '^nightly'; then
    echo "fuzz: no nightly toolchain (rustup toolchain list); skipped"
    exit 0
fi
if ! cargo fuzz --version >/dev/null 2>&1; then
    echo "fuzz: installing cargo-fuzz $cargo_fuzz_version"
    cargo install cargo-fuzz --version "$cargo_fuzz_version" --locked
fi

targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
    # The files of fuzz/fuzz_targets/ (`cargo fuzz list` also names the seed program).
    for f in fuzz/fuzz_targets/*.rs; do
        targets+=("$(basename "$f" .rs)")
    done
fi

# The fuzz builds (release, sanitizer) are kept apart from the workspace's.
export CARGO_TARGET_DIR="${FUZZ_TARGET_DIR:-$PWD/target/fuzz}"
log_dir="$CARGO_TARGET_DIR/logs"
mkdir -p "$log_dir"
for t in "${targets[@]}"; do
    mkdir -p "fuzz/corpus/$t"
    echo "=== fuzz $t: ${seconds} s (log: $log_dir/$t.log)"
    status=0
    nice -n 10 cargo +nightly fuzz run -O "$t" "fuzz/corpus/$t" "fuzz/seeds/$t" -- \
        -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
        >"$log_dir/$t.log" 2>&1 || status=$?
    grep -E '^(stat::number_of_executed_units|stat::peak_rss_mb)|^#[0-9]+ +DONE|^SUMMARY|panicked' \
        "$log_dir/$t.log" || true
    if [ "$status" -ne 0 ]; then
        tail -n 30 "$log_dir/$t.log"
        echo "fuzz: $t FAILED (input kept under fuzz/artifacts/$t/)"
        exit 1
    fi
done
echo "fuzz: ${#targets[@]} target(s) ran ${seconds} s each without a crash"
