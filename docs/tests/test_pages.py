"""The user guide's commands run as written (docs/tests/pages.py)."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

import pages

BIN = os.environ.get("RIBBAR_BIN_DIR")
# Pages that name a program they need (`<!-- requires: … -->`) run in the
# on-demand suite (scripts/test-long.sh sets RIBBAR_LONG_PAGES=1), the
# others in CI.
LONG = os.environ.get("RIBBAR_LONG_PAGES") == "1"


def page_id(page: Path) -> str:
    return str(page.relative_to(pages.BOOK))


# The suite's pages: without requirements in CI, with them in the long run.
SUITE = [p for p in pages.pages_with_commands() if bool(pages.requirements(p)) == LONG]


@pytest.fixture(scope="session")
def root(tmp_path_factory) -> Path:
    """One scratch root for all pages: they share its ribbar-work."""
    return tmp_path_factory.mktemp("pages")


@pytest.mark.parametrize("page", SUITE, ids=page_id)
def test_page_commands_run_as_written(page: Path, root: Path) -> None:
    """Every command of the page exits as the page says and prints what it shows."""
    missing = [n for n in pages.requirements(page) if shutil.which(n) is None]
    assert not missing, f"{page_id(page)} needs {missing} on PATH"
    failures = pages.run_page(page, root, pages.environment(Path(BIN) if BIN else None))
    assert not failures, "\n\n".join(failures)


def test_the_runner_sees_commands_and_outputs(tmp_path: Path) -> None:
    """The runner reads commands, continuations, exit statuses and output patterns."""
    page = tmp_path / "p.md"
    page.write_text(
        "text\n```console\n$ echo a \\\n  b\na b\n$ false\n? 1\n```\n```sh\n$ not run\n```\n"
        "```python,norun\nimport not_run\n```\n```python\nx = 1\n```\n"
    )
    found = pages.commands(page)
    assert [c.text for c in found] == ["echo a \\\n  b", "false", "x = 1\n"]
    assert found[0].expected == ["a b"] and found[1].status == 1
    assert pages.mismatch(["x [..] z", "..."], ["x y z", "more", "lines"]) is None
    assert pages.mismatch(["x"], ["x", "more"]) is not None
    assert pages.mismatch(["a", "...", "c"], ["a", "b", "b", "c"]) is None
