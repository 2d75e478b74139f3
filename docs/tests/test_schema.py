"""`ribbar schema scene|study` validate every shipped file with a standard
JSON Schema validator, and refuse what ribbar refuses."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import jsonschema
import pytest
import yaml

REPO = Path(__file__).resolve().parents[2]
SCHEMA_LINE = "# yaml-language-server: $schema="
# The ribbar under test: RIBBAR_BIN_DIR's (scripts/test.sh: the installed
# package's), else the one on PATH.
RIBBAR = str(Path(os.environ["RIBBAR_BIN_DIR"]) / "ribbar") if os.environ.get("RIBBAR_BIN_DIR") else "ribbar"


def shipped_files() -> list[Path]:
    """The shipped scenes and studies (material-point tests are neither)."""
    found = []
    for folder in ["specs", "specs/studies", "tests/data", "examples"]:
        found += sorted((REPO / folder).glob("*.yaml"))
    return found


def is_study(path: Path) -> bool:
    return "base" in (yaml.safe_load(path.read_text()) or {})


def schema(kind: str) -> dict:
    done = subprocess.run([RIBBAR, "schema", kind], capture_output=True, text=True, check=True)
    return json.loads(done.stdout)


@pytest.fixture(scope="module")
def validators() -> dict[str, jsonschema.protocols.Validator]:
    out = {}
    for kind in ["scene", "study"]:
        s = schema(kind)
        jsonschema.Draft202012Validator.check_schema(s)
        out[kind] = jsonschema.Draft202012Validator(s)
    return out


def test_there_are_scenes_and_studies() -> None:
    """The files checked below are the shipped ones, scenes and studies both."""
    files = shipped_files()
    assert sum(is_study(f) for f in files) >= 5 and sum(not is_study(f) for f in files) >= 5


@pytest.mark.parametrize("path", shipped_files(), ids=lambda p: str(p.relative_to(REPO)))
def test_shipped_file_validates(path: Path, validators) -> None:
    """A shipped scene or study is valid against the schema ribbar prints."""
    kind = "study" if is_study(path) else "scene"
    errors = [e.message for e in validators[kind].iter_errors(yaml.safe_load(path.read_text()))]
    assert not errors, f"{path}: {errors}"


@pytest.mark.parametrize("path", shipped_files(), ids=lambda p: str(p.relative_to(REPO)))
def test_shipped_file_names_its_schema(path: Path) -> None:
    """A shipped file's first line points editors to the committed schema of its kind."""
    first = path.read_text().splitlines()[0]
    assert first.startswith(SCHEMA_LINE), f"{path}: {first}"
    target = (path.parent / first[len(SCHEMA_LINE):]).resolve()
    kind = "study" if is_study(path) else "scene"
    assert target == REPO / "docs" / "src" / "reference" / f"{kind}.schema.json", target
    assert json.loads(target.read_text()) == schema(kind)


BASE = {"name": "s", "bar": {"kind": "smooth", "diameter": "8 mm"}}


@pytest.mark.parametrize(
    "change, key",
    [
        ({"mesh": {"h_interfac": "1 mm"}}, "h_interfac"),
        ({"bar": {"kind": "smooth", "diameter": ["8 mm"]}}, "diameter"),
        ({"materials": {"interface": {"mu": [0.3, 0.1]}}}, "mu"),
        ({"specimen": {"symmetry": "eighth"}}, "symmetry"),
        ({"loading": {"u_finale": "1 mm"}}, "u_finale"),
    ],
)
def test_wrong_scene_is_refused(change: dict, key: str, validators, tmp_path: Path) -> None:
    """An unknown key, a list where a quantity belongs or an unknown choice is
    refused by the schema, and by ribbar naming the key."""
    scene = {**BASE, **change}
    errors = list(validators["scene"].iter_errors(scene))
    assert errors, scene
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(scene))
    done = subprocess.run([RIBBAR, "geometry", str(path), "--work", str(tmp_path / "w")],
                          capture_output=True, text=True)
    assert done.returncode == 1 and key in done.stderr, done.stderr


def test_right_scene_passes(validators) -> None:
    """The check above can pass: quantities as numbers or with units, choices by name."""
    scene = {**BASE, "mesh": {"h_interface": 0.001, "optimize": "netgen"},
             "materials": {"interface": {"law": "fczm", "mu": "0.3"}}}
    assert not list(validators["scene"].iter_errors(scene))
