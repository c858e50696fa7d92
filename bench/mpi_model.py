#!/usr/bin/env python3
"""Predicts ilf-mpi's speed-up on a cluster from bench/mpi.sh's measurements (BENCHMARKS-journal.md, section 6).

Usage: python3 bench/mpi_model.py OUT [--cores-per-rank T] [--bandwidth GBPS] [--latency US]

OUT is bench/mpi.sh's folder: each case's stats.json of one process (CASE-1x2)
and of two ranks (CASE-2x1), and runs.txt for the whole runs' times.

The model, per case, for K ranks of T threads each (one rank per node):

  T(K) = S + C / (K * T * e) + sum over passes of X(K, B_p) + W(K)

  S     the part every rank does whole, measured: the run's wall time less
        its passes and its radiance.h5 write (start-up, scene load, maps,
        ray tracer), from the one-process run;
  C     CPU seconds of the passes, summed over threads (one process run);
  e     the threads' efficiency measured here: C / (2 x the passes' wall);
  X     one exchange, a ring all-gather of B_p bytes: (K - 1) latency +
        B_p (K - 1) / K / bandwidth (B_p measured: 24 bytes a cell of the
        pass's receivers);
  W(K)  the collective write, measured with one process (W1, HDF5's core
        driver) and two ranks (W2, MPI-IO): W1 for K = 1, else W2 growing
        with the collectives' depth, W2 (1 + 0.5 log2(K / 2)).

A scene 100 times larger (data/gen_scenes.py --building 10 10) scales S, C,
B and W by 100: each rank still holds the whole scene. The exchange
dominates where sum X exceeds C / (K T e).
"""
import argparse
import json
import math
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


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("out")
    p.add_argument("--cores-per-rank", type=int, default=32)
    p.add_argument("--bandwidth", type=float, default=10.0, help="GB/s per node (100 Gb/s InfiniBand: about 10)")
    p.add_argument("--latency", type=float, default=2.0, help="microseconds per message")
    a = p.parse_args()
    whole = whole_runs(a.out)
    t, bw, lat = a.cores_per_rank, a.bandwidth * 1e9, a.latency * 1e-6
    print("Predicted speed-up over one rank of %d threads; %.0f GB/s, %.0f us per message.\n" % (t, a.bandwidth, a.latency))
    print("| case | S (s) | C (cpu s) | exchanged per run | W1, W2 (s) | K = 1 | 8 | 64 | 512 | at 512: write, exchange, compute (s) | exchange > compute from K = | 512, write as W1 |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for case in sorted({k.split(":")[0] for k in whole}):
        one = load(os.path.join(a.out, case + "-1x2", "stats.json"))
        two = load(os.path.join(a.out, case + "-2x1", "stats.json"))
        passes_wall = sum(x["wall_seconds"] for x in one["passes"])
        c = sum(x["cpu_seconds"] for x in one["passes"])
        e = min(1.0, c / (2 * passes_wall))
        w1, w2 = one["radiance_write_seconds"], two["radiance_write_seconds"]
        s = max(0.0, whole[case + ":1x2"] - passes_wall - w1)
        bytes_ = [x["bytes"] for x in two.get("exchanges", [])]
        for scale, name in ((1, case), (100, case + " x 100")):
            def time(k, flat_write=False):
                compute = scale * c / (k * t * e)
                exchange = sum((k - 1) * lat + scale * b * (k - 1) / k / bw for b in bytes_) if k > 1 else 0.0
                write = scale * (w1 if k == 1 or flat_write else w2 * (1 + 0.5 * math.log2(k / 2)))
                return scale * s + compute + exchange + write, compute, exchange, write
            t1 = time(1)[0]
            cross = next((k for k in (2 ** i for i in range(1, 21)) if time(k)[2] > time(k)[1]), None)
            at = time(512)
            print("| %s | %.1f | %.1f | %.1f MB | %.1f, %.1f | %.1f s | %.2fx | %.2fx | %.2fx | %.1f, %.2f, %.2f | %s | %.2fx |" % (
                name, scale * s, scale * c, scale * sum(bytes_) / 1e6, scale * w1, scale * w2, t1,
                t1 / time(8)[0], t1 / time(64)[0], t1 / at[0], at[3], at[2], at[1],
                cross if cross else "beyond 10^6", t1 / time(512, True)[0]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
