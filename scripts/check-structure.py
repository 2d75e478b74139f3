#!/usr/bin/env python3
"""Structure rules of the library crates (docs/architecture.md), checked in CI:

* no function longer than 120 lines (signature to closing brace);
* no source file importing another that imports it back (`use crate::…`,
  `use super::…`, paths written in code; doc comments and test modules are
  not imports);
* no `#[allow(clippy::too_many_arguments)]`, and no parameters packed into
  tuples to stay under clippy's argument count (in the solver's driver,
  `solve/src/nonlinear/`, no tuple parameters at all);
* in `solve/src/nonlinear/`, no file over 600 lines, and the driver's loop
  (`driver/mod.rs`) within 200.

Prints every violation and exits 1 if there is one.
"""

import pathlib
import re
import sys

MAX_FUNCTION_LINES = 120
DRIVER = "solve/src/nonlinear"
MAX_DRIVER_FILE_LINES = 600
MAX_LOOP_FILE_LINES = 200
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


GROUP = re.compile(r"\b(crate|super)((?:::\w+)*)::\{")


def paths(text):
    """Every `crate::…`/`super::…` path of `text` as (head, segments),
    the members of a `{…}` group each as a path of its own."""
    for m in PATH.finditer(text):
        yield m.group(1), m.group(2).strip(":").split("::")
    for m in GROUP.finditer(text):
        prefix = [s for s in m.group(2).split("::") if s]
        depth, i = 1, m.end()
        while depth and i < len(text):
            depth += {"{": 1, "}": -1}.get(text[i], 0)
            i += 1
        for member in split_top_level(text[m.end() : i - 1]):
            names = re.findall(r"\w+", member.split("{")[0])
            if names and names[0] not in ("self",):
                yield m.group(1), prefix + names[:1]
            elif names:
                yield m.group(1), prefix


def import_cycles(src):
    """Pairs of modules that reference each other: through `crate::` and
    `super::` paths, a parent through its children's names (`child::…`),
    and a child through `super::Item` of its parent. A child that reads its
    parent's items while the parent calls into the child is a cycle too."""
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
        for head, segments in paths(text):
            base = [] if head == "crate" else list(parent)
            while head == "super" and segments and segments[0] == "super":
                base, segments = base[:-1], segments[1:]
            target = resolve(base + segments)
            if target is not None and target != mod:
                deps.add(target)
        children = {c[-1] for c in files if len(c) == len(mod) + 1 and c[: len(mod)] == mod}
        for child in children:
            if re.search(r"(?<![\w:])(self::)?" + child + r"::", text):
                deps.add(mod + (child,))
        edges[mod] = deps
    out = []
    for a, deps in edges.items():
        for b in deps:
            if a < b and a in edges.get(b, ()):
                name = lambda m: "/".join(m) or "lib"
                out.append(f"{src}: {name(a)} and {name(b)} import each other")
    return out


FN_SIGNATURE = re.compile(r"\bfn\s+(\w+)")
MAX_ARGUMENTS = 7  # clippy's too_many_arguments


def split_top_level(text):
    """`text` split at the commas outside brackets."""
    parts, depth, current = [], 0, ""
    for ch in text:
        if ch in "([<{":
            depth += 1
        elif ch in ")]>}":
            depth -= 1
        if ch == "," and depth == 0:
            parts.append(current)
            current = ""
        else:
            current += ch
    if current.strip():
        parts.append(current)
    return [p.strip() for p in parts]


def parameters(text, start):
    """The parameter list of the function whose `fn` is at `start`."""
    i = text.index("(", start)
    depth, j = 0, i
    while True:
        if text[j] in "([{":
            depth += 1
        elif text[j] in ")]}":
            depth -= 1
            if depth == 0:
                return text[i + 1 : j]
        j += 1


def tuple_count(parameter):
    """How many values a parameter packs into a tuple (1 for a plain one)."""
    if ":" not in parameter:
        return 1
    pattern, kind = (x.strip() for x in parameter.split(":", 1))
    packed = kind if kind.startswith("(") else pattern if pattern.startswith("(") else None
    if packed is None or packed == "()":
        return 1
    return len(split_top_level(packed[1:-1]))


def tuple_parameters(path, strict):
    """Functions that pack parameters into tuples: anywhere when the
    unpacked count passes clippy's limit (a dodge of too_many_arguments),
    and in `strict` files at all."""
    text = re.sub(r"//[^\n]*", "", path.read_text())
    text = re.sub(r"#\[cfg\(test\)\]\s*mod tests\s*\{.*", "", text, flags=re.S)
    out = []
    for m in FN_SIGNATURE.finditer(text):
        try:
            params = split_top_level(parameters(text, m.end()))
        except (ValueError, IndexError):
            continue
        counts = [tuple_count(p) for p in params]
        packed = [p for p, c in zip(params, counts) if c > 1]
        if packed and (strict or sum(counts) > MAX_ARGUMENTS):
            line = text[: m.start()].count("\n") + 1
            out.append(f"{path}:{line}: fn {m.group(1)} packs parameters into a tuple: {packed[0]}")
    return out


def main():
    root = pathlib.Path(__file__).resolve().parent.parent
    problems = []
    for crate in CRATES:
        src = root / crate / "src"
        for path in sorted(src.rglob("*.rs")):
            problems += long_functions(path)
            in_driver = DRIVER in path.as_posix()
            problems += tuple_parameters(path, strict=in_driver)
            if in_driver:
                lines = path.read_text().count("\n")
                limit = MAX_LOOP_FILE_LINES if path.as_posix().endswith("driver/mod.rs") else MAX_DRIVER_FILE_LINES
                if lines > limit:
                    problems.append(f"{path}: {lines} lines (> {limit})")
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
