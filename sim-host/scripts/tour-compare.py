#!/usr/bin/env python3
"""Issue 17, the frontier tour in the efficient objective: missions of one binary, and pairs of
two runs compared (docs/experiments.md, "Issue 17: the efficient objective").

Usage (from the repository root, after
`cargo build --release -p papillon-sim --bin papillon-sim --example world_set`):
    sim-host/scripts/tour-compare.py run OUTDIR LABEL BIN MAPS METHODS
        seeds 25..34 of each map (comma-separated: house,empty,lab or gen-00,...) and method
        (comma-separated; TOUR_SEEDS=25,26 runs those seeds instead), one mission at a time under nice; generated plans get the set's
        battery rule, ceil(2 x free area in m²) steps. Writes OUTDIR/LABEL.json and prints
        medians per map and method. TOUR_ARGS adds mission options to every run (e.g.
        TOUR_ARGS="--localize on" or "--slip none"); each row ends with the mission's wall
        time in seconds (it depends on the machine's load), the end pose error and the map's wall
        position error (m), the map accuracy (fraction) and the end heading error (rad).
    sim-host/scripts/tour-compare.py pairs A.json:METHOD B.json:METHOD
        per map and over all: runs >= 99 %, mean coverage, medians of steps and metres over the
        seeds where both reach 99 %; and at equal coverage (the lower final coverage of the
        pair, pairs where it is >= 50 %: the first step count and distance at which each
        mission reached it).
    sim-host/scripts/tour-compare.py summary A.json:METHOD [B.json:METHOD ...]
        per map, each run's runs >= 99 % and mean coverage side by side; then per run the
        totals: runs >= 99 %, maps with >= 9 of 10, mean coverage, end reasons, the sum of
        the missions' wall times; then per run the medians: steps and metres, wall time per
        mission, end pose and heading error, wall position error, map accuracy (and its
        minimum, and the missions at >= 97 %).
"""
import json, math, os, shlex, statistics as st, subprocess, sys, time

SEEDS = ([int(x) for x in os.environ["TOUR_SEEDS"].split(",")] if os.environ.get("TOUR_SEEDS")
         else list(range(25, 35)))


def batteries(binp):
    exe = os.path.join(os.path.dirname(binp), "examples", "world_set")
    table = subprocess.run([exe], capture_output=True, text=True, check=True).stdout
    out = {}
    for line in table.splitlines():
        cols = [c.strip() for c in line.split("|")]
        if len(cols) > 10 and cols[1].startswith("gen-"):
            out[cols[1]] = math.ceil(2 * float(cols[9]))
    return out


def run(outdir, label, binp, maps, methods):
    os.makedirs(outdir, exist_ok=True)
    maps = maps.split(",")
    batt = batteries(binp) if any(m.startswith("gen-") for m in maps) else {}
    extra = shlex.split(os.environ.get("TOUR_ARGS", ""))
    out = {}
    for m in maps:
        for meth in methods.split(","):
            rows = []
            for s in SEEDS:
                cmd = ["nice", "-n", "10", binp, "mission", "--map", m, "--method", meth,
                       "--seed", str(s), "--json"]
                if m in batt:
                    cmd += ["--battery", str(batt[m])]
                cmd += extra
                t0 = time.monotonic()
                d = json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)
                wall_s = time.monotonic() - t0
                rows.append((d["coverage"], d["steps"], d["distance_m"], d["decisions"], d["reason"],
                             d["coverage_curve"], d["coverage_distance_curve"], d["decision_ms_p50"], wall_s,
                             max(r["pose_error_m"] for r in d["per_robot"]),
                             d["map_accuracy"]["wall_error_m"], d["map_accuracy"]["accuracy"],
                             max(abs(r["localization"]["heading_error_rad"]) for r in d["per_robot"])))
            ok = sum(r[0] >= 0.99 for r in rows)
            print(f"{label} {m} {meth}: runs >= 99 % {ok}/{len(rows)}, median steps {st.median(r[1] for r in rows):.1f}, "
                  f"metres {st.median(r[2] for r in rows):.1f}, decisions {st.median(r[3] for r in rows):.1f}, "
                  f"mean coverage {st.mean(r[0] for r in rows):.3f}, wall {sum(r[8] for r in rows):.1f} s", flush=True)
            out[f"{m}/{meth}"] = rows
    json.dump(out, open(os.path.join(outdir, f"{label}.json"), "w"))


def first(curve, c):
    return next((x for x, cov in curve if cov >= c), None)


def pct(a, b):
    return f"{a:.1f} vs {b:.1f} ({100 * (a / b - 1):+.1f} %)"


def pairs(spec_a, spec_b):
    (fa, ma), (fb, mb) = spec_a.split(":"), spec_b.split(":")
    a, b = json.load(open(fa)), json.load(open(fb))
    plans = sorted({k.split("/")[0] for k in a if k.endswith("/" + ma)})
    both_all, eq = [], []
    for p in plans:
        ra, rb = a.get(f"{p}/{ma}"), b.get(f"{p}/{mb}")
        if not ra or not rb:
            continue
        both = [(x, y) for x, y in zip(ra, rb) if x[0] >= 0.99 and y[0] >= 0.99]
        both_all += both
        line = (f"{p}: runs >= 99 % {sum(x[0] >= 0.99 for x in ra)} vs {sum(y[0] >= 0.99 for y in rb)}, "
                f"mean coverage {st.mean(x[0] for x in ra):.3f} vs {st.mean(y[0] for y in rb):.3f}")
        if both:
            line += (f"; both at 99 % ({len(both)}): steps {pct(st.median(x[1] for x, _ in both), st.median(y[1] for _, y in both))}, "
                     f"metres {pct(st.median(x[2] for x, _ in both), st.median(y[2] for _, y in both))}")
        print(line)
        for x, y in zip(ra, rb):
            c = min(x[0], y[0])
            if c >= 0.5 and len(x) > 6 and len(y) > 6:
                v = (first(x[5], c), first(y[5], c), first(x[6], c), first(y[6], c))
                if None not in v:
                    eq.append((p, c) + v)
    if both_all:
        print(f"all pairs at 99 % ({len(both_all)}): steps {pct(st.median(x[1] for x, _ in both_all), st.median(y[1] for _, y in both_all))}, "
              f"metres {pct(st.median(x[2] for x, _ in both_all), st.median(y[2] for _, y in both_all))}")
    if eq:
        print(f"equal coverage: {len(eq)} pairs on {len(set(e[0] for e in eq))} maps, median coverage "
              f"{st.median(e[1] for e in eq):.3f}: steps {pct(st.median(e[2] for e in eq), st.median(e[3] for e in eq))}, "
              f"metres {pct(st.median(e[4] for e in eq), st.median(e[5] for e in eq))}")


def med(rows, i):
    v = [x[i] for x in rows if len(x) > i]
    return f"{st.median(v):.3f}" if v else "—"


def summary(*specs):
    runs = []
    for spec in specs:
        f, m = spec.rsplit(":", 1)
        d = json.load(open(f))
        runs.append((spec, {k.split("/")[0]: v for k, v in d.items() if k.endswith("/" + m)}))
    maps = sorted({p for _, r in runs for p in r})
    print("| map | " + " | ".join(s for s, _ in runs) + " |")
    print("|---|" + "---|" * len(runs))
    for p in maps:
        cells = []
        for _, r in runs:
            rows = r.get(p)
            cells.append("—" if not rows else
                         f"{sum(x[0] >= 0.99 for x in rows)}, {100 * st.mean(x[0] for x in rows):.1f} %")
        print(f"| {p} | " + " | ".join(cells) + " |")
    print()
    print("| run | missions | runs >= 99 % | maps >= 9/10 | mean coverage | ends | wall (s) | end pose error (median, m) | wall error (median, m) |")
    print("|---|--:|--:|--:|--:|---|--:|--:|--:|")
    for spec, r in runs:
        rows = [x for v in r.values() for x in v]
        ends = {}
        for x in rows:
            ends[x[4]] = ends.get(x[4], 0) + 1
        wall = sum(x[8] for x in rows if len(x) > 8)
        good = sum(sum(x[0] >= 0.99 for x in v) >= 9 for v in r.values())
        print(f"| {spec} | {len(rows)} | {sum(x[0] >= 0.99 for x in rows)} | {good} | "
              f"{100 * st.mean(x[0] for x in rows):.1f} % | "
              + ", ".join(f"{k} {n}" for k, n in sorted(ends.items(), key=lambda kv: -kv[1]))
              + f" | {wall:.0f} | {med(rows, 9)} | {med(rows, 10)} |")
    print()
    print("| run | median steps / metres | wall per mission (median, s) | end pose error (median / max, m) "
          "| end heading error (median / max, °) | wall error (median, m) | map accuracy (median / min; runs >= 97 %) |")
    print("|---|---|--:|---|---|--:|---|")
    for spec, r in runs:
        rows = [x for v in r.values() for x in v]
        acc = [x[11] for x in rows if len(x) > 11]
        hdg = [math.degrees(x[12]) for x in rows if len(x) > 12]
        pos = [x[9] for x in rows if len(x) > 9]
        print(f"| {spec} | {st.median(x[1] for x in rows):.1f} / {st.median(x[2] for x in rows):.1f} | "
              f"{st.median(x[8] for x in rows if len(x) > 8):.1f} | "
              + (f"{st.median(pos):.3f} / {max(pos):.3f}" if pos else "—") + " | "
              + (f"{st.median(hdg):.2f} / {max(hdg):.2f}" if hdg else "—") + f" | {med(rows, 10)} | "
              + (f"{100 * st.median(acc):.1f} / {100 * min(acc):.1f} %; {sum(a >= 0.97 for a in acc)}" if acc else "—")
              + " |")


if __name__ == "__main__":
    if len(sys.argv) == 7 and sys.argv[1] == "run":
        run(*sys.argv[2:])
    elif len(sys.argv) == 4 and sys.argv[1] == "pairs":
        pairs(*sys.argv[2:])
    elif len(sys.argv) >= 3 and sys.argv[1] == "summary":
        summary(*sys.argv[2:])
    else:
        sys.exit(__doc__)
