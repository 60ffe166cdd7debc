#!/usr/bin/env python3
"""List the Rust functions longer than a limit (the engineering standard: no function over 120 lines
outside tests).

A function's length is counted from the line of its `fn` keyword to the line of its closing brace,
both included. Scanned: every `.rs` file under src/, benches/, examples/ and build.rs. Not scanned:
`#[cfg(test)] mod NAME { ... }` blocks, files that are a `#[cfg(test)] mod NAME;` (such as
src/accel/bvh4/tests.rs) and the integration tests in tests/. Comments, string, raw-string and
character literals are read as such, so a brace inside them is not counted.

    scripts/long-functions.py              # functions over 120 lines, longest first; exit 1 if any
    scripts/long-functions.py --limit 100  # another limit
"""

import argparse
import os
import re
import sys

ROOTS = ["src", "benches", "examples", "build.rs"]


def blank_literals(text):
    """The source with every comment and every string/char literal's content replaced by spaces
    (newlines kept, so line numbers and brace positions are unchanged)."""
    out = list(text)
    i, n = 0, len(text)

    def blank(a, b):
        for k in range(a, b):
            if out[k] != "\n":
                out[k] = " "

    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            blank(i, j)
            i = j
        elif text.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            blank(i, j)
            i = j
        elif (m := re.compile(r'b?r(#*)"').match(text, i)) and (i == 0 or not is_ident(text[i - 1])):
            end = text.find('"' + m.group(1), m.end())
            end = n if end < 0 else end + 1 + len(m.group(1))
            blank(m.end(), end - 1 - len(m.group(1)))
            i = end
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            blank(i + 1, j)
            i = j + 1
        elif c == "'":
            # A character literal ('x', '\n', '\u{7b}', '{'), not a lifetime or label ('a, 'outer).
            m = re.compile(r"'(\\u\{[0-9a-fA-F_]*\}|\\.|[^\\'])'").match(text, i)
            if m:
                blank(i + 1, m.end() - 1)
                i = m.end()
            else:
                i += 1
        else:
            i += 1
    return "".join(out)


def is_ident(ch):
    return ch.isalnum() or ch == "_"


def matching_brace(code, open_at):
    """The index of the `}` closing the `{` at `open_at`."""
    depth = 0
    for j in range(open_at, len(code)):
        if code[j] == "{":
            depth += 1
        elif code[j] == "}":
            depth -= 1
            if depth == 0:
                return j
    return len(code) - 1


CFG_TEST = re.compile(r"#\[cfg\(test\)\]\s*(?:#\[[^\]]*\]\s*)*(?:pub(?:\([^)]*\))?\s+)?mod\s+(\w+)\s*([{;])")
FN = re.compile(r"\bfn\s+(\w+)")


def functions(code):
    """(name, first line, last line) of every function with a body outside `#[cfg(test)]` modules."""
    test_spans = []
    for m in CFG_TEST.finditer(code):
        if m.group(2) == "{":
            test_spans.append((m.start(), matching_brace(code, m.end() - 1)))
    found = []
    for m in FN.finditer(code):
        if any(a <= m.start() <= b for a, b in test_spans):
            continue
        # The body is the first `{` after the signature; a `;` first means a declaration without one.
        # Parentheses, brackets and angle brackets are skipped so that `-> [u8; N]` does not end it.
        depth, j = 0, m.end()
        while j < len(code):
            ch = code[j]
            if ch in "([":
                depth += 1
            elif ch in ")]":
                depth -= 1
            elif depth == 0 and ch in "{;":
                break
            j += 1
        if j >= len(code) or code[j] == ";":
            continue
        end = matching_brace(code, j)
        first = code.count("\n", 0, m.start()) + 1
        last = code.count("\n", 0, end) + 1
        found.append((m.group(1), first, last))
    return found


def test_module_files(path, code):
    """The files that `#[cfg(test)] mod NAME;` in `path` brings in (NAME.rs or NAME/mod.rs beside it,
    or under the module's own directory)."""
    out = []
    base, name = os.path.split(path)
    stem = name[:-3]
    own_dir = base if stem in ("mod", "lib", "main") else os.path.join(base, stem)
    for m in CFG_TEST.finditer(code):
        if m.group(2) == ";":
            for cand in (os.path.join(own_dir, m.group(1) + ".rs"), os.path.join(own_dir, m.group(1), "mod.rs")):
                out.append(os.path.normpath(cand))
    return out


def rust_files(root):
    files = []
    for r in ROOTS:
        p = os.path.join(root, r)
        if os.path.isfile(p):
            files.append(p)
        for dirpath, _, names in os.walk(p):
            files += [os.path.join(dirpath, f) for f in names if f.endswith(".rs")]
    return sorted(files)


def long_functions(root, limit):
    """(lines, path relative to root, first line, name) of every function longer than `limit` lines."""
    codes = {}
    for f in rust_files(root):
        with open(f, encoding="utf-8") as fh:
            codes[f] = blank_literals(fh.read())
    excluded = set()
    for f, code in codes.items():
        excluded.update(test_module_files(f, code))
    out = []
    for f, code in codes.items():
        if os.path.normpath(f) in excluded:
            continue
        for name, first, last in functions(code):
            if last - first + 1 > limit:
                out.append((last - first + 1, os.path.relpath(f, root), first, name))
    return sorted(out, key=lambda t: (-t[0], t[1], t[2]))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--limit", type=int, default=120, help="the longest a function may be, in lines (120)")
    ap.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    args = ap.parse_args()
    found = long_functions(args.root, args.limit)
    for lines, path, first, name in found:
        print(f"{path}:{first}: fn {name} is {lines} lines")
    if found:
        print(f"{len(found)} function(s) over {args.limit} lines", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
