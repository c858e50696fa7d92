#!/usr/bin/python3
"""man_pages.py - writes the manual pages of `ilf` from its own --help, so that they cannot drift.

Usage: man_pages.py ILF OUT_DIR

Runs `ILF --help`, takes the commands from its "Commands:" section, runs `ILF COMMAND --help` for
each, and writes OUT_DIR/ilf.1 and OUT_DIR/ilf-COMMAND.1 in man(7) roff. The help text has one
shape (tools/cli.c prints it): "Usage:" lines, description paragraphs, then sections that open
with a line "Title:"; in "Options:" each option starts a line with "-" after two blanks, and a
line indented further continues the one before. Nothing but the help text goes into a page, and
the pages are made at build time from the built command, so a page says exactly what --help says.
"""

import os
import re
import subprocess
import sys

SECTION = re.compile(r"^([A-Z][A-Za-z ]*):$")
OPTION = re.compile(r"^ {2,8}(-\S.*?)(?:\s{2,}(\S.*))?$")


def roff(text):
    """Escapes a line of text for roff: backslashes, hyphens of options and a leading control
    character."""
    text = text.replace("\\", "\\e").replace("-", "\\-")
    return "\\&" + text if text.startswith((".", "'")) else text


def help_text(ilf, *args):
    return subprocess.run([ilf, *args, "--help"], check=True, capture_output=True, text=True).stdout


def split_sections(text):
    """@return (usage lines, description lines, [(title, lines)]) of a help text."""
    lines = text.rstrip("\n").split("\n")
    usage = []
    k = 0
    while k < len(lines) and lines[k].strip():
        usage.append(re.sub(r"^(Usage:)?\s*", "", lines[k]))
        k += 1
    description, sections = [], []
    for line in lines[k:]:
        m = SECTION.match(line)
        if m:
            sections.append((m.group(1), []))
        elif sections:
            sections[-1][1].append(line)
        else:
            description.append(line)
    return usage, description, sections


def paragraphs(lines):
    """roff for free text: blank lines separate paragraphs; indented lines are kept as laid out."""
    out, verbatim = [], False
    for line in lines:
        if not line.strip():
            if verbatim:
                out.append(".fi")
                verbatim = False
            out.append(".PP")
        elif line.startswith("  "):
            if not verbatim:
                out.append(".nf")
                verbatim = True
            out.append(roff(line))
        else:
            if verbatim:
                out.append(".fi")
                verbatim = False
            out.append(roff(line))
    if verbatim:
        out.append(".fi")
    while out and out[0] == ".PP":
        out.pop(0)
    while out and out[-1] == ".PP":
        out.pop()
    return out


def options(lines):
    """roff for an option table: one .TP per option, its help joined from its lines."""
    out = []
    for line in lines:
        m = OPTION.match(line)
        if m:
            out += [".TP", "\\fB" + roff(m.group(1).strip()) + "\\fR"]
            if m.group(2):
                out.append(roff(m.group(2)))
        elif line.strip() and out:
            out.append(roff(line.strip()))
    return out


def page(name, summary, text, see_also):
    usage, description, sections = split_sections(text)
    out = ['.TH %s 1 "" "ilfkit" "User Commands"' % name.upper(), ".SH NAME", "%s \\- %s" % (name, roff(summary)),
           ".SH SYNOPSIS", ".nf"] + [roff(u) for u in usage] + [".fi", ".SH DESCRIPTION"] + paragraphs(description)
    for title, lines in sections:
        out.append(".SH " + title.upper())
        if title == "Options":
            out += options(lines)
        elif title.startswith("Example"):
            out += [".nf"] + [roff(line[2:] if line.startswith("  ") else line) for line in lines if line.strip()]
            out.append(".fi")
        else:
            out += paragraphs(lines)
    out += [".SH SEE ALSO", ", ".join("\\fB%s\\fR(1)" % roff(s) for s in see_also)]
    return "\n".join(out) + "\n"


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__.split("\n\n")[1])
    ilf, out_dir = sys.argv[1], sys.argv[2]
    top = help_text(ilf)
    _, _, sections = split_sections(top)
    commands = [(m.group(1), m.group(2)) for line in dict(sections).get("Commands", [])
                for m in [re.match(r"^\s+(\S+)\s+(.*)$", line)] if m]
    if not commands:
        sys.exit("man_pages.py: no commands found in '%s --help'" % ilf)
    os.makedirs(out_dir, exist_ok=True)
    names = ["ilf-" + c for c, _ in commands]
    pages = {"ilf": page("ilf", "tools for incident light fields", top, names)}
    for command, summary in commands:
        pages["ilf-" + command] = page("ilf-" + command, summary, help_text(ilf, command), ["ilf"])
    for name, text in pages.items():
        path = os.path.join(out_dir, name + ".1")
        with open(path + ".tmp", "w") as f:
            f.write(text)
        os.replace(path + ".tmp", path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
