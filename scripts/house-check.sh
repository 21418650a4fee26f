#!/usr/bin/env bash
# The house check of the user guide (section 7): for each seed, `papillon-sim serve --map house`
# in real time (its laser with the board's `laser.noise_fraction`, the noise the runner
# simulates), `papillon run --board boards/sim.json` against it (the board's mission seed set
# to the seed), then `papillon-sim score` of the saved map against the world's truth.
#
#   scripts/house-check.sh [--map house|lab|...] [--limit-s N] [--board FILE] [--faults SPEC]
#                          [--slip thesis|full|realistic|none] [--localize on|off]
#                          [--laser-noise-m S] SEED...
#
# One line per seed: coverage of the truth, map accuracy (known observable cells whose class
# matches the truth), final position and heading error (`papillon run`'s saved pose against
# serve's truth log), mission time, energy steps used, decisions, re-plans per decision and
# how the mission ended (its `done` telemetry; `limit` if it was stopped with SIGTERM at the
# time limit). `--slip` goes to serve (default: serve's, the thesis's slide), `--localize` to
# run (default: the board's $.localize.enabled). Issue 18's check: `--slip realistic
# --localize on`. `--laser-noise-m S` adds serve's range noise that does not grow with the
# range (S metres, 1 sigma; 0.012 for an LMS1xx's statistical error) to the board's fraction.
# A house mission takes 15-20 minutes of real time.
# Release binaries are built into $CARGO_TARGET_DIR (default ./target). Needs jq 1.6+.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
map=house
limit_s=1800
board="$root/boards/sim.json"
faults=""
slip=""
localize=""
noise_m=""
seeds=()
while [ $# -gt 0 ]; do
    case "$1" in
        --map) map=$2; shift 2 ;;
        --limit-s) limit_s=$2; shift 2 ;;
        --board) board=$2; shift 2 ;;
        --faults) faults=$2; shift 2 ;;
        --slip) slip=$2; shift 2 ;;
        --localize) localize=$2; shift 2 ;;
        --laser-noise-m) noise_m=$2; shift 2 ;;
        -h|--help) sed -n 2,20p "$0"; exit 0 ;;
        -*) echo "house-check: unknown option $1" >&2; exit 2 ;;
        *) seeds+=("$1"); shift ;;
    esac
done
[ ${#seeds[@]} -gt 0 ] || seeds=(1)
command -v jq >/dev/null || { echo "house-check: needs jq" >&2; exit 2; }

target=${CARGO_TARGET_DIR:-$root/target}
(cd "$root" && cargo build --quiet --release -p papillon -p papillon-sim --bins)
papillon=$target/release/papillon
sim=$target/release/papillon-sim
work=$(mktemp -d "${TMPDIR:-/tmp}/papillon-house-check.XXXXXX")
# (No apostrophe inside ${...:-...} within double quotes: bash pairs it with the next one and
# the text between is lost.)
echo "house-check: map $map, board $board, slip ${slip:-as serve defaults}, localize ${localize:-as the board says}, laser noise ${noise_m:-0} m beside the board's fraction, logs in $work" >&2

serve_pid=""
cleanup() { [ -n "$serve_pid" ] && kill "$serve_pid" 2>/dev/null || true; }
trap cleanup EXIT

printf '%-6s %9s %9s %8s %8s %10s %7s %9s %13s %s\n' seed coverage accuracy pos_m head_deg time_s steps decisions replans/dec end
for seed in "${seeds[@]}"; do
    dir=$work/seed-$seed
    mkdir -p "$dir"
    jq ".mission.seed = $seed" "$board" > "$dir/board.json"
    # The laser the board describes: its range noise, as the runner simulates it.
    noise=$(jq '.laser.noise_fraction // 0' "$board")
    args=(serve --map "$map" --tcp 127.0.0.1:0 --laser 127.0.0.1:0 --seed "$seed" --laser-noise "$noise"
          --truth-log "$dir/truth.jsonl")
    [ -n "$faults" ] && args+=(--faults "$faults")
    [ -n "$slip" ] && args+=(--slip "$slip")
    [ -n "$noise_m" ] && args+=(--laser-noise-m "$noise_m")
    run_args=()
    [ -n "$localize" ] && run_args+=(--localize "$localize")
    "$sim" "${args[@]}" > "$dir/serve.out" 2> "$dir/serve.err" &
    serve_pid=$!
    for _ in $(seq 100); do
        grep -q '^laser ' "$dir/serve.out" 2>/dev/null && break
        sleep 0.1
    done
    arcos=$(awk '/^arcos tcp/ {print $3; exit}' "$dir/serve.out")
    laser=$(awk '/^laser lms1xx tcp/ {print $4; exit}' "$dir/serve.out")
    [ -n "$arcos" ] && [ -n "$laser" ] || { echo "house-check: serve did not start: $(cat "$dir/serve.err")" >&2; exit 1; }
    "$papillon" run --board "$dir/board.json" --tcp "$arcos" --laser "$laser" \
        --log-dir "$dir/log" "${run_args[@]}" 2> "$dir/papillon.err" &
    run_pid=$!
    end=""
    for _ in $(seq "$limit_s"); do
        kill -0 "$run_pid" 2>/dev/null || break
        sleep 1
    done
    if kill -0 "$run_pid" 2>/dev/null; then
        kill -TERM "$run_pid"
        end=limit
    fi
    wait "$run_pid" || echo "house-check: papillon run exited with $? (seed $seed, see $dir/papillon.err)" >&2
    kill "$serve_pid" 2>/dev/null || true
    wait "$serve_pid" 2>/dev/null || true
    serve_pid=""
    scored=$("$sim" score --map "$map" --robot-map "$dir/log/map.yaml" --json)
    coverage=$(echo "$scored" | jq '.coverage * 100')
    accuracy=$(echo "$scored" | jq '.accuracy * 100')
    state=$dir/log/state.json
    # The truth log's first sample is the start pose: the robot's map frame has it at the
    # origin, so the last true pose is brought into that frame and compared with the saved one.
    read -r pos_err head_err < <(jq -rs --slurpfile s "$state" '
        map(select(.robot == 0)) | .[0] as $a | .[-1] as $b | $s[0].pose as $p
        | ($a.theta_rad | cos) as $c | ($a.theta_rad | sin) as $n
        | ($b.x_m - $a.x_m) as $dx | ($b.y_m - $a.y_m) as $dy
        | ($c * $dx + $n * $dy) as $x | (-$n * $dx + $c * $dy) as $y
        | (($p.theta_rad - ($b.theta_rad - $a.theta_rad)) as $d
           | ($d - 6.283185307179586 * (($d / 6.283185307179586) + 0.5 | floor))) as $h
        | "\((($p.x_m - $x) * ($p.x_m - $x) + ($p.y_m - $y) * ($p.y_m - $y)) | sqrt) \($h * 57.29577951308232)"
        ' "$dir/truth.jsonl")
    done_line=$(grep '"kind":"done"' "$dir/log/telemetry.jsonl" | tail -1 || true)
    [ -n "$end" ] || end=$(echo "$done_line" | jq -r '.reason // "?"' 2>/dev/null || echo "?")
    replans=$(echo "${done_line:-{\}}" | jq -r '.replans_per_decision // empty' 2>/dev/null || true)
    [ -n "$replans" ] || replans=$(grep '"kind":"mission"' "$dir/log/telemetry.jsonl" | tail -1 | jq '.replans_per_decision')
    printf '%-6s %8.2f%% %8.2f%% %8.3f %8.2f %10.0f %7.1f %9d %13.2f %s\n' "$seed" "$coverage" \
        "$accuracy" "$pos_err" "$head_err" \
        "$(jq .mission_time_s "$state")" "$(jq .counters.energy_used_steps "$state")" \
        "$(jq .counters.decisions "$state")" "$replans" "$end"
done
