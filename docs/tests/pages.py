"""The runner of the user guide's commands.

Every ```console block of a page is run, in the order of the page, in one
scratch directory per page that holds copies of the repository's specs/,
examples/ and tests/data/ (so a page may edit them) and the scripts/ folder.
In a block, a line starting with `$ ` is a command (bash; a line ending in
`\\` continues it); the lines after it, up to the next command, are its
expected output, stdout and stderr together:

- each expected line must match an output line, in order; `[..]` in a line
  matches any text, and a line `...` any number of lines;
- without `...` at the end the output must end where the expected lines do;
- a command must exit 0, unless its expected output starts with `? N`, the
  exit status it must end with.

A ```python block runs with `python3`, preceded by the page's earlier Python
blocks, and must exit 0. A ```python,norun block is shown and not run: it
reads the results of commands the page shows in plain blocks because they
take minutes (a study's runs); python/tests runs the same calls on a small
study.

A page that needs a program the test machine may lack names it in a
comment `<!-- requires: pvpython -->`.
"""

from __future__ import annotations

import functools
import os
import re
import shutil
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
BOOK = REPO / "docs" / "src"


@dataclass
class Command:
    line: int
    text: str
    expected: list[str] = field(default_factory=list)
    status: int = 0
    # A ```python block: run with python3, after the page's earlier blocks.
    python: bool = False


def commands(page: Path) -> list[Command]:
    """The commands of the page's console blocks with their expected output,
    and its Python blocks, in page order."""
    out: list[Command] = []
    in_block = None
    pending: str | None = None
    for number, line in enumerate(page.read_text().splitlines(), 1):
        stripped = line.strip()
        if in_block is None:
            if stripped in ("```console", "```python"):
                in_block = stripped[3:]
                if in_block == "python":
                    out.append(Command(number, "", python=True))
            continue
        if stripped.startswith("```"):
            in_block = None
            continue
        if in_block == "python":
            out[-1].text += line + "\n"
            continue
        if pending is not None:
            pending += "\n" + line
            if not line.endswith("\\"):
                out[-1].text, pending = pending, None
            continue
        if line.startswith("$ "):
            out.append(Command(number, line[2:]))
            if line.endswith("\\"):
                pending = line[2:]
        elif out:
            if not out[-1].expected and re.fullmatch(r"\? \d+", stripped):
                out[-1].status = int(stripped[2:])
            else:
                out[-1].expected.append(line)
    return out


def requirements(page: Path) -> list[str]:
    return re.findall(r"<!-- requires: ([\w.-]+) -->", page.read_text())


def pages_with_commands() -> list[Path]:
    """The pages with commands, in the order of the book's table of
    contents: a reader's order, which the shared work directory follows."""
    listed = re.findall(r"\]\(([^)]+\.md)\)", (BOOK / "SUMMARY.md").read_text())
    order = {BOOK / p: i for i, p in enumerate(listed)}
    # A page whose blocks are marked `<!-- test-slurm: … -->` needs a Slurm
    # cluster: scripts/test-slurm.sh starts one and runs those blocks itself.
    found = [
        p for p in BOOK.rglob("*.md") if commands(p) and "<!-- test-slurm:" not in p.read_text()
    ]
    return sorted(found, key=lambda p: (order.get(p, len(order)), str(p)))


def line_matches(pattern: str, line: str) -> bool:
    parts = [re.escape(p) for p in pattern.rstrip().split("[..]")]
    return re.fullmatch(".*".join(parts), line.rstrip()) is not None


def mismatch(expected: list[str], output: list[str]) -> str | None:
    """None when `output` matches `expected`, else what did not match."""

    @functools.lru_cache(maxsize=None)
    def match(e: int, o: int) -> bool:
        if e == len(expected):
            return o == len(output)
        if expected[e].strip() == "...":
            return any(match(e + 1, k) for k in range(o, len(output) + 1))
        return o < len(output) and line_matches(expected[e], output[o]) and match(e + 1, o + 1)

    if match(0, 0):
        return None
    return "expected:\n" + "\n".join(expected) + "\n\ngot:\n" + "\n".join(output)


def scratch(page: Path, root: Path) -> Path:
    """A working directory for `page` with the files its commands read. The
    pages share one `ribbar-work`, as a reader's do who follows them in
    turn: a scene an earlier page ran is up to date on a later one."""
    work = root / page.relative_to(BOOK).with_suffix("").as_posix().replace("/", "-")
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    for name in ["specs", "examples"]:
        shutil.copytree(REPO / name, work / name, ignore=shutil.ignore_patterns("ribbar-work"))
    shutil.copytree(REPO / "tests" / "data", work / "tests" / "data")
    (work / "scripts").symlink_to(REPO / "scripts")
    (root / "ribbar-work").mkdir(exist_ok=True)
    (work / "ribbar-work").symlink_to(root / "ribbar-work")
    return work


def run_page(page: Path, root: Path, env: dict[str, str]) -> list[str]:
    """Runs every command of `page`; returns one message per failure."""
    work = scratch(page, root)
    failures = []
    python = ""
    for command in commands(page):
        if command.python:
            python += command.text
            argv = ["python3", "-c", python]
        else:
            argv = ["bash", "-c", "set -o pipefail\n" + command.text]
        done = subprocess.run(
            argv,
            cwd=work,
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            timeout=900,
        )
        output = done.stdout.splitlines()
        where = f"{page.relative_to(REPO)}:{command.line}: $ {command.text}"
        if done.returncode != command.status:
            failures.append(
                f"{where}\nexit status {done.returncode}, expected {command.status}:\n"
                + "\n".join(output[-40:])
            )
            break
        problem = None if command.python else mismatch(command.expected, output)
        if problem:
            failures.append(f"{where}\n{problem}")
    return failures


def environment(bin_dir: Path | None) -> dict[str, str]:
    """The environment of the commands: `ribbar` (and the Python package's
    interpreter) first on PATH, no colours, no terminal."""
    env = dict(os.environ)
    path = [str(bin_dir)] if bin_dir else []
    env["PATH"] = os.pathsep.join(path + [env.get("PATH", "")])
    env.pop("GMSH", None)
    env["NO_COLOR"] = "1"
    return env
