//! Material laws at one point (SPEC §5), each a pure step function:
//! (parameters, committed state, total strain or jump, tangent kind)
//! → (stress or traction, trial state, tangent) or an error the solver can
//! act on (cut the step). History goes in by reference and comes out as a new
//! value; nothing here knows about elements or global indices.
//!
//! Conventions (SI):
//! * Bulk strains and stresses in Voigt order `[xx, yy, zz, xy, yz, xz]`;
//!   strain shear components are *engineering* (γ = 2ε), so that
//!   `σ·ε` is the work density and `B` matrices are the usual ones.
//! * Interface jump `u = (u_n, u_t, u_h)` in the element's local frame,
//!   `u_n > 0` opening; traction `(t_n, t_t, t_h)` in Pa.

mod contract;
pub mod coulomb;
pub mod elastic;
pub mod fczm;
pub mod j2;
pub mod mazars;
pub mod tvergaard;

pub use contract::*;

use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

/// Any interface law of SPEC §5, dispatched at run time (one per interface group).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "law", rename_all = "snake_case")]
pub enum AnyInterfaceLaw {
    Fczm(fczm::Fczm),
    Tvergaard(tvergaard::Tvergaard),
    Coulomb(coulomb::Coulomb),
    Elastic(elastic::ElasticInterface),
}

impl AnyInterfaceLaw {
    /// The non-adhesive "contact" option of SPEC §2: no tension, no friction,
    /// normal stiffness `normal_stiffness` (N/m³) in compression. It is the
    /// FCZM with D = 1 and μ = 0; the cohesive parameters then play no role
    /// and are set to harmless values.
    pub fn contact(normal_stiffness: f64) -> Self {
        AnyInterfaceLaw::Fczm(fczm::Fczm::contact(normal_stiffness))
    }

    /// Short name of the law (as written in specs).
    pub fn name(&self) -> &'static str {
        match self {
            AnyInterfaceLaw::Fczm(_) => "fczm",
            AnyInterfaceLaw::Tvergaard(_) => "tvergaard",
            AnyInterfaceLaw::Coulomb(_) => "coulomb",
            AnyInterfaceLaw::Elastic(_) => "elastic",
        }
    }
}

impl InterfaceLaw for AnyInterfaceLaw {
    fn respond(
        &self,
        committed: &InterfaceState,
        jump: &Vector3<f64>,
        kind: TangentKind,
        evolve: bool,
    ) -> Result<InterfaceResponse, LawError> {
        match self {
            AnyInterfaceLaw::Fczm(l) => l.respond(committed, jump, kind, evolve),
            AnyInterfaceLaw::Tvergaard(l) => l.respond(committed, jump, kind, evolve),
            AnyInterfaceLaw::Coulomb(l) => l.respond(committed, jump, kind, evolve),
            AnyInterfaceLaw::Elastic(l) => l.respond(committed, jump, kind, evolve),
        }
    }

    fn extrapolate(&self, committed: &InterfaceState, ratio: f64) -> InterfaceState {
        match self {
            AnyInterfaceLaw::Fczm(l) => l.extrapolate(committed, ratio),
            AnyInterfaceLaw::Tvergaard(l) => l.extrapolate(committed, ratio),
            AnyInterfaceLaw::Coulomb(l) => l.extrapolate(committed, ratio),
            AnyInterfaceLaw::Elastic(l) => l.extrapolate(committed, ratio),
        }
    }

    fn stored_energy(
        &self,
        state: &InterfaceState,
        jump: &Vector3<f64>,
        traction: &Vector3<f64>,
    ) -> f64 {
        match self {
            AnyInterfaceLaw::Fczm(l) => l.stored_energy(state, jump, traction),
            AnyInterfaceLaw::Tvergaard(l) => l.stored_energy(state, jump, traction),
            AnyInterfaceLaw::Coulomb(l) => l.stored_energy(state, jump, traction),
            AnyInterfaceLaw::Elastic(l) => l.stored_energy(state, jump, traction),
        }
    }

    fn elastic_stiffness(&self) -> Matrix3<f64> {
        match self {
            AnyInterfaceLaw::Fczm(l) => l.elastic_stiffness(),
            AnyInterfaceLaw::Tvergaard(l) => l.elastic_stiffness(),
            AnyInterfaceLaw::Coulomb(l) => l.elastic_stiffness(),
            AnyInterfaceLaw::Elastic(l) => l.elastic_stiffness(),
        }
    }
}

/// Any bulk law of SPEC §5, dispatched at run time (one per element).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "law", rename_all = "snake_case")]
pub enum AnyBulkLaw {
    Mazars(mazars::Mazars),
    J2(j2::J2),
    Elastic(elastic::LinearElastic),
}

impl BulkLaw for AnyBulkLaw {
    fn step(
        &self,
        committed: &BulkState,
        strain: &Vector6<f64>,
        kind: TangentKind,
    ) -> Result<BulkResponse, LawError> {
        match self {
            AnyBulkLaw::Mazars(l) => l.step(committed, strain, kind),
            AnyBulkLaw::J2(l) => l.step(committed, strain, kind),
            AnyBulkLaw::Elastic(l) => l.step(committed, strain, kind),
        }
    }

    fn history_deferrable(&self, committed: &BulkState) -> bool {
        match self {
            AnyBulkLaw::Mazars(l) => l.history_deferrable(committed),
            AnyBulkLaw::J2(l) => l.history_deferrable(committed),
            AnyBulkLaw::Elastic(l) => l.history_deferrable(committed),
        }
    }

    fn step_without_history(
        &self,
        committed: &BulkState,
        strain: &Vector6<f64>,
        kind: TangentKind,
    ) -> Result<BulkResponse, LawError> {
        match self {
            AnyBulkLaw::Mazars(l) => l.step_without_history(committed, strain, kind),
            AnyBulkLaw::J2(l) => l.step_without_history(committed, strain, kind),
            AnyBulkLaw::Elastic(l) => l.step_without_history(committed, strain, kind),
        }
    }

    fn elastic_stiffness(&self) -> Matrix6<f64> {
        match self {
            AnyBulkLaw::Mazars(l) => l.stiffness(),
            AnyBulkLaw::J2(l) => l.stiffness(),
            AnyBulkLaw::Elastic(l) => l.stiffness(),
        }
    }

    fn extrapolate(&self, committed: &BulkState, ratio: f64) -> BulkState {
        match self {
            AnyBulkLaw::Mazars(l) => l.extrapolate(committed, ratio),
            AnyBulkLaw::J2(l) => l.extrapolate(committed, ratio),
            AnyBulkLaw::Elastic(l) => l.extrapolate(committed, ratio),
        }
    }

    fn yield_stress(&self) -> Option<f64> {
        match self {
            AnyBulkLaw::J2(l) => l.yield_stress(),
            _ => None,
        }
    }

    fn stored_energy(
        &self,
        state: &BulkState,
        strain: &Vector6<f64>,
        stress: &Vector6<f64>,
    ) -> f64 {
        match self {
            AnyBulkLaw::Mazars(l) => l.stored_energy(state, strain, stress),
            AnyBulkLaw::J2(l) => l.stored_energy(state, strain, stress),
            AnyBulkLaw::Elastic(l) => l.stored_energy(state, strain, stress),
        }
    }
}

macro_rules! law_into_any {
    ($any:ident { $($variant:ident($ty:ty)),+ $(,)? }) => {
        $(impl From<$ty> for $any {
            fn from(law: $ty) -> Self {
                $any::$variant(law)
            }
        })+
    };
}

law_into_any!(AnyBulkLaw {
    Mazars(mazars::Mazars),
    J2(j2::J2),
    Elastic(elastic::LinearElastic),
});
law_into_any!(AnyInterfaceLaw {
    Fczm(fczm::Fczm),
    Tvergaard(tvergaard::Tvergaard),
    Coulomb(coulomb::Coulomb),
    Elastic(elastic::ElasticInterface),
});
