//! PETSc's CG + GAMG on the linear benchmark's system, through petsc4py
//! (`scripts/petsc-gamg.py`, built into the binary and written beside the
//! system): the matrix and right-hand side that ribbar's AMG solves, with
//! the Dirichlet rows and columns as identity ones, exported as scalar CSR;
//! the reaction is computed by ribbar from PETSc's displacements, as for its
//! own solvers.

use crate::measure::{run_logged, Measured};
use crate::progress::Printer;
use anyhow::{bail, Context, Result};
use solve::laws::elastic::LinearElastic;
use solve::linalg::amg::Bsr;
use solve::problems::linear_elastic::{apply_dirichlet, assemble, reaction, PerfectBond};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

const SCRIPT: &str = include_str!("../../scripts/petsc-gamg.py");

/// What PETSc's solve gave and cost.
pub(crate) struct PetscResult {
    pub version: String,
    pub measured: Measured,
    pub reaction: f64,
    pub iterations: usize,
    pub phases: String,
}

#[derive(serde::Deserialize)]
struct ScriptResult {
    version: String,
    iterations: usize,
    converged: i32,
    relative_residual: f64,
    t_load: f64,
    t_setup: f64,
    t_solve: f64,
}

/// The first interpreter that imports petsc4py: `RIBBAR_PETSC_PYTHON`, then
/// `python3` on PATH, then Debian's `/usr/bin/python3` (where the
/// `python3-petsc4py` package installs it).
fn find_python(script: &Path) -> Option<PathBuf> {
    let candidates = std::env::var_os("RIBBAR_PETSC_PYTHON")
        .map(PathBuf::from)
        .into_iter()
        .chain([PathBuf::from("python3"), PathBuf::from("/usr/bin/python3")]);
    for py in candidates {
        let ok = Command::new(&py)
            .arg(script)
            .arg("--probe")
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        if ok {
            return Some(py);
        }
    }
    None
}

fn write_le<T: Copy, const N: usize>(
    path: &Path,
    values: &[T],
    bytes: impl Fn(T) -> [u8; N],
) -> Result<()> {
    let mut out = Vec::with_capacity(N * values.len());
    for &v in values {
        out.extend_from_slice(&bytes(v));
    }
    std::fs::write(path, out).with_context(|| format!("writing {}", path.display()))
}

/// Scalar CSR (int32 indices, sorted columns) of a 3×3-block matrix.
fn scalar_csr(k: &Bsr) -> Result<(Vec<i32>, Vec<i32>, Vec<f64>)> {
    let n = 3 * k.rows;
    let nnz = 9 * k.blocks();
    if nnz > i32::MAX as usize {
        bail!("{nnz} matrix entries: more than PETSc's 32-bit indices hold");
    }
    let (mut indptr, mut indices, mut values) = (
        Vec::with_capacity(n + 1),
        Vec::with_capacity(nnz),
        Vec::with_capacity(nnz),
    );
    indptr.push(0i32);
    for bi in 0..k.rows {
        let mut blocks: Vec<usize> = (k.row_ptr[bi]..k.row_ptr[bi + 1]).collect();
        blocks.sort_unstable_by_key(|&kk| k.col_idx[kk]);
        for r in 0..3 {
            for &kk in &blocks {
                let bj = k.col_idx[kk] as usize;
                for c in 0..3 {
                    indices.push((3 * bj + c) as i32);
                    values.push(k.values[9 * kk + 3 * r + c]);
                }
            }
            indptr.push(indices.len() as i32);
        }
    }
    Ok((indptr, indices, values))
}

/// Solves `problem` with PETSc in `dir`; `Ok(None)` when no interpreter
/// with petsc4py is found.
pub(crate) fn run(
    problem: &PerfectBond,
    concrete: &LinearElastic,
    steel: &LinearElastic,
    tolerance: f64,
    dir: &Path,
    timeout: f64,
    printer: &Printer,
) -> Result<Option<PetscResult>> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let script = dir.join("petsc-gamg.py");
    std::fs::write(&script, SCRIPT).with_context(|| format!("writing {}", script.display()))?;
    let Some(python) = find_python(&script) else {
        printer.line("petsc4py not found: PETSc skipped");
        return Ok(None);
    };
    let mut k = assemble(problem, concrete, steel)?;
    let rhs = apply_dirichlet(&mut k, &problem.constrained);
    let (indptr, indices, values) = scalar_csr(&k)?;
    drop(k);
    write_le(&dir.join("indptr.bin"), &indptr, i32::to_le_bytes)?;
    write_le(&dir.join("indices.bin"), &indices, i32::to_le_bytes)?;
    write_le(&dir.join("values.bin"), &values, f64::to_le_bytes)?;
    write_le(&dir.join("rhs.bin"), &rhs, f64::to_le_bytes)?;
    let coords: Vec<f64> = problem.nodes.iter().flatten().copied().collect();
    write_le(&dir.join("coords.bin"), &coords, f64::to_le_bytes)?;
    let meta =
        serde_json::json!({ "rows": rhs.len(), "nnz": values.len(), "tolerance": tolerance });
    std::fs::write(dir.join("system.json"), meta.to_string()).context("writing system.json")?;
    drop((indptr, indices, values, coords));
    printer.line(&format!("PETSc: {} DOFs, CG + GAMG", rhs.len()));
    let measured = run_logged(
        Command::new(&python).arg(&script).arg(dir),
        &format!("PETSc ({})", python.display()),
        &dir.join("petsc.log"),
        timeout,
    )?;
    let r: ScriptResult = serde_json::from_str(
        &std::fs::read_to_string(dir.join("result.json")).context("reading result.json")?,
    )
    .context("result.json")?;
    if r.converged <= 0 {
        bail!(
            "PETSc's CG did not converge (reason {}, {} iterations, residual {:.1e})",
            r.converged,
            r.iterations,
            r.relative_residual
        );
    }
    let bytes = std::fs::read(dir.join("u.bin")).context("reading u.bin")?;
    let mut u: Vec<f64> = bytes
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")))
        .collect();
    if u.len() != problem.dofs() {
        bail!("u.bin holds {} values for {} DOFs", u.len(), problem.dofs());
    }
    for &(d, v) in &problem.constrained {
        u[d] = v;
    }
    let reaction = reaction(problem, concrete, steel, &u)?;
    printer.line(&format!(
        "PETSc {}: {:.2} s, {:.0} MiB, F = {:.6e} N",
        r.version,
        measured.wall,
        measured.max_rss as f64 / 1048576.0,
        reaction
    ));
    Ok(Some(PetscResult {
        version: r.version,
        measured,
        reaction,
        iterations: r.iterations,
        phases: format!(
            "read + matrix {:.2} + setup {:.2} + solve {:.2} s; residual {:.1e} (petsc4py, one process)",
            r.t_load, r.t_setup, r.t_solve, r.relative_residual
        ),
    }))
}
