//! VTU (VTK XML unstructured grid, ASCII) output of a converged state, for
//! ParaView or meshio (SPEC §7):
//! * bulk file: tets with point displacement (m) and per-cell region
//!   (0 steel, 1 concrete), damage D, principal stresses (Pa, ascending),
//!   masks "all three principal stresses tensile", "all compressive", D > 0.99;
//! * interface file: the steel-side triangles of the assembled interface
//!   elements with per-cell mean D_int, local tractions (t_n, t_t, t_h, Pa)
//!   and frictional slip (m), averaged over the element's node pairs.
//!
//! Stresses are recomputed from the committed state and the converged
//! strain (the laws are pure functions of both), so nothing extra is stored.
//!
//! A half or quarter model's fields can be written on the whole specimen
//! ([`mesh::Unfolded`]): the values are computed on the model once and
//! copied to the images, displacements reflected, the interface's local h
//! components (t_h, s_h) signed with the image's frame; the other cell
//! quantities (damage, principal stresses and their masks, t_n, t_t, s_t)
//! are invariant under the reflection.

use crate::assembly::{ElementLaws, States};
use crate::elements::interface::{InterfaceKernel, INTERFACE_POINTS};
use crate::elements::tet::TetGeometry;
use crate::laws::{BulkLaw, TangentKind};
use mesh::{Model, Region};
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::Path;

/// A field file that cannot be written.
#[derive(Debug, thiserror::Error)]
pub enum FieldsError {
    #[error("{path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("element {index}: {detail}")]
    Element { index: usize, detail: String },
}

fn data_array(out: &mut String, name: &str, comps: usize, values: impl Iterator<Item = f64>) {
    let _ = writeln!(
        out,
        r#"<DataArray type="Float64" Name="{name}" NumberOfComponents="{comps}" format="ascii">"#
    );
    for v in values {
        // A non-finite value never reaches the file.
        let v = if v.is_finite() { v } else { 0.0 };
        let _ = write!(out, "{v:e} ");
    }
    out.push_str("\n</DataArray>\n");
}

fn write_atomic(path: &Path, text: &str) -> Result<(), FieldsError> {
    geom::fsutil::write_atomic(path, text.as_bytes()).map_err(|source| FieldsError::Io {
        path: path.display().to_string(),
        source,
    })
}

fn header(out: &mut String, nodes: &[[f64; 3]], n_cells: usize) {
    out.push_str(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n",
    );
    let _ = writeln!(
        out,
        r#"<Piece NumberOfPoints="{}" NumberOfCells="{n_cells}">"#,
        nodes.len()
    );
    out.push_str("<Points>\n");
    data_array(
        out,
        "Points",
        3,
        nodes.iter().flat_map(|p| p.iter().copied()),
    );
    out.push_str("</Points>\n");
}

/// The grid a field file is written on: the model itself, or the whole
/// specimen unfolded from it.
struct Grid<'a> {
    model: &'a Model,
    whole: Option<&'a mesh::Unfolded>,
}

impl Grid<'_> {
    fn nodes(&self) -> &[[f64; 3]] {
        self.whole.map_or(&self.model.nodes, |w| &w.model.nodes)
    }
    fn tets(&self) -> &[[u32; 4]] {
        self.whole.map_or(&self.model.tets, |w| &w.model.tets)
    }
    /// The model's tet of each written tet.
    fn tet_source(&self) -> Box<dyn Iterator<Item = usize> + '_> {
        match self.whole {
            None => Box::new(0..self.model.tets.len()),
            Some(w) => Box::new(w.tet_source.iter().map(|&t| t as usize)),
        }
    }
    /// The displacement of every written node.
    fn displacement<'b>(&'b self, u: &'b [f64]) -> Box<dyn Iterator<Item = f64> + 'b> {
        match self.whole {
            None => Box::new(u.iter().copied()),
            Some(w) => Box::new(
                w.node_source
                    .iter()
                    .zip(&w.node_reflection)
                    .flat_map(move |(&n, r)| (0..3).map(move |c| r[c] * u[3 * n as usize + c])),
            ),
        }
    }
    /// (model element, sign of h) of every written interface element.
    fn interfaces(&self) -> Vec<(usize, f64)> {
        match self.whole {
            None => (0..self.model.interfaces.len()).map(|i| (i, 1.0)).collect(),
            Some(w) => w
                .interface_source
                .iter()
                .zip(&w.interface_h_sign)
                .map(|(&i, &s)| (i as usize, s))
                .collect(),
        }
    }
    fn interface_nodes(&self, k: usize) -> [u32; 6] {
        match self.whole {
            None => self.model.interfaces[k].nodes,
            Some(w) => w.model.interfaces[k].nodes,
        }
    }
}

fn cells(out: &mut String, conn: &[Vec<u32>], vtk_type: u8) {
    out.push_str("<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for c in conn {
        for n in c {
            let _ = write!(out, "{n} ");
        }
    }
    out.push_str("\n</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    let mut off = 0;
    for c in conn {
        off += c.len();
        let _ = write!(out, "{off} ");
    }
    out.push_str("\n</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    for _ in conn {
        let _ = write!(out, "{vtk_type} ");
    }
    out.push_str("\n</DataArray>\n</Cells>\n");
}

/// Principal stresses (ascending, Pa) of a Voigt stress.
pub fn principal_stresses(s: &nalgebra::Vector6<f64>) -> [f64; 3] {
    let m = Matrix3::new(s[0], s[3], s[5], s[3], s[1], s[4], s[5], s[4], s[2]);
    let mut e: Vec<f64> = m.symmetric_eigenvalues().iter().copied().collect();
    e.sort_by(f64::total_cmp);
    [e[0], e[1], e[2]]
}

/// Writes the bulk field file (see module doc); `u` global displacement
/// (m); on the whole specimen when `whole` is the model's unfolding.
pub fn write_bulk_vtu(
    path: &Path,
    model: &Model,
    laws: &ElementLaws,
    u: &[f64],
    states: &States,
    whole: Option<&mesh::Unfolded>,
) -> Result<(), FieldsError> {
    let mut principal = Vec::with_capacity(model.tets.len());
    for (index, t) in model.tets.iter().enumerate() {
        let g = TetGeometry::new(&t.map(|n| model.nodes[n as usize])).map_err(|e| {
            FieldsError::Element {
                index,
                detail: e.to_string(),
            }
        })?;
        let ue: [f64; 12] = std::array::from_fn(|i| u[3 * t[i / 3] as usize + i % 3]);
        let r = laws.tets[index]
            .step(&states.bulk[index], &g.strain(&ue), TangentKind::Secant)
            .map_err(|e| FieldsError::Element {
                index,
                detail: e.to_string(),
            })?;
        principal.push(principal_stresses(&r.stress));
    }
    let grid = Grid { model, whole };
    let mut out = String::new();
    header(&mut out, grid.nodes(), grid.tets().len());
    let conn: Vec<Vec<u32>> = grid.tets().iter().map(|t| t.to_vec()).collect();
    cells(&mut out, &conn, 10);
    out.push_str("<PointData>\n");
    data_array(&mut out, "displacement", 3, grid.displacement(u));
    out.push_str("</PointData>\n<CellData>\n");
    let region = grid.tet_source().map(|t| {
        if model.tet_region[t] == Region::Concrete {
            1.0
        } else {
            0.0
        }
    });
    data_array(&mut out, "region", 1, region);
    let damage = |t: usize| states.bulk[t].damage;
    data_array(&mut out, "D", 1, grid.tet_source().map(damage));
    data_array(
        &mut out,
        "principal_stress",
        3,
        grid.tet_source().flat_map(|t| principal[t].into_iter()),
    );
    let flag = |b: bool| if b { 1.0 } else { 0.0 };
    data_array(
        &mut out,
        "all_tensile",
        1,
        grid.tet_source().map(|t| flag(principal[t][0] > 0.0)),
    );
    data_array(
        &mut out,
        "all_compressive",
        1,
        grid.tet_source().map(|t| flag(principal[t][2] < 0.0)),
    );
    data_array(
        &mut out,
        "D_above_0.99",
        1,
        grid.tet_source().map(|t| flag(damage(t) > 0.99)),
    );
    out.push_str("</CellData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    write_atomic(path, &out)
}

/// One interface element's written values: mean D_int, local traction
/// (t_n, t_t, t_h, Pa), frictional slip (s_t, s_h, m).
type InterfaceCell = (f64, [f64; 3], [f64; 2]);

/// Writes the interface field file (see module doc); on the whole
/// specimen when `whole` is the model's unfolding.
pub fn write_interface_vtu(
    path: &Path,
    model: &Model,
    laws: &ElementLaws,
    u: &[f64],
    states: &States,
    whole: Option<&mesh::Unfolded>,
) -> Result<(), FieldsError> {
    let mut values: Vec<Option<InterfaceCell>> = vec![None; model.interfaces.len()];
    for (index, e) in model.interfaces.iter().enumerate() {
        let Some(law) = &laws.interfaces[index] else {
            continue;
        };
        let states = &states.interface[INTERFACE_POINTS * index..INTERFACE_POINTS * (index + 1)];
        let points = InterfaceKernel::new(e)
            .tractions(law, u, states, TangentKind::Secant)
            .map_err(|err| FieldsError::Element {
                index,
                detail: format!("node pair {}: {}", err.point, err.source),
            })?;
        let (mut d, mut t, mut s) = (0.0, [0.0; 3], [0.0; 2]);
        for (st, r) in states.iter().zip(&points) {
            d += st.damage / INTERFACE_POINTS as f64;
            for (tc, rc) in t.iter_mut().zip(r.law.traction.iter()) {
                *tc += rc / INTERFACE_POINTS as f64;
            }
            for (sc, pc) in s.iter_mut().zip(st.slip.iter()) {
                *sc += pc / INTERFACE_POINTS as f64;
            }
        }
        values[index] = Some((d, t, s));
    }
    let grid = Grid { model, whole };
    let (mut conn, mut damage, mut traction, mut slip) = (vec![], vec![], vec![], vec![]);
    for (k, (source, h_sign)) in grid.interfaces().into_iter().enumerate() {
        let Some((d, t, s)) = values[source] else {
            continue;
        };
        conn.push(grid.interface_nodes(k)[..3].to_vec());
        damage.push(d);
        traction.push([t[0], t[1], h_sign * t[2]]);
        slip.push([s[0], h_sign * s[1]]);
    }
    let mut out = String::new();
    header(&mut out, grid.nodes(), conn.len());
    cells(&mut out, &conn, 5);
    out.push_str("<CellData>\n");
    data_array(&mut out, "D_int", 1, damage.into_iter());
    data_array(
        &mut out,
        "traction_ntn",
        3,
        traction.iter().flat_map(|t| t.iter().copied()),
    );
    data_array(
        &mut out,
        "slip_th",
        2,
        slip.iter().flat_map(|s| s.iter().copied()),
    );
    out.push_str("</CellData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    write_atomic(path, &out)
}

/// Mean interface tractions in axial bins along the adhesive zone, for the
/// paper's Fig. 12 style profile: (z, t_n, t_t) per bin with elements.
fn interface_profile(
    model: &Model,
    laws: &ElementLaws,
    u: &[f64],
    states: &States,
) -> Vec<(f64, f64, f64)> {
    let bins = 80usize;
    let (z0, z1) = (0.0, model.adhesive_length);
    let mut acc = vec![(0.0f64, 0.0f64, 0.0f64); bins];
    for (i, e) in model.interfaces.iter().enumerate() {
        if e.zone != mesh::InterfaceZone::Adhesive || laws.interfaces[i].is_none() {
            continue;
        }
        let z = e.nodes[..3]
            .iter()
            .map(|&n| model.nodes[n as usize][2])
            .sum::<f64>()
            / 3.0;
        let b = (((z - z0) / (z1 - z0)) * bins as f64)
            .floor()
            .clamp(0.0, bins as f64 - 1.0) as usize;
        let law = laws.interfaces[i].as_ref().expect("checked above");
        if let Some(t) = mean_traction(e, law, u, &states.interface[INTERFACE_POINTS * i..]) {
            acc[b].0 += e.area;
            acc[b].1 += e.area * t[0];
            acc[b].2 += e.area * t[1];
        }
    }
    acc.iter()
        .enumerate()
        .filter(|(_, a)| a.0 > 0.0)
        .map(|(b, a)| {
            (
                z0 + (b as f64 + 0.5) * (z1 - z0) / bins as f64,
                a.1 / a.0,
                a.2 / a.0,
            )
        })
        .collect()
}

/// Local traction (t_n, t_t, t_h) of one interface element, averaged over
/// its integration points, at the committed state.
fn mean_traction(
    e: &mesh::InterfaceElement,
    law: &dyn crate::laws::InterfaceLaw,
    u: &[f64],
    states: &[crate::laws::InterfaceState],
) -> Option<[f64; 3]> {
    let points = InterfaceKernel::new(e)
        .tractions(law, u, &states[..INTERFACE_POINTS], TangentKind::Secant)
        .ok()?;
    let mut t = [0.0; 3];
    for r in &points {
        for (tc, rc) in t.iter_mut().zip(r.law.traction.iter()) {
            *tc += rc / INTERFACE_POINTS as f64;
        }
    }
    Some(t)
}

/// One bin of an interface traction profile (`interface_profile.csv`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ProfileRow {
    /// Converged step the profile was taken at.
    pub step: usize,
    /// Free-end displacement at that step, m.
    pub fed: f64,
    /// Axial position of the bin's centre, m.
    pub z: f64,
    /// Area-weighted mean normal and shear traction t_n, t_t in the bin, Pa.
    pub normal: f64,
    pub shear: f64,
}

/// Columns of `interface_profile.csv`.
pub const PROFILE_COLUMNS: [&str; 5] = ["step", "fed", "z", "normal", "shear"];

/// The profile of the converged state (`u`, `states`) at a curve step.
pub fn profile_rows(
    model: &Model,
    laws: &ElementLaws,
    u: &[f64],
    states: &States,
    step: usize,
    fed: f64,
) -> Vec<ProfileRow> {
    interface_profile(model, laws, u, states)
        .into_iter()
        .map(|(z, normal, shear)| ProfileRow {
            step,
            fed,
            z,
            normal,
            shear,
        })
        .collect()
}

/// The text of `interface_profile.csv` for `rows`, ordered by step
/// (stable), repeated rows once.
pub fn write_profile_csv(rows: &[ProfileRow]) -> String {
    let mut rows = rows.to_vec();
    rows.sort_by_key(|r| r.step);
    rows.dedup();
    let mut out = PROFILE_COLUMNS.join(",");
    out.push('\n');
    for r in &rows {
        let _ = writeln!(
            out,
            "{},{:e},{:e},{:e},{:e}",
            r.step, r.fed, r.z, r.normal, r.shear
        );
    }
    out
}

/// One written field step of a ParaView collection: its loading parameter
/// and the files holding it (bulk and interface, as separate parts).
#[derive(Debug, Clone, PartialEq)]
pub struct CollectionStep {
    /// The collection's time value: the imposed displacement, m.
    pub u_imposed: f64,
    /// File names relative to the collection file.
    pub files: Vec<String>,
}

/// A ParaView `.pvd` collection opening `steps` as one time series (each
/// step's files as the parts of one multiblock); `steps` in loading order.
pub fn collection_pvd(steps: &[CollectionStep]) -> String {
    let mut out = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n<Collection>\n",
    );
    for step in steps {
        for (part, file) in step.files.iter().enumerate() {
            let _ = writeln!(
                out,
                "  <DataSet timestep=\"{:e}\" group=\"\" part=\"{part}\" file=\"{}\"/>",
                step.u_imposed,
                xml_escape(file)
            );
        }
    }
    out.push_str("</Collection>\n</VTKFile>\n");
    out
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
