//! `ribbar._native`: the `ribbar` command line and the spec readers, for
//! the Python package. Everything else of the API is Python over the files
//! the stages write, so Python and the CLI share one implementation.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::path::Path;

/// Runs the `ribbar` command line with `argv` (program name first) in this
/// process and returns its exit status. The interpreter's lock is released
/// while it runs.
#[pyfunction]
fn main(py: Python<'_>, argv: Vec<String>) -> u8 {
    py.detach(|| pipeline::app::main_with_args(argv))
}

/// The scene `spec` resolves to with `overrides` (`key=value`), as JSON in
/// SI units; a bad spec raises `ValueError` with the CLI's message.
#[pyfunction]
fn resolve_scene(spec: &str, overrides: Vec<String>) -> PyResult<String> {
    let scene = pipeline::scene::Scene::load(Path::new(spec), &overrides)
        .map_err(|e| PyValueError::new_err(pipeline::app::error_report(&e.into())))?;
    serde_json::to_string(&scene).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// A study file's name, kind and cases (name, overrides, swept values as
/// written, or sampled values in SI), as JSON; a sampled or sensitivity
/// study adds its parameters' SI units, its responses with theirs, its
/// design and the draws outside the design bounds. A bad study raises
/// `ValueError` with the CLI's message.
#[pyfunction]
fn resolve_study(study: &str) -> PyResult<String> {
    let study = pipeline::study::Study::load(Path::new(study))
        .map_err(|e| PyValueError::new_err(pipeline::app::error_report(&e.into())))?;
    let cases: Vec<serde_json::Value> = study
        .cases
        .iter()
        .map(|c| {
            serde_json::json!({
                "name": c.name,
                "overrides": c.overrides,
                "parameters": c.parameters.iter().map(|(k, v)| (k.clone(), serde_json::to_value(v).unwrap_or_default())).collect::<serde_json::Map<_, _>>(),
            })
        })
        .collect();
    let design = study.design.as_ref().map(|d| {
        serde_json::json!({
            "plan": d.plan.describe(),
            "units": d.axes.iter().map(|a| (a.key.clone(), serde_json::json!(a.unit()))).collect::<serde_json::Map<_, _>>(),
            "responses": d.responses.iter().map(|r| serde_json::json!({"name": r.name(), "unit": r.unit()})).collect::<Vec<_>>(),
            "rejected": d.points.rejected.iter().map(|r| serde_json::json!({"draw": r.draw, "reason": r.reason})).collect::<Vec<_>>(),
        })
    });
    Ok(serde_json::json!({
        "name": study.name,
        "base": study.base,
        "kind": study.kind.name(),
        "convergence": study.kind == pipeline::study::StudyKind::Convergence,
        "cases": cases,
        "design": design,
    })
    .to_string())
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(main, m)?)?;
    m.add_function(wrap_pyfunction!(resolve_scene, m)?)?;
    m.add_function(wrap_pyfunction!(resolve_study, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
