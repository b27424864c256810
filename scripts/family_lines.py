#!/usr/bin/env python3
"""Lines of each method family and each shared engine of `dae-solvers`.

Issue 26, done-when 1: "every method family's own code is at most 500 lines
beyond the shared engines". For every family (`bdf`, `odbdf`, `mebdf`,
`idec`, `radau5`, `odradau`, `gauss`: a directory or a single file under
`dae-solvers/src/`) and every shared engine (`core`, `collocation`,
`multistep`, and `linalg`, the crate's linear algebra) this prints

- total: every line of the `.rs` files;
- blank: lines with nothing but white space;
- comment: lines that are a `//`, `///` or `//!` comment and nothing else
  (the crate has no block comments);
- test: lines of `#[cfg(test)]` items (test modules, test-only
  functions), blank and comment lines inside them included;
- code: the rest — the count that decides.

It exits with status 1 when a family's code lines exceed the bound (500),
else 0 — except that a family in `OVER` (the families still above the
bound, issue 26 open) may keep the code lines it has there but not grow;
`--strict` ignores `OVER`. A file inside an engine that one family alone
uses (`ATTRIBUTED`) counts as that family's code, not the engine's: code
does not become shared by moving. `.ci/run` runs it. Deterministic (files in
sorted order), standard library only.

Usage: `python3 scripts/family_lines.py [--strict] [--files] [--bound N]
[ROOT]`, ROOT the repository (default: the parent of this script's
directory).
"""

import argparse
import os
import sys

FAMILIES = ["bdf", "odbdf", "mebdf", "idec", "radau5", "odradau", "gauss"]
ENGINES = ["core", "collocation", "multistep", "linalg"]
BOUND = 500
# Families above the bound and the code lines they have (branch fold10,
# BENCHMARKS.md §12g): not to grow; lower each entry as code moves out, and
# drop it at 500. Session 11 dropped both: idec 592 -> 496 (branch
# idec11, BENCHMARKS.md §12h: the one-step state core::onestep::OneStep
# shared with the collocation engine) and mebdf 625 -> 497 (branch mebdf11,
# BENCHMARKS.md §12i).
OVER: dict = {}
# Files inside an engine that a single family uses: that family's own code,
# wherever it lives. None now: multistep/stale.rs (mebdf11), counted as
# mebdf's while mebdf alone called it, is called by bdf and odbdf too since
# the lead's merge of session 11 (branch stale11, BENCHMARKS.md §12i).
ATTRIBUTED: dict = {}


def strip_code(line):
    """The line without its string and char literals and its trailing
    `//` comment, for counting braces."""
    out = []
    i, n = 0, len(line)
    while i < n:
        c = line[i]
        if c == "/" and line.startswith("//", i):
            break
        if c == '"':
            i += 1
            while i < n and line[i] != '"':
                i += 2 if line[i] == "\\" else 1
            i += 1
            continue
        if c == "'":
            # A char literal ('{', '\n') or a lifetime ('a): a literal
            # closes within three characters (four with an escape).
            end = line.find("'", i + 1)
            if end != -1 and end - i <= 3 + (line[i + 1] == "\\"):
                i = end + 1
                continue
        out.append(c)
        i += 1
    return "".join(out)


def count_file(path):
    """(total, blank, comment, test, code) of one source file."""
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    total = len(lines)
    blank = comment = test = code = 0
    i = 0
    while i < total:
        s = lines[i].strip()
        if s.startswith("#[cfg(test)]"):
            # The item that follows: through its closing brace, or through
            # its `;`/`,` when it has no body.
            start = i
            depth = 0
            opened = False
            i += 1
            while i < total:
                body = strip_code(lines[i])
                depth += body.count("{") - body.count("}")
                opened = opened or "{" in body
                t = body.strip()
                i += 1
                if opened and depth <= 0:
                    break
                if not opened and (t.endswith(";") or t.endswith(",")):
                    break
            test += i - start
            continue
        if not s:
            blank += 1
        elif s.startswith("//"):
            comment += 1
        else:
            code += 1
        i += 1
    return total, blank, comment, test, code


def rust_files(path):
    """The `.rs` files of a directory (recursively) or the file itself."""
    if os.path.isfile(path):
        return [path]
    found = []
    for root, dirs, files in os.walk(path):
        dirs.sort()
        found += [os.path.join(root, f) for f in sorted(files) if f.endswith(".rs")]
    return found


def unit_path(src, name):
    """A family's or engine's directory, or its single file."""
    d = os.path.join(src, name)
    return d if os.path.isdir(d) else d + ".rs"


def count_unit(src, name):
    """Summed counts of a unit, and per-file counts: a family's with the
    engine files ATTRIBUTED to it, an engine's without them."""
    per_file = []
    sums = [0] * 5
    paths = [p for p in rust_files(unit_path(src, name))
             if os.path.relpath(p, src) not in ATTRIBUTED]
    paths += [os.path.join(src, f) for f, fam in sorted(ATTRIBUTED.items()) if fam == name]
    for path in paths:
        c = count_file(path)
        per_file.append((os.path.relpath(path, src), c))
        sums = [a + b for a, b in zip(sums, c)]
    return sums, per_file


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("root", nargs="?", default=os.path.join(os.path.dirname(__file__), ".."))
    parser.add_argument("--bound", type=int, default=BOUND)
    parser.add_argument("--files", action="store_true", help="also every file")
    parser.add_argument("--strict", action="store_true", help="no family above the bound")
    args = parser.parse_args()
    src = os.path.join(args.root, "dae-solvers", "src")
    header = f"{'':<26}{'total':>7}{'blank':>7}{'comment':>8}{'test':>6}{'code':>6}"
    over = []
    for title, names in (("family", FAMILIES), ("engine", ENGINES)):
        print(header.replace(" " * 26, f"{title:<26}", 1))
        for name in names:
            if not os.path.exists(unit_path(src, name)):
                print(f"{name}: missing", file=sys.stderr)
                return 2
            sums, per_file = count_unit(src, name)
            print(f"{name:<26}" + "".join(f"{v:>{w}}" for v, w in zip(sums, (7, 7, 8, 6, 6))))
            if args.files and len(per_file) > 1:
                for rel, c in per_file:
                    print(f"  {rel:<24}" + "".join(f"{v:>{w}}" for v, w in zip(c, (7, 7, 8, 6, 6))))
            if title == "family" and sums[4] > args.bound:
                over.append((name, sums[4]))
    failed = False
    for name, code in over:
        allowed = None if args.strict else OVER.get(name)
        if allowed is not None and code <= allowed:
            print(f"family {name}: {code} code lines, above the bound of {args.bound} "
                  f"(known, at most {allowed}: issue 26)", file=sys.stderr)
        else:
            failed = True
            print(f"family {name}: {code} code lines, above the bound of {args.bound}"
                  + (f" and its known {allowed}" if allowed is not None else ""), file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
