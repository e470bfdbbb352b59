#!/usr/bin/env python3
"""Counts what the house rules limit in the product's Rust sources: files over 600 lines and
functions over 80 lines, tests left out (a `#[cfg(test)]` module, `tests.rs`, `tests/`).

Usage: scripts/house_count.py [--list] [--strict] [DIR ...]
  (default: every `src/` under crates/ and dev/)
  --list    name each file and function over its limit, longest first
  --strict  exit 1 when anything is over (for CI once the counts reach zero)

A file's length is its lines before its test module; a function's is from its `fn` line to
its closing brace (braces inside strings, characters and comments ignored).
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
FILE_LIMIT = 600
FN_LIMIT = 80
FN_START = re.compile(r"^\s*(?:pub(?:\([^)]*\))?\s+)?(?:const\s+)?(?:async\s+)?(?:unsafe\s+)?fn\s+(\w+)")
TEST_MOD = re.compile(r"^\s*#\[cfg\(test\)\]\s*$")


def blank_literals(line: str) -> str:
    """The line with strings, characters and comments blanked (braces in them do not count)."""
    line = re.sub(r'"(?:\\.|[^"\\])*"', '""', line)
    line = re.sub(r"'(?:\\.|[^'\\])'", "' '", line)
    return line.split("//", 1)[0]


def product_lines(path: Path) -> list[str]:
    """The file's lines before its test module."""
    lines = path.read_text().splitlines()
    for i, line in enumerate(lines):
        if TEST_MOD.match(line) and i + 1 < len(lines) and re.match(r"^\s*mod\s+\w+", lines[i + 1]):
            return lines[:i]
    return lines


def long_functions(path: Path, lines: list[str]) -> list[tuple[int, str, int]]:
    """(length, name, first line) of each function over the limit."""
    out = []
    i = 0
    while i < len(lines):
        m = FN_START.match(lines[i])
        if not m:
            i += 1
            continue
        depth, opened, j = 0, False, i
        while j < len(lines):
            code = blank_literals(lines[j])
            if not opened and ";" in code and "{" not in code:
                break  # a declaration without a body (trait method)
            depth += code.count("{") - code.count("}")
            opened = opened or "{" in code
            if opened and depth <= 0:
                break
            j += 1
        length = j - i + 1
        if opened and length > FN_LIMIT:
            out.append((length, f"{path.relative_to(ROOT)}:{i + 1} {m.group(1)}", i + 1))
        i += 1
    return out


def main() -> int:
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    listing, strict = "--list" in sys.argv, "--strict" in sys.argv
    dirs = [Path(a).resolve() for a in args] or sorted(
        p for base in ("crates", "dev") for p in (ROOT / base).glob("*/src")
    )
    files, functions = [], []
    for d in dirs:
        for path in sorted(d.rglob("*.rs")):
            rel = path.relative_to(d).parts
            if path.name == "tests.rs" or "tests" in rel[:-1]:
                continue
            lines = product_lines(path)
            if len(lines) > FILE_LIMIT:
                files.append((len(lines), str(path.relative_to(ROOT))))
            functions += long_functions(path, lines)
    print(f"files over {FILE_LIMIT} lines: {len(files)}; functions over {FN_LIMIT} lines: {len(functions)}")
    if listing:
        for n, name in sorted(files, reverse=True):
            print(f"  file {n:5} {name}")
        for n, name, _ in sorted(functions, reverse=True):
            print(f"  fn   {n:5} {name}")
    return 1 if strict and (files or functions) else 0


if __name__ == "__main__":
    sys.exit(main())
