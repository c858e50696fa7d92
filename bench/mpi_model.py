#!/usr/bin/env python3
"""Predicts ilf-mpi's speed-up on a cluster from bench/mpi.sh's measurements (BENCHMARKS-journal.md, section 6).

Usage: python3 bench/mpi_model.py OUT [--cores-per-rank T] [--bandwidth GBPS] [--latency US]
                                      [--efficiency E] [--write-fixed F] [--write-ratio R]
                                      [--setup-x100 CASE=S]

OUT is bench/mpi.sh's folder: each case's stats.json of one process (CASE-1x2)
and of two ranks (CASE-2x1), and runs.txt for the whole runs' times.

The model, per case, for K ranks of T threads each (one rank per node):

  T(K) = S + C (1 + I) / (K * T * e) + sum over passes of X(K, B_p) + W(K)

  S     the part every rank does whole, measured: the run's wall time less
        its passes and its radiance.h5 write (start-up, scene load, maps,
        ray tracer), from the one-process run;
  C     CPU seconds of the passes, summed over threads (one process run);
  e     the threads' efficiency, C / (2 x the passes' wall) of the one-process
        run, at most 1 (--efficiency replaces it: a loaded machine's runs
        measure the load, not the threads);
  I     the ranks' imbalance: what the 2-rank run's exchanges waited for the
        slowest rank, over its passes' wall time (tiles claimed as ranks
        become free leave about one tile's time a pass);
  X     one exchange, a ring all-gather of B_p bytes: (K - 1) latency +
        B_p (K - 1) / K / bandwidth (B_p measured: 24 bytes a cell of the
        pass's receivers), plus the sum of which rank claimed which tile
        (16 bytes a tile, small beside B_p: left out);
  W(K)  the write of format 2, measured with one process (W1, after the
        engine) and two ranks (W2): W1 for K = 1; else a part F of W2 that
        rank 0 does alone whatever K (describing every map, HDF5's storing
        of the compressed chunks, a few agreements; --write-fixed, default
        0.25: by callgrind, 0.13 of the write's instructions at 1.3 M cells
        and 0.24 at 51 k, BENCHMARKS-journal.md 6d) and the rest, each
        rank compressing its share of the chunks, divided by K / 2; plus
        the compressed file (Z bytes, the 2-rank run's radiance.h5)
        crossing rank 0's link once, Z (K - 1) / K / bandwidth, and one
        latency a rank for the gather of the chunks' sizes and the trade
        of boundary rows. --write-ratio R takes W2 as R W1 instead of the
        2-rank run's.

A scene 100 times larger (data/gen_scenes.py --building 10 10) scales S, C,
B and W by 100: each rank still holds the whole scene. --setup-x100
classroom=S replaces the classroom's scaled S by the setup measured on that
scene itself (its 303,500 polygons read, 5.1 M cells made, ray tracer
built: BENCHMARKS-journal.md 6g); only for a case whose cells are the
building's (the classroom at its own 0.1 m cells, not at 0.018 m). Measured on the
building itself (one process, 2 threads, --bounces 0; BENCHMARKS-journal.md
6e): from 1 to 25 rooms the setup grows less than 100-fold scaling says
(0.63 s at 25 rooms against 25 x 0.11 s) and the relighting more (2.4 CPU
s a room against 0.9 s: lamps of diagonal rooms, hidden by two walls
together, escape the emitter cull), so the model's S is pessimistic and its
C optimistic for that scene. Two more columns say
what lifts the limits: "setup divided" takes S as S / K (each rank loading
and building only what its tiles need), and "and write apart" also takes
the write off the ranks' time, one rank's too (the speed-up of the
relighting alone: what a write overlapped with the engine, or done by
separate writers, would leave).
"""
import argparse
import json
import os
import sys


def load(path):
    with open(path) as f:
        return json.load(f)


def whole_runs(out):
    """The whole-run wall time of the last run of each label of runs.txt (its stats.json is the one kept)."""
    runs = {}
    for line in open(os.path.join(out, "runs.txt")):
        f = line.split()
        runs[f[0]] = float(f[1])
    return runs


def measure(out, case, whole, efficiency, write_ratio):
    """The model's inputs for one case, from its runs."""
    one = load(os.path.join(out, case + "-1x2", "stats.json"))
    two = load(os.path.join(out, case + "-2x1", "stats.json"))
    passes_wall = sum(x["wall_seconds"] for x in one["passes"])
    c = sum(x["cpu_seconds"] for x in one["passes"])
    e = efficiency if efficiency else min(1.0, c / (2 * passes_wall))
    ex = two.get("exchanges", [])
    waited = sum(x["wait_seconds"] for x in ex)
    imbalance = waited / max(1e-9, sum(x["wall_seconds"] for x in two["passes"]))
    w1, w2 = one["radiance_write_seconds"], two["radiance_write_seconds"]
    if write_ratio:
        w2 = write_ratio * w1
    s = max(0.0, whole[case + ":1x2"] - passes_wall - w1)
    z = os.path.getsize(os.path.join(out, case + "-2x1", "radiance.h5"))
    return {"s": s, "c": c, "e": e, "i": imbalance, "w1": w1, "w2": w2, "z": z, "bytes": [x["bytes"] for x in ex]}


def predict(m, scale, k, a, setup_divided=False, write_apart=False):
    """@return (total, compute, exchange, write, setup) seconds at k ranks."""
    t, bw, lat = a.cores_per_rank, a.bandwidth * 1e9, a.latency * 1e-6
    compute = scale * m["c"] * (1 + (m["i"] if k > 1 else 0.0)) / (k * t * m["e"])
    exchange = sum((k - 1) * lat + scale * b * (k - 1) / k / bw for b in m["bytes"]) if k > 1 else 0.0
    if write_apart:
        write = 0.0
    elif k == 1:
        write = scale * m["w1"]
    else:
        f = a.write_fixed
        write = scale * m["w2"] * (f + (1 - f) * 2 / k) + scale * m["z"] * (k - 1) / k / bw + 2 * (k - 1) * lat
    s = m["s100"] if scale == 100 and m.get("s100") else scale * m["s"]
    setup = s / (k if setup_divided else 1)
    return setup + compute + exchange + write, compute, exchange, write, setup


def first_limit(parts):
    """The largest of the parts at 512 ranks, by name."""
    names = ("compute", "exchange", "write", "setup")
    return max(zip(parts[1:], names))[1]


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("out")
    p.add_argument("--cores-per-rank", type=int, default=32)
    p.add_argument("--bandwidth", type=float, default=10.0, help="GB/s per node (100 Gb/s InfiniBand: about 10)")
    p.add_argument("--latency", type=float, default=2.0, help="microseconds per message")
    p.add_argument("--efficiency", type=float, default=0.0, help="the threads' efficiency (0: as measured)")
    p.add_argument("--write-fixed", type=float, default=0.25, help="part of the 2-rank write rank 0 does alone, whatever the ranks")
    p.add_argument("--write-ratio", type=float, default=0.0, help="W2 as this times W1 (0: as measured)")
    p.add_argument("--setup-x100", action="append", default=[], metavar="CASE=S",
                   help="case's setup at 100 times the scene, seconds, measured on that scene (else 100 times S)")
    a = p.parse_args()
    whole = whole_runs(a.out)
    setups = {}
    for item in a.setup_x100:
        name, _, value = item.partition("=")
        setups[name] = float(value)
    print("Predicted speed-up over one rank of %d threads; %.0f GB/s, %.0f us per message.\n"
          % (a.cores_per_rank, a.bandwidth, a.latency))
    print("| case | S (s) | C (cpu s) | e | I | exchanged per run | W1, W2 (s) | K = 1 | 64 | 512 "
          "| at 512: setup, write, exchange, compute (s) | first limit | 64, 512: setup divided "
          "| 64, 512: and write apart |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|")
    for case in sorted({k.split(":")[0] for k in whole}):
        m = measure(a.out, case, whole, a.efficiency, a.write_ratio)
        m["s100"] = setups.get(case)
        for scale, name in ((1, case), (100, case + " x 100")):
            t1 = predict(m, scale, 1, a)[0]
            at = predict(m, scale, 512, a)
            lifted = [t1 / predict(m, scale, k, a, True)[0] for k in (64, 512)]
            t1_apart = predict(m, scale, 1, a, True, True)[0]
            apart = [t1_apart / predict(m, scale, k, a, True, True)[0] for k in (64, 512)]
            print("| %s | %.1f | %.1f | %.2f | %.3f | %.1f MB | %.2f, %.2f | %.1f s | %.1fx | %.1fx "
                  "| %.2f, %.2f, %.2f, %.2f | %s | %.1fx, %.1fx | %.1fx, %.1fx |" % (
                      name, predict(m, scale, 1, a)[4], scale * m["c"], m["e"], m["i"], scale * sum(m["bytes"]) / 1e6,
                      scale * m["w1"], scale * m["w2"], t1, t1 / predict(m, scale, 64, a)[0], t1 / at[0],
                      at[4], at[3], at[2], at[1], first_limit(at), lifted[0], lifted[1], apart[0], apart[1]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
