//! The material-point driver (our mtest): one law at one point along a
//! piecewise-linear loading path of imposed strain or jump components, with
//! optional held stress components (mixed control), written as CSV.
//!
//! Test file (YAML):
//!
//! ```yaml
//! law: fczm                  # fczm | tvergaard | coulomb | mazars | j2 | elastic
//! parameters: {ft: "3 MPa", Gf: "300 N/m", lambda0: 2.0e-5, delta_s: 1.0,
//!              mu: 0.4, zeta: 1.0, gamma: "-1 MPa"}
//! increments: 200            # per segment
//! path:                      # a component not named in a row keeps its last value
//!   - {t: 0}
//!   - {t: 1, un: -2.0e-5}
//!   - {t: 2, ut: 6.0e-4}
//! stress: {}                 # held components, e.g. {syy: 0, szz: 0} (bulk) or {tn: "-5 MPa"}
//! ```
//!
//! Interface components `un, ut, uh` (m, `un > 0` opens) and tractions
//! `tn, tt, th`; bulk components `exx … exz` (tensor strains) and stresses
//! `sxx … sxz`. Held components are found by Newton's method on the
//! consistent tangent restricted to them.
//!
//! ```
//! let test: solve::problems::material_point::MaterialTest = serde_yaml::from_str(r#"
//! law: j2
//! parameters: {E: "200 GPa", nu: 0.3, sigma_y: "365 MPa"}
//! increments: 10
//! path: [{t: 0}, {t: 1, exx: 0.004}]
//! stress: {syy: 0, szz: 0}
//! "#).unwrap();
//! let table = solve::problems::material_point::run(&test).unwrap();
//! let sxx = table.column("sxx").unwrap();
//! assert!((sxx.last().unwrap() - 365e6).abs() < 1.0);
//! ```

use crate::laws::mazars::MazarsSizeError;
use crate::laws::{
    AnyBulkLaw, AnyInterfaceLaw, BulkLaw, BulkState, InterfaceLaw, InterfaceState, LawError,
    TangentKind,
};
use crate::spec::materials::{
    resolve_concrete, resolve_interface, resolve_steel, ConcreteModel, MaterialsSpecError,
    RawConcrete, RawInterface, RawSteel,
};
use geom::units::{Dim, RawQuantity};
use nalgebra::{DMatrix, DVector, Vector3, Vector6};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Parameters of any law, as written (each law accepts its own subset).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawParameters {
    #[serde(rename = "E")]
    pub young_modulus: Option<RawQuantity>,
    pub nu: Option<RawQuantity>,
    pub eps_d0: Option<RawQuantity>,
    pub beta: Option<RawQuantity>,
    /// Element size for Mazars (m).
    pub l: Option<RawQuantity>,
    #[serde(rename = "At")]
    pub a_t: Option<RawQuantity>,
    #[serde(rename = "Bt")]
    pub b_t: Option<RawQuantity>,
    #[serde(rename = "Ac")]
    pub a_c: Option<RawQuantity>,
    #[serde(rename = "Bc")]
    pub b_c: Option<RawQuantity>,
    pub sigma_y: Option<RawQuantity>,
    pub ft: Option<RawQuantity>,
    #[serde(rename = "Gf")]
    pub gf: Option<RawQuantity>,
    pub lambda0: Option<RawQuantity>,
    pub delta_s: Option<RawQuantity>,
    pub mu: Option<RawQuantity>,
    pub zeta: Option<RawQuantity>,
    pub gamma: Option<RawQuantity>,
    #[serde(rename = "Kn")]
    pub kn: Option<RawQuantity>,
    #[serde(rename = "Ks")]
    pub ks: Option<RawQuantity>,
    #[serde(rename = "C")]
    pub cohesion: Option<RawQuantity>,
    pub phi: Option<RawQuantity>,
}

/// One row of the loading path: the time `t` and the components it sets.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PathRow {
    pub t: f64,
    pub un: Option<RawQuantity>,
    pub ut: Option<RawQuantity>,
    pub uh: Option<RawQuantity>,
    pub exx: Option<f64>,
    pub eyy: Option<f64>,
    pub ezz: Option<f64>,
    pub exy: Option<f64>,
    pub eyz: Option<f64>,
    pub exz: Option<f64>,
}

fn default_increments() -> usize {
    100
}

/// The most rows a test writes unless its `max_rows` says more: a million
/// rows is about 200 MB of CSV.
pub const DEFAULT_MAX_ROWS: usize = 1_000_000;

/// A material-point test as written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialTest {
    pub law: String,
    #[serde(default)]
    pub parameters: RawParameters,
    /// Increments per path segment.
    #[serde(default = "default_increments")]
    pub increments: usize,
    pub path: Vec<PathRow>,
    /// Held stress (traction) components and their values.
    #[serde(default)]
    pub stress: BTreeMap<String, RawQuantity>,
    /// The most rows the test may write (default [`DEFAULT_MAX_ROWS`]):
    /// `increments` × segments + 1, refused before any is computed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_rows: Option<usize>,
}

/// What went wrong; `key` is the dotted path in the test file.
#[derive(Debug, thiserror::Error)]
pub enum MaterialPointError {
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: {message}", path.display())]
    Yaml { path: PathBuf, message: String },
    #[error("{}: {source}", path.display())]
    InFile {
        path: PathBuf,
        source: Box<MaterialPointError>,
    },
    #[error(transparent)]
    Spec(#[from] MaterialsSpecError),
    #[error("law: unknown law {0:?} (accepted: fczm, tvergaard, coulomb, mazars, j2, elastic)")]
    UnknownLaw(String),
    #[error("{key}: {detail}")]
    Input { key: String, detail: String },
    #[error("parameters.l: {0}")]
    Size(#[from] MazarsSizeError),
    #[error("at t = {t}: {source}")]
    Law { t: f64, source: LawError },
    #[error("at t = {t}: held stress components did not converge ({detail})")]
    NoConvergence { t: f64, detail: String },
}

/// The driver's output: one row per converged point.
#[derive(Debug, Clone, PartialEq)]
pub struct PointTable {
    pub columns: Vec<String>,
    pub rows: Vec<Vec<f64>>,
}

impl PointTable {
    /// Values of one column, if present.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let i = self.columns.iter().position(|c| c == name)?;
        Some(self.rows.iter().map(|r| r[i]).collect())
    }

    /// Writes the table as CSV (header row, then full-precision values).
    pub fn write_csv(&self, mut w: impl Write) -> std::io::Result<()> {
        writeln!(w, "{}", self.columns.join(","))?;
        for row in &self.rows {
            let line: Vec<String> = row.iter().map(|v| format!("{v}")).collect();
            writeln!(w, "{}", line.join(","))?;
        }
        Ok(())
    }
}

const INTERFACE_COMPONENTS: [&str; 3] = ["un", "ut", "uh"];
const INTERFACE_STRESSES: [&str; 3] = ["tn", "tt", "th"];
const BULK_COMPONENTS: [&str; 6] = ["exx", "eyy", "ezz", "exy", "eyz", "exz"];
const BULK_STRESSES: [&str; 6] = ["sxx", "syy", "szz", "sxy", "syz", "sxz"];

enum PointLaw {
    Bulk(AnyBulkLaw),
    Interface(AnyInterfaceLaw),
}

fn concrete_from(p: &RawParameters) -> RawConcrete {
    RawConcrete {
        law: Some("mazars".into()),
        young_modulus: p.young_modulus.clone(),
        nu: p.nu.clone(),
        ft: p.ft.clone(),
        eps_d0: p.eps_d0.clone(),
        beta: p.beta.clone(),
        gf: p.gf.clone(),
        a_t: p.a_t.clone(),
        b_t: p.b_t.clone(),
        a_c: p.a_c.clone(),
        b_c: p.b_c.clone(),
        // A material point is driven at its own element size `l`.
        regularisation_length: None,
        nonlocal_length: None,
        fcm: None,
    }
}

fn interface_from(p: &RawParameters, law: &str) -> RawInterface {
    RawInterface {
        law: Some(law.into()),
        ft: p.ft.clone(),
        gf: p.gf.clone(),
        lambda0: p.lambda0.clone(),
        delta_s: p.delta_s.clone(),
        mu: p.mu.clone(),
        zeta: p.zeta.clone(),
        gamma: p.gamma.clone(),
        contact_smoothing: None,
        xi: None,
        kn: p.kn.clone(),
        ks: p.ks.clone(),
        cohesion: p.cohesion.clone(),
        phi: p.phi.clone(),
    }
}

/// Rejects parameters the law does not read.
fn only(p: &RawParameters, law: &str, allowed: &[&str]) -> Result<(), MaterialPointError> {
    let all: [(&str, bool); 21] = [
        ("E", p.young_modulus.is_some()),
        ("nu", p.nu.is_some()),
        ("eps_d0", p.eps_d0.is_some()),
        ("beta", p.beta.is_some()),
        ("l", p.l.is_some()),
        ("At", p.a_t.is_some()),
        ("Bt", p.b_t.is_some()),
        ("Ac", p.a_c.is_some()),
        ("Bc", p.b_c.is_some()),
        ("sigma_y", p.sigma_y.is_some()),
        ("ft", p.ft.is_some()),
        ("Gf", p.gf.is_some()),
        ("lambda0", p.lambda0.is_some()),
        ("delta_s", p.delta_s.is_some()),
        ("mu", p.mu.is_some()),
        ("zeta", p.zeta.is_some()),
        ("gamma", p.gamma.is_some()),
        ("Kn", p.kn.is_some()),
        ("Ks", p.ks.is_some()),
        ("C", p.cohesion.is_some()),
        ("phi", p.phi.is_some()),
    ];
    match all
        .iter()
        .find(|(name, set)| *set && !allowed.contains(name))
    {
        Some((name, _)) => Err(MaterialPointError::Input {
            key: format!("parameters.{name}"),
            detail: format!("not a parameter of law {law}"),
        }),
        None => Ok(()),
    }
}

fn build_law(test: &MaterialTest) -> Result<PointLaw, MaterialPointError> {
    let p = &test.parameters;
    const PFX: &str = "parameters";
    Ok(match test.law.as_str() {
        "mazars" => {
            only(
                p,
                "mazars",
                &[
                    "E", "nu", "eps_d0", "ft", "beta", "l", "Gf", "At", "Bt", "Ac", "Bc",
                ],
            )?;
            let ConcreteModel::Mazars(m) = resolve_concrete(&concrete_from(p), PFX)? else {
                unreachable!("law forced to mazars")
            };
            let needs_l = p.gf.is_some() || p.a_t.is_none() || p.a_c.is_none();
            let l = match &p.l {
                Some(q) => q.to_si(Dim::Length, "parameters.l").map_err(MaterialsSpecError::from)?,
                None if needs_l => {
                    return Err(MaterialPointError::Input {
                        key: "parameters.l".into(),
                        detail: "missing: the element size is needed for Gf (eq. 10) or for Ac, Bc from eqs. (12)-(13)".into(),
                    })
                }
                // Unused when At, Bt, Ac, Bc are all explicit.
                None => 1.0,
            };
            PointLaw::Bulk(AnyBulkLaw::Mazars(m.at_size(l)?))
        }
        "j2" => {
            only(p, "j2", &["E", "nu", "sigma_y"])?;
            let raw = RawSteel {
                law: Some("j2".into()),
                young_modulus: p.young_modulus.clone(),
                nu: p.nu.clone(),
                sigma_y: p.sigma_y.clone(),
            };
            PointLaw::Bulk(resolve_steel(&raw, PFX)?.law())
        }
        "elastic" => {
            only(p, "elastic", &["E", "nu"])?;
            let raw = RawSteel {
                law: Some("elastic".into()),
                young_modulus: p.young_modulus.clone(),
                nu: p.nu.clone(),
                sigma_y: None,
            };
            PointLaw::Bulk(resolve_steel(&raw, PFX)?.law())
        }
        "fczm" => {
            only(
                p,
                "fczm",
                &["ft", "Gf", "lambda0", "delta_s", "mu", "zeta", "gamma"],
            )?;
            PointLaw::Interface(resolve_interface(&interface_from(p, "fczm"), None, PFX)?.law)
        }
        "tvergaard" => {
            only(p, "tvergaard", &["ft", "Gf", "lambda0", "delta_s"])?;
            PointLaw::Interface(resolve_interface(&interface_from(p, "tvergaard"), None, PFX)?.law)
        }
        "coulomb" => {
            only(p, "coulomb", &["Kn", "Ks", "ft", "C", "phi"])?;
            PointLaw::Interface(resolve_interface(&interface_from(p, "coulomb"), None, PFX)?.law)
        }
        other => return Err(MaterialPointError::UnknownLaw(other.to_string())),
    })
}

/// Component values named in a row, in law units (Voigt: engineering shear).
fn row_values(row: &PathRow, i: usize, bulk: bool) -> Result<Vec<Option<f64>>, MaterialPointError> {
    if bulk {
        if let Some((name, _)) = [("un", &row.un), ("ut", &row.ut), ("uh", &row.uh)]
            .iter()
            .find(|(_, v)| v.is_some())
        {
            return Err(MaterialPointError::Input {
                key: format!("path[{i}].{name}"),
                detail: "an interface jump in a bulk-law test (use exx … exz)".into(),
            });
        }
        let v = [row.exx, row.eyy, row.ezz, row.exy, row.eyz, row.exz];
        for (k, x) in v.iter().enumerate() {
            if let Some(x) = x {
                if !x.is_finite() {
                    return Err(MaterialPointError::Input {
                        key: format!("path[{i}].{}", BULK_COMPONENTS[k]),
                        detail: "not finite".into(),
                    });
                }
            }
        }
        Ok(v.iter()
            .enumerate()
            .map(|(k, x)| x.map(|x| if k >= 3 { 2.0 * x } else { x }))
            .collect())
    } else {
        let strains = [row.exx, row.eyy, row.ezz, row.exy, row.eyz, row.exz];
        if let Some(k) = strains.iter().position(|v| v.is_some()) {
            return Err(MaterialPointError::Input {
                key: format!("path[{i}].{}", BULK_COMPONENTS[k]),
                detail: "a strain in an interface-law test (use un, ut, uh)".into(),
            });
        }
        [(&row.un, "un"), (&row.ut, "ut"), (&row.uh, "uh")]
            .iter()
            .map(|(q, name)| {
                q.as_ref()
                    .map(|q| q.to_si(Dim::Length, &format!("path[{i}].{name}")))
                    .transpose()
                    .map_err(|e| MaterialPointError::Spec(e.into()))
            })
            .collect()
    }
}

/// Evaluates the law, solving for the held components (Newton on the
/// consistent tangent). `x` holds the imposed values on entry and the
/// solved ones on exit.
struct Solved {
    stress: Vec<f64>,
    bulk_state: BulkState,
    iface_state: InterfaceState,
}

fn evaluate(
    law: &PointLaw,
    bulk: &BulkState,
    iface: &InterfaceState,
    x: &mut [f64],
    held: &[(usize, f64)],
    scale: f64,
    t: f64,
) -> Result<Solved, MaterialPointError> {
    let eval =
        |x: &[f64]| -> Result<(Vec<f64>, DMatrix<f64>, BulkState, InterfaceState), LawError> {
            match law {
                PointLaw::Bulk(l) => {
                    let r = l.step(
                        bulk,
                        &Vector6::from_column_slice(x),
                        TangentKind::Consistent,
                    )?;
                    Ok((
                        r.stress.as_slice().to_vec(),
                        DMatrix::from_column_slice(6, 6, r.tangent.as_slice()),
                        r.state,
                        *iface,
                    ))
                }
                PointLaw::Interface(l) => {
                    let r = l.step(
                        iface,
                        &Vector3::from_column_slice(x),
                        TangentKind::Consistent,
                    )?;
                    Ok((
                        r.traction.as_slice().to_vec(),
                        DMatrix::from_column_slice(3, 3, r.tangent.as_slice()),
                        *bulk,
                        r.state,
                    ))
                }
            }
        };
    let mut last = f64::INFINITY;
    for _ in 0..60 {
        let (s, k, bs, is) = eval(x).map_err(|source| MaterialPointError::Law { t, source })?;
        let r = DVector::from_iterator(held.len(), held.iter().map(|&(i, v)| s[i] - v));
        last = r.amax();
        // Relative to the largest stress seen, so round-off of large components passes.
        let tol = 1e-9 * s.iter().fold(scale, |m, v| m.max(v.abs()));
        if held.is_empty() || last <= tol {
            return Ok(Solved {
                stress: s,
                bulk_state: bs,
                iface_state: is,
            });
        }
        let khh = DMatrix::from_fn(held.len(), held.len(), |a, b| k[(held[a].0, held[b].0)]);
        let dx = khh
            .lu()
            .solve(&r)
            .ok_or_else(|| MaterialPointError::NoConvergence {
                t,
                detail: "the tangent on the held components is singular".into(),
            })?;
        for (a, &(i, _)) in held.iter().enumerate() {
            x[i] -= dx[a];
        }
    }
    Err(MaterialPointError::NoConvergence {
        t,
        detail: format!("residual {last:e} Pa after 60 iterations"),
    })
}

/// Runs a parsed test.
pub fn run(test: &MaterialTest) -> Result<PointTable, MaterialPointError> {
    let law = build_law(test)?;
    let bulk = matches!(law, PointLaw::Bulk(_));
    let (names, stresses): (&[&str], &[&str]) = if bulk {
        (&BULK_COMPONENTS, &BULK_STRESSES)
    } else {
        (&INTERFACE_COMPONENTS, &INTERFACE_STRESSES)
    };
    let n = names.len();
    if test.increments == 0 {
        return Err(MaterialPointError::Input {
            key: "increments".into(),
            detail: "must be >= 1".into(),
        });
    }
    if test.path.len() < 2 {
        return Err(MaterialPointError::Input {
            key: "path".into(),
            detail: "needs at least two rows (start and end)".into(),
        });
    }
    check_rows(test)?;
    let held = held_stresses(test, stresses)?;
    let points = path_points(test, bulk, names, stresses, &held)?;
    let columns = table_columns(&law, names, stresses);

    let mut bulk_state = BulkState::default();
    let mut iface_state = InterfaceState::default();
    let mut x = points[0].1.clone();
    let mut scale = held.iter().map(|(_, v)| v.abs()).fold(1.0, f64::max);
    let mut rows = Vec::new();
    let first = evaluate(
        &law,
        &bulk_state,
        &iface_state,
        &mut x,
        &held,
        scale,
        points[0].0,
    )?;
    rows.push(table_row(&law, points[0].0, &x, &first));
    for seg in points.windows(2) {
        let ((t0, a), (t1, b)) = (&seg[0], &seg[1]);
        for step in 1..=test.increments {
            let f = step as f64 / test.increments as f64;
            let t = t0 + f * (t1 - t0);
            for k in 0..n {
                if !held.iter().any(|(h, _)| *h == k) {
                    x[k] = a[k] + f * (b[k] - a[k]);
                }
            }
            let s = evaluate(&law, &bulk_state, &iface_state, &mut x, &held, scale, t)?;
            scale = s.stress.iter().fold(scale, |m, v| m.max(v.abs()));
            bulk_state = s.bulk_state;
            iface_state = s.iface_state;
            rows.push(table_row(&law, t, &x, &s));
        }
    }
    Ok(PointTable { columns, rows })
}

/// The stress components the test holds (index among `stresses`, Pa).
fn held_stresses(
    test: &MaterialTest,
    stresses: &[&str],
) -> Result<Vec<(usize, f64)>, MaterialPointError> {
    let mut held = Vec::new();
    for (name, q) in &test.stress {
        let key = format!("stress.{name}");
        let i =
            stresses
                .iter()
                .position(|s| s == name)
                .ok_or_else(|| MaterialPointError::Input {
                    key: key.clone(),
                    detail: format!(
                        "not a stress component of this law (accepted: {})",
                        stresses.join(", ")
                    ),
                })?;
        held.push((
            i,
            q.to_si(Dim::Stress, &key)
                .map_err(MaterialsSpecError::from)?,
        ));
    }
    Ok(held)
}

/// The path's rows as full vectors (t, components): unnamed components
/// keep their last value; held components may not be imposed.
fn path_points(
    test: &MaterialTest,
    bulk: bool,
    names: &[&str],
    stresses: &[&str],
    held: &[(usize, f64)],
) -> Result<Vec<(f64, Vec<f64>)>, MaterialPointError> {
    let n = names.len();
    let mut points: Vec<(f64, Vec<f64>)> = Vec::new();
    let mut current = vec![0.0; n];
    for (i, row) in test.path.iter().enumerate() {
        if !row.t.is_finite() {
            return Err(MaterialPointError::Input {
                key: format!("path[{i}].t"),
                detail: "not finite".into(),
            });
        }
        if let Some((tp, _)) = points.last() {
            if row.t <= *tp {
                return Err(MaterialPointError::Input {
                    key: format!("path[{i}].t"),
                    detail: format!("{} must exceed the previous row's t = {tp}", row.t),
                });
            }
        }
        for (k, v) in row_values(row, i, bulk)?.into_iter().enumerate() {
            if let Some(v) = v {
                if let Some(&(_, _)) = held.iter().find(|(h, _)| *h == k) {
                    return Err(MaterialPointError::Input {
                        key: format!("path[{i}].{}", names[k]),
                        detail: format!("imposed, but {} is held in `stress`", stresses[k]),
                    });
                }
                current[k] = v;
            }
        }
        points.push((row.t, current.clone()));
    }

    Ok(points)
}

/// The table's columns: t, the strain or jump components, the stresses,
/// D and the law's own state variables.
fn table_columns(law: &PointLaw, names: &[&str], stresses: &[&str]) -> Vec<String> {
    let mut columns: Vec<String> = std::iter::once("t")
        .chain(names.iter().copied())
        .chain(stresses.iter().copied())
        .chain(std::iter::once("D"))
        .map(String::from)
        .collect();
    match law {
        PointLaw::Bulk(AnyBulkLaw::Mazars(_)) => columns.push("kappa".into()),
        PointLaw::Bulk(AnyBulkLaw::J2(_)) => {
            columns.extend(["epxx", "epyy", "epzz", "epxy", "epyz", "epxz"].map(String::from))
        }
        PointLaw::Interface(AnyInterfaceLaw::Elastic(_))
        | PointLaw::Bulk(AnyBulkLaw::Elastic(_)) => {}
        PointLaw::Interface(_) => {
            columns.extend(["lambda_tilde", "slip_t", "slip_h"].map(String::from))
        }
    }
    columns
}

/// One table row (see [`table_columns`]); strains in tensor components.
fn table_row(law: &PointLaw, t: f64, x: &[f64], s: &Solved) -> Vec<f64> {
    let bulk = matches!(law, PointLaw::Bulk(_));
    let mut row = vec![t];
    // Strain output in tensor components.
    row.extend(
        x.iter()
            .enumerate()
            .map(|(k, v)| if bulk && k >= 3 { v / 2.0 } else { *v }),
    );
    row.extend(&s.stress);
    row.push(if bulk {
        s.bulk_state.damage
    } else {
        s.iface_state.damage
    });
    match law {
        PointLaw::Bulk(AnyBulkLaw::Mazars(_)) => row.push(s.bulk_state.kappa),
        PointLaw::Bulk(AnyBulkLaw::J2(_)) => row.extend(
            s.bulk_state
                .plastic_strain
                .iter()
                .enumerate()
                .map(|(k, v)| if k >= 3 { v / 2.0 } else { *v }),
        ),
        PointLaw::Interface(AnyInterfaceLaw::Elastic(_))
        | PointLaw::Bulk(AnyBulkLaw::Elastic(_)) => {}
        PointLaw::Interface(_) => {
            row.push(s.iface_state.lambda_max);
            row.extend(s.iface_state.slip);
        }
    }
    row
}

/// Refuses a test whose table would have more rows than its `max_rows`.
fn check_rows(test: &MaterialTest) -> Result<(), MaterialPointError> {
    let segments = test.path.len() - 1;
    let rows = test
        .increments
        .checked_mul(segments)
        .and_then(|n| n.checked_add(1));
    let max = test.max_rows.unwrap_or(DEFAULT_MAX_ROWS);
    match rows {
        Some(n) if n <= max => Ok(()),
        _ => Err(MaterialPointError::Input {
            key: "increments".into(),
            detail: format!(
                "{} increments × {segments} segments give {} rows, more than max_rows = {max}; \
                 lower increments, or raise max_rows if that many rows are meant",
                test.increments,
                rows.map_or("more than 2^64".to_string(), |n| (n).to_string())
            ),
        }),
    }
}

/// Reads and runs a test file; errors name the file.
pub fn run_file(path: &Path) -> Result<PointTable, MaterialPointError> {
    let text = geom::fsutil::read_capped(path, geom::fsutil::MAX_SPEC_BYTES).map_err(|source| {
        MaterialPointError::Io {
            path: path.to_path_buf(),
            source,
        }
    })?;
    let test: MaterialTest = serde_yaml::from_str(&text).map_err(|e| MaterialPointError::Yaml {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    run(&test).map_err(|e| MaterialPointError::InFile {
        path: path.to_path_buf(),
        source: Box::new(e),
    })
}
