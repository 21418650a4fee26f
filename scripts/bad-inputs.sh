#!/usr/bin/env bash
# Tries bad inputs on every subcommand of `papillon` and `papillon-sim` (issue 20) and writes
# the table of docs/reliability.md, section "Bad inputs tried".
#
#   scripts/bad-inputs.sh            # print the table and the summary
#   scripts/bad-inputs.sh --doc      # also replace the table in docs/reliability.md
#
# Builds the debug binaries, writes the bad files (scripts/bad-inputs.py, fixed seed) into a
# fresh directory under ${TMPDIR:-/tmp} and runs each command there, with no standard input,
# at most LIMIT_S seconds (default 20) and at most MEM_MIB MiB of address space (default 2048,
# so that a runaway allocation aborts instead of swapping). Each run is classified:
#   panic    exit 101 or "panicked" on standard error
#   abort    killed by a signal (an abort on a failed allocation is SIGABRT)
#   hang     still running after LIMIT_S seconds
#   accepted exit 0 (a bad input taken as good)
#   refused  any other exit; its error is the last line of standard error.
# The location check (a heuristic): each case lists the words its error must contain, the
# flag (`--pop`) for a bad flag, or the file's name plus the field (`$.mission.seed`, a YAML
# key, `maps[0]`) for a file the program reads; a refusal whose error lacks one of them is
# counted "without a location". The word LINE stands for a line number (`line 3`,
# `file.map:3:`), which is the field's location in a file that does not parse; `a|b` accepts
# either. A file that cannot be read at all (missing, a directory, larger than its limit, not
# text) needs only its name.
#
# Needs bash, coreutils (timeout), python3 and cargo. Exits 1 if any run panicked, aborted,
# hung, was accepted or had an error without a location.
set -u

ROOT=$(cd "$(dirname "$0")/.." && pwd)
LIMIT_S=${LIMIT_S:-20}
MEM_MIB=${MEM_MIB:-2048}
DOC=0
[ "${1:-}" = "--doc" ] && DOC=1

(cd "$ROOT" && cargo build -q -p papillon -p papillon-sim --bins) || exit 2
BIN=${CARGO_TARGET_DIR:-$ROOT/target}/debug
[ -x "$BIN/papillon" ] && [ -x "$BIN/papillon-sim" ] || {
    echo "bad-inputs: no debug binaries in $BIN" >&2
    exit 2
}

W=$(mktemp -d "${TMPDIR:-/tmp}/bad-inputs.XXXXXX")
PIDS=()
cleanup() {
    for p in "${PIDS[@]}"; do kill "$p" 2>/dev/null; done
    rm -rf "$W"
}
trap cleanup EXIT
cd "$W" || exit 2
cp "$ROOT/boards/sim.json" sim.json
python3 "$ROOT/scripts/bad-inputs.py" sim.json \
    "$ROOT/fixtures/house-mid-mission.yaml" "$ROOT/fixtures/house-mid-mission.pgm" || exit 2

ROWS="$W/.rows"
: >"$ROWS"
N=0 PANICS=0 ABORTS=0 HANGS=0 ACCEPTED=0 NOLOC=0

# Markdown cell: pipes escaped, backticks dropped.
cell() { printf '%s' "$1" | tr -d '`' | sed 's/|/\\|/g'; }

# The endpoints of this run's servers by name, so that the table does not change between runs.
named() {
    local x=$1
    if [ -n "${ROBOT:-}" ]; then x=${x//$ROBOT/\$ROBOT}; fi
    if [ -n "${LASER:-}" ]; then x=${x//$LASER/\$LASER}; fi
    if [ -n "${SILENT:-}" ]; then x=${x//$SILENT/\$SILENT}; fi
    if [ -n "${NOISE:-}" ]; then x=${x//$NOISE/\$NOISE}; fi
    printf '%s' "$x"
}

# t NEEDLES PROGRAM ARGS...: runs one case. NEEDLES: words separated by `;` that the error
# must contain. PROGRAM: papillon or papillon-sim. Arguments and errors are shown as given,
# but the servers' endpoints by their names ($ROBOT, $LASER, $SILENT, $NOISE).
t() {
    local needles=$1 prog=$2
    shift 2
    local rc start=$SECONDS
    (
        ulimit -v $((MEM_MIB * 1024))
        exec timeout -k 2 "$LIMIT_S" "$BIN/$prog" "$@"
    ) </dev/null >"$W/.out" 2>"$W/.err"
    rc=$?
    N=$((N + 1))
    local line kind="" err
    line=$(grep -v '^[[:space:]]*$' "$W/.err" | tail -n 1 | cut -c1-400)
    if [ $rc -eq 124 ] || [ $rc -eq 137 ]; then
        kind="HANG"
        HANGS=$((HANGS + 1))
        err="HANG: still running after ${LIMIT_S} s"
    elif [ $rc -eq 101 ] || grep -q panicked "$W/.err"; then
        kind="PANIC"
        PANICS=$((PANICS + 1))
        err="PANIC: $(grep -m1 panicked -A1 "$W/.err" | tr '\n' ' ' | cut -c1-300)"
    elif [ $rc -gt 128 ]; then
        kind="ABORT"
        ABORTS=$((ABORTS + 1))
        err="ABORT: signal $((rc - 128)); $line"
    elif [ $rc -eq 0 ]; then
        kind="ACCEPTED"
        ACCEPTED=$((ACCEPTED + 1))
        err="ACCEPTED (exit 0): $(head -n 1 "$W/.out" | cut -c1-200)"
    else
        err=$line
        local n missing=""
        IFS=';' read -ra words <<<"$needles"
        for n in "${words[@]}"; do
            local alt ok=0
            IFS='|' read -ra alts <<<"$n"
            for alt in "${alts[@]}"; do
                if [ "$alt" = LINE ]; then
                    [[ "$line" =~ (line\ [0-9]+|:[0-9]+:) ]] && ok=1
                else
                    [[ "$line" == *"$alt"* ]] && ok=1
                fi
            done
            [ $ok -eq 1 ] || missing="$missing '$n'"
        done
        if [ -n "$missing" ]; then
            kind="NOLOC"
            NOLOC=$((NOLOC + 1))
            err="NO LOCATION (lacks$missing): $line"
        fi
    fi
    local shown="$prog" a
    err=$(named "$err")
    for a in "$@"; do
        a=$(named "$a")
        case $a in
            "") a="''" ;;
            *[[:space:]]*) a="'$a'" ;;
        esac
        [ ${#a} -gt 60 ] && a="${a:0:40}…(${#a} chars)"
        shown="$shown $a"
    done
    printf '| `%s` | %s | %s |\n' "$(cell "$shown")" "$rc" "$(cell "$err")" >>"$ROWS"
    if [ -n "$kind" ]; then
        printf '%s %s (%s s): %s\n' "$kind" "$shown" $((SECONDS - start)) "$err" >&2
    fi
}

P=papillon
S=papillon-sim
LONG=$(printf 'x%.0s' $(seq 70))

# ---------------------------------------------------------------- papillon: arguments
t "subcommand" $P
t "frobnicate" $P frobnicate
t "--board" $P --board sim.json
t "--board" $P check
t "--board" $P check --board
t "--bored" $P check --bored sim.json
t "--board" $P check --board sim.json --board sim.json
t "extra" $P ports extra
t "--all" $P ports --all
# ---------------------------------------------------------------- papillon check: the file
t "--board" $P check --board ''
t "/nonexistent/board.json" $P check --board /nonexistent/board.json
t "/tmp" $P check --board /tmp
t "/dev/zero" $P check --board /dev/zero
t "/dev/null" $P check --board /dev/null
t "/dev/urandom" $P check --board /dev/urandom
mkfifo fifo.json
t "fifo.json" $P check --board fifo.json
t "huge.json" $P check --board huge.json
for f in empty blank random trunc trailing bom utf16 badutf8 array nulldoc number string deep deepobj \
    comment quote comma ctrl surrogate escape hex plus zeros; do
    t "$f.json;LINE|\$." $P check --board $f.json
done
# ---------------------------------------------------------------- papillon check: the values
check_field() { t "$1.json;$2" $P check --board "$1.json"; }
check_field neg '$.mission.population'
check_field float '$.laser.beam_count'
check_field str '$.link.baud'
check_field bool '$.mission.generations'
check_field null '$.robot.radius_m'
check_field dup '$.mission.seed'
check_field long '$.robot.name'
check_field big '$.mission.population'
check_field e400 '$.robot.max_speed_mm_s'
check_field nan 'LINE'
check_field inf 'LINE'
check_field typo '$.mission.populaton'
check_field missing '$.mission.seed'
check_field exp '$.mission.generations'
check_field minus0 '$.mission.population'
check_field u64 '$.mission.seed'
check_field nopid '$.pid'
check_field noport '$.link.port'
check_field section-num '$.robot'
check_field section-arr '$.laser'
check_field radius0 '$.robot.radius_m'
check_field radiusneg '$.robot.radius_m'
check_field radius100 '$.robot.radius_m'
check_field speed0 '$.robot.max_speed_mm_s'
check_field speedbig '$.robot.max_speed_mm_s'
check_field accel0 '$.robot.accel_mm_s2'
check_field subclass '$.robot.subclass'
check_field baud '$.link.baud'
check_field switchbaud '$.link.switch_to_baud'
check_field port-empty '$.link.port'
check_field tcp-noport '$.link.tcp'
check_field tcp-bigport '$.link.tcp'
check_field model '$.laser.model'
check_field beams0 '$.laser.beam_count'
check_field beams-many '$.laser.beam_count'
check_field step0 '$.laser.step_deg'
check_field stepneg '$.laser.step_deg'
check_field range0 '$.laser.max_range_m'
check_field range-order '$.laser.max_range_m'
check_field noise '$.laser.noise_fraction'
check_field rate0 '$.laser.rate_hz'
check_field address '$.laser.address'
check_field address-empty '$.laser.address'
check_field lms200-noport '$.laser.port'
check_field mount '$.laser.mount.theta_deg'
check_field width0 '$.grid.width_m'
check_field width-huge '$.grid'
check_field res0 '$.grid.resolution_m'
check_field res-tiny '$.grid'
check_field origin '$.grid'
check_field method '$.mission.method'
check_field strategy '$.mission.strategy'
check_field targets0 '$.mission.targets'
check_field targets-big '$.mission.targets'
check_field battery '$.mission.battery_steps'
check_field reserve '$.mission.reserve_steps'
check_field coverage '$.mission.coverage_target'
check_field pop0 '$.mission.population'
check_field gens0 '$.mission.generations'
check_field kp '$.pid.heading_kp'
check_field kp-huge '$.pid.distance_kp'
check_field stop '$.safety.obstacle_stop_m'
check_field stale '$.safety.stale_timeout_s'
check_field footprint-width '$.robot.footprint.width_m'
check_field footprint-swing '$.robot.footprint.width_m'
check_field footprint-typo '$.robot.footprint.width'
check_field clearance '$.planning.clearance_m'
check_field clearance-neg '$.planning.clearance_m'
check_field occupied-thresh '$.mapping.occupied_thresh'
check_field occupied-thresh-one '$.mapping.occupied_thresh'
check_field save0 '$.persistence.save_every_s'
check_field saveneg '$.persistence.save_every_s'
# ---------------------------------------------------------------- papillon run
t "--board" $P run
t "/nonexistent/board.json" $P run --board /nonexistent/board.json
t "/dev/zero" $P run --board /dev/zero
t "neg.json;\$.mission.population" $P run --board neg.json --log-dir l
t "radius0.json;\$.robot.radius_m" $P run --board radius0.json --log-dir l
t "width-huge.json;\$.grid" $P run --board width-huge.json --log-dir l
t "--resume;--fresh" $P run --board sim.json --resume --fresh --log-dir l
t "--port;--tcp" $P run --board sim.json --port /dev/null --tcp 127.0.0.1:1 --log-dir l
t "--port;/dev/nonexistent" $P run --board sim.json --port /dev/nonexistent --log-dir l
t "--port;/dev/null" $P run --board sim.json --port /dev/null --log-dir l
t "--port;/dev/zero" $P run --board sim.json --port /dev/zero --log-dir l
t "--port;/tmp" $P run --board sim.json --port /tmp --log-dir l
t "--port;sim.json" $P run --board sim.json --port sim.json --log-dir l
t "--port" $P run --board sim.json --port '' --log-dir l
t "--port" $P run --board sim.json --port "/dev/$LONG" --log-dir l
t "--tcp" $P run --board sim.json --tcp "$LONG" --log-dir l
t "--tcp;nohost" $P run --board sim.json --tcp nohost --log-dir l
t "--tcp;127.0.0.1:99999" $P run --board sim.json --tcp 127.0.0.1:99999 --log-dir l
t "--tcp" $P run --board sim.json --tcp '' --log-dir l
t "--laser" $P run --board sim.json --laser "$LONG" --log-dir l
t "--log-dir;afile" $P run --board sim.json --log-dir afile
t "--log-dir;afile/sub" $P run --board sim.json --log-dir afile/sub
t "--log-dir;/dev/null" $P run --board sim.json --log-dir /dev/null
t "--log-dir;/proc" $P run --board sim.json --log-dir /proc/self/nothing
t "telemetry-dir;telemetry.jsonl" $P run --board sim.json --log-dir telemetry-dir
t "--resume;empty-log" $P run --board sim.json --resume --log-dir empty-log
t "unfinished;--resume" $P run --board sim.json --log-dir unfinished
for d in garbage empty trunc version type neg array dir zero fifo; do
    t "$d-state/state.json" $P run --board sim.json --resume --log-dir $d-state
done
t "pgm-state;map.pgm" $P run --board sim.json --resume --log-dir pgm-state
t "yaml-state;map.yaml" $P run --board sim.json --resume --log-dir yaml-state
# ---------------------------------------------------------------- papillon probe
t "--port;--tcp" $P probe
t "--port;--tcp" $P probe --port /dev/null --tcp 127.0.0.1:1
t "--port;--tcp" $P probe --drive
t "--port;/dev/nonexistent" $P probe --port /dev/nonexistent
t "--port;/dev/null" $P probe --port /dev/null
t "--port;/dev/zero" $P probe --port /dev/zero
t "--port;/tmp" $P probe --port /tmp
t "--port;fifo.json" $P probe --port fifo.json
t "--port" $P probe --port ''
t "--tcp;nohost" $P probe --tcp nohost
t "--tcp;127.0.0.1:99999" $P probe --tcp 127.0.0.1:99999
t "--tcp" $P probe --tcp ''
t "--tcp;127.0.0.1:1" $P probe --tcp 127.0.0.1:1
t "--tcp;256.1.1.1:80" $P probe --tcp 256.1.1.1:80
t "--tcp" $P probe --tcp "$LONG"

# Servers that accept a connection and then say nothing or send noise.
python3 - >"$W/.servers" 2>/dev/null <<'EOF' &
import os, socket, sys, threading, time
def serve(kind):
    s = socket.socket(); s.bind(("127.0.0.1", 0)); s.listen(8)
    print(kind, s.getsockname()[1], flush=True)
    def loop():
        while True:
            c, _ = s.accept()
            if kind == "noise":
                def talk(c=c):
                    try:
                        while True:
                            c.sendall(os.urandom(256)); time.sleep(0.01)
                    except OSError:
                        pass
                threading.Thread(target=talk, daemon=True).start()
            else:
                threading.Thread(target=lambda c=c: (time.sleep(3600), c), daemon=True).start()
    threading.Thread(target=loop, daemon=True).start()
serve("silent"); serve("noise")
time.sleep(600)
EOF
PIDS+=($!)
for _ in $(seq 50); do [ "$(wc -l <"$W/.servers")" -ge 2 ] && break; sleep 0.1; done
SILENT=127.0.0.1:$(awk '$1=="silent"{print $2}' "$W/.servers")
NOISE=127.0.0.1:$(awk '$1=="noise"{print $2}' "$W/.servers")
t "--tcp;$SILENT" $P probe --tcp "$SILENT"
t "--tcp;$NOISE" $P probe --tcp "$NOISE"
t "--tcp;$SILENT" $P run --board sim.json --tcp "$SILENT" --log-dir l
t "--tcp;$NOISE" $P run --board sim.json --tcp "$NOISE" --log-dir l

# A served robot, for what is checked once connected.
(
    ulimit -v $((MEM_MIB * 1024))
    exec "$BIN/$S" serve --map lab --tcp 127.0.0.1:0 --laser 127.0.0.1:0
) </dev/null >"$W/.serve" 2>/dev/null &
PIDS+=($!)
for _ in $(seq 200); do grep -q '^ready' "$W/.serve" && break; sleep 0.1; done
ROBOT=$(awk '$1=="arcos"&&$2=="tcp"{print $3}' "$W/.serve")
LASER=$(awk '$1=="laser"&&$3=="tcp"{print $4}' "$W/.serve")
# The emulator serves one client at a time: give it a moment to see the last one leave.
tw() { sleep 1; t "$@"; }
if [ -n "$ROBOT" ] && [ -n "$LASER" ]; then
    tw "--laser;$ROBOT" $P run --board sim.json --tcp "$ROBOT" --laser "$ROBOT" --log-dir l1
    tw "--tcp;$LASER" $P run --board sim.json --tcp "$LASER" --laser "$LASER" --log-dir l2
    tw "--laser;nohost" $P run --board sim.json --tcp "$ROBOT" --laser nohost --log-dir l3
    tw "--laser;$SILENT" $P run --board sim.json --tcp "$ROBOT" --laser "$SILENT" --log-dir l4
    tw "--laser;$NOISE" $P run --board sim.json --tcp "$ROBOT" --laser "$NOISE" --log-dir l5
    tw "--tcp;$LASER" $P probe --tcp "$LASER"
    for d in time negtime pose; do
        tw "$d-state/state.json" $P run --board sim.json --tcp "$ROBOT" --laser "$LASER" \
            --resume --log-dir $d-state
    done
else
    echo "bad-inputs: papillon-sim serve did not start; skipping the cases with a robot" >&2
fi
ROBOT="" LASER=""

# ---------------------------------------------------------------- papillon-sim: arguments
t "subcommand" $S
t "frobnicate" $S frobnicate
t "--map" $S --map lab
# ---------------------------------------------------------------- papillon-sim mission: flags
m() { t "$1" $S mission --map lab "${@:2}"; }
m "--robots" --robots 0
m "--robots" --robots 101
m "--robots" --robots -1
m "--robots" --robots 1e3
m "--robots" --robots ''
m "--method" --method nope
m "--method" --method ''
m "--objective" --objective greedy
m "--pop" --pop 0
m "--pop" --pop -1
m "--pop" --pop 1000000000
m "--pop" --pop 99999999999999999999
m "--gens" --gens 0
m "--gens" --gens -1
m "--gens" --gens 4000000000
m "--strategy" --strategy medium
m "--targets" --targets 0
m "--targets" --targets 9 --strategy long
m "--targets" --targets 3 --strategy short
m "--targets" --targets -1 --strategy long
m "--seed" --seed -1
m "--seed" --seed 1.5
m "--seed" --seed 18446744073709551616
m "--battery" --battery 0
m "--battery" --battery -5
m "--battery" --battery nan
m "--battery" --battery inf
m "--battery" --battery 1e30
m "--battery" --battery lots
m "--start" --start 1
m "--start" --start 1 2 3 4
m "--start" --start nan 1
m "--start" --start inf inf
m "--start" --start 1e9 1e9
m "--start" --start -1 -1
m "--start" --start 0.1 0.1
m "--start" --start 1 1 nan
m "--start" --start 1 1 1e30
m "--slip" --slip ice
m "--localize" --localize maybe
m "--resolution" --resolution 0
m "--resolution" --resolution -0.1
m "--resolution" --resolution nan
m "--resolution" --resolution inf
m "--resolution" --resolution 1e-9
m "--resolution" --resolution 0.001
m "--resolution" --resolution 100
m "--resolution" --resolution fine
m "--clearance" --clearance -0.05
m "--clearance" --clearance 0.5
m "--clearance" --clearance nan
m "--clearance" --clearance wide
m "--occupied-thresh" --occupied-thresh 0.4
m "--occupied-thresh" --occupied-thresh 0.99
m "--occupied-thresh" --occupied-thresh nan
m "--occupied-thresh" --occupied-thresh most
m "--png;/nonexistent/dir/map.png" --png /nonexistent/dir/map.png
m "--png;/tmp" --png /tmp
m "--frames;afile" --frames afile
m "--mcap;/tmp" --mcap /tmp
m "--json" --json=yes
# ---------------------------------------------------------------- papillon-sim mission: worlds
w() { t "$1" $S mission --map "${@:2}"; }
w "nowhere" nowhere
w "unknown world ''" ''
w "x.bmp;.bmp" x.bmp
w "noext" noext
w "gen-99" gen-99
w "gen-nope-1" gen-nope-1
w "gen-maze-x" gen-maze-x
w "lab,house" lab,house
w "missing.csv" missing.csv
w "fifo.csv" fifo.csv
w "zero.csv" zero.csv
w "empty.csv" empty.csv
w "blank.csv" blank.csv
w "garbage.csv" garbage.csv
w "ragged.csv;LINE" ragged.csv
w "two.csv;LINE" two.csv
w "neg.csv;LINE" neg.csv
w "text.csv;LINE" text.csv
w "one.csv" one.csv
w "walls.csv;--start" walls.csv
w "wide.csv" wide.csv
w "magic.pgm" magic.pgm
w "header.pgm" header.pgm
w "huge.pgm" huge.pgm
w "maxval0.pgm;maxval" maxval0.pgm
w "maxval-big.pgm;maxval" maxval-big.pgm
w "words.pgm" words.pgm
w "over.pgm" over.pgm
w "negdim.pgm" negdim.pgm
w "zerodim.pgm" zerodim.pgm
w "short.pgm" short.pgm
w "garbage.pgm" garbage.pgm
w "zero.pgm" zero.pgm
w "dir.pgm" dir.pgm
w "garbage.png" garbage.png
w "trunc.png" trunc.png
w "big.png" big.png
w "zerodim.png" zerodim.png
w "tiny.png" tiny.png
w "baddata.png" baddata.png
w "depth.png" depth.png
w "zero.png" zero.png
w "dir.png" dir.png
w "empty.map" empty.map
w "noheader.map;LINE" noheader.map
w "huge.map" huge.map
w "negwidth.map;width" negwidth.map
w "rows.map;LINE" rows.map
w "chars.map;LINE" chars.map
w "notype.map;LINE" notype.map
w "width0.map;width" width0.map
w "garbage.map" garbage.map
w "zero.map" zero.map
w "ok.map;--start" ok.map
w "noimage.yaml;image" noimage.yaml
w "lost.pgm" lost.yaml
w "self.yaml" self.yaml
w "zero.pgm" zeroimg.yaml
w "dir.pgm" dirimg.yaml
w "emptyimg.yaml;image" emptyimg.yaml
w "garbage.pgm" garbageimg.yaml
w "res.yaml;resolution" res.yaml
w "resneg.yaml;resolution" resneg.yaml
w "res0.yaml;resolution" res0.yaml
w "resnan.yaml;resolution" resnan.yaml
w "resword.yaml;resolution" resword.yaml
w "nores.yaml;resolution" nores.yaml
w "origin.yaml;origin" origin.yaml
w "origin2.yaml;origin" origin2.yaml
w "originword.yaml;origin" originword.yaml
w "yaw.yaml;origin" yaw.yaml
w "negate.yaml;negate" negate.yaml
w "occ.yaml;occupied_thresh" occ.yaml
w "thresh.yaml;thresh" thresh.yaml
w "mode.yaml;mode" mode.yaml
w "dupkey.yaml;negate" dupkey.yaml
w "tabs.yaml;resolution" tabs.yaml
w "garbage.yaml" garbage.yaml
w "empty.yaml" empty.yaml
w "huge.yaml" huge.yaml
w "dir.yaml" dir.yaml
# ---------------------------------------------------------------- papillon-sim score
t "--robot-map" $S score --map lab
t "nowhere.yaml" $S score --map lab --robot-map nowhere.yaml
t "dir.yaml" $S score --map lab --robot-map dir.yaml
t "garbage.yaml" $S score --map lab --robot-map garbage.yaml
t "res.yaml;resolution" $S score --map lab --robot-map res.yaml
t "lost.pgm" $S score --map lab --robot-map lost.yaml
t "zero.pgm" $S score --map lab --robot-map zeroimg.yaml
t "nowhere" $S score --map nowhere --robot-map ok.yaml
t "--resolution" $S score --map lab --robot-map ok.yaml --resolution 0
t "--resolution" $S score --map lab --robot-map ok.yaml --resolution nan
t "--resolution" $S score --map lab --robot-map ok.yaml --resolution 1e-9
t "--resolution" $S score --map lab --robot-map ok.yaml --resolution -1
t "--start" $S score --map lab --robot-map ok.yaml --start nan 1
t "--start" $S score --map lab --robot-map ok.yaml --start 1e9 1e9
t "--start" $S score --map lab --robot-map ok.yaml --start 1
t "--robot-start" $S score --map lab --robot-map ok.yaml --robot-start inf 0
t "--robot-start" $S score --map lab --robot-map ok.yaml --robot-start 1e30 1e30
t "--robot-start" $S score --map lab --robot-map ok.yaml --robot-start 0 0 nan
t "garbage.png" $S score --map garbage.png --robot-map ok.yaml
# ---------------------------------------------------------------- papillon-sim serve
s() { t "$1" $S serve --map lab --tcp 127.0.0.1:0 --laser 127.0.0.1:0 "${@:2}"; }
t "nowhere" $S serve --map nowhere --tcp 127.0.0.1:0 --laser 127.0.0.1:0
t "garbage.png" $S serve --map garbage.png --tcp 127.0.0.1:0 --laser 127.0.0.1:0
t "--tcp;nohost" $S serve --map lab --tcp nohost --laser 127.0.0.1:0
t "--tcp;127.0.0.1:99999" $S serve --map lab --tcp 127.0.0.1:99999 --laser 127.0.0.1:0
t "--tcp;192.0.2.1:0" $S serve --map lab --tcp 192.0.2.1:0 --laser 127.0.0.1:0
t "--laser;nohost" $S serve --map lab --tcp 127.0.0.1:0 --laser nohost
t "--pty;/nonexistent/dir/robot" $S serve --map lab --pty /nonexistent/dir/robot --laser 127.0.0.1:0
t "--pty;/tmp" $S serve --map lab --pty /tmp --laser 127.0.0.1:0
t "--pty;afile" $S serve --map lab --pty afile --laser 127.0.0.1:0
t "--laser;/nonexistent/dir/laser" $S serve --map lab --tcp 127.0.0.1:0 --laser-model lms200 --laser /nonexistent/dir/laser
s "--laser-model" --laser-model lms500
s "--seed" --seed -1
s "--seed" --seed many
s "--robots" --robots 0
s "--robots" --robots 17
s "--watchdog-ms" --watchdog-ms 99
s "--watchdog-ms" --watchdog-ms 70000
s "--identity" --identity ros
s "--subclass" --subclass p3at
s "--truth-log;/tmp" --truth-log /tmp
s "--truth-log;/nonexistent/dir/truth.jsonl" --truth-log /nonexistent/dir/truth.jsonl
for f in corrupt=-0.1 corrupt=nan corrupt=2 drop=1.5 drop=inf latency=-5 latency=1e12 \
    jitter=nan jitter=1e12 cut=5 cut=-1+2 cut=1e30+1 cut=1+nan cut=a+b laser-drop=x \
    laser-drop=1+-1 slip=-1 slip=nan slip=1e9 estop=x estop=1e30+1 drain=-1 drain=nan \
    drain=1e30 bogus=1 corrupt = ,,, corrupt=0.1,corrupt=0.2; do
    s "--faults" --faults "$f"
done
# ---------------------------------------------------------------- papillon-sim bench
b() { t "$1" $S bench "${@:2}"; }
b "--experiment;--config"
b "--experiment" --experiment nope
b "--experiment;--config" --experiment horizon --config ok-sweep.json
b "--thesis-maps;--no-thesis-maps" --experiment horizon --thesis-maps . --no-thesis-maps
b "--thesis-maps;/nonexistent" --experiment horizon --thesis-maps /nonexistent --out o
b "missing.json" --config missing.json --out o
b "/tmp" --config /tmp --out o
b "/dev/zero" --config /dev/zero --out o
b "sweep-garbage.json" --config sweep-garbage.json --out o
b "sweep-empty.json;LINE" --config sweep-empty.json --out o
b "sweep-array.json;LINE" --config sweep-array.json --out o
b "sweep-trunc.json;LINE" --config sweep-trunc.json --out o
b "sweep-type.json;LINE" --config sweep-type.json --out o
b "sweep-unknown.json;run" --config sweep-unknown.json --out o
b "sweep-nomaps.json;maps" --config sweep-nomaps.json --out o
b "sweep-method.json;methods[0]" --config sweep-method.json --out o
b "sweep-map.json;maps[0]" --config sweep-map.json --out o
b "sweep-strategy.json;strateg" --config sweep-strategy.json --out o
b "sweep-pop0.json;populations" --config sweep-pop0.json --out o
b "sweep-robots0.json;robots" --config sweep-robots0.json --out o
b "sweep-robots101.json;robots" --config sweep-robots101.json --out o
b "sweep-runs0.json;runs" --config sweep-runs0.json --out o
b "sweep-runs-huge.json;runs" --config sweep-runs-huge.json --out o
b "sweep-gens.json;generations|LINE" --config sweep-gens.json --out o
b "sweep-res0.json;resolution_m" --config sweep-res0.json --out o
b "sweep-res-tiny.json;resolution_m" --config sweep-res-tiny.json --out o
b "sweep-res-big.json;resolution_m" --config sweep-res-big.json --out o
b "sweep-battery.json;battery_steps" --config sweep-battery.json --out o
b "sweep-seed.json;base_seed|LINE" --config sweep-seed.json --out o
b "sweep-objective.json;objective" --config sweep-objective.json --out o
b "--runs" --config ok-sweep.json --runs 0 --out o
b "--runs" --config ok-sweep.json --runs -1 --out o
b "--jobs" --config ok-sweep.json --jobs -1 --out o
b "--jobs" --config ok-sweep.json --jobs 100000 --out o
b "--shard" --config ok-sweep.json --shard 3/2 --out o
b "--shard" --config ok-sweep.json --shard 1/0 --out o
b "--shard" --config ok-sweep.json --shard half --out o
b "--maps" --config ok-sweep.json --maps '' --out o
b "--maps;nowhere" --config ok-sweep.json --maps nowhere --out o
b "--battery" --config ok-sweep.json --battery -1 --out o
b "--battery" --config ok-sweep.json --battery nan --out o
b "--objective" --config ok-sweep.json --objective greedy --out o
b "--out;afile" --config ok-sweep.json --out afile/sub
b "--out;/dev/null" --config ok-sweep.json --out /dev/null
b "DIRS" merge
b "nowhere" merge nowhere
b "shard-empty;sweep.json" merge shard-empty
b "shard-garbage/sweep.json" merge shard-garbage
b "shard-runs/sweep.json;LINE" merge shard-runs
b "shard-runs" merge shard-runs shard-other
# ---------------------------------------------------------------- papillon-sim optimize
o() { t "$1" $S optimize --runs 1 --gens 2 "${@:2}"; }
o "--function" --function banana
o "--dim" --dim 0
o "--dim" --dim 17
o "--dim" --dim -1
o "--dim" --dim 1 --function rosenbrock
o "--method" --method nope
o "--preset" --preset pygmo
o "--shift" --shift nan
o "--shift" --shift inf
o "--shift" --shift 1e30
o "--shift" --shift east
o "--pop" --pop 0
o "--pop" --pop 1
o "--pop" --pop 65
o "--gens" --gens 0
o "--gens" --gens 1000
t "--runs" $S optimize --runs 0
t "--runs" $S optimize --runs 1000000000000
t "--runs" $S optimize --runs -1
o "--seed" --seed -1
o "--seed" --seed 18446744073709551616
o "--patience" --patience 0
o "--patience" --patience -1
o "--patience" --patience soon
# ---------------------------------------------------------------- papillon-sim plan
t "--map" $S plan --scen ok.scen
t "--scen" $S plan --map ok.map
t "missing.map" $S plan --map missing.map --scen ok.scen
t "/tmp" $S plan --map /tmp --scen ok.scen
t "/dev/zero" $S plan --map /dev/zero --scen ok.scen
t "empty.map" $S plan --map empty.map --scen ok.scen
t "garbage.map" $S plan --map garbage.map --scen ok.scen
t "huge.map" $S plan --map huge.map --scen ok.scen
t "negwidth.map;width" $S plan --map negwidth.map --scen ok.scen
t "rows.map;LINE" $S plan --map rows.map --scen ok.scen
t "chars.map;LINE" $S plan --map chars.map --scen ok.scen
t "notype.map;LINE" $S plan --map notype.map --scen ok.scen
t "missing.scen" $S plan --map ok.map --scen missing.scen
t "/dev/zero" $S plan --map ok.map --scen /dev/zero
t "garbage.scen" $S plan --map ok.map --scen garbage.scen
for f in empty noversion fields outside negative wall nan words size; do
    t "$f.scen;LINE" $S plan --map ok.map --scen $f.scen
done

# ---------------------------------------------------------------- the table
SUMMARY="$N inputs: $PANICS panics, $ABORTS aborts, $HANGS hangs, $ACCEPTED accepted (exit 0), $NOLOC errors without a location"
TABLE="$W/.table"
{
    echo "| command | exit | error |"
    echo "|---|---|---|"
    cat "$ROWS"
    echo
    echo "$SUMMARY."
} >"$TABLE"
if [ $DOC -eq 1 ]; then
    DOCFILE="$ROOT/docs/reliability.md"
    python3 - "$DOCFILE" "$TABLE" <<'EOF'
import sys
doc, table = sys.argv[1], open(sys.argv[2]).read()
text = open(doc).read()
begin, end = "<!-- bad-inputs: begin -->\n", "<!-- bad-inputs: end -->\n"
i, j = text.index(begin) + len(begin), text.index(end)
open(doc, "w").write(text[:i] + table + text[j:])
EOF
    echo "bad-inputs: table written to docs/reliability.md" >&2
else
    cat "$TABLE"
fi
echo "bad-inputs: $SUMMARY" >&2
[ $((PANICS + ABORTS + HANGS + ACCEPTED + NOLOC)) -eq 0 ]
