#!/bin/sh
# Runs the generated world set (gen-00 .. gen-23, docs/simulator.md "Generated worlds") with
# xBOA and nearest-frontier and prints one tab-separated line per mission:
#   plan method seed battery coverage reason steps distance_m replans steps_to_99
# steps_to_99 is the first step count at which coverage reached 0.99 ("-" if never).
#
# Usage (from the repository root, after `cargo build --release -p papillon-sim --examples`):
#   sim-host/scripts/world-set.sh [SEEDS] [BATTERY_RULE] [PLANS] [METHODS]
#   SEEDS         seeds, default "25 26 27"
#   BATTERY_RULE  "default" (the mission's 500 steps) or K: battery = ceil(K x free area in m²)
#   PLANS         plan names, default gen-00 .. gen-23
#   METHODS       default "xboa nearest-frontier"
# MISSION_ARGS (environment) is added to every mission's options, e.g.
#   MISSION_ARGS="--laser-noise 0.003" sim-host/scripts/world-set.sh "25 26 27" 2
# Missions run one at a time under `nice` (the machine may be shared).
set -eu
BIN=${BIN:-${CARGO_TARGET_DIR:-target}/release}
SEEDS=${1:-"25 26 27"}
RULE=${2:-default}
PLANS=${3:-$(seq -f 'gen-%02g' 0 23)}
METHODS=${4:-"xboa nearest-frontier"}
# Free area per plan, from the set's table (column 10 of the Markdown rows).
AREAS=$("$BIN/examples/world_set" | awk -F'|' '/^\| gen-/ { gsub(/ /, "", $2); gsub(/ /, "", $10); print $2, $10 }')
printf 'plan\tmethod\tseed\tbattery\tcoverage\treason\tsteps\tdistance_m\treplans\tsteps_to_99\n'
for plan in $PLANS; do
    area=$(echo "$AREAS" | awk -v p="$plan" '$1 == p { print $2 }')
    if [ "$RULE" = default ]; then
        battery=""
    else
        battery=$(awk -v k="$RULE" -v a="$area" 'BEGIN { b = k * a; c = int(b); if (c < b) c++; print c }')
    fi
    for method in $METHODS; do
        for seed in $SEEDS; do
            nice -n 5 "$BIN/papillon-sim" mission --map "$plan" --method "$method" --seed "$seed" \
                ${battery:+--battery "$battery"} ${MISSION_ARGS:-} --json |
                jq -r --arg plan "$plan" '
                    (.coverage_curve | map(select(.[1] >= 0.99)) | first) as $hit
                    | [$plan, .method, .seed, .battery_steps, (.coverage * 1000 | round / 1000),
                       (.reason // "-"), .steps, (.distance_m * 10 | round / 10), .replans,
                       (if $hit then $hit[0] else "-" end)] | @tsv'
        done
    done
done
