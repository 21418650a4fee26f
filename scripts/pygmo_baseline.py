#!/usr/bin/env python3
"""pygmo's same-named methods on the issue-23 protocol, for docs/optimizers.md.

Dimension 10, bounds [-5.12, 5.12], population 20, 100 generations, 25 runs, each method with
pygmo's defaults; median, min and max of the best fitness. `--shift S` moves the optimum to
x_i = S (f(x - S)).

Time per run: `ms/run` is the mean wall-clock time and `cpu_ms/run` the mean CPU time of the
process (`time.process_time()`), each around `pg.population(prob, 20, seed)` (20 evaluations)
plus `algorithm.evolve(pop)`, i.e. everything one run needs, measured from Python. With the
Python problem below every evaluation is a call from pygmo's C++ into Python and numpy, and
that call is most of the time; `--native-rastrigin` uses pygmo's own C++ rastrigin (unshifted
only) to show pygmo's algorithms without it. On a shared machine the wall-clock time includes
the waits for a core; the CPU time does not.

    python3 -m venv venv && venv/bin/pip install pygmo==2.20.0
    venv/bin/python scripts/pygmo_baseline.py [--shift 1.7] [--native-rastrigin]
"""
import argparse
import statistics
import time

import numpy as np
import pygmo as pg


class Fn:
    def __init__(self, name, dim, shift):
        self.name, self.dim, self.shift = name, dim, shift

    def fitness(self, x):
        z = np.asarray(x) - self.shift
        if self.name == "sphere":
            return [float(np.dot(z, z))]
        return [float(10.0 * len(z) + np.sum(z * z - 10.0 * np.cos(2.0 * np.pi * z)))]

    def get_bounds(self):
        return ([-5.12] * self.dim, [5.12] * self.dim)

    def get_name(self):
        return self.name


METHODS = {
    "ga": lambda g, s: pg.sga(gen=g, seed=s),
    "pso": lambda g, s: pg.pso(gen=g, seed=s),
    "gwo": lambda g, s: pg.gwo(gen=g, seed=s),
    "abc": lambda g, s: pg.bee_colony(gen=g, seed=s),
    "cmaes": lambda g, s: pg.cmaes(gen=g, seed=s),
}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--shift", type=float, default=0.0)
    ap.add_argument("--dim", type=int, default=10)
    ap.add_argument("--pop", type=int, default=20)
    ap.add_argument("--gens", type=int, default=100)
    ap.add_argument("--runs", type=int, default=25)
    ap.add_argument("--seed", type=int, default=25)
    ap.add_argument("--native-rastrigin", action="store_true")
    a = ap.parse_args()
    for fn in ["sphere", "rastrigin"]:
        if a.native_rastrigin and fn == "sphere":
            continue
        if a.native_rastrigin:
            prob = pg.problem(pg.rastrigin(a.dim))
        else:
            prob = pg.problem(Fn(fn, a.dim, a.shift))
        for name, make in METHODS.items():
            bests, ms, cpu_ms = [], 0.0, 0.0
            for r in range(a.runs):
                s = a.seed * 1000 + r
                t0, c0 = time.perf_counter(), time.process_time()
                pop = pg.population(prob, a.pop, seed=s)
                pop = pg.algorithm(make(a.gens, s)).evolve(pop)
                ms += (time.perf_counter() - t0) * 1e3
                cpu_ms += (time.process_time() - c0) * 1e3
                bests.append(pop.champion_f[0])
            print(
                f"{fn}\t{name}\tshift={a.shift}\tmedian={statistics.median(bests):.3g}"
                f"\tmin={min(bests):.3g}\tmax={max(bests):.3g}\tms/run={ms / a.runs:.2f}"
                f"\tcpu_ms/run={cpu_ms / a.runs:.2f}",
                flush=True,
            )


if __name__ == "__main__":
    main()
