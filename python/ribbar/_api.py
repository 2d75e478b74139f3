"""ribbar's Python API: runs the `ribbar` command line (the same stages and
cache) and reads what its stages write into pandas and meshio objects."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import tempfile
import time
import warnings
import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, Iterable, List, Mapping, Optional, Union

import pandas as pd

from ribbar import _native
from ribbar._environment import prepare_environment

PathLike = Union[str, "os.PathLike[str]"]
Spec = Union[PathLike, Mapping[str, Any]]

#: Units of `curve.csv`'s columns (SI).
CURVE_UNITS: Dict[str, str] = {
    "step": "1",
    "u_imposed": "m",
    "force": "N",
    "fed": "m",
    "bond_stress": "Pa",
    "iterations": "1",
    "w_ext": "J",
    "w_int": "J",
    "stored": "J",
    "dissipated": "J",
}

#: Units of the bond-law parameters (SI).
BOND_LAW_UNITS: Dict[str, str] = {
    "tau_max": "Pa",
    "s1": "m",
    "s2": "m",
    "s3": "m",
    "alpha": "1",
    "tau_f": "Pa",
    "fit_error": "1",
}

#: Units of a material-point table's columns (SI; strains as tensor components).
MATERIAL_UNITS: Dict[str, str] = {
    "t": "1",
    **{f"e{c}": "1" for c in ("xx", "yy", "zz", "xy", "yz", "xz")},
    **{f"ep{c}": "1" for c in ("xx", "yy", "zz", "xy", "yz", "xz")},
    **{f"s{c}": "Pa" for c in ("xx", "yy", "zz", "xy", "yz", "xz")},
    "un": "m",
    "ut": "m",
    "uh": "m",
    "tn": "Pa",
    "tt": "Pa",
    "th": "Pa",
    "D": "1",
    "kappa": "1",
    "lambda_tilde": "m",
    "slip_t": "m",
    "slip_h": "m",
}

# Exact floats from the CSVs (pandas 3 parses them exactly by default and
# deprecates the option).
_CSV_OPTIONS: Dict[str, Any] = (
    {} if int(pd.__version__.split(".")[0]) >= 3 else {"float_precision": "round_trip"}
)

# Study tables are written for reading (MPa, mm); the API gives them in SI.
_TABLE_SUFFIXES = (("_MPa", 1e6, "Pa"), ("_mm", 1e-3, "m"), ("_J_per_m2", 1.0, "J/m^2"), ("_s", 1.0, "s"))


class RibbarError(RuntimeError):
    """A ribbar command failed; the message is the command line's own report
    (`error: ...` and its causes)."""

    def __init__(self, message: str, returncode: Optional[int] = None, output: str = ""):
        super().__init__(message)
        self.returncode = returncode
        self.output = output


@dataclass(frozen=True)
class Status:
    """How a scene's solve ended."""

    #: The loading ran to its end (u_final or fed_stop), or to a limit load or
    #: brittle failure that the solver identified.
    completed: bool
    #: `solve.json`'s `ending`: `{"kind": "completed" | "limit_load" | ...}`.
    ending: Dict[str, Any]
    #: Why the solve stopped early (step, imposed u, residuals), or None.
    stopped: Optional[str]


@dataclass(frozen=True)
class FieldFiles:
    """The VTU files of one written field step."""

    name: str
    step: int
    u_imposed: float
    bulk: Path
    interface: Optional[Path]


@dataclass
class Result:
    """One scene's results as its stages published them under `work/scene`."""

    work: Path
    scene: str
    #: Wall time of the call that produced this object, s (0 for `load`).
    elapsed_s: float = 0.0
    _curve: Optional[pd.DataFrame] = dataclasses.field(default=None, repr=False)

    @property
    def directory(self) -> Path:
        return self.work / self.scene

    @property
    def curve(self) -> pd.DataFrame:
        """`curve.csv`: one row per converged step, SI columns; the units are
        in `curve.attrs["units"]`."""
        if self._curve is None:
            frame = pd.read_csv(self.directory / "curve.csv", **_CSV_OPTIONS)
            frame.attrs["units"] = {c: CURVE_UNITS.get(c, "") for c in frame.columns}
            frame.attrs["scene"] = self.scene
            self._curve = frame
        return self._curve

    @property
    def summary(self) -> Dict[str, Any]:
        """`summary.json`: peak and residual bond stress, energy, solver counts
        and wall times (SI)."""
        return _read_json(self.directory / "summary.json")

    @property
    def solve_report(self) -> Dict[str, Any]:
        """`solve.json`: the solver's own report."""
        return _read_json(self.directory / "solve.json")

    @property
    def status(self) -> Status:
        report = self.solve_report
        return Status(
            completed=bool(report.get("completed")),
            ending=report.get("ending") or {},
            stopped=report.get("stopped"),
        )

    @property
    def bond_law(self) -> pd.Series:
        """The MC2010 bond-slip form fitted to the curve (`bond_law.json`):
        tau_max, s1, s2, s3, alpha, tau_f and fit_error, SI; the parameters
        the curve does not determine in `attrs["unidentified"]`, the whole
        file in `attrs["bond_law"]`. Empty when the run has no fit (its
        reason in `attrs["none"]`)."""
        report = _read_json(self.directory / "bond_law.json")
        fit = report.get("mc2010") or {}
        names = ["tau_max", "s1", "s2", "s3", "alpha", "tau_f", "fit_error"]
        series = pd.Series({k: fit[k] for k in names if k in fit}, dtype=float, name=self.scene)
        series.attrs["units"] = {k: BOND_LAW_UNITS[k] for k in series.index}
        series.attrs["unidentified"] = list(fit.get("unidentified", []))
        series.attrs["none"] = fit.get("none")
        series.attrs["bond_law"] = report
        return series

    @property
    def bond_law_points(self) -> pd.DataFrame:
        """The piecewise-linear bond law fitted to the curve: its points
        (slip m, bond_stress Pa) from the origin; its error in
        `attrs["fit_error"]`."""
        law = _read_json(self.directory / "bond_law.json").get("piecewise_linear") or {}
        frame = pd.DataFrame(law.get("points", []), columns=["slip", "bond_stress"])
        frame.attrs["units"] = {"slip": "m", "bond_stress": "Pa"}
        frame.attrs["fit_error"] = law.get("fit_error")
        return frame

    @property
    def fields(self) -> Dict[Union[int, str], FieldFiles]:
        """The written field steps: by step number, and as "peak" and "end"."""
        directory = self.directory / "fields"
        if not directory.is_dir():
            return {}
        rows = self.curve
        by_step = dict(zip(rows["step"].astype(int), rows["u_imposed"]))
        found: Dict[Union[int, str], FieldFiles] = {}
        for bulk in sorted(directory.glob("*_bulk.vtu")):
            name = bulk.name[: -len("_bulk.vtu")]
            step = self._step_of(name, rows)
            if step is None:
                continue
            interface = directory / f"{name}_interface.vtu"
            files = FieldFiles(
                name=name,
                step=step,
                u_imposed=float(by_step.get(step, float("nan"))),
                bulk=bulk,
                interface=interface if interface.is_file() else None,
            )
            found[name if name in ("peak", "end") else step] = files
        return found

    @property
    def collection(self) -> Path:
        """`fields/fields.pvd`, every written step as one ParaView time series."""
        return self.directory / "fields" / "fields.pvd"

    def field(self, step: Union[int, str] = "end", part: str = "bulk"):
        """The fields of `step` (a step number, "peak" or "end") as a meshio
        mesh; `part` is "bulk" (tets) or "interface"."""
        import meshio

        available = self.fields
        if step not in available:
            keys = ", ".join(str(k) for k in available) or "none"
            raise KeyError(
                f"{self.scene}: no fields at step {step!r} (written: {keys}); "
                "request steps with outputs.fields.steps"
            )
        files = available[step]
        if part == "bulk":
            path = files.bulk
        elif part == "interface" and files.interface is not None:
            path = files.interface
        else:
            raise ValueError(f"part must be 'bulk' or 'interface', not {part!r}")
        return meshio.read(path)

    def _step_of(self, name: str, rows: pd.DataFrame) -> Optional[int]:
        if name.startswith("step"):
            try:
                return int(name[4:])
            except ValueError:
                return None
        if name == "end":
            return int(rows["step"].iloc[-1]) if len(rows) else None
        if name == "peak":
            # The peak fields hold the first (adhesion) peak.
            peak = self.summary.get("curve", {}).get("first_peak_bond_stress")
            if peak is None or not len(rows):
                return None
            return int(rows["step"].iloc[int((rows["bond_stress"] - peak).abs().argmin())])
        return None


@dataclass
class StudyResult:
    """A study's table (SI, units in `table.attrs["units"]`), its cases, and
    what its kind adds: the bond laws of every case, a sampled study's
    designs and responses, a sensitivity study's indices."""

    work: Path
    name: str
    table: pd.DataFrame
    cases: Dict[str, Result]
    elapsed_s: float = 0.0
    #: `sweep`, `convergence`, `sample` or `sensitivity`.
    kind: str = "sweep"
    #: A sampled or sensitivity study's design as the study file resolves
    #: it: `plan`, parameter `units`, `responses`, `rejected` draws.
    design: Optional[Dict[str, Any]] = None

    @property
    def directory(self) -> Path:
        return self.work / self.name

    @property
    def convergence(self) -> Optional[pd.DataFrame]:
        """A convergence study's `convergence.csv` (per quantity and grid:
        error against the Richardson value, GCI, least-squares
        uncertainty), else None."""
        path = self.directory / "convergence.csv"
        return pd.read_csv(path) if path.is_file() else None

    @property
    def bond_laws(self) -> pd.DataFrame:
        """`bond_laws.csv`: per case its parameters, the fitted MC2010 law
        (`mc2010_*`, with the parameters its curve does not determine in
        `mc2010_unidentified`), the piecewise law's error and points, the
        design code's law (`code_*`, `fcm`) and the fitted tau_max as a
        share of 2.5 sqrt(f_cm), all SI."""
        return self._csv("bond_laws.csv")

    @property
    def responses(self) -> Optional[pd.DataFrame]:
        """A sampled or sensitivity study's `responses.csv`: per case
        whether it counts (its solve completed), its f_R and each response,
        SI (units in `attrs["units"]`); else None."""
        frame = self._csv("responses.csv", missing_ok=True)
        if frame is not None and self.design:
            frame.attrs["units"] = {r["name"]: r["unit"] for r in self.design["responses"]}
        return frame

    @property
    def designs(self) -> Optional[pd.DataFrame]:
        """A sampled or sensitivity study's `designs.csv`: per case its role
        in the design, its unit-cube coordinates (`u_KEY`) and its values
        (SI); else None."""
        return self._csv("designs.csv", missing_ok=True)

    @property
    def rejected(self) -> Optional[pd.DataFrame]:
        """The draws outside the design bounds (`rejected.csv`), each with
        the spec's reason; they were replaced by the next draws."""
        return self._csv("rejected.csv", missing_ok=True)

    @property
    def sensitivity(self) -> Optional[pd.DataFrame]:
        """A sensitivity study's `sensitivity.csv`: per parameter and
        response S1, S1_conf, ST, ST_conf and rows (Sobol'), or mu_star,
        sigma, mu, mu_star_conf and effects (Morris); the estimators and the
        cases left out are stated in `sensitivity.md`. Else None."""
        return self._csv("sensitivity.csv", missing_ok=True)

    def _csv(self, name: str, missing_ok: bool = False) -> Optional[pd.DataFrame]:
        path = self.directory / name
        if not path.is_file():
            if missing_ok:
                return None
            raise RibbarError(f"{path}: missing; run the study first")
        return pd.read_csv(path, **_CSV_OPTIONS)


def run(
    spec: Spec,
    work: PathLike = "ribbar-work",
    set: Optional[Mapping[str, Any]] = None,
    progress: bool = True,
    verbose: bool = False,
) -> Result:
    """Runs every stale stage of a scene, as `ribbar run SPEC` does, and
    returns its results.

    `spec` is a scene spec file or the spec itself as a mapping (written to
    `work/.specs/NAME.yaml`); `set` overrides spec keys as `--set` does
    (`{"bar.ribs.angle": "60 deg", "mesh.h_interface": 0.8e-3}`). Stages
    whose inputs did not change are taken from the cache. A solve that
    stopped before the end of the loading still returns its converged part,
    with a warning and `result.status.stopped` saying why. Ctrl-C stops the
    run; running it again resumes from the last checkpoint.
    """
    work = Path(work)
    spec_path = _spec_file(spec, work)
    overrides = _overrides(set)
    scene = _resolve_scene(spec_path, overrides)
    argv = ["run", str(spec_path), "--work", str(work)]
    for o in overrides:
        argv += ["--set", o]
    start = time.perf_counter()
    code, output = _call(argv, progress=progress, verbose=verbose)
    result = Result(work=work, scene=scene["name"], elapsed_s=time.perf_counter() - start)
    if code != 0:
        if (result.directory / "solve.json").is_file() and not result.status.completed:
            warnings.warn(
                f"{result.scene}: the solve stopped early: {result.status.stopped}",
                RuntimeWarning,
                stacklevel=2,
            )
            return result
        raise RibbarError(_error_message(output, argv), code, output)
    return result


def load(work: PathLike, scene: str) -> Result:
    """Reopens the published results of `scene` in `work`."""
    result = Result(work=Path(work), scene=scene)
    if not (result.directory / "curve.csv").is_file():
        raise RibbarError(f"{result.directory}: no solved scene here (no curve.csv); run it first")
    return result


def study(
    study: Spec,
    work: PathLike = "ribbar-work",
    jobs: int = 1,
    memory_gib: Optional[float] = None,
    progress: bool = True,
) -> StudyResult:
    """Runs a study as `ribbar study STUDY` does (cases as child processes,
    shared stages cached) and returns its table and per-case results, with
    every case's bond laws (`bond_laws`), a sampled study's designs and
    responses (`designs`, `responses`, `rejected`) and a sensitivity
    study's indices (`sensitivity`) as DataFrames.

    `study` is a study file or a mapping; a mapping's `base` is taken
    relative to the current directory."""
    work = Path(work)
    study_path = _spec_file(study, work, resolve_base=True)
    plan = _resolve_study(study_path)
    argv = ["study", str(study_path), "--work", str(work), "--jobs", str(jobs)]
    if memory_gib is not None:
        argv += ["--memory-gib", str(memory_gib)]
    start = time.perf_counter()
    code, output = _call(argv, progress=progress, verbose=False)
    table_path = work / plan["name"] / "table.csv"
    if not table_path.is_file():
        raise RibbarError(_error_message(output, argv), code, output)
    if code != 0:
        warnings.warn(
            f"study {plan['name']}: some cases did not complete "
            f"(their logs: {work / plan['name'] / 'logs'})",
            RuntimeWarning,
            stacklevel=2,
        )
    cases = {}
    for case in plan["cases"]:
        if (work / case["name"] / "curve.csv").is_file():
            cases[case["name"]] = Result(work=work, scene=case["name"])
    design = plan.get("design")
    return StudyResult(
        work=work,
        name=plan["name"],
        table=_si_table(
            pd.read_csv(table_path, **_CSV_OPTIONS),
            parameter_units=(design or {}).get("units"),
        ),
        cases=cases,
        elapsed_s=time.perf_counter() - start,
        kind=plan.get("kind", "sweep"),
        design=design,
    )


def material(
    law: Union[PathLike, Mapping[str, Any]],
    path: Optional[Iterable[Mapping[str, Any]]] = None,
    increments: Optional[int] = None,
) -> pd.DataFrame:
    """Drives one law along a loading path, as `ribbar material` does.

    `law` is a material-point test file, or a mapping with `law` and
    `parameters` (`{"law": "fczm", "parameters": {"ft": "3 MPa", ...}}`);
    `path` lists the path's points (`{"t": 1, "un": 1e-4}`; a key `s...`/`t...`
    holds a stress), replacing the file's. Returns one row per increment,
    SI columns, units in `frame.attrs["units"]`."""
    if not isinstance(law, Mapping) and (path is not None or increments is not None):
        raise ValueError(
            "material: give `law` as a mapping to combine it with `path` or "
            "`increments`, or a test file alone"
        )
    with tempfile.TemporaryDirectory(prefix="ribbar-material-") as tmp:
        if isinstance(law, Mapping):
            test: Dict[str, Any] = dict(law)
            if path is not None:
                test["path"] = [dict(p) for p in path]
            if increments is not None:
                test["increments"] = int(increments)
            test_file = Path(tmp) / "test.yaml"
            test_file.write_text(json.dumps(test))
        else:
            test_file = Path(law)
        out = Path(tmp) / "table.csv"
        argv = ["material", str(test_file), "-o", str(out)]
        code, output = _call(argv, progress=False, verbose=False)
        if code != 0:
            raise RibbarError(_error_message(output, argv), code, output)
        frame = pd.read_csv(out, **_CSV_OPTIONS)
    frame.attrs["units"] = {c: MATERIAL_UNITS.get(c, "") for c in frame.columns}
    return frame


def _read_json(path: Path) -> Dict[str, Any]:
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        raise RibbarError(f"{path}: missing; run the scene first") from None


def _spec_file(spec: Spec, work: Path, resolve_base: bool = False) -> Path:
    if not isinstance(spec, Mapping):
        path = Path(spec)
        if not path.is_file():
            raise RibbarError(f"{path}: no such spec file")
        return path
    name = spec.get("name")
    if not isinstance(name, str) or not name:
        raise RibbarError("spec: `name` is required (a non-empty string)")
    data = dict(spec)
    if resolve_base and isinstance(data.get("base"), str):
        data["base"] = str(Path(data["base"]).resolve())
    directory = work / ".specs"
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / f"{name}.yaml"
    text = json.dumps(data, indent=2)  # JSON is YAML
    # Rewrite only on change, so that the file's time never matters.
    if not path.is_file() or path.read_text() != text:
        path.write_text(text)
    return path


def _overrides(values: Optional[Mapping[str, Any]]) -> List[str]:
    if not values:
        return []
    out = []
    for key, value in values.items():
        if isinstance(value, str):
            text = value
        elif isinstance(value, bool):
            text = "true" if value else "false"
        else:
            text = json.dumps(value)
        out.append(f"{key}={text}")
    return out


def _resolve_scene(spec: Path, overrides: List[str]) -> Dict[str, Any]:
    try:
        return json.loads(_native.resolve_scene(str(spec), overrides))
    except ValueError as e:
        raise RibbarError(str(e)) from None


def _resolve_study(study: Path) -> Dict[str, Any]:
    try:
        return json.loads(_native.resolve_study(str(study)))
    except ValueError as e:
        raise RibbarError(str(e)) from None


def _call(argv: List[str], progress: bool, verbose: bool) -> "tuple[int, str]":
    """Runs `ribbar ARGV` in a child interpreter, echoing its lines when
    `progress`; returns the exit status and everything it printed."""
    env = prepare_environment(dict(os.environ))
    command = [sys.executable, "-m", "ribbar", *(["-v"] if verbose else []), *argv]
    lines: List[str] = []
    child = subprocess.Popen(
        command,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        stdin=subprocess.DEVNULL,
        env=env,
        text=True,
        errors="replace",
        bufsize=1,
        # Its own process group, so that an interrupt reaches a study's case
        # processes too, and in Jupyter (where only the kernel gets SIGINT).
        start_new_session=True,
    )
    try:
        assert child.stdout is not None
        for line in child.stdout:
            lines.append(line)
            if progress:
                sys.stderr.write(line)
                sys.stderr.flush()
        code = child.wait()
    except KeyboardInterrupt:
        # The child's group ends; a solve's checkpoint stays for the resume.
        _stop(child)
        sys.stderr.write(
            "ribbar: interrupted; run the same call again to resume from the last checkpoint\n"
        )
        raise
    return code, "".join(lines)


def _stop(child: "subprocess.Popen[str]") -> None:
    for sig, wait in ((signal.SIGINT, 10), (signal.SIGKILL, None)):
        try:
            os.killpg(child.pid, sig)
        except ProcessLookupError:
            return
        try:
            child.wait(timeout=wait)
            return
        except subprocess.TimeoutExpired:
            continue


def _error_message(output: str, argv: List[str]) -> str:
    lines = output.splitlines()
    for i, line in enumerate(lines):
        if line.startswith("error:"):
            report = [line] + [l for l in lines[i + 1 :] if l.startswith("  caused by:")]
            return "\n".join(report)
    tail = "\n".join(lines[-20:])
    return f"ribbar {' '.join(argv)} failed:\n{tail}"


def _si_table(table: pd.DataFrame, parameter_units: Optional[Mapping[str, str]] = None) -> pd.DataFrame:
    units: Dict[str, str] = {}
    renamed = {}
    for column in table.columns:
        if parameter_units and column in parameter_units:
            # A sampled spec key: SI, in the unit its range was written in.
            units[column] = parameter_units[column] or "as written"
            continue
        if "." in column:
            # A swept spec key, as written in the study.
            units[column] = "as written"
            continue
        for suffix, scale, unit in _TABLE_SUFFIXES:
            if column.endswith(suffix):
                base = column[: -len(suffix)]
                table[column] = table[column] * scale
                renamed[column] = base
                units[base] = unit
                break
        else:
            units[column] = "" if column == "case" else "1"
    table = table.rename(columns=renamed)
    table.attrs["units"] = units
    return table
