#!/usr/bin/python3
"""doc_examples_test.py - runs every command example of the documentation and checks what it shows.

Usage: doc_examples_test.py SOURCE_DIR BUILD_DIR WORK_DIR [CMAKE]

The documents are data/README.md and the READMEs under data/ (they make files the others use), then
README.md, then docs/*.md in name order. Their fenced blocks follow the convention of tests/README.md:

  ```sh                   commands, run one logical line at a time (backslash continuations and
                          here-documents joined), in order, in one scratch folder (WORK_DIR/run, holding
                          a copy of data/), with bash; each must exit 0, or N when its comment says
                          "exit status N". State does not carry from line to line (no cd, no variables).
  ```python               run with this test's python3 (h5py and numpy) from the scratch folder, after the python blocks before it
                          in the same document (as one session: a later block uses an earlier one's imports),
                          with the installed package ilfkit on PYTHONPATH (skipped, and said so, when a block
                          needs it and the build has no Python module)
  ```sh illustration      shown, not run (a build, a cluster, a long benchmark: say why beside it)
  ```output [rtol=R]      what the last command of the sh block just before printed (stdout and stderr);
                          a line "..." stands for any number of lines; numbers agree within relative
                          tolerance R (default 0.01); times (a number before " s") and sizes (before
                          "KiB", "MiB", "GiB") are not compared, since they depend on the machine
  ```c file=NAME          a C program, written to NAME in the scratch folder for a later sh block to build
                          (any block with file=NAME is written so: a scene, a mesh; a C block needs one)
  ```json schema=PATH [optional=K1,K2]
                          the shape of the JSON file PATH, which an example of the same document makes
                          (checked once its examples have run): every key of the file must be in the
                          block, and every key of the block in the file unless listed as optional.
                          "// ..." comments and placeholder letters (x, y, z, r, g, b, i, j) are allowed
  ```ANYTHING-ELSE        text, JSON, Python...: not run
  ```                     a block without an info string is an error: every block says what it is

Then docs/cli.md is held against the built `ilf --help` (check_cli_reference: commands, options,
listed values, the help's column). Commands find `ilf` in BUILD_DIR/tools first on PATH; the build is also installed into WORK_DIR/prefix
(cmake --install), whose bin/ comes next, whose pkg-config files are on PKG_CONFIG_PATH and which is
CMAKE_PREFIX_PATH, so C examples build against an install, as a user's would. Every failure names the document, the line, the command and
what it printed; all examples run even after one fails.
"""

import json
import os
import re
import shutil
import subprocess
import sys
import time

COMMAND_TIMEOUT = 300  # seconds for one command; the whole suite of examples takes far less
DEFAULT_RTOL = 0.01
SHOWN_LINES = 25  # lines of a failing command's output quoted in the report

NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
UNCOMPARED_UNIT = re.compile(r"^\s*(?:s\b|[KMG]iB\b)")
FENCE = re.compile(r"^(\s*)```(.*)$")
HEREDOC = re.compile(r"<<-?\s*'?\"?(\w+)'?\"?")
EXPECTED_STATUS = re.compile(r"#.*\bexit status (\d+)")


class Block:
    def __init__(self, doc, line, info, body):
        self.doc, self.line, self.body = doc, line, body
        words = info.split()
        self.kind = words[0] if words else ""
        self.words = words[1:]
        self.options = dict(w.split("=", 1) for w in self.words if "=" in w)


def read_blocks(path, rel):
    """@return the fenced blocks of a Markdown file, with the line number of their opening fence."""
    blocks, lines = [], open(path, encoding="utf-8").read().split("\n")
    k = 0
    while k < len(lines):
        m = FENCE.match(lines[k])
        if not m:
            k += 1
            continue
        start, indent, body = k, len(m.group(1)), []
        k += 1
        while k < len(lines) and not lines[k].strip().startswith("```"):
            body.append(lines[k][indent:] if lines[k][:indent].strip() == "" else lines[k])
            k += 1
        blocks.append(Block(rel, start + 1, m.group(2).strip(), body))
        k += 1
    return blocks


def documents(src):
    data = ["data/README.md"] + sorted(
        os.path.relpath(os.path.join(d, "README.md"), src)
        for d, _, files in os.walk(os.path.join(src, "data")) if "README.md" in files and d != os.path.join(src, "data"))
    docs = sorted("docs/" + f for f in os.listdir(os.path.join(src, "docs")) if f.endswith(".md"))
    return [d for d in data + ["README.md"] + docs if os.path.isfile(os.path.join(src, d))]


def commands(block):
    """@return (line number, command text, expected status) for each logical line of an sh block."""
    out, k, body = [], 0, block.body
    while k < len(body):
        first, text = k, body[k]
        k += 1
        while text.endswith("\\") and k < len(body):
            text += "\n" + body[k]  # bash joins the lines itself
            k += 1
        m = HEREDOC.search(text)
        if m and not text.lstrip().startswith("#"):
            end = m.group(1)
            while k < len(body) and body[k].strip() != end:
                text += "\n" + body[k]
                k += 1
            if k < len(body):
                text += "\n" + body[k]
                k += 1
        if text.strip() == "" or text.lstrip().startswith("#"):
            continue
        status = EXPECTED_STATUS.search(text.split("\n")[0] if m else text)
        out.append((block.line + 1 + first, text, int(status.group(1)) if status else 0))
    return out


def split_numbers(line):
    """@return (texts, numbers, compared): the line's text between numbers (collapsed blanks), its
    numbers, and for each whether it is compared (not a time or a size)."""
    texts, numbers, compared, pos = [], [], [], 0
    for m in NUMBER.finditer(line):
        texts.append(" ".join(line[pos:m.start()].split()))
        numbers.append(float(m.group()))
        compared.append(not UNCOMPARED_UNIT.match(line[m.end():]))
        pos = m.end()
    texts.append(" ".join(line[pos:].split()))
    return texts, numbers, compared


def line_matches(expected, actual, rtol):
    te, ne, ce = split_numbers(expected)
    ta, na, _ = split_numbers(actual)
    if te != ta or len(ne) != len(na):
        return False
    return all(not c or abs(a - e) <= rtol * max(abs(a), abs(e)) + 1e-12 for e, a, c in zip(ne, na, ce))


def output_matches(expected, actual, rtol):
    """Whether actual lines match expected lines, where an expected "..." matches any run of lines."""
    expected = [e for e in expected if e.strip() != ""]
    actual = [a for a in actual if a.strip() != ""]
    memo = {}

    def match(i, j):
        if (i, j) not in memo:
            if i == len(expected):
                memo[(i, j)] = j == len(actual)
            elif expected[i].strip() == "...":
                memo[(i, j)] = any(match(i + 1, k) for k in range(j, len(actual) + 1))
            else:
                memo[(i, j)] = j < len(actual) and line_matches(expected[i], actual[j], rtol) and match(i + 1, j + 1)
        return memo[(i, j)]

    return match(0, 0)


PLACEHOLDER = re.compile(r"(?<=[\[,])\s*[a-z]\s*(?=[,\]])")


def schema_of(block):
    """@return the block's JSON with comments removed and placeholder letters made numbers."""
    text = "\n".join(re.sub(r"\s//.*$", "", line) for line in block.body)
    return json.loads(PLACEHOLDER.sub("0", text))


def key_differences(doc, real, optional, where="", out=None):
    """@return ["where: problem"] for keys of real missing from doc and keys of doc missing from real."""
    out = [] if out is None else out
    if isinstance(doc, dict) and isinstance(real, dict):
        for k in real:
            if k not in doc:
                out.append("%s%s: in the file, not in the document" % (where, k))
        for k in doc:
            if k not in real and k not in optional:
                out.append("%s%s: in the document, not in the file" % (where, k))
            elif k in real:
                key_differences(doc[k], real[k], optional, "%s%s." % (where, k), out)
    elif isinstance(doc, list) and isinstance(real, list) and doc and real:
        for item in real:
            key_differences(doc[0], item, optional, where[:-1] + "[]." if where else "[].", out)
    return out


IMPORTS_ILFKIT = re.compile(r"^\s*(?:import|from)\s+ilfkit\b", re.M)


class Run:
    def __init__(self, src, build, work, cmake):
        self.src, self.build, self.work = src, build, work
        self.scratch = os.path.join(work, "run")
        self.failures, self.count, self.times = [], 0, []
        shutil.rmtree(work, ignore_errors=True)
        os.makedirs(self.scratch)
        # data/ as a fresh clone has it: without generated files (classroom_lightfield.h5, bench caches)
        shutil.copytree(os.path.join(src, "data"), os.path.join(self.scratch, "data"),
                        ignore=shutil.ignore_patterns("__pycache__", ".*", "classroom_lightfield.h5"))
        prefix = os.path.join(work, "prefix")
        log = subprocess.run([cmake, "--install", build, "--prefix", prefix], capture_output=True, text=True)
        if log.returncode != 0:
            self.failures.append("cmake --install %s failed:\n%s" % (build, log.stdout + log.stderr))
        libdir = next((d for d, _, files in os.walk(prefix) if "liblfio.so" in files), prefix + "/lib")
        self.env = dict(os.environ)
        self.env.pop("LD_LIBRARY_PATH", None)  # a C example must run without it: the rpath carries the way
        self.env["PATH"] = os.pathsep.join([os.path.join(build, "tools"), os.path.join(prefix, "bin"),
                                            self.env.get("PATH", "/usr/bin:/bin")])
        self.env["PKG_CONFIG_PATH"] = os.path.join(libdir, "pkgconfig")
        self.env["CMAKE_PREFIX_PATH"] = prefix
        # docs/python.md imports the package ilfkit as a user would, from the install
        package = next((d for d, _, files in os.walk(prefix) if os.path.basename(d) == "ilfkit" and "__init__.py" in files),
                       None)
        if package is not None:
            self.env["PYTHONPATH"] = os.path.dirname(package)
        self.has_ilfkit, self.skipped = package is not None, []

    def fail(self, block, line, what, command=None, output=None):
        text = "%s:%d: %s" % (block.doc, line, what)
        if command is not None:
            text += "\n    command: " + command.replace("\n", "\n             ")
        if output is not None:
            lines = output.rstrip("\n").split("\n")
            shown = lines[-SHOWN_LINES:]
            text += "\n    it printed%s:\n      | " % (" (last %d lines)" % SHOWN_LINES if len(lines) > SHOWN_LINES else "")
            text += "\n      | ".join(shown)
        self.failures.append(text)

    def run_sh(self, block):
        """Runs the block's commands; @return the output of its last command (None if it has none)."""
        last = None
        for line, text, expected in commands(block):
            self.count += 1
            started = time.monotonic()
            try:
                p = subprocess.run(["bash", "-c", "set -o pipefail\n" + text], cwd=self.scratch, env=self.env,
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                   timeout=COMMAND_TIMEOUT, errors="replace")
                last = p.stdout
                if p.returncode != expected:
                    self.fail(block, line, "exit status %d, expected %d" % (p.returncode, expected), text, p.stdout)
            except subprocess.TimeoutExpired as e:
                last = None
                self.fail(block, line, "still running after %d s" % COMMAND_TIMEOUT, text,
                          e.stdout.decode(errors="replace") if isinstance(e.stdout, bytes) else e.stdout or "")
            self.times.append((time.monotonic() - started, "%s:%d" % (block.doc, line), text.split("\n")[0]))
        return last

    def check_output(self, block, previous, output):
        if previous is None:
            self.fail(block, block.line, "an output block must follow an sh block that is run")
            return
        if output is None:
            return  # its command failed and was reported
        rtol = float(block.options.get("rtol", DEFAULT_RTOL))
        if not output_matches(block.body, output.split("\n"), rtol):
            last = commands(previous)[-1]
            self.fail(block, block.line, "the output shown (relative tolerance %g; times and sizes not compared) "
                      "differs from the real one" % rtol, last[1], output)

    def check_schema(self, block):
        path = os.path.join(self.scratch, block.options["schema"])
        try:
            doc = schema_of(block)
        except ValueError as e:
            self.fail(block, block.line, "the schema block does not parse as JSON once comments are removed: %s" % e)
            return
        try:
            real = json.load(open(path))
        except (OSError, ValueError) as e:
            self.fail(block, block.line, "cannot read %s, which the schema describes (no example made it?): %s"
                      % (block.options["schema"], e))
            return
        optional = set(block.options.get("optional", "").split(",")) - {""}
        problems = key_differences(doc, real, optional)
        if problems:
            self.fail(block, block.line, "the schema of %s differs from the file:\n    %s"
                      % (block.options["schema"], "\n    ".join(problems)))

    def run_python(self, block, session):
        """Runs the block after the document's earlier python blocks (session), as one script."""
        script = "\n".join(session + block.body) + "\n"
        if not self.has_ilfkit and IMPORTS_ILFKIT.search(script):
            self.skipped.append("%s:%d" % (block.doc, block.line))  # a build without the Python module
            session += block.body
            return
        self.count += 1
        started = time.monotonic()
        try:
            p = subprocess.run([sys.executable, "-c", script], cwd=self.scratch, env=self.env, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True, timeout=COMMAND_TIMEOUT, errors="replace")
            if p.returncode != 0:
                self.fail(block, block.line, "the python block exited %d" % p.returncode, "python3 (the block)",
                          p.stdout)
        except subprocess.TimeoutExpired:
            self.fail(block, block.line, "the python block still ran after %d s" % COMMAND_TIMEOUT)
        self.times.append((time.monotonic() - started, "%s:%d" % (block.doc, block.line), "python block"))
        session += block.body

    def run_document(self, doc):
        previous, output, schemas, session = None, None, [], []
        for block in read_blocks(os.path.join(self.src, doc), doc):
            illustration = "illustration" in block.words
            if block.kind == "":
                self.fail(block, block.line, "a fenced block without an info string: tag it ```sh (run), "
                          "```sh illustration (shown only), ```output, or ```text (see tests/README.md)")
            elif block.kind in ("sh", "bash", "shell") and not illustration:
                output, previous = self.run_sh(block), block
                continue
            elif block.kind == "python" and not illustration:
                self.run_python(block, session)
            elif block.kind == "output":
                self.check_output(block, previous, output)
            elif block.kind == "c" and not illustration and "file" not in block.options:
                self.fail(block, block.line, "a C block needs file=NAME (or illustration)")
            elif "file" in block.options and not illustration:
                path = os.path.join(self.scratch, block.options["file"])
                os.makedirs(os.path.dirname(path), exist_ok=True)
                with open(path, "w") as f:
                    f.write("\n".join(block.body) + "\n")
            elif "schema" in block.options:
                schemas.append(block)
            previous, output = None, None
        for block in schemas:
            self.check_schema(block)


HELP_OPTION = re.compile(r"^ {2,8}(?:(-[A-Za-z]), )?(--[a-z0-9-]+)", re.M)
VALUE_LIST = re.compile(r"((?:[a-z]+, )+[a-z]+,? or [a-z]+)")  # "culled, naive, area or adaptive"


def check_cli_reference(run):
    """docs/cli.md against the built ilf's --help: its command table names every command, and the
    section of each command it documents (a heading "## `ilf CMD`") names every option of that
    command's --help (by its long name or its letter), and where the help lists an option's values
    ("culled, naive or area"), that option's row of the section's table lists each of them."""
    path = os.path.join(run.src, "docs/cli.md")
    text = open(path, encoding="utf-8").read()
    help_of = lambda *args: subprocess.run(["ilf", *args, "--help"], env=run.env, capture_output=True,
                                           text=True).stdout
    top = help_of()
    commands = re.findall(r"^  (\S+)  +\S", top.split("Commands:", 1)[-1].split("\n\n", 1)[0], re.M)
    where = Block("docs/cli.md", 1, "", [])
    columns = {re.match(r"^  \S+ +", l).end() for l in top.split("Commands:", 1)[-1].split("\n\n", 1)[0].split("\n")
               if re.match(r"^  \S+ +", l)}
    if len(columns) != 1:
        run.fail(where, 1, "the summaries of 'ilf --help' start in columns %s, not in one" % sorted(columns))
    for c in commands:
        if "| `%s`" % c not in text:
            run.fail(where, 1, "the command table has no row for `%s`, which 'ilf --help' lists" % c)
    sections = re.split(r"^## ", text, flags=re.M)
    for c in commands:
        section = next((s for s in sections if s.startswith("`ilf %s`\n" % c)), None)
        if section is None:
            continue
        line = text[:text.index("## " + section[:40])].count("\n") + 1
        for letter, name in HELP_OPTION.findall(help_of(c)):
            by_letter = letter and re.search(r"(?<![\w-])%s\b" % letter, section)
            if name != "--help" and name not in section and not by_letter:
                run.fail(Block("docs/cli.md", line, "", []), line, "the section of `ilf %s` does not name %s, "
                         "an option of 'ilf %s --help'" % (c, name, c))
        for help_line in help_of(c).split("\n"):
            m, values = HELP_OPTION.match(help_line), VALUE_LIST.search(help_line)
            rows = [r for r in section.split("\n") if m and r.startswith("|") and "`%s" % m.group(2) in r]
            for value in re.split(r",? or |, ", values.group(1)) if values and rows else []:
                if "`%s`" % value not in rows[0]:
                    run.fail(Block("docs/cli.md", line, "", []), line, "the row of %s in the section of `ilf %s` does "
                             "not list `%s`, a value 'ilf %s --help' gives" % (m.group(2), c, value, c))


def main():
    if len(sys.argv) not in (4, 5):
        sys.exit(__doc__.split("\n\n")[1])
    src, build, work = (os.path.abspath(a) for a in sys.argv[1:4])
    run = Run(src, build, work, sys.argv[4] if len(sys.argv) == 5 else "cmake")
    for doc in documents(src):
        run.run_document(doc)
    check_cli_reference(run)
    print("%d commands run from %d documents, in %.1f s; the slowest:" % (run.count, len(documents(src)),
                                                                       sum(t[0] for t in run.times)))
    for seconds, where, command in sorted(run.times, reverse=True)[:5]:
        print("  %6.1f s  %s: %s" % (seconds, where, command))
    if run.skipped:
        print("%d python blocks skipped, the build having no Python module ilfkit: %s" % (len(run.skipped),
                                                                                          " ".join(run.skipped)))
    for f in run.failures:
        print("FAILED " + f + "\n")
    print("%d failures" % len(run.failures))
    return 1 if run.failures else 0


if __name__ == "__main__":
    sys.exit(main())
