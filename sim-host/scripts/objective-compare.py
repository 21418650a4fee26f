#!/usr/bin/env python3
"""Issue 17: xBOA on the efficient objective against the frontier baselines (docs/experiments.md,
"Issue 17: the efficient objective").

Usage (from the repository root, after
`cargo build --release -p papillon-sim --bin papillon-sim --example world_set`):
    sim-host/scripts/objective-compare.py run OUTDIR     # the missions, one at a time under nice
    sim-host/scripts/objective-compare.py report OUTDIR  # the tables

`run` does, for seeds 25..34: house, empty and lab with xboa (default objective),
nearest-frontier and frontier-utility, and xboa with --objective thesis; then gen-00..gen-23
with xboa, nearest-frontier and frontier-utility and the battery rule of the generated set
(ceil(2 x free area in m²) steps). Each mission's JSON summary and curves go to OUTDIR/*.json.
"""
import glob, json, math, os, statistics as st, subprocess, sys, collections

BIN = os.environ.get("BIN", os.path.join(os.environ.get("CARGO_TARGET_DIR", "target"), "release"))
SEEDS = list(range(25, 35))
med = st.median


def mission(plan, method, seed, extra):
    cmd = ["nice", "-n", "5", f"{BIN}/papillon-sim", "mission", "--map", plan, "--method", method,
           "--seed", str(seed), "--json"] + extra
    d = json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)
    return dict(map=plan, method=method, seed=seed, cov=d["coverage"], reason=d.get("reason"),
                steps=d["steps"], dist=d["distance_m"], replans=d["replans"], decisions=d["decisions"],
                scurve=d["coverage_curve"], dcurve=d["coverage_distance_curve"])


def run(out):
    os.makedirs(out, exist_ok=True)
    rows = [mission(m, meth, s, []) for m in ["house", "empty", "lab"]
            for meth in ["xboa", "nearest-frontier", "frontier-utility"] for s in SEEDS]
    json.dump(rows, open(f"{out}/builtin.json", "w"))
    rows = [mission(m, "xboa", s, ["--objective", "thesis"]) for m in ["house", "empty", "lab"] for s in SEEDS]
    json.dump(rows, open(f"{out}/builtin-thesis.json", "w"))
    table = subprocess.run([f"{BIN}/examples/world_set"], capture_output=True, text=True, check=True).stdout
    areas = {}
    for line in table.splitlines():
        cols = [c.strip() for c in line.split("|")]
        if len(cols) > 10 and cols[1].startswith("gen-"):
            areas[cols[1]] = float(cols[9])
    for plan in sorted(areas):
        battery = str(math.ceil(2 * areas[plan]))
        rows = [mission(plan, meth, s, ["--battery", battery])
                for meth in ["xboa", "nearest-frontier", "frontier-utility"] for s in SEEDS]
        json.dump(rows, open(f"{out}/{plan}.json", "w"))


def first(curve, c):
    return next((x for x, cov in curve if cov >= c), None)


def load(files):
    return [r for f in files for r in json.load(open(f))]


def builtin_table(rows, thesis):
    print("| map | method | runs ≥ 99 % | steps | metres | re-plans | decisions | re-plans per decision |")
    print("|---|---|---|---|---|---|---|---|")
    for m in ["house", "empty", "lab"]:
        for label, rr in [("xboa (efficient)", [r for r in rows if r["map"] == m and r["method"] == "xboa"]),
                          ("xboa (thesis)", [r for r in thesis if r["map"] == m]),
                          ("nearest-frontier", [r for r in rows if r["map"] == m and r["method"] == "nearest-frontier"]),
                          ("frontier-utility", [r for r in rows if r["map"] == m and r["method"] == "frontier-utility"])]:
            print(f"| {m} | {label} | {sum(r['cov'] >= 0.99 for r in rr)}/{len(rr)} | {med(r['steps'] for r in rr):.1f} "
                  f"| {med(r['dist'] for r in rr):.1f} | {med(r['replans'] for r in rr)} | {med(r['decisions'] for r in rr)} "
                  f"| {med(r['replans'] / max(r['decisions'], 1) for r in rr):.2f} |")


def compare(rows, a, b, label):
    by = collections.defaultdict(dict)
    for r in rows:
        by[(r["map"], r["seed"])][r["method"]] = r
    ps = [(k, d[a], d[b]) for k, d in sorted(by.items()) if a in d and b in d]
    both = [(k, x, y) for k, x, y in ps if x["cov"] >= 0.99 and y["cov"] >= 0.99]
    print(f"\n{label}: {a} vs {b}: {len(ps)} pairs (plan, seed); both ≥ 99 %: {len(both)} "
          f"(plans {sorted(set(k[0] for k, _, _ in both))})")
    if both:
        sa, sb = med(x["steps"] for _, x, _ in both), med(y["steps"] for _, _, y in both)
        da, db = med(x["dist"] for _, x, _ in both), med(y["dist"] for _, _, y in both)
        print(f"  to 99 %: steps {sa:.1f} vs {sb:.1f} ({100 * (sa / sb - 1):+.1f} %), "
              f"metres {da:.1f} vs {db:.1f} ({100 * (da / db - 1):+.1f} %)")
    eq = []
    for k, x, y in ps:
        c = min(x["cov"], y["cov"])
        if c < 0.5:
            continue
        v = (first(x["scurve"], c), first(y["scurve"], c), first(x["dcurve"], c), first(y["dcurve"], c))
        if None not in v:
            eq.append((k, c) + v)
    if eq:
        sa, sb, da, db = (med(e[i] for e in eq) for i in (2, 3, 4, 5))
        print(f"  to equal coverage (the lower final coverage of the pair; pairs where it is ≥ 50 %): {len(eq)} pairs "
              f"on {len(set(e[0][0] for e in eq))} plans, median coverage {med(e[1] for e in eq):.3f}: "
              f"steps {sa:.1f} vs {sb:.1f} ({100 * (sa / sb - 1):+.1f} %), metres {da:.1f} vs {db:.1f} "
              f"({100 * (da / db - 1):+.1f} %)")
    for m in (a, b):
        rr = [r for r in rows if r["method"] == m]
        print(f"  {m}: {len(rr)} runs, ≥ 99 %: {sum(r['cov'] >= 0.99 for r in rr)}, mean coverage "
              f"{st.mean(r['cov'] for r in rr):.3f}, re-plans {med(r['replans'] for r in rr)}, "
              f"re-plans per decision {med(r['replans'] / max(r['decisions'], 1) for r in rr):.2f} (medians)")


def report(out):
    b, t = load([f"{out}/builtin.json"]), load([f"{out}/builtin-thesis.json"])
    builtin_table(b, t)
    for m in ["house", "empty", "lab"]:
        for base in ["nearest-frontier", "frontier-utility"]:
            compare([r for r in b if r["map"] == m], "xboa", base, m)
    g = load(sorted(glob.glob(f"{out}/gen-*.json")))
    for base in ["nearest-frontier", "frontier-utility"]:
        compare(g, "xboa", base, "generated set")


if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] not in ("run", "report"):
        sys.exit(__doc__)
    (run if sys.argv[1] == "run" else report)(sys.argv[2])
