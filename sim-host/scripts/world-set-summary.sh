#!/bin/sh
# Summarises the output of world-set.sh (a TSV file) as a Markdown table, one row per plan and
# method: mean and lowest coverage, runs that reached 99 %, end reasons, median steps, metres
# and re-plans over the seeds.
# Usage: sim-host/scripts/world-set-summary.sh RESULTS.tsv
set -eu
jq -R -s -r '
  def median: sort | if length == 0 then null else .[(length - 1) / 2 | floor] end;
  def r1: . * 10 | round / 10;
  split("\n") | map(select(length > 0) | split("\t")) | .[1:]
  | map({plan: .[0], method: .[1], seed: .[2], battery: .[3], coverage: (.[4] | tonumber),
         reason: .[5], steps: (.[6] | tonumber), distance: (.[7] | tonumber),
         replans: (.[8] | tonumber)})
  | group_by(.plan) | map(group_by(.method) | sort_by(.[0].method != "xboa")) | flatten(1)
  | (["| plan | method | battery | seeds | coverage mean (min) | runs ≥ 99 % | end reasons | steps (median) | metres (median) | re-plans (median) |",
      "|---|---|---|---|---|---|---|---|---|---|"] | .[]),
    (.[] | "| \(.[0].plan) | \(.[0].method) | \(.[0].battery) | \(length) | \((map(.coverage) | add / length) * 100 | r1) % (\((map(.coverage) | min) * 100 | r1) %) | \(map(select(.coverage >= 0.99)) | length) | \(group_by(.reason) | map("\(.[0].reason) \(length)") | join(", ")) | \(map(.steps) | median | round) | \(map(.distance) | median | r1) | \(map(.replans) | median) |")
' "$1"
