#!/usr/bin/python3
"""bench/flamegraph.py - a flame graph and a table of where the time goes, from `perf script`.

    perf script -i perf.data | bench/flamegraph.py --svg OUT.svg [--title T] [--top N] [--collapsed OUT.txt]

Reads the samples `perf script` prints (a header line per sample, then its
stack, innermost frame first, one frame a line, then a blank line), folds
each stack into one line of frame names from the outermost in (weighted by
the sample's period when the header gives one, else 1), and writes:

- with --svg, a flame graph: one rectangle per (stack prefix, frame), as wide
  as its share of the samples, callers below, callees above; hovering shows
  the frame and its share (an SVG <title>);
- with --collapsed, the folded stacks ("a;b;c WEIGHT" a line);
- on stdout, the top N functions by inclusive share (the samples with the
  function anywhere on their stack, each counted once) with their self share
  (the samples in the function itself), as a Markdown table.

A frame is named by its symbol without the offset; a frame perf could not
name is named by its library's file name ("[libembree3.so.3]"). The standard
library only, so that it runs with Debian's /usr/bin/python3 as it is.
"""
import argparse
import collections
import html
import os
import re
import sys
import zlib

PERIOD = re.compile(r":\s+(\d+)\s+\S+:\s*$")
FRAME = re.compile(r"^\s+[0-9a-f]+\s+(.*?)\s+\((.*)\)\s*$")


def frame_name(symbol, dso):
    """The name of one frame: its symbol without +0x offset, or its library's file name."""
    symbol = re.sub(r"\+0x[0-9a-f]+$", "", symbol)
    if symbol and symbol != "[unknown]":
        return symbol
    dso = os.path.basename(dso)
    return dso if dso.startswith("[") else "[%s]" % dso


def fold(lines):
    """{stack tuple, outermost first: weight} from the lines of `perf script`."""
    stacks = collections.Counter()
    frames, weight = [], 0
    for line in lines:
        line = line.rstrip("\n")
        if not line.strip():
            if frames:
                stacks[tuple(reversed(frames))] += weight
            frames, weight = [], 0
            continue
        m = FRAME.match(line)
        if m and line[0].isspace():
            frames.append(frame_name(m.group(1), m.group(2)))
            continue
        if not line[0].isspace():  # a sample's header
            if frames:
                stacks[tuple(reversed(frames))] += weight
            p = PERIOD.search(line)
            frames, weight = [], int(p.group(1)) if p else 1
    if frames:
        stacks[tuple(reversed(frames))] += weight
    return stacks


def shares(stacks):
    """(inclusive, self) weights per function: inclusive counts a stack once however often it recurs."""
    inclusive, own = collections.Counter(), collections.Counter()
    for stack, w in stacks.items():
        for name in set(stack):
            inclusive[name] += w
        own[stack[-1]] += w
    return inclusive, own


def tree(stacks):
    """The stacks as a tree of nested {name: [weight, children]}, children by name."""
    root = [0, {}]
    for stack, w in stacks.items():
        node = root
        node[0] += w
        for name in stack:
            node = node[1].setdefault(name, [0, {}])
            node[0] += w
    return root


def colour(name):
    """A warm colour from the name's hash: the same function the same colour in every graph."""
    h = zlib.crc32(name.encode())
    return "rgb(%d,%d,%d)" % (205 + h % 50, 80 + (h >> 8) % 130, 40 + (h >> 16) % 40)


def svg(stacks, title, width=1200, row=16):
    """The flame graph of stacks as an SVG document (a string)."""
    root = tree(stacks)
    total = root[0] or 1
    rects, depth = [], [0]

    def walk(node, x, level):
        depth[0] = max(depth[0], level)
        for name, child in sorted(node[1].items()):
            w = child[0] * (width - 20) / total
            if w >= 0.3:  # narrower than a third of a pixel: not drawn, nor its callees
                rects.append((name, x, level, w, child[0]))
                walk(child, x, level + 1)
            x += w

    walk(root, 10.0, 0)
    height = (depth[0] + 1) * row + 50
    out = ['<?xml version="1.0" standalone="no"?>',
           '<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" font-family="monospace" '
           'font-size="11">' % (width, height),
           '<rect width="100%" height="100%" fill="#f8f8f0"/>',
           '<text x="%d" y="20" text-anchor="middle" font-size="15">%s</text>' % (width // 2, html.escape(title))]
    for name, x, level, w, weight in rects:
        y = height - 20 - (level + 1) * row
        label = html.escape(name)
        share = 100.0 * weight / total
        out.append('<g><title>%s: %.2f%%</title><rect x="%.2f" y="%d" width="%.2f" height="%d" fill="%s" '
                   'rx="2"/>' % (label, share, x, y, w, row - 1, colour(name)))
        chars = int(w / 7)
        if chars >= 3:
            text = name if len(name) <= chars else name[:chars - 2] + ".."
            out.append('<text x="%.2f" y="%d">%s</text>' % (x + 3, y + row - 4, html.escape(text)))
        out.append('</g>')
    out.append('</svg>')
    return "\n".join(out) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("input", nargs="?", help="perf script output (default: stdin)")
    ap.add_argument("--svg", help="write the flame graph here")
    ap.add_argument("--collapsed", help="write the folded stacks here")
    ap.add_argument("--title", default="flame graph")
    ap.add_argument("--top", type=int, default=20, help="functions in the table (default 20)")
    a = ap.parse_args()
    with (open(a.input) if a.input else sys.stdin) as f:
        stacks = fold(f)
    if not stacks:
        sys.exit("flamegraph.py: no samples with stacks in the input")
    total = sum(stacks.values())
    if a.svg:
        with open(a.svg, "w") as f:
            f.write(svg(stacks, a.title))
    if a.collapsed:
        with open(a.collapsed, "w") as f:
            for stack, w in sorted(stacks.items()):
                f.write("%s %d\n" % (";".join(stack), w))
    inclusive, own = shares(stacks)
    print("| function | inclusive | self |")
    print("|---|---:|---:|")
    for name, w in inclusive.most_common(a.top):
        print("| `%s` | %.1f%% | %.1f%% |" % (name, 100.0 * w / total, 100.0 * own[name] / total))


if __name__ == "__main__":
    main()
