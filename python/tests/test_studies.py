"""Sampled and sensitivity studies from Python on the installed package:
the example notebook examples/rib-sensitivity.ipynb executed end to end on
its small Morris study, then the DataFrames `ribbar.study` returns for it
(the study again, every stage cached)."""

import json
import math
import shutil
from pathlib import Path

import nbclient
import nbformat
import numpy as np
import pytest

import ribbar

REPO = Path(__file__).resolve().parents[2]
EXAMPLES = REPO / "examples"
NOTEBOOK = "rib-sensitivity.ipynb"
STUDY = "example-rib-sensitivity"


@pytest.fixture(autouse=True)
def no_gmsh_env(monkeypatch):
    monkeypatch.delenv("GMSH", raising=False)
    monkeypatch.delenv("RIBBAR_EXE", raising=False)


@pytest.fixture(scope="module")
def executed(tmp_path_factory):
    """The notebook run in a copy of examples/ (its work directory there)."""
    folder = tmp_path_factory.mktemp("notebook")
    for name in (NOTEBOOK, "small-ribbed.yaml"):
        shutil.copy(EXAMPLES / name, folder / name)
    notebook = nbformat.read(folder / NOTEBOOK, as_version=4)
    client = nbclient.NotebookClient(
        notebook, timeout=1800, kernel_name="python3", resources={"metadata": {"path": str(folder)}}
    )
    client.execute()
    return folder, notebook


@pytest.fixture(scope="module")
def study(executed):
    folder, _ = executed
    spec = folder / "ribbar-work" / ".specs" / f"{STUDY}.yaml"
    return ribbar.study(spec, work=folder / "ribbar-work", jobs=2, progress=False)


def test_the_sensitivity_notebook_runs_end_to_end(executed):
    """Every cell of the example runs without an error and shows its study's
    cases, indices and plots."""
    _, notebook = executed
    outputs = [o for c in notebook.cells if c.cell_type == "code" for o in c.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    text = "".join(o.get("text", "") for o in outputs)
    assert "12 cases" in text, text
    images = [o for o in outputs if "image/png" in o.get("data", {})]
    assert len(images) == 3, len(images)


def test_a_sensitivity_study_returns_its_indices_designs_and_bond_laws(study):
    """`ribbar.study` gives the Morris indices of every parameter and named
    response, the design in SI, the responses and every case's bond laws as
    DataFrames, consistent with the cases' own files."""
    assert study.kind == "sensitivity" and len(study.cases) == 12
    keys = ["bar.ribs.height", "bar.ribs.angle", "bar.ribs.spacing"]
    indices = study.sensitivity
    assert list(indices.columns) == ["parameter", "response", "mu_star", "sigma", "mu", "mu_star_conf", "effects"]
    first = indices[indices.response == "first_peak_bond_stress"]
    assert sorted(first.parameter) == sorted(keys)
    assert (first.mu_star >= first.mu.abs() - 1e-9).all()
    # Three trajectories: three elementary effects per parameter.
    assert (first.effects == 3).all()

    designs = study.designs
    assert len(designs) == 12 and list(designs.case) == [f"{STUDY}--{i}" for i in range(12)]
    for key in keys:
        assert designs[f"u_{key}"].between(0, 1).all()
    # The range as ribbar reads "0.35 mm" and "0.65 mm": the number times
    # the unit's factor, as Python computes it too.
    assert designs["bar.ribs.height"].between(0.35 * 1e-3, 0.65 * 1e-3).all()
    assert designs["bar.ribs.angle"].between(math.radians(45) - 1e-12, math.radians(90) + 1e-12).all()
    assert study.rejected is not None and len(study.rejected) == 0

    table = study.table.set_index("case")
    assert table.attrs["units"]["bar.ribs.height"] == "m"
    assert table.attrs["units"]["bar.ribs.angle"] == "rad"
    np.testing.assert_allclose(table.loc[designs.case, "bar.ribs.height"], designs["bar.ribs.height"], rtol=1e-12)

    responses = study.responses.set_index("case")
    assert (responses.counted == "yes").all()
    assert responses.attrs["units"]["first_peak_bond_stress"] == "Pa"
    np.testing.assert_allclose(
        responses.first_peak_bond_stress, table.loc[responses.index, "first_peak_bond_stress"], rtol=1e-12
    )

    laws = study.bond_laws.set_index("case")
    assert (laws.mc2010_tau_max > 0).all() and laws.mc2010_fit_error.between(0, 1).all()
    expected_ratio = laws.mc2010_tau_max / (2.5e6 * np.sqrt(laws.fcm / 1e6))
    np.testing.assert_allclose(laws.tau_max_ratio, expected_ratio, rtol=1e-9)
    assert (laws.fcm_source == "derived_from_tensile_strength").all()


def test_a_runs_bond_law_reads_as_series_and_points(study):
    """A case's fitted MC2010 law is a Series of bond_law.json's values in
    SI, and its piecewise law the points that file lists, from the origin."""
    case = study.cases[f"{STUDY}--0"]
    report = json.loads((case.directory / "bond_law.json").read_text())
    law = case.bond_law
    for name in ("tau_max", "s1", "s2", "s3", "alpha", "tau_f", "fit_error"):
        assert law[name] == report["mc2010"][name]
    assert law.attrs["units"]["tau_max"] == "Pa"
    points = case.bond_law_points
    assert list(points.iloc[0]) == [0.0, 0.0]
    assert len(points) == report["piecewise_linear"]["count"] == 8
    assert points.attrs["fit_error"] == report["piecewise_linear"]["fit_error"]
    summary = case.summary
    assert summary["bond_law"]["mc2010"]["tau_max"] == law["tau_max"]
    assert summary["design_code"]["fcm_source"] == "derived_from_tensile_strength"
