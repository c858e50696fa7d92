#!/usr/bin/env python3
"""measure.py - runs one command and reports what it cost.

Usage: measure.py LIMIT USAGE_FILE COMMAND [ARG...]

Runs COMMAND (its output goes where this script's goes), kills it after
LIMIT seconds of wall time, and writes to USAGE_FILE one line: the CPU
seconds (user + system) and the peak resident memory (KiB) of the command,
from the kernel's accounting of the one child waited for. Exits with the
command's exit status, 128 + N when signal N ended it, or 124 on timeout,
as timeout(1) does.
"""
import os
import resource
import subprocess
import sys


def main():
    if len(sys.argv) < 4:
        sys.stderr.write(__doc__)
        return 2
    limit, usage_file, command = float(sys.argv[1]), sys.argv[2], sys.argv[3:]
    try:
        child = subprocess.Popen(command)
    except OSError as e:
        sys.stderr.write("measure.py: cannot run %s: %s\n" % (command[0], e))
        return 127
    try:
        status = child.wait(timeout=limit)
        code = 128 - status if status < 0 else status
    except subprocess.TimeoutExpired:
        child.kill()
        child.wait()
        code = 124
    use = resource.getrusage(resource.RUSAGE_CHILDREN)
    with open(usage_file, "w") as f:
        f.write("%.3f %d\n" % (use.ru_utime + use.ru_stime, use.ru_maxrss))
    return code


if __name__ == "__main__":
    sys.exit(main())
