"""The Python API end to end on the installed package, with the gmsh that
the package's dependency installed (GMSH unset): a tiny scene through every
stage, compared with the bundled command line on the same spec."""

import io
import json
import math
import os
import signal
import subprocess
import sys
import textwrap
from contextlib import redirect_stderr
from pathlib import Path

import meshio
import numpy as np
import pandas as pd
import pytest

import ribbar
from ribbar._environment import prepare_environment

REPO = Path(__file__).resolve().parents[2]
TINY = REPO / "tests" / "data" / "tiny-smooth.yaml"
TINY_STUDY = REPO / "tests" / "data" / "tiny-friction.yaml"
FCZM_TENSION = REPO / "specs" / "material" / "fczm-tension.yaml"


@pytest.fixture(autouse=True)
def no_gmsh_env(monkeypatch):
    # ribbar must find the PyPI gmsh by itself.
    monkeypatch.delenv("GMSH", raising=False)
    monkeypatch.delenv("RIBBAR_EXE", raising=False)


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    os.environ.pop("GMSH", None)
    work = tmp_path_factory.mktemp("api")
    return ribbar.run(TINY, work=work, progress=False)


def test_gmsh_is_the_package_dependency():
    # The installed package is under test, not the source tree.
    assert Path(sys.prefix) in Path(ribbar.__file__).parents, ribbar.__file__
    env = prepare_environment({})
    gmsh = Path(env["GMSH"])
    assert gmsh.is_file()
    assert Path(sys.prefix) in gmsh.parents, gmsh
    assert Path(sys.prefix) in Path(env["RIBBAR_EXE"]).parents, env["RIBBAR_EXE"]


def test_curve_is_a_dataframe_in_si_units(tiny):
    curve = tiny.curve
    assert isinstance(curve, pd.DataFrame)
    assert list(curve.columns)[:6] == ["step", "u_imposed", "force", "fed", "bond_stress", "iterations"]
    units = curve.attrs["units"]
    assert units["u_imposed"] == "m" and units["fed"] == "m"
    assert units["force"] == "N" and units["bond_stress"] == "Pa"
    assert set(units) == set(curve.columns)
    # SI: the tiny scene pulls 0.3 mm and carries a few MPa of bond stress.
    assert curve["u_imposed"].iloc[-1] == pytest.approx(0.3e-3)
    assert 1e6 < curve["bond_stress"].max() < 2e7
    # sigma_mb = F / (pi d l_b), d = 8 mm, l_b = 12 mm.
    expected = curve["force"] / (math.pi * 8e-3 * 12e-3)
    np.testing.assert_allclose(curve["bond_stress"], expected, rtol=1e-9)
    assert tiny.status.completed and tiny.status.ending["kind"] == "completed"
    assert tiny.status.stopped is None


def test_summary_equals_the_command_lines(tiny, tmp_path):
    work = tmp_path / "cli"
    done = subprocess.run(
        [sys.executable, "-m", "ribbar", "run", str(TINY), "--work", str(work), "-q"],
        env=prepare_environment(dict(os.environ)),
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    cli = json.loads((work / "tiny-smooth" / "summary.json").read_text())
    api = tiny.summary
    assert api["curve"] == cli["curve"]
    for key in ("steps", "total_iterations", "dofs", "krylov_iterations", "peak_bond_stress"):
        assert api["solver"]["summary"][key] == cli["solver"]["summary"][key], key
    assert api["curve"]["peak_bond_stress"] == tiny.curve["bond_stress"].max()


def test_fields_read_with_meshio(tiny):
    assert {"peak", "end", 2} <= set(tiny.fields)
    end = tiny.field("end")
    assert isinstance(end, meshio.Mesh)
    displacement = end.point_data["displacement"]
    assert displacement.shape == (len(end.points), 3)
    # The bar is pulled along z by the imposed displacement at its loaded end.
    assert np.abs(displacement[:, 2]).max() == pytest.approx(0.3e-3, rel=1e-6)
    damage = np.concatenate(end.cell_data["D"])
    assert damage.min() >= 0.0 and damage.max() <= 1.0
    interface = tiny.field("peak", part="interface")
    assert len(interface.cells) > 0
    with pytest.raises(KeyError, match="no fields at step 7"):
        tiny.field(7)
    pvd = tiny.collection.read_text()
    for files in tiny.fields.values():
        assert files.bulk.name in pvd


def test_bad_spec_raises_with_the_clis_message(tmp_path):
    with pytest.raises(ribbar.RibbarError, match=r"mesh\.h_interface: must be > 0"):
        ribbar.run(TINY, work=tmp_path, set={"mesh.h_interface": "-1 mm"}, progress=False)
    bad = tmp_path / "bad.yaml"
    bad.write_text(TINY.read_text().replace("law: mazars", "law: marzars"))
    with pytest.raises(ribbar.RibbarError) as caught:
        ribbar.run(bad, work=tmp_path, progress=False)
    assert "bad.yaml" in str(caught.value) and "marzars" in str(caught.value)
    with pytest.raises(ribbar.RibbarError, match="no such spec file"):
        ribbar.run(tmp_path / "missing.yaml", work=tmp_path, progress=False)
    # Nothing was written for the refused specs.
    assert not (tmp_path / "tiny-smooth").exists()


def test_cached_second_run_runs_nothing(tiny, capsys):
    before = (tiny.directory / "curve.csv").stat().st_mtime_ns
    again = ribbar.run(TINY, work=tiny.work, progress=True)
    printed = capsys.readouterr().err
    for stage in ("geometry", "mesh", "solve", "post"):
        assert f"{stage}: up to date" in printed, printed
    assert (tiny.directory / "curve.csv").stat().st_mtime_ns == before
    pd.testing.assert_frame_equal(again.curve, tiny.curve)


def test_spec_as_mapping_and_overrides(tmp_path):
    spec = {
        "name": "tiny-mapping",
        "bar": {"kind": "smooth", "diameter": "8 mm"},
        "specimen": {"cube_side": "24 mm", "adhesive_length": "12 mm", "free_overhang": "2 mm", "loaded_overhang": "4 mm"},
        "mesh": {"h_interface": "2 mm", "h_outer": "6 mm"},
        "materials": {
            "concrete": {"law": "mazars", "E": "25 GPa", "nu": 0.2, "ft": "2.5 MPa", "Gf": "120 N/m"},
            "steel": {"law": "j2"},
            "interface": {"law": "fczm", "ft": "1.8 MPa", "Gf": "85 N/m", "lambda0": "5e-5 m", "delta_s": 0.3, "mu": 0.3, "zeta": 8},
        },
        "loading": {"u_final": "0.1 mm", "initial_step": "5 um", "max_step": "20 um"},
    }
    result = ribbar.run(spec, work=tmp_path, set={"loading.u_final": 0.05e-3}, progress=False)
    assert result.scene == "tiny-mapping"
    assert result.curve["u_imposed"].iloc[-1] == pytest.approx(0.05e-3)
    reopened = ribbar.load(tmp_path, "tiny-mapping")
    pd.testing.assert_frame_equal(reopened.curve, result.curve)
    with pytest.raises(ribbar.RibbarError, match="no solved scene"):
        ribbar.load(tmp_path, "nothing-here")


def test_study_table_in_si_with_cases(tmp_path):
    study = ribbar.study(TINY_STUDY, work=tmp_path, progress=False)
    table = study.table
    assert list(table["case"]) == ["tiny-friction--0", "tiny-friction--1"]
    assert list(table["materials.interface.mu"]) == [0.3, 0.001]
    assert table.attrs["units"]["peak_bond_stress"] == "Pa"
    for name, result in study.cases.items():
        row = table.set_index("case").loc[name]
        assert row["peak_bond_stress"] == pytest.approx(result.summary["curve"]["peak_bond_stress"], rel=1e-12)
        assert row["final_fed"] == pytest.approx(result.curve["fed"].iloc[-1], rel=1e-12)
    with pytest.raises(ribbar.RibbarError):
        ribbar.study(TINY, work=tmp_path, progress=False)


def test_material_point_table():
    table = ribbar.material(FCZM_TENSION)
    assert table.attrs["units"]["tn"] == "Pa" and table.attrs["units"]["un"] == "m"
    # FCZM in pure tension: the normal traction peaks at f_t = 3 MPa.
    assert table["tn"].max() == pytest.approx(3e6, rel=1e-3)
    law = {"law": "tvergaard", "parameters": {"ft": "3 MPa", "Gf": "100 N/m", "lambda0": "2e-5 m", "delta_s": 1.0}}
    short = ribbar.material(law, path=[{"t": 0}, {"t": 1, "un": 1e-5}], increments=10)
    assert len(short) == 11
    assert short["tn"].iloc[-1] > 0
    with pytest.raises(ribbar.RibbarError):
        ribbar.material({"law": "no-such-law", "parameters": {}}, path=[{"t": 0}, {"t": 1, "un": 1e-5}])


def test_interrupt_and_resume(tmp_path):
    """Ctrl-C stops a run from Python; the same call resumes after the last
    checkpoint and ends with the curve of an uninterrupted run."""
    slow = tmp_path / "slow.yaml"
    slow.write_text(
        TINY.read_text()
        .replace("name: tiny-smooth", "name: tiny-slow")
        .replace("initial_step: 5 um, max_step: 20 um", "initial_step: 0.5 um, max_step: 0.5 um")
    )
    # A process started in the background by a non-interactive shell (a CI
    # runner's `cmd &`, nohup) inherits SIGINT ignored, and Python then
    # keeps it ignored: the child takes the handler an interactive session
    # has, so the Ctrl-C below reaches ribbar.run as KeyboardInterrupt.
    script = textwrap.dedent(
        f"""
        import signal
        signal.signal(signal.SIGINT, signal.default_int_handler)
        import ribbar
        ribbar.run({str(slow)!r}, work={str(tmp_path / 'w')!r}, progress=True)
        """
    )
    child = subprocess.Popen(
        [sys.executable, "-c", script],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    seen = []
    for line in child.stdout:
        seen.append(line)
        if "solve: step   50" in line:
            child.send_signal(signal.SIGINT)
            break
    rest = child.stdout.read()
    code = child.wait(timeout=60)
    assert code != 0, "".join(seen) + rest
    assert "KeyboardInterrupt" in rest and "resume" in rest, rest
    buffer = io.StringIO()
    with redirect_stderr(buffer):
        resumed = ribbar.run(slow, work=tmp_path / "w", progress=True)
    assert "solve: resuming after step" in buffer.getvalue(), buffer.getvalue()
    straight = ribbar.run(slow, work=tmp_path / "straight", progress=False)
    pd.testing.assert_frame_equal(resumed.curve, straight.curve, check_exact=True)
