//! Global assembly: DOF numbering with eliminated Dirichlet DOFs, the sparse
//! pattern (lower triangle, CSC) built once per mesh with a scatter map per
//! element, and the per-iteration refill of the tangent values and of the
//! internal force vector, with the constitutive updates done in parallel.
//!
//! Global DOFs are node-major (`3·node + component`). Constrained DOFs are
//! eliminated: they get no row or column; their values are set directly in
//! the displacement vector, so the residual of the first iteration of a step
//! already carries the effect of an imposed increment and every Newton
//! correction is zero there. The system is symmetric whenever the laws'
//! tangents are.

use crate::elements::interface::{InterfaceKernel, INTERFACE_POINTS};
use crate::elements::tet::{ElementError, TetGeometry};
use crate::laws::{
    AnyBulkLaw, AnyInterfaceLaw, BulkLaw, BulkState, InterfaceState, LawError, TangentKind,
};
use mesh::Model;
use nalgebra::Vector6;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// The law of every element of a model.
#[derive(Clone)]
pub struct ElementLaws {
    /// One law per tetrahedron (same order as `Model::tets`): per element
    /// where parameters depend on it (Mazars' size l).
    pub tets: Vec<AnyBulkLaw>,
    /// One law per interface element; `None` leaves the element out
    /// (the free, non-adhesive zone by default: its twins are unconnected).
    pub interfaces: Vec<Option<AnyInterfaceLaw>>,
    /// Internal length of the concrete's gradient-enhanced damage, m
    /// (`materials.concrete.nonlocal_length`): the Mazars tets' κ then
    /// follows their averaged equivalent strain (`crate::nonlocal`).
    pub nonlocal_length: Option<f64>,
}

impl ElementLaws {
    /// The same law per region: `concrete` and `steel` for the tets, the
    /// adhesive and (optional) free-zone interface laws.
    pub fn by_region(
        model: &Model,
        concrete: AnyBulkLaw,
        steel: AnyBulkLaw,
        adhesive: AnyInterfaceLaw,
        free: Option<AnyInterfaceLaw>,
    ) -> Self {
        Self {
            tets: model
                .tet_region
                .iter()
                .map(|r| match r {
                    mesh::Region::Concrete => concrete,
                    mesh::Region::Steel => steel,
                })
                .collect(),
            interfaces: model
                .interfaces
                .iter()
                .map(|e| match e.zone {
                    mesh::InterfaceZone::Adhesive => Some(adhesive),
                    mesh::InterfaceZone::Free => free,
                })
                .collect(),
            nonlocal_length: None,
        }
    }
}

impl ElementLaws {
    /// Per-element laws where the concrete law depends on the element size
    /// l (m, `Model::tet_size`, paper eq. 11), e.g. Mazars' Hillerborg
    /// regularisation: `concrete(l)` is called once per concrete tet.
    pub fn sized<E>(
        model: &Model,
        concrete: impl Fn(f64) -> Result<AnyBulkLaw, E>,
        steel: AnyBulkLaw,
        adhesive: AnyInterfaceLaw,
        free: Option<AnyInterfaceLaw>,
    ) -> Result<Self, (usize, E)> {
        let mut laws = Self::by_region(model, steel, steel, adhesive, free);
        for (i, r) in model.tet_region.iter().enumerate() {
            if *r == mesh::Region::Concrete {
                let l = model.tet_size.get(i).copied().unwrap_or(f64::NAN);
                laws.tets[i] = concrete(l).map_err(|e| (i, e))?;
            }
        }
        Ok(laws)
    }
}

/// Committed or trial history of every integration point.
#[derive(Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct States {
    /// One per tetrahedron.
    pub bulk: Vec<BulkState>,
    /// [`INTERFACE_POINTS`] per interface element (node pair order).
    pub interface: Vec<InterfaceState>,
}

impl Clone for States {
    fn clone(&self) -> Self {
        Self {
            bulk: self.bulk.clone(),
            interface: self.interface.clone(),
        }
    }

    /// Into the existing vectors: the solver copies states several times a
    /// step, and the derived `clone_from` allocated fresh ones each time
    /// (tens of MB on R1, first touched page by page).
    fn clone_from(&mut self, source: &Self) {
        self.bulk.clone_from(&source.bulk);
        self.interface.clone_from(&source.interface);
    }
}

impl States {
    pub fn initial(model: &Model) -> Self {
        Self {
            bulk: vec![BulkState::default(); model.tets.len()],
            interface: vec![InterfaceState::default(); INTERFACE_POINTS * model.interfaces.len()],
        }
    }
}

/// What went wrong while assembling.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AssemblyError {
    #[error("tetrahedron {index}: {source}")]
    Element {
        index: usize,
        #[source]
        source: ElementError,
    },
    #[error("model: {0}")]
    Model(String),
    #[error("tetrahedron {index} ({region:?}): {source}")]
    BulkLaw {
        index: usize,
        region: mesh::Region,
        #[source]
        source: LawError,
    },
    #[error("interface element {index}, node pair {point}: {source}")]
    InterfaceLaw {
        index: usize,
        point: usize,
        #[source]
        source: LawError,
    },
    #[error("non-finite {what} in tetrahedron {index}")]
    NonFiniteBulk { index: usize, what: &'static str },
    #[error("non-finite {what} in interface element {index}, node pair {point}")]
    NonFiniteInterface {
        index: usize,
        point: usize,
        what: &'static str,
    },
}

const NONE: u32 = u32::MAX;
/// Set in a scatter-map entry when the element's local lower entry (a ≥ b)
/// lands in the global upper triangle (free index of a < that of b): its
/// value then belongs to the transposed position. Without this the lower
/// store of an unsymmetric element matrix (Mazars and FCZM consistent
/// tangents) mixes K_ab and K_ba by the accident of the DOF numbering.
const SWAP: u32 = 1 << 31;
/// Set in a scatter-map entry whose two DOFs are tied with opposite signs
/// (one of them the half-turn image of a DOF of the other's node): the
/// entry enters negated.
const NEG: u32 = 1 << 30;
/// Set in a scatter-map entry (a, b), a ≠ b, whose two DOFs share one free
/// index (a DOF and its tie): K_ab + K_ba both land on that diagonal.
const FOLD: u32 = 1 << 29;
const POS: u32 = FOLD - 1;
const TET_LOWER: usize = 78;
/// Lower-triangle entries of one node pair's 6×6 block (s_i, c_i).
const PAIR_LOWER: usize = 21;

/// A DOF that moves as ± another one: u[dof] = sign · u[to] (the cut face
/// of a half-turn half model, u(Rx) = R u(x)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tie {
    pub dof: usize,
    pub to: usize,
    /// +1 or −1.
    pub sign: f64,
}

/// Free/constrained numbering of the global DOFs. A tied DOF shares the free
/// index of the DOF it is tied to, with a sign: the reduced system is
/// Tᵀ K T with u = T u_free, so gathering sums a tie's entries into its
/// free index and scattering copies the free value with the sign.
#[derive(Debug, Clone, PartialEq)]
pub struct DofMap {
    /// Free index of each global DOF, or `u32::MAX` when constrained.
    free: Vec<u32>,
    /// Per global DOF, whether it moves as the negative of its free value
    /// (empty when no DOF is tied).
    negated: Vec<bool>,
    /// The global DOF each free index belongs to (not a tied one).
    owner: Vec<u32>,
    n_free: usize,
}

impl DofMap {
    /// `constrained`: global DOF indices (`3·node + component`), any order, repeats allowed.
    pub fn new(n_nodes: usize, constrained: &[usize]) -> Self {
        Self::with_ties(n_nodes, constrained, &[]).expect("no ties, nothing to refuse")
    }

    /// As [`DofMap::new`], with `ties` between free DOFs. Refuses a tie of a
    /// constrained DOF (the caller constrains both or neither), a tie to a
    /// tied DOF and a DOF tied twice.
    pub fn with_ties(n_nodes: usize, constrained: &[usize], ties: &[Tie]) -> Result<Self, String> {
        const TIED: u32 = u32::MAX - 1;
        let mut free = vec![0u32; 3 * n_nodes];
        for &d in constrained {
            free[d] = NONE;
        }
        for t in ties {
            if t.dof >= free.len() || t.to >= free.len() || t.dof == t.to {
                return Err(format!("tie {} → {}: no such pair of DOFs", t.dof, t.to));
            }
            if free[t.dof] == NONE || free[t.to] == NONE {
                return Err(format!(
                    "tie {} → {}: a constrained DOF cannot be tied (constrain both)",
                    t.dof, t.to
                ));
            }
            if free[t.dof] == TIED {
                return Err(format!("DOF {} is tied twice", t.dof));
            }
            free[t.dof] = TIED;
        }
        let mut owner = Vec::with_capacity(free.len());
        for (d, f) in free.iter_mut().enumerate() {
            if *f == 0 {
                *f = owner.len() as u32;
                owner.push(d as u32);
            }
        }
        let mut negated = if ties.is_empty() {
            Vec::new()
        } else {
            vec![false; free.len()]
        };
        for t in ties {
            if free[t.to] == TIED {
                return Err(format!(
                    "tie {} → {}: the target is itself tied",
                    t.dof, t.to
                ));
            }
            free[t.dof] = free[t.to];
            negated[t.dof] = t.sign < 0.0;
        }
        let n_free = owner.len();
        Ok(Self {
            free,
            negated,
            owner,
            n_free,
        })
    }
    pub fn n_total(&self) -> usize {
        self.free.len()
    }
    pub fn n_free(&self) -> usize {
        self.n_free
    }
    /// Free index of global DOF `d` (its tie's for a tied DOF), if free.
    pub fn free_index(&self, d: usize) -> Option<usize> {
        let f = self.free[d];
        (f != NONE).then_some(f as usize)
    }
    /// Free index and sign of global DOF `d`: u[d] = sign · u_free[index].
    pub fn signed_index(&self, d: usize) -> Option<(usize, f64)> {
        self.free_index(d).map(|f| (f, self.sign(d)))
    }
    /// Free index of `d` when `d` owns it (free and not tied).
    pub fn owned_index(&self, d: usize) -> Option<usize> {
        self.free_index(d).filter(|&f| self.owner[f] as usize == d)
    }
    fn sign(&self, d: usize) -> f64 {
        if self.negated.get(d).copied().unwrap_or(false) {
            -1.0
        } else {
            1.0
        }
    }
    /// Sums the free entries of a global vector of forces into `out`
    /// (length n_free): a tied DOF's entry adds to its free index with its
    /// sign (Tᵀ f).
    pub fn gather(&self, global: &[f64], out: &mut [f64]) {
        if self.negated.is_empty() {
            for (d, &f) in self.free.iter().enumerate() {
                if f != NONE {
                    out[f as usize] = global[d];
                }
            }
            return;
        }
        out.iter_mut().for_each(|v| *v = 0.0);
        for (d, &f) in self.free.iter().enumerate() {
            if f != NONE {
                out[f as usize] += self.sign(d) * global[d];
            }
        }
    }
    /// Adds `scale · free` into the free entries of a global vector (T u).
    pub fn scatter_add(&self, free: &[f64], scale: f64, global: &mut [f64]) {
        for (d, &f) in self.free.iter().enumerate() {
            if f != NONE {
                global[d] += self.sign(d) * scale * free[f as usize];
            }
        }
    }
}

/// Wall time of one evaluation, s.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct EvalTimings {
    /// Constitutive updates and element kernels (parallel).
    pub constitutive: f64,
    /// Scatter of element contributions into the global arrays.
    pub assembly: f64,
}

/// The assembled problem of one mesh: geometry, DOF numbering, sparse pattern
/// and scatter maps. Built once; [`System::evaluate`] refills values.
pub struct System {
    dofs: DofMap,
    /// CSC column pointers of the lower triangle (free DOFs).
    pub col_ptr: Vec<usize>,
    /// CSC row indices (sorted within each column).
    pub row_idx: Vec<usize>,
    tets: Vec<[u32; 4]>,
    tet_geom: Vec<TetGeometry>,
    tet_region: Vec<mesh::Region>,
    tet_map: Vec<[u32; TET_LOWER]>,
    iface_kernels: Vec<InterfaceKernel>,
    /// Indices of the interface elements that carry a law.
    iface_active: Vec<usize>,
    /// Per active element, per node pair, lower entries of its 6×6 block.
    iface_map: Vec<[[u32; PAIR_LOWER]; INTERFACE_POINTS]>,
    /// Element matrix entries coupling a free DOF to a DOF that moves with
    /// the load factor, sorted by tet (for the load column).
    tet_load: Vec<LoadCoupling>,
    /// The same for the node pairs of the active interface elements
    /// (`element` is the index among the active ones).
    pair_load: Vec<LoadCoupling>,
}

/// An element matrix entry K_ab that couples the load factor λ to the
/// system: `weight` · K_ab enters the load column at the free index of a
/// (b moves with λ, weight = rate_b), the load row at the free index of b
/// (a moves with λ, weight = rate_a), or the load diagonal (both move,
/// weight = rate_a rate_b; `free` unused).
#[derive(Debug, Clone, Copy)]
struct LoadCoupling {
    element: u32,
    /// Node pair of an interface element (0 for tets).
    point: u8,
    row: u8,
    col: u8,
    kind: CouplingKind,
    free: u32,
    weight: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum CouplingKind {
    Column,
    Row,
    Diagonal,
}

/// Derivatives with respect to the load factor λ, for path-following: F is
/// the generalised load Σ_a rate_a f_int,a over the DOFs that move with λ.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LoadDerivatives {
    /// ∂f_int/∂λ on the free DOFs, N/m.
    pub column: Vec<f64>,
    /// ∂F/∂u on the free DOFs, N/m.
    pub row: Vec<f64>,
    /// ∂F/∂λ, N/m.
    pub diagonal: f64,
}

impl LoadDerivatives {
    /// Zeroed derivatives for `n_free` free DOFs.
    pub fn new(n_free: usize) -> Self {
        Self {
            column: vec![0.0; n_free],
            row: vec![0.0; n_free],
            diagonal: 0.0,
        }
    }
    fn clear(&mut self) {
        self.column.iter_mut().for_each(|v| *v = 0.0);
        self.row.iter_mut().for_each(|v| *v = 0.0);
        self.diagonal = 0.0;
    }
    fn add(&mut self, e: &LoadCoupling, k: f64) {
        let v = e.weight * k;
        match e.kind {
            CouplingKind::Column => self.column[e.free as usize] += v,
            CouplingKind::Row => self.row[e.free as usize] += v,
            CouplingKind::Diagonal => self.diagonal += v,
        }
    }
}

/// The tangent kind of each element family.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tangents {
    pub bulk: TangentKind,
    pub interface: TangentKind,
}

impl Tangents {
    /// The same kind for tets and interface elements.
    pub fn all(kind: TangentKind) -> Self {
        Self {
            bulk: kind,
            interface: kind,
        }
    }
}

/// What an evaluation writes (every array is overwritten, not added to).
pub struct Outputs<'a> {
    /// Internal forces, global (length 3·nodes), N.
    pub f_int: &'a mut [f64],
    /// Lower-triangle tangent values (N/m): K_ij for i ≥ j in the
    /// system's pattern. An unsymmetric tangent's transposed entries go to
    /// `upper`, if given, else they are dropped.
    pub lower: Option<&'a mut [f64]>,
    /// In the same pattern, the transposed entries: `upper[k]` = K_ji where
    /// `lower[k]` = K_ij (i ≥ j). Together they hold the whole (possibly
    /// unsymmetric) consistent tangent.
    pub upper: Option<&'a mut [f64]>,
    /// The derivatives in the load factor λ: the coupling of the free DOFs
    /// to the constrained ones that move with λ at their rates (see
    /// [`System::new`]). Needs `lower`.
    pub load: Option<&'a mut LoadDerivatives>,
    /// The tets' element matrices kept from an earlier evaluation of the
    /// same step, used and refreshed when the matrix is asked for without
    /// the load derivatives (see [`KeptBulkMatrix`]).
    pub kept_bulk: Option<&'a mut KeptBulkMatrix>,
    /// Which tets' history the evaluation updates into the trial states.
    pub history: TetHistory,
}

/// Which tets' history an evaluation updates into the trial states.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TetHistory {
    /// Every tet's ([`BulkLaw::step`]).
    Updated,
    /// Every tet's but those whose stress and tangent do not depend on it
    /// ([`BulkLaw::history_deferrable`]: IMPL-EX concrete), whose trial
    /// states are left as they are until [`System::update_history`] at the
    /// converged iterate: Newton's iterates skip their eigen-decompositions.
    Deferred,
    /// None: the stresses of [`BulkLaw::stress`], forces only (no matrix).
    Skipped,
}

impl<'a> Outputs<'a> {
    /// Internal forces only.
    pub fn forces(f_int: &'a mut [f64]) -> Self {
        Self {
            f_int,
            lower: None,
            upper: None,
            load: None,
            kept_bulk: None,
            history: TetHistory::Updated,
        }
    }

    /// Internal forces only, from the tets' stresses without their history
    /// ([`TetHistory::Skipped`]).
    pub fn forces_of_stresses(f_int: &'a mut [f64]) -> Self {
        Self {
            history: TetHistory::Skipped,
            ..Self::forces(f_int)
        }
    }
    /// Internal forces and the lower-triangle tangent values.
    pub fn with_matrix(f_int: &'a mut [f64], lower: &'a mut [f64]) -> Self {
        Self {
            lower: Some(lower),
            ..Self::forces(f_int)
        }
    }
}

/// The assembled matrices of the tets whose tangent was fixed by their
/// committed state ([`crate::laws::BulkResponse::fixed_scale`]) at the
/// evaluation that built it, kept between the evaluations of one step: in
/// an IMPL-EX step every concrete tet is such, and so is elastic steel, so
/// after the step's first evaluation only the tets whose tangent moves with
/// the strain are built and scattered again. A kept tet whose tangent stops
/// being the kept one enters as the difference of its two matrices.
///
/// It is rebuilt whenever the start states, the tangent kind, the imposed
/// displacements or the laws differ from those it was built with (a
/// fingerprint of them), so every evaluation of a step sees the same kept
/// sum whatever ran before the step: a resumed run assembles bit for bit
/// what the uninterrupted one did. One per run (or per [`ElementLaws`]).
#[derive(Debug, Default)]
pub struct KeptBulkMatrix {
    fingerprint: Option<u64>,
    /// Sum of the kept tets' matrices in the lower pattern, N/m.
    values: Vec<f64>,
    /// Per tet, the scale its kept matrix was built with; NaN: not kept.
    scale: Vec<f64>,
}

/// What an evaluation does with one tet's element matrix.
#[derive(Debug, Clone, Copy, PartialEq)]
enum TetMatrix {
    /// Into the evaluation's own values.
    Scatter,
    /// Into the kept sum, with its scale.
    Keep(f64),
    /// Already in the kept sum.
    Kept,
}

/// How the tets' matrices are assembled in one evaluation.
#[derive(Debug, Clone, Copy, PartialEq)]
enum MatrixReuse {
    /// No kept sum: every matrix built and scattered.
    Off,
    /// The kept sum is built in this evaluation.
    Build,
    /// The kept sum holds for this evaluation.
    Reuse,
}

impl KeptBulkMatrix {
    /// Number of tets whose matrix is in the kept sum.
    pub fn kept_tets(&self) -> usize {
        self.scale.iter().filter(|s| !s.is_nan()).count()
    }

    /// How this evaluation uses the kept sum: as it is when `fingerprint`
    /// is the one it was built for, else emptied to be built again.
    fn prepare(&mut self, fingerprint: u64, nnz: usize, n_tets: usize) -> MatrixReuse {
        if self.fingerprint == Some(fingerprint) {
            return MatrixReuse::Reuse;
        }
        self.fingerprint = Some(fingerprint);
        self.values.clear();
        self.values.resize(nnz, 0.0);
        self.scale.clear();
        self.scale.resize(n_tets, f64::NAN);
        MatrixReuse::Build
    }

    /// Adds the kept sum to the lower values and to the transposed ones:
    /// the kept matrices are symmetric (scaled elastic stiffnesses).
    fn add_into(&self, lower: &mut [f64], upper: Option<&mut [f64]>) {
        lower
            .par_iter_mut()
            .zip(&self.values)
            .for_each(|(a, b)| *a += b);
        if let Some(up) = upper {
            up.par_iter_mut()
                .zip(&self.values)
                .for_each(|(a, b)| *a += b);
        }
    }
}

/// `Ok` when every value of tet `index`'s `what` is finite.
fn finite(values: &[f64], index: usize, what: &'static str) -> Result<(), AssemblyError> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(AssemblyError::NonFiniteBulk { index, what })
    }
}

/// One tet's element matrix for the response `r` into `k`, unless it is
/// already in the kept sum (`kept`: the scale it was kept with, NaN if
/// not); a kept tet whose tangent has moved gets the difference.
fn tet_matrix(
    g: &TetGeometry,
    law: &AnyBulkLaw,
    r: &crate::laws::BulkResponse,
    reuse: MatrixReuse,
    kept: f64,
    k: &mut [f64; 144],
) -> TetMatrix {
    let action = match reuse {
        MatrixReuse::Off => TetMatrix::Scatter,
        MatrixReuse::Build => r.fixed_scale.map_or(TetMatrix::Scatter, TetMatrix::Keep),
        MatrixReuse::Reuse if r.fixed_scale.map(f64::to_bits) == Some(kept.to_bits()) => {
            return TetMatrix::Kept;
        }
        MatrixReuse::Reuse => TetMatrix::Scatter,
    };
    g.stiffness(&r.tangent, k);
    if reuse == MatrixReuse::Reuse && !kept.is_nan() {
        // Left the kept tangent: its kept matrix comes off.
        let mut k_kept = [0.0; 144];
        g.stiffness(&(law.elastic_stiffness() * kept), &mut k_kept);
        k.iter_mut().zip(&k_kept).for_each(|(a, b)| *a -= b);
    }
    action
}

/// SplitMix64's finaliser over `state ⊕ value`: the fingerprint's mixing.
fn mix(state: u64, value: u64) -> u64 {
    let mut z = state.wrapping_add(0x9E37_79B9_7F4A_7C15) ^ value;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

fn bulk_state_fingerprint(index: usize, s: &BulkState) -> u64 {
    let words = [
        s.kappa.to_bits(),
        s.damage.to_bits(),
        s.explicit_damage.map_or(u64::MAX, f64::to_bits),
        s.kappa_increment.to_bits(),
        s.alpha_t.to_bits(),
    ];
    let h = words
        .iter()
        .chain(&s.plastic_strain.map(f64::to_bits))
        .fold(index as u64, |h, &w| mix(h, w));
    mix(h, index as u64)
}

/// Block size of the parallel constitutive pass (elements).
const BLOCK: usize = 8192;

fn tet_dofs(t: &[u32; 4]) -> [usize; 12] {
    std::array::from_fn(|i| 3 * t[i / 3] as usize + i % 3)
}

fn pair_dofs(nodes: &[u32; 6], p: usize) -> [usize; 6] {
    std::array::from_fn(|i| {
        let node = if i < 3 { nodes[p] } else { nodes[p + 3] };
        3 * node as usize + i % 3
    })
}

impl System {
    /// Builds geometry, pattern and scatter maps. `constrained` as in
    /// [`DofMap::new`]; `load_rates`: the constrained DOFs that move with
    /// the load factor λ and their rates du/dλ (for the load column of
    /// [`Outputs`]); `active_interfaces[i]` tells whether interface element
    /// `i` is assembled.
    pub fn new(
        model: &Model,
        constrained: &[usize],
        load_rates: &[(usize, f64)],
        active_interfaces: &[bool],
    ) -> Result<Self, AssemblyError> {
        Self::with_ties(model, constrained, &[], load_rates, active_interfaces)
    }

    /// As [`System::new`], with `ties` between free DOFs
    /// ([`DofMap::with_ties`]).
    pub fn with_ties(
        model: &Model,
        constrained: &[usize],
        ties: &[Tie],
        load_rates: &[(usize, f64)],
        active_interfaces: &[bool],
    ) -> Result<Self, AssemblyError> {
        check_model(model, active_interfaces)?;
        let dofs = DofMap::with_ties(model.nodes.len(), constrained, ties)
            .map_err(AssemblyError::Model)?;
        let tet_geom = model
            .tets
            .par_iter()
            .enumerate()
            .map(|(index, t)| {
                let x = t.map(|n| model.nodes[n as usize]);
                TetGeometry::new(&x).map_err(|source| AssemblyError::Element { index, source })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let iface_active: Vec<usize> = (0..model.interfaces.len())
            .filter(|&i| active_interfaces[i])
            .collect();
        let (col_ptr, row_idx) = lower_pattern(model, &dofs, &iface_active)?;
        let (tet_map, iface_map) = scatter_maps(model, &dofs, &iface_active, &col_ptr, &row_idx);
        let (tet_load, pair_load) = load_couplings(model, &dofs, &iface_active, load_rates)?;
        Ok(Self {
            tet_load,
            pair_load,
            dofs,
            col_ptr,
            row_idx,
            tets: model.tets.clone(),
            tet_geom,
            tet_region: model.tet_region.clone(),
            tet_map,
            iface_kernels: model.interfaces.iter().map(InterfaceKernel::new).collect(),
            iface_active,
            iface_map,
        })
    }

    pub fn dofs(&self) -> &DofMap {
        &self.dofs
    }
    /// Number of stored (lower-triangle) matrix entries.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }
    pub fn tet_geometry(&self) -> &[TetGeometry] {
        &self.tet_geom
    }

    /// What a [`KeptBulkMatrix`] is valid for: the tets' laws and start
    /// states, the tangent kind and the imposed displacements.
    fn kept_fingerprint(
        &self,
        laws: &ElementLaws,
        start: &States,
        kind: TangentKind,
        u: &[f64],
    ) -> u64 {
        let states = start
            .bulk
            .par_iter()
            .enumerate()
            .map(|(i, s)| bulk_state_fingerprint(i, s))
            .reduce(|| 0, u64::wrapping_add);
        let imposed = (0..self.dofs.n_total())
            .filter(|&d| self.dofs.free_index(d).is_none())
            .fold(0u64, |h, d| mix(h, u[d].to_bits()));
        let identity = mix(laws.tets.as_ptr() as u64, laws.tets.len() as u64);
        mix(mix(mix(states, imposed), identity), kind as u64)
    }

    /// Constitutive update at every integration point for the global
    /// displacement `u` (m, length 3·nodes) from the `start` states: writes
    /// the trial states and what `out` asks for (see [`Outputs`]) with the
    /// tangent kinds `tangents`.
    pub fn evaluate(
        &self,
        laws: &ElementLaws,
        u: &[f64],
        start: &States,
        trial: &mut States,
        tangents: Tangents,
        mut out: Outputs<'_>,
    ) -> Result<EvalTimings, AssemblyError> {
        if out.load.is_some() && out.lower.is_none() {
            return Err(AssemblyError::Model(
                "the load derivatives need the element matrices: ask for the matrix too".into(),
            ));
        }
        if out.history == TetHistory::Skipped && out.lower.is_some() {
            return Err(AssemblyError::Model(
                "an evaluation without the tets' history gives forces only".into(),
            ));
        }
        if let Some(l) = out.load.as_deref_mut() {
            l.clear();
        }
        out.f_int.iter_mut().for_each(|v| *v = 0.0);
        if let Some(m) = out.lower.as_deref_mut() {
            m.iter_mut().for_each(|v| *v = 0.0);
        }
        if let Some(m) = out.upper.as_deref_mut() {
            m.iter_mut().for_each(|v| *v = 0.0);
        }
        let input = Input {
            laws,
            u,
            committed: start,
        };
        let mut timings = EvalTimings::default();
        self.evaluate_tets(&input, tangents.bulk, trial, &mut out, &mut timings)?;
        self.evaluate_interfaces(&input, tangents.interface, trial, &mut out, &mut timings)?;
        Ok(timings)
    }

    /// Completes the trial states that an evaluation with
    /// [`TetHistory::Deferred`] left as they were: each such tet's history
    /// update at the displacement `u` from the `start` states, as
    /// [`BulkLaw::step`] makes it. Returns the time spent (s).
    pub fn update_history(
        &self,
        laws: &ElementLaws,
        u: &[f64],
        start: &States,
        trial: &mut States,
    ) -> Result<f64, AssemblyError> {
        let t = Instant::now();
        trial
            .bulk
            .par_iter_mut()
            .enumerate()
            .try_for_each(|(index, state)| {
                let law = &laws.tets[index];
                let committed = &start.bulk[index];
                if !law.history_deferrable(committed) {
                    return Ok(());
                }
                let strain = self.tet_strain(index, u);
                let r = law
                    .step(committed, &strain, TangentKind::Secant)
                    .map_err(self.bulk_law_error(index))?;
                *state = r.state;
                Ok(())
            })?;
        Ok(t.elapsed().as_secs_f64())
    }

    /// The strain of tet `index` at the displacement `u` (global, m).
    pub(crate) fn tet_strain(&self, index: usize, u: &[f64]) -> Vector6<f64> {
        let d = tet_dofs(&self.tets[index]);
        self.tet_geom[index].strain(&std::array::from_fn(|i| u[d[i]]))
    }

    /// The error of tet `index`'s law `source`, with where it happened.
    fn bulk_law_error(&self, index: usize) -> impl Fn(LawError) -> AssemblyError + '_ {
        move |source| AssemblyError::BulkLaw {
            index,
            region: self.tet_region[index],
            source,
        }
    }

    /// The tets' part of [`System::evaluate`], block by block: parallel
    /// kernels into buffers, serial scatter.
    fn evaluate_tets(
        &self,
        input: &Input<'_>,
        bulk_kind: TangentKind,
        trial: &mut States,
        out: &mut Outputs<'_>,
        timings: &mut EvalTimings,
    ) -> Result<(), AssemblyError> {
        let Input { laws, u, committed } = *input;
        let want_k = out.lower.is_some();
        let history = out.history;
        let f_int = &mut *out.f_int;
        let mut matrix = out.lower.as_deref_mut();
        let mut upper = out.upper.as_deref_mut();
        let mut load = out.load.as_deref_mut();
        let mut kept = out
            .kept_bulk
            .as_deref_mut()
            .filter(|_| want_k && load.is_none());
        let reuse = match kept.as_deref_mut() {
            None => MatrixReuse::Off,
            Some(k) => k.prepare(
                self.kept_fingerprint(laws, committed, bulk_kind, u),
                self.row_idx.len(),
                self.tets.len(),
            ),
        };
        let mut actions = vec![TetMatrix::Scatter; BLOCK.min(self.tets.len())];
        let mut fbuf = vec![[0.0f64; 12]; BLOCK.min(self.tets.len())];
        let mut kbuf = vec![[0.0f64; 144]; if want_k { fbuf.len() } else { 0 }];
        let mut start = 0;
        while start < self.tets.len() {
            let end = (start + BLOCK).min(self.tets.len());
            let len = end - start;
            let t0 = Instant::now();
            let states = &mut trial.bulk[start..end];
            let kslice: &mut [[f64; 144]] = if want_k { &mut kbuf[..len] } else { &mut [] };
            let kept_scale: &[f64] = kept.as_deref().map_or(&[], |k| &k.scale[start..end]);
            let body = |(off, (state, f)): (usize, (&mut BulkState, &mut [f64; 12])),
                        k: Option<(&mut [f64; 144], &mut TetMatrix)>|
             -> Result<(), AssemblyError> {
                let index = start + off;
                let g = &self.tet_geom[index];
                let strain = self.tet_strain(index, u);
                let law_error = self.bulk_law_error(index);
                let law = &laws.tets[index];
                let start = &committed.bulk[index];
                if history == TetHistory::Skipped {
                    let stress = law.stress(start, &strain).map_err(law_error)?;
                    finite(stress.as_slice(), index, "stress")?;
                    g.internal_force(&stress, f);
                    return Ok(());
                }
                let r = if history == TetHistory::Deferred && law.history_deferrable(start) {
                    law.step_without_history(start, &strain, bulk_kind)
                        .map_err(law_error)?
                } else {
                    let r = law.step(start, &strain, bulk_kind).map_err(law_error)?;
                    *state = r.state;
                    r
                };
                finite(r.stress.as_slice(), index, "stress")?;
                g.internal_force(&r.stress, f);
                if let Some((k, action)) = k {
                    finite(r.tangent.as_slice(), index, "tangent")?;
                    let kept = kept_scale.get(off).copied().unwrap_or(f64::NAN);
                    *action = tet_matrix(g, law, &r, reuse, kept, k);
                }
                Ok(())
            };
            if want_k {
                states
                    .par_iter_mut()
                    .zip(fbuf[..len].par_iter_mut())
                    .zip(kslice.par_iter_mut().zip(actions[..len].par_iter_mut()))
                    .enumerate()
                    .try_for_each(|(off, ((s, f), (k, a)))| body((off, (s, f)), Some((k, a))))?;
            } else {
                states
                    .par_iter_mut()
                    .zip(fbuf[..len].par_iter_mut())
                    .enumerate()
                    .try_for_each(|(off, (s, f))| body((off, (s, f)), None))?;
            }
            timings.constitutive += t0.elapsed().as_secs_f64();
            let t1 = Instant::now();
            if let Some(l) = load.as_deref_mut() {
                self.add_tet_load(l, start, &kbuf[..len]);
            }
            for off in 0..len {
                let index = start + off;
                let d = tet_dofs(&self.tets[index]);
                for (i, &di) in d.iter().enumerate() {
                    f_int[di] += fbuf[off][i];
                }
                if let Some(m) = matrix.as_deref_mut() {
                    let map = &self.tet_map[index];
                    match (actions[off], kept.as_deref_mut()) {
                        (TetMatrix::Keep(scale), Some(k)) => {
                            scatter_block::<12>(map, &kbuf[off], &mut k.values, None);
                            k.scale[index] = scale;
                        }
                        (TetMatrix::Kept, _) => {}
                        _ => scatter_block::<12>(map, &kbuf[off], m, upper.as_deref_mut()),
                    }
                }
            }
            timings.assembly += t1.elapsed().as_secs_f64();
            start = end;
        }
        if let (Some(k), Some(m)) = (kept, matrix) {
            let t1 = Instant::now();
            k.add_into(m, upper);
            timings.assembly += t1.elapsed().as_secs_f64();
        }

        Ok(())
    }

    /// The load-derivative entries of the tets from `start` on, whose
    /// element matrices are `kbuf`.
    fn add_tet_load(&self, load: &mut LoadDerivatives, start: usize, kbuf: &[[f64; 144]]) {
        let first = self
            .tet_load
            .partition_point(|e| (e.element as usize) < start);
        for e in self.tet_load[first..]
            .iter()
            .take_while(|e| (e.element as usize) < start + kbuf.len())
        {
            let k = &kbuf[e.element as usize - start];
            load.add(e, k[12 * e.row as usize + e.col as usize]);
        }
    }

    /// The interface elements' part of [`System::evaluate`]: few compared
    /// with tets, one parallel pass.
    fn evaluate_interfaces(
        &self,
        input: &Input<'_>,
        iface_kind: TangentKind,
        trial: &mut States,
        out: &mut Outputs<'_>,
        timings: &mut EvalTimings,
    ) -> Result<(), AssemblyError> {
        let Input { laws, u, committed } = *input;
        let want_k = out.lower.is_some();
        let f_int = &mut *out.f_int;
        let mut matrix = out.lower.as_deref_mut();
        let mut upper = out.upper.as_deref_mut();
        let load = out.load.as_deref_mut();
        let t0 = Instant::now();
        type PairOut = ([f64; 18], [[f64; 36]; INTERFACE_POINTS]);
        let results: Vec<(usize, [InterfaceState; INTERFACE_POINTS], PairOut)> = self
            .iface_active
            .par_iter()
            .map(|&index| {
                let law = laws.interfaces[index].as_ref().ok_or_else(|| {
                    AssemblyError::Model(format!(
                        "interface element {index} is active but has no law"
                    ))
                })?;
                let kern = &self.iface_kernels[index];
                let committed =
                    &committed.interface[INTERFACE_POINTS * index..INTERFACE_POINTS * (index + 1)];
                let points = kern.tractions(law, u, committed, iface_kind).map_err(|e| {
                    AssemblyError::InterfaceLaw {
                        index,
                        point: e.point,
                        source: e.source,
                    }
                })?;
                let mut f = [0.0; 18];
                let mut kpair = [[0.0; 36]; INTERFACE_POINTS];
                let mut st = [InterfaceState::default(); INTERFACE_POINTS];
                for (p, r) in points.iter().enumerate() {
                    let r = &r.law;
                    if !r.traction.iter().all(|v| v.is_finite()) {
                        return Err(AssemblyError::NonFiniteInterface {
                            index,
                            point: p,
                            what: "traction",
                        });
                    }
                    st[p] = r.state;
                    kern.add_force(p, &r.traction, &mut f);
                    if want_k {
                        if !r.tangent.iter().all(|v| v.is_finite()) {
                            return Err(AssemblyError::NonFiniteInterface {
                                index,
                                point: p,
                                what: "tangent",
                            });
                        }
                        kpair[p] = kern.pair_stiffness(&r.tangent);
                    }
                }
                Ok((index, st, (f, kpair)))
            })
            .collect::<Result<_, AssemblyError>>()?;
        timings.constitutive += t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        if let Some(l) = load {
            for e in &self.pair_load {
                let kp = &results[e.element as usize].2 .1[e.point as usize];
                l.add(e, kp[6 * e.row as usize + e.col as usize]);
            }
        }
        for (slot, (index, st, (f, kpair))) in results.into_iter().enumerate() {
            trial.interface[INTERFACE_POINTS * index..INTERFACE_POINTS * (index + 1)]
                .copy_from_slice(&st);
            let nodes = &self.iface_kernels[index].nodes;
            for (i, fi) in f.iter().enumerate() {
                f_int[3 * nodes[i / 3] as usize + i % 3] += fi;
            }
            if let Some(m) = matrix.as_deref_mut() {
                for (map, kp) in self.iface_map[slot].iter().zip(&kpair) {
                    scatter_block::<6>(map, kp, m, upper.as_deref_mut());
                }
            }
        }
        timings.assembly += t1.elapsed().as_secs_f64();
        Ok(())
    }
}

/// What the element kernels read in one evaluation.
#[derive(Clone, Copy)]
struct Input<'a> {
    laws: &'a ElementLaws,
    u: &'a [f64],
    committed: &'a States,
}

/// Refuses a model whose elements reference missing nodes or whose
/// interface activity flags do not match its interface elements.
fn check_model(model: &Model, active_interfaces: &[bool]) -> Result<(), AssemblyError> {
    let n_nodes = model.nodes.len();
    if model.tet_region.len() != model.tets.len() {
        return Err(AssemblyError::Model(format!(
            "{} tets but {} tet regions",
            model.tets.len(),
            model.tet_region.len()
        )));
    }
    for (i, t) in model.tets.iter().enumerate() {
        if t.iter().any(|&n| n as usize >= n_nodes) {
            return Err(AssemblyError::Model(format!(
                "tet {i} references a node ≥ {n_nodes}"
            )));
        }
    }
    for (i, e) in model.interfaces.iter().enumerate() {
        if e.nodes.iter().any(|&n| n as usize >= n_nodes) {
            return Err(AssemblyError::Model(format!(
                "interface element {i} references a node ≥ {n_nodes}"
            )));
        }
    }
    if active_interfaces.len() != model.interfaces.len() {
        return Err(AssemblyError::Model(
            "one activity flag per interface element expected".into(),
        ));
    }
    Ok(())
}

/// The lower-triangle CSC pattern (column pointers, row indices) of the
/// free DOFs coupled by the tets and the active interface node pairs.
fn lower_pattern(
    model: &Model,
    dofs: &DofMap,
    iface_active: &[usize],
) -> Result<(Vec<usize>, Vec<usize>), AssemblyError> {
    let n_nodes = model.nodes.len();
    // The nodes owning a node's free DOFs: itself, or the nodes its tied
    // DOFs move with (their columns hold its couplings).
    let reps = |n: u32| -> [u32; 3] {
        std::array::from_fn(|c| {
            dofs.free_index(3 * n as usize + c)
                .map_or(n, |f| dofs.owner[f] / 3)
        })
    };
    let tied = !dofs.negated.is_empty();
    // Node graph (lower: neighbour ≥ node), from tets and node pairs.
    let mut adj: Vec<Vec<u32>> = vec![Vec::new(); n_nodes];
    let mut link = |a: u32, b: u32| {
        if tied {
            for ra in reps(a) {
                for rb in reps(b) {
                    let (hi, lo) = if ra >= rb { (ra, rb) } else { (rb, ra) };
                    adj[lo as usize].push(hi);
                }
            }
        } else {
            let (hi, lo) = if a >= b { (a, b) } else { (b, a) };
            adj[lo as usize].push(hi);
        }
    };
    for t in &model.tets {
        for &a in t {
            for &b in t {
                if a >= b {
                    link(a, b);
                }
            }
        }
    }
    for &i in iface_active {
        let n = &model.interfaces[i].nodes;
        for p in 0..3 {
            for (a, b) in [(n[p], n[p]), (n[p + 3], n[p + 3]), (n[p], n[p + 3])] {
                link(a, b);
            }
        }
    }
    adj.par_iter_mut().for_each(|v| {
        v.sort_unstable();
        v.dedup();
    });
    let mut col_ptr = Vec::with_capacity(dofs.n_free + 1);
    let mut row_idx = Vec::new();
    col_ptr.push(0);
    for (b, nbrs) in adj.iter().enumerate() {
        for cb in 0..3 {
            let Some(j) = dofs.owned_index(3 * b + cb) else {
                continue;
            };
            for &a in nbrs {
                for ca in 0..3 {
                    if let Some(i) = dofs.owned_index(3 * a as usize + ca) {
                        if i >= j {
                            row_idx.push(i);
                        }
                    }
                }
            }
            col_ptr.push(row_idx.len());
        }
    }
    if row_idx.len() >= POS as usize {
        return Err(AssemblyError::Model(
            "too many matrix entries for 32-bit scatter maps".into(),
        ));
    }
    Ok((col_ptr, row_idx))
}

/// Lower-triangle entries of each element matrix (per tet; per active
/// interface element and node pair) as positions in the pattern.
type ScatterMaps = (
    Vec<[u32; TET_LOWER]>,
    Vec<[[u32; PAIR_LOWER]; INTERFACE_POINTS]>,
);

fn scatter_maps(
    model: &Model,
    dofs: &DofMap,
    iface_active: &[usize],
    col_ptr: &[usize],
    row_idx: &[usize],
) -> ScatterMaps {
    let position = |gi: usize, gj: usize| -> u32 {
        match (dofs.signed_index(gi), dofs.signed_index(gj)) {
            (Some((i, si)), Some((j, sj))) => {
                let (r, c, mut flag) = if i >= j { (i, j, 0) } else { (j, i, SWAP) };
                if si * sj < 0.0 {
                    flag |= NEG;
                }
                if i == j && gi != gj {
                    flag |= FOLD;
                }
                let col = &row_idx[col_ptr[c]..col_ptr[c + 1]];
                let k = col
                    .binary_search(&r)
                    .expect("pattern holds every element entry");
                (col_ptr[c] + k) as u32 | flag
            }
            _ => NONE,
        }
    };
    let tet_map = model
        .tets
        .par_iter()
        .map(|t| {
            let d = tet_dofs(t);
            let mut m = [NONE; TET_LOWER];
            let mut k = 0;
            for a in 0..12 {
                for b in 0..=a {
                    m[k] = position(d[a], d[b]);
                    k += 1;
                }
            }
            m
        })
        .collect();
    let iface_map = iface_active
        .iter()
        .map(|&i| {
            let nodes = &model.interfaces[i].nodes;
            std::array::from_fn(|p| {
                let d = pair_dofs(nodes, p);
                let mut m = [NONE; PAIR_LOWER];
                let mut k = 0;
                for a in 0..6 {
                    for b in 0..=a {
                        m[k] = position(d[a], d[b]);
                        k += 1;
                    }
                }
                m
            })
        })
        .collect();
    (tet_map, iface_map)
}

/// The element matrix entries that couple the load factor to the system
/// (see [`LoadCoupling`]): per tet, and per active interface node pair.
fn load_couplings(
    model: &Model,
    dofs: &DofMap,
    iface_active: &[usize],
    load_rates: &[(usize, f64)],
) -> Result<(Vec<LoadCoupling>, Vec<LoadCoupling>), AssemblyError> {
    let n_nodes = model.nodes.len();
    let mut rate = vec![0.0; 3 * n_nodes];
    for &(d, r) in load_rates {
        if d >= rate.len() || dofs.free_index(d).is_some() {
            return Err(AssemblyError::Model(format!(
                "load rate on DOF {d}, which is not a constrained DOF of the model"
            )));
        }
        rate[d] = r;
    }
    let couplings = |element: usize, point: usize, d: &[usize]| {
        let mut out = Vec::new();
        for (a, &da) in d.iter().enumerate() {
            for (b, &db) in d.iter().enumerate() {
                let (kind, free, weight) = match (dofs.signed_index(da), dofs.signed_index(db)) {
                    (Some((fa, sa)), None) if rate[db] != 0.0 => {
                        (CouplingKind::Column, fa, sa * rate[db])
                    }
                    (None, Some((fb, sb))) if rate[da] != 0.0 => {
                        (CouplingKind::Row, fb, sb * rate[da])
                    }
                    (None, None) if rate[da] != 0.0 && rate[db] != 0.0 => {
                        (CouplingKind::Diagonal, 0, rate[da] * rate[db])
                    }
                    _ => continue,
                };
                out.push(LoadCoupling {
                    element: element as u32,
                    point: point as u8,
                    row: a as u8,
                    col: b as u8,
                    kind,
                    free: free as u32,
                    weight,
                });
            }
        }
        out
    };
    let tet_load = model
        .tets
        .iter()
        .enumerate()
        .flat_map(|(i, t)| couplings(i, 0, &tet_dofs(t)))
        .collect();
    let pair_load = iface_active
        .iter()
        .enumerate()
        .flat_map(|(slot, &i)| {
            (0..INTERFACE_POINTS)
                .flat_map(|p| couplings(slot, p, &pair_dofs(&model.interfaces[i].nodes, p)))
                .collect::<Vec<_>>()
        })
        .collect();
    Ok((tet_load, pair_load))
}

/// Adds a row-major N×N element matrix `k` into the global lower values
/// (and the transposed values `upper`) through the element's lower-triangle
/// scatter map (entries (a, b), a ≥ b, row by row).
fn scatter_block<const N: usize>(
    map: &[u32],
    k: &[f64],
    lower: &mut [f64],
    mut upper: Option<&mut [f64]>,
) {
    let mut c = 0;
    for a in 0..N {
        for b in 0..=a {
            let e = map[c];
            c += 1;
            if e == NONE {
                continue;
            }
            let pos = (e & POS) as usize;
            let (kab, kba) = (k[N * a + b], k[N * b + a]);
            let (mut lo, mut up) = if e & SWAP == 0 {
                (kab, kba)
            } else {
                (kba, kab)
            };
            if e & FOLD != 0 {
                lo = kab + kba;
                up = lo;
            }
            if e & NEG != 0 {
                lo = -lo;
                up = -up;
            }
            lower[pos] += lo;
            if let Some(u) = upper.as_deref_mut() {
                u[pos] += up;
            }
        }
    }
}
