#!/usr/bin/env python3
"""Structure rules of the library crates (docs/architecture.md), checked in CI:

* no function longer than 120 lines (signature to closing brace);
* no source file importing another that imports it back (`use crate::…`,
  `use super::…`, paths written in code; doc comments and test modules are
  not imports);
* no `#[allow(clippy::too_many_arguments)]`.

Prints every violation and exits 1 if there is one.
"""

import pathlib
import re
import sys

MAX_FUNCTION_LINES = 120
CRATES = ["geom", "mesh", "solve", "pipeline"]
FN = re.compile(r"\s*(pub(\([^)]*\))?\s+)?(const\s+)?(async\s+)?(unsafe\s+)?fn\s+(\w+)")
PATH = re.compile(r"\b(crate|super)((?:::\w+)+)")


def code_only(line):
    """The line without string/char literals and its `//` comment."""
    line = re.sub(r'"(\\.|[^"\\])*"', '""', line)
    line = re.sub(r"'(\\.|[^'\\])'", "''", line)
    return line.split("//")[0]


def long_functions(path):
    lines = path.read_text().split("\n")
    out = []
    i = 0
    while i < len(lines):
        m = FN.match(lines[i])
        if not m or lines[i].lstrip().startswith("//"):
            i += 1
            continue
        depth, opened, j = 0, False, i
        while j < len(lines):
            s = code_only(lines[j])
            for ch in s:
                if ch == "{":
                    depth, opened = depth + 1, True
                elif ch == "}":
                    depth -= 1
            if opened and depth == 0:
                break
            if not opened and s.rstrip().endswith(";"):
                break
            j += 1
        n = j - i + 1
        if opened and n > MAX_FUNCTION_LINES:
            out.append(f"{path}:{i + 1}: fn {m.group(6)} is {n} lines (> {MAX_FUNCTION_LINES})")
        i += 1
    return out


def module_of(src, path):
    parts = list(path.relative_to(src).with_suffix("").parts)
    if parts[-1] in ("mod", "lib", "main"):
        parts = parts[:-1]
    return tuple(parts)


def import_cycles(src):
    files = {module_of(src, p): p for p in src.rglob("*.rs")}

    def resolve(segments):
        for k in range(len(segments), 0, -1):
            if tuple(segments[:k]) in files:
                return tuple(segments[:k])
        return None

    edges = {}
    for mod, path in files.items():
        text = path.read_text()
        text = re.sub(r"^\s*//.*$", "", text, flags=re.M)
        text = re.sub(r"#\[cfg\(test\)\]\s*mod tests\s*\{.*", "", text, flags=re.S)
        deps = set()
        # `super` of a file module is its parent; of a `mod.rs`, the folder's parent.
        parent = list(mod[:-1])
        for m in PATH.finditer(text):
            segments = m.group(2).strip(":").split("::")
            base = [] if m.group(1) == "crate" else parent
            target = resolve(base + segments)
            if target is not None and target != mod and target != mod[: len(target)]:
                deps.add(target)
        edges[mod] = deps
    out = []
    for a, deps in edges.items():
        for b in deps:
            if a < b and a in edges.get(b, ()):
                name = lambda m: "/".join(m) or "lib"
                out.append(f"{src}: {name(a)} and {name(b)} import each other")
    return out


def main():
    root = pathlib.Path(__file__).resolve().parent.parent
    problems = []
    for crate in CRATES:
        src = root / crate / "src"
        for path in sorted(src.rglob("*.rs")):
            problems += long_functions(path)
            if "too_many_arguments" in path.read_text():
                problems.append(f"{path}: allows clippy::too_many_arguments")
        problems += import_cycles(src)
    for p in problems:
        print(p)
    if problems:
        sys.exit(1)
    print(f"structure: {len(CRATES)} crates, no long function, no import cycle")


if __name__ == "__main__":
    main()
