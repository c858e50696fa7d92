#!/usr/bin/env python3
"""bench/memory_split.py - a command's peak memory, split into what it allocated and what it mapped from files.

    bench/memory_split.py [--stats STATS_JSON] [--name NAME] COMMAND [ARG ...]

Runs COMMAND (its standard output thrown away, its errors shown) and reads /proc/PID/status every 5 ms
while it runs, keeping the peak of RssAnon (pages the process allocated: heap, stacks, relocated data)
and of RssFile (pages of the program and its shared libraries, shared with every process that maps
them). Sampling can miss a peak shorter than the interval; a relight run holds its peak for most of
its run. Linux only.

Prints "anon_peak_kib A file_peak_kib F exit C". With --stats, the stats.json an `ilf relight` COMMAND
writes, it prints instead one line for BENCHMARKS-journal.md: the light the run held (memory.accumulator_bytes +
memory.lightfield_bytes) and the anon and whole-process peaks (memory.peak_resident_bytes) against it.
Exit code: COMMAND's (128 + the signal when a signal ended it); 2 when it cannot be started or the stats
cannot be read.
"""
import argparse
import json
import re
import subprocess
import sys
import time


def sample(command):
    """Runs command; @return (peak RssAnon KiB, peak RssFile KiB, exit code)."""
    child = subprocess.Popen(command, stdout=subprocess.DEVNULL)
    peak = {"RssAnon": 0, "RssFile": 0}
    status = f"/proc/{child.pid}/status"
    while child.poll() is None:
        try:
            with open(status) as f:
                text = f.read()
        except OSError:  # /proc has no entry for it any more
            break
        for key in peak:
            m = re.search(rf"^{key}:\s+(\d+) kB", text, re.M)
            if m:
                peak[key] = max(peak[key], int(m.group(1)))
        time.sleep(0.005)
    code = child.wait()
    return peak["RssAnon"], peak["RssFile"], code if code >= 0 else 128 - code


def mib(b):
    """@return b bytes as MiB, one decimal."""
    return "%.1f MiB" % (b / 2**20)


def ratio(b, light):
    """@return b against light as "1.23x", or "n/a" when the run held no light."""
    return "%.2fx" % (b / light) if light > 0 else "n/a"


def main():
    ap = argparse.ArgumentParser(description="A command's peak anonymous and file-backed resident memory.")
    ap.add_argument("--stats", help="the stats.json the command writes: print its memory against the peaks")
    ap.add_argument("--name", default="run", help="the name the --stats line starts with")
    ap.add_argument("command", nargs=argparse.REMAINDER)
    a = ap.parse_args()
    if not a.command:
        ap.error("no command given")
    try:
        anon, files, code = sample(a.command)
    except OSError as e:
        sys.stderr.write(f"memory_split.py: {a.command[0]}: {e.strerror}\n")
        return 2
    if a.stats is None or code != 0:
        print(f"anon_peak_kib {anon} file_peak_kib {files} exit {code}")
        return code
    try:
        with open(a.stats) as f:
            m = json.load(f)["memory"]
        light = m["accumulator_bytes"] + m["lightfield_bytes"]
        whole = m["peak_resident_bytes"]
    except (OSError, ValueError, KeyError, TypeError) as e:
        sys.stderr.write(f"memory_split.py: {a.stats}: no memory figures ({e})\n")
        return 2
    anon *= 1024
    print("%s: accumulators %s + light fields %s = %s; anon peak %s (%s), file peak %s, whole peak %s (%s)"
          % (a.name, mib(m["accumulator_bytes"]), mib(m["lightfield_bytes"]), mib(light), mib(anon),
             ratio(anon, light), mib(files * 1024), mib(whole), ratio(whole, light)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
