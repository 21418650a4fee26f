#!/usr/bin/env bash
# Fault soak (docs/reliability.md, section "Soaks"): for each seed, `papillon-sim serve` in real
# time with the faults given (`--faults SPEC`, seeded with the seed) and a truth log, and
# `papillon run --board boards/sim.json` against it (the board's mission seed set to the seed),
# several missions at once.
#
#   scripts/soak.sh [--map lab] [--faults SPEC] [--link tcp|pty] [--watchdog-ms MS]
#                   [--jobs N] [--limit-s N] [--board FILE] [--resume-check] [--keep] SEED...
#
# Defaults: the lab, no fault, tcp, serve's watchdog (2000 ms), 4 jobs, a limit of 600 s per
# mission, boards/sim.json, seeds 1 to 10.
#
# One line per mission, in seed order:
#   seed       the seed (serve's faults and slip, the mission's RNG)
#   connected  whether `papillon run` got through the ARCOS start-up (its "connected" line)
#   end        finished (the mission ended by itself, exit 0), stopped (exit 0 before the end:
#              the time limit's SIGTERM) or failed (non-zero exit)
#   reason     the `done` record's reason, `limit`, or the error's first words
#   coverage   of the world's truth by the saved map (`papillon-sim score`)
#   time_s     mission time saved in state.json
#   faults     fault records in the telemetry (each a stop with its reason logged)
#   reconnects robot or laser link re-established during the mission
#   contacts   contacts in serve's truth log (a wheel stall or a bumper; rising edges)
#   moving_end whether the robot still moved 1.5 s after `papillon` ended (the truth log's last
#              half second)
#   cut_stop_s for each `cut=T+D` during which the robot was moving at T: seconds until the
#              truth log shows it still (`-` for none)
#   lost       with --resume-check: cells of the saved map known before `papillon run
#              --resume` and unknown after it (run until its first save after 6 s, or its
#              end); `-` without
#
# --link pty serves ARCOS on a pseudo-terminal (a serial line: a cut is silence and only the
# firmware watchdog, `--watchdog-ms`, stops the robot); tcp (default) disconnects the client
# on a cut. Release binaries are built into $CARGO_TARGET_DIR (default ./target). Logs stay in
# a directory under ${TMPDIR:-/tmp} (named on stderr; removed at the end unless --keep). A lab
# mission takes 2-4 minutes of real time and little CPU, so --jobs 4 suits two cores. Needs jq
# and python3.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
map=lab
faults=""
link=tcp
watchdog_ms=""
jobs=4
limit_s=600
resume_check=0
keep=0
board="$root/boards/sim.json"
seeds=()
while [ $# -gt 0 ]; do
    case "$1" in
        --map) map=$2; shift 2 ;;
        --faults) faults=$2; shift 2 ;;
        --link) link=$2; shift 2 ;;
        --watchdog-ms) watchdog_ms=$2; shift 2 ;;
        --jobs) jobs=$2; shift 2 ;;
        --limit-s) limit_s=$2; shift 2 ;;
        --resume-check) resume_check=1; shift ;;
        --keep) keep=1; shift ;;
        --board) board=$2; shift 2 ;;
        -h|--help) sed -n 2,37p "$0"; exit 0 ;;
        -*) echo "soak: unknown option $1" >&2; exit 2 ;;
        *) seeds+=("$1"); shift ;;
    esac
done
[ ${#seeds[@]} -gt 0 ] || seeds=(1 2 3 4 5 6 7 8 9 10)
case "$link" in tcp|pty) ;; *) echo "soak: --link is tcp or pty, not $link" >&2; exit 2 ;; esac
command -v jq >/dev/null || { echo "soak: needs jq" >&2; exit 2; }
command -v python3 >/dev/null || { echo "soak: needs python3" >&2; exit 2; }

target=${CARGO_TARGET_DIR:-$root/target}
(cd "$root" && cargo build --quiet --release -p papillon -p papillon-sim --bins)
papillon=$target/release/papillon
sim=$target/release/papillon-sim
work=$(mktemp -d "${TMPDIR:-/tmp}/papillon-soak.XXXXXX")
echo "soak: map $map, link $link, faults '${faults}', watchdog ${watchdog_ms:-2000} ms, logs in $work" >&2

# Truth-log figures: contacts (rising edges), whether the robot moved in the last second, and
# the stop time of each cut the robot was moving into.
truth_figures() {
    python3 - "$1" "$faults" <<'EOF'
import json, sys
path, spec = sys.argv[1], sys.argv[2]
cuts = []
for item in spec.split(','):
    name, _, value = item.strip().partition('=')
    if name == 'cut':
        t, d = value.split('+')
        cuts.append((float(t), float(d)))
rows = []
with open(path) as f:
    for line in f:
        try:
            r = json.loads(line)
        except ValueError:
            continue
        if r.get('robot') == 0:
            rows.append(r)
moving = lambda r: r['speed_mm_s'] != 0 or r['turn_deg_s'] != 0
contacts, was = 0, False
for r in rows:
    c = bool(r.get('contact', False))
    contacts += c and not was
    was = c
end = rows[-1]['t_s'] if rows else 0
moving_end = any(moving(r) for r in rows if r['t_s'] >= end - 0.5)
stops = []
for t, d in cuts:
    at = [r for r in rows if r['t_s'] >= t]
    if not at or not moving(at[0]):
        continue
    still = next((r['t_s'] for r in at if not moving(r)), None)
    stops.append('never' if still is None else '%.2f' % (still - t))
print(contacts, 'yes' if moving_end else 'no', ','.join(stops) or '-')
EOF
}

# Cells known in PGM $1 and unknown (205) in PGM $2 of the same size.
lost_cells() {
    python3 - "$1" "$2" <<'EOF'
import sys
def pgm(path):
    data = open(path, 'rb').read()
    fields, i = [], 0
    while len(fields) < 4:
        while data[i:i+1].isspace():
            i += 1
        if data[i:i+1] == b'#':
            i = data.index(b'\n', i)
            continue
        j = i
        while not data[j:j+1].isspace():
            j += 1
        fields.append(data[i:j]); i = j
    return (int(fields[1]), int(fields[2])), data[i+1:]
(size_a, a), (size_b, b) = pgm(sys.argv[1]), pgm(sys.argv[2])
if size_a != size_b:
    print('size-changed'); sys.exit()
print(sum(1 for x, y in zip(a, b) if x != 205 and y == 205))
EOF
}

# Waits for pid $1 at most $2 s; SIGTERM (then 20 s later SIGKILL) past it. Prints "limit" if
# it had to be stopped.
wait_limit() {
    local pid=$1 limit=$2 i
    for ((i = 0; i < limit * 2; i++)); do
        kill -0 "$pid" 2>/dev/null || return 0
        sleep 0.5
    done
    echo limit
    kill -TERM "$pid" 2>/dev/null || true
    for ((i = 0; i < 40; i++)); do
        kill -0 "$pid" 2>/dev/null || return 0
        sleep 0.5
    done
    kill -KILL "$pid" 2>/dev/null || true
}

mission() {
    local seed=$1 dir=$work/seed-$1
    mkdir -p "$dir"
    jq ".mission.seed = $seed" "$board" > "$dir/board.json"
    local args=(serve --map "$map" --laser 127.0.0.1:0 --seed "$seed" --truth-log "$dir/truth.jsonl")
    [ "$link" = tcp ] && args+=(--tcp 127.0.0.1:0) || args+=(--pty "$dir/robot")
    [ -n "$faults" ] && args+=(--faults "$faults")
    [ -n "$watchdog_ms" ] && args+=(--watchdog-ms "$watchdog_ms")
    "$sim" "${args[@]}" > "$dir/serve.out" 2> "$dir/serve.err" &
    local serve_pid=$!
    for _ in $(seq 100); do
        grep -q '^laser ' "$dir/serve.out" 2>/dev/null && break
        sleep 0.1
    done
    local laser robot_args
    laser=$(awk '/^laser lms1xx tcp/ {print $4; exit}' "$dir/serve.out")
    if [ "$link" = tcp ]; then
        robot_args=(--tcp "$(awk '/^arcos tcp/ {print $3; exit}' "$dir/serve.out")")
    else
        robot_args=(--port "$dir/robot")
    fi
    if [ -z "$laser" ]; then
        echo "$seed serve-did-not-start: $(head -c 200 "$dir/serve.err")" > "$dir/result"
        kill "$serve_pid" 2>/dev/null || true
        return
    fi
    "$papillon" run --board "$dir/board.json" "${robot_args[@]}" --laser "$laser" \
        --log-dir "$dir/log" > "$dir/papillon.out" 2> "$dir/papillon.err" &
    local run_pid=$! limited code=0
    limited=$(wait_limit "$run_pid" "$limit_s")
    wait "$run_pid" || code=$?
    local tel=$dir/log/telemetry.jsonl state=$dir/log/state.json
    local connected=no end reason
    grep -q ' connected ' "$dir/papillon.err" && connected=yes
    if [ "$code" -ne 0 ]; then
        end=failed
        reason=$(grep -v '^\s*$' "$dir/papillon.err" | tail -1 | sed 's/^papillon: //' | tr -s ' \t' '__' | cut -c1-60)
    elif [ -n "$limited" ]; then
        end=stopped reason=limit
    elif [ -f "$state" ] && [ "$(jq .finished "$state")" = true ]; then
        end=finished
        reason=$(grep '"kind":"done"' "$tel" | tail -1 | jq -r '.reason // "?"')
    else
        end=stopped
        reason=$(grep '"kind":"fault"' "$tel" 2>/dev/null | tail -1 | jq -r '.what // .fault // "?"' | tr ' ' '_')
    fi
    local lost=-
    if [ "$resume_check" = 1 ] && [ -f "$dir/log/map.pgm" ]; then
        cp "$dir/log/map.pgm" "$dir/before.pgm"
        local saved_s
        saved_s=$(jq .mission_time_s "$state")
        "$papillon" run --board "$dir/board.json" "${robot_args[@]}" --laser "$laser" \
            --log-dir "$dir/log" --resume > "$dir/resume.out" 2> "$dir/resume.err" &
        local resume_pid=$! i
        for ((i = 0; i < 120; i++)); do
            kill -0 "$resume_pid" 2>/dev/null || break
            [ "$i" -ge 12 ] && [ "$(jq .mission_time_s "$state" 2>/dev/null)" != "$saved_s" ] && break
            sleep 0.5
        done
        kill -TERM "$resume_pid" 2>/dev/null || true
        wait "$resume_pid" || true
        lost=$(lost_cells "$dir/before.pgm" "$dir/log/map.pgm")
        grep -q 'resuming saved mission' "$dir/resume.err" || lost="not-resumed"
    fi
    sleep 1.5 # the truth log's last half second: the robot after `papillon` ended
    kill "$serve_pid" 2>/dev/null || true
    wait "$serve_pid" 2>/dev/null || true
    local coverage=nan time_s=nan nfaults=0 reconnects=0
    [ -f "$dir/log/map.yaml" ] && coverage=$("$sim" score --map "$map" --robot-map "$dir/log/map.yaml" --json | jq '.coverage * 100')
    [ -f "$state" ] && time_s=$(jq .mission_time_s "$state")
    [ -f "$tel" ] && nfaults=$(grep -c '"kind":"fault"' "$tel" || true)
    [ -f "$tel" ] && reconnects=$(grep -c '"kind":"reconnect"' "$tel" || true)
    local contacts moving_end cut_stops
    read -r contacts moving_end cut_stops < <(truth_figures "$dir/truth.jsonl")
    printf '%-5s %-9s %-8s %-22s %7.2f%% %7.0f %6s %10s %8s %10s %-12s %s\n' "$seed" "$connected" \
        "$end" "$reason" "$coverage" "$time_s" "$nfaults" "$reconnects" "$contacts" \
        "$moving_end" "$cut_stops" "$lost" > "$dir/result"
}

running=0
for seed in "${seeds[@]}"; do
    mission "$seed" &
    running=$((running + 1))
    if [ "$running" -ge "$jobs" ]; then
        wait -n || true
        running=$((running - 1))
    fi
    sleep 1
done
wait
printf '%-5s %-9s %-8s %-22s %8s %7s %6s %10s %8s %10s %-12s %s\n' seed connected end reason \
    coverage time_s faults reconnects contacts moving_end cut_stop_s lost
for seed in "${seeds[@]}"; do
    cat "$work/seed-$seed/result" 2>/dev/null || echo "$seed (no result; see $work/seed-$seed)"
done
[ "$keep" = 1 ] || rm -rf "$work"
