#!/usr/bin/env python3
"""Prints the `use crate::…` / `super::…` edges between each crate's source files and fails
(exit 1) when the files of a crate form a cycle: a stage's files must form a line, not a circle.

Usage: scripts/module_cycles.py [--edges] [CRATE_SRC_DIR ...]
  (default: every `src/` under crates/ and dev/)

How a reference is read: `crate::a::b::Item`, `super::b::Item` or `self::b::Item`, in a `use`
statement (braces expanded) or inline in code, is resolved to the deepest file module it names;
when the next segment is an item that the module only re-exports (`pub use child::Item`), the
edge goes to the file that defines it. A module's re-exports themselves (`pub use`) are its
public face, not a dependency, and a `mod` declaration is ownership, not a use. A file using
its own ancestors (`super::Item` written in the parent) is a part using its whole, the one
direction Rust's modules always allow; every other edge counts. A `#[cfg(test)]`
file (`tests.rs`, `tests/…`) is left out: tests may use everything.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

COMMENT_LINE = re.compile(r"//[^\n]*")
COMMENT_BLOCK = re.compile(r"/\*.*?\*/", re.S)
STRING = re.compile(r'"(?:\\.|[^"\\])*"')
CHAR = re.compile(r"'(?:\\.|[^'\\])'")
USE_STMT = re.compile(r"\b(pub(?:\([^)]*\))?\s+)?use\s+([^;]+);")
INLINE_PATH = re.compile(r"\b(crate|super|self)((?:\s*::\s*(?:[A-Za-z_][A-Za-z0-9_]*|super))+)")


def strip(text: str) -> str:
    text = COMMENT_BLOCK.sub(" ", text)
    text = COMMENT_LINE.sub(" ", text)
    text = STRING.sub('""', text)
    return CHAR.sub("' '", text)


def expand(tree: str) -> list[str]:
    """`a::{b, c::{d, e}}` -> [`a::b`, `a::c::d`, `a::c::e`] (aliases dropped)."""
    tree = re.sub(r"\s+", "", tree)
    start = tree.find("{")
    if start < 0:
        return [tree]
    prefix = tree[:start]
    depth, parts, cur = 0, [], ""
    for ch in tree[start + 1 : tree.rfind("}")]:
        if ch == "{":
            depth += 1
        elif ch == "}":
            depth -= 1
        if ch == "," and depth == 0:
            parts.append(cur)
            cur = ""
        else:
            cur += ch
    parts.append(cur)
    out = []
    for p in parts:
        if p:
            out.extend(prefix + q for q in expand(p))
    return out


class Crate:
    def __init__(self, src: Path):
        self.src = src
        self.files: dict[tuple[str, ...], Path] = {}
        for f in sorted(src.rglob("*.rs")):
            rel = f.relative_to(src).with_suffix("")
            parts = list(rel.parts)
            if parts[-1] in ("mod", "lib", "main"):
                parts = parts[:-1]
            if parts and parts[-1] == "tests" or "tests" in parts[:-1]:
                continue
            if parts and parts[0] == "bin":
                continue
            self.files[tuple(parts)] = f
        self.texts = {m: strip(p.read_text()) for m, p in self.files.items()}
        self.reexports = {m: self._reexports(t) for m, t in self.texts.items()}

    def _uses(self, text: str, public_only: bool | None):
        for m in USE_STMT.finditer(text):
            is_pub = bool(m.group(1))
            if public_only is True and not is_pub:
                continue
            if public_only is False and is_pub:
                continue
            body = re.sub(r"\s+as\s+\w+", "", m.group(2))
            for path in expand(body):
                yield path

    def _reexports(self, text: str) -> dict[str, str]:
        names = {}
        for path in self._uses(text, None):
            name = path.rsplit("::", 1)[-1]
            if name not in ("*", "self"):
                names[name] = path
        return names

    def resolve(self, here: tuple[str, ...], path: str, depth: int = 0):
        segs = [s for s in path.replace(" ", "").split("::") if s]
        if not segs or depth > 8:
            return None
        head = segs[0]
        if head == "crate":
            mod: tuple[str, ...] = ()
        elif head == "super":
            mod = here[:-1]
        elif head == "self":
            mod = here
        else:
            # a path relative to `here` (a child module, as in `use child::Item`)
            if here + (head,) in self.files:
                mod = here
                segs = ["self"] + segs
            else:
                return None
        rest = segs[1:]
        while rest and rest[0] == "super":
            mod = mod[:-1]
            rest = rest[1:]
        while rest and mod + (rest[0],) in self.files:
            mod = mod + (rest[0],)
            rest = rest[1:]
        if rest and mod in self.reexports and rest[0] in self.reexports[mod]:
            target = self.reexports[mod][rest[0]]
            if target.split("::", 1)[0] not in ("crate", "super", "self") and mod + (
                target.split("::", 1)[0],
            ) not in self.files:
                return mod  # re-exported from another crate: defined "here" for our purpose
            got = self.resolve(mod, target, depth + 1)
            return got if got is not None else mod
        return mod

    def edges(self):
        out = set()
        for here, text in self.texts.items():
            refs = list(self._uses(text, False))
            # public re-exports are the module's face; inline paths are real uses
            no_uses = USE_STMT.sub(" ", text)
            refs += [m.group(1) + re.sub(r"\s+", "", m.group(2)) for m in INLINE_PATH.finditer(no_uses)]
            for ref in refs:
                target = self.resolve(here, ref)
                if target is None or target == here or target not in self.files:
                    continue
                if here[: len(target)] == target:
                    continue  # a file's own ancestors: the module it belongs to
                out.add((here, target))
        return out


def cycles(nodes, edges):
    graph = {n: [] for n in nodes}
    for a, b in edges:
        graph[a].append(b)
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]
    sys.setrecursionlimit(10000)

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for n in nodes:
        if n not in index:
            visit(n)
    return out


def name(crate: Crate, mod) -> str:
    return str(crate.files[mod].relative_to(ROOT))


def main(argv):
    show_edges = "--edges" in argv
    dirs = [Path(a) for a in argv if not a.startswith("--")]
    if not dirs:
        dirs = sorted(p for p in ROOT.glob("crates/*/src")) + sorted(ROOT.glob("dev/*/src"))
    failed = False
    for src in dirs:
        crate = Crate(src.resolve())
        edges = crate.edges()
        if show_edges:
            for a, b in sorted(edges):
                print(f"{name(crate, a)} -> {name(crate, b)}")
        for comp in cycles(list(crate.files), edges):
            failed = True
            inner = [(a, b) for a, b in sorted(edges) if a in comp and b in comp]
            print(f"cycle among {len(comp)} files of {src.relative_to(ROOT) if src.is_relative_to(ROOT) else src}:")
            for a, b in inner:
                print(f"  {name(crate, a)} -> {name(crate, b)}")
    if failed:
        print("module_cycles: the files above use each other in a circle; move what they share "
              "into a file of its own below them", file=sys.stderr)
        return 1
    print("module_cycles: no cycle among any crate's files")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
