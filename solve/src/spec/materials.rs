//! The scene's `materials` section (SPEC §5): raw as written, resolved to SI
//! laws with defaults and bounds. Keys and defaults are listed in
//! `specs/README.md` under `## materials`.
//!
//! ```
//! use solve::spec::materials::{RawMaterials, ConcreteModel};
//! let raw: RawMaterials = serde_yaml::from_str(r#"
//! concrete: {law: mazars, E: "30 GPa", nu: 0.2, ft: "3 MPa", Gf: "130 N/m"}
//! interface: {law: fczm, delta_s: 0.16}
//! "#).unwrap();
//! let m = raw.resolve().unwrap();
//! let ConcreteModel::Mazars(c) = &m.concrete else { panic!() };
//! let element_law = c.at_size(0.4e-3).unwrap(); // per element, l from eq. (11)
//! # let _ = element_law;
//! ```

use crate::assembly::ElementLaws;
use crate::laws::coulomb::Coulomb;
use crate::laws::elastic::{ElasticInterface, LinearElastic};
use crate::laws::fczm::{Fczm, DEFAULT_GAMMA};
use crate::laws::j2::J2;
use crate::laws::mazars::{
    CompressionSoftening, MazarsMaterial, MazarsSizeError, TensionSoftening, DEFAULT_EPS_D0,
    DEFAULT_SHEAR_EXPONENT,
};
use crate::laws::tvergaard::Tvergaard;
use crate::laws::{AnyBulkLaw, AnyInterfaceLaw};
use geom::units::{Dim, RawQuantity, UnitError};
use mesh::Model;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Calibration ratio ξ of eqs. (27)–(28).
pub const DEFAULT_XI: f64 = 0.72;
/// Calibrated interface damage threshold λ_0, m (Table 4).
pub const DEFAULT_LAMBDA0: f64 = 5e-5;
/// Calibrated friction coefficient μ (Table 4).
pub const DEFAULT_MU: f64 = 0.3;
/// Calibrated ζ of eq. (22) (§3.3).
pub const DEFAULT_ZETA: f64 = 8.0;
/// Default half-width of the FCZM's smoothed contact switch, m (0: sharp).
pub const DEFAULT_CONTACT_SMOOTHING: f64 = 0.0;

/// δ_s from eq. (29): 1 − 0.3889e-6 f_t, f_t the interface strength in Pa.
pub fn delta_s_eq29(ft: f64) -> f64 {
    1.0 - 0.3889e-6 * ft
}

/// A materials spec error; `key` is the dotted spec path.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MaterialsSpecError {
    #[error(transparent)]
    Unit(#[from] UnitError),
    #[error("{key}: missing (required by law {law})")]
    Missing { key: String, law: String },
    #[error("{key}: {value} is out of range: must be {bound}")]
    OutOfRange {
        key: String,
        value: f64,
        bound: String,
    },
    #[error("{key}: unknown law {law:?} (accepted: {accepted})")]
    UnknownLaw {
        key: String,
        law: String,
        accepted: String,
    },
    #[error("{key}: not a parameter of law {law}")]
    NotForLaw { key: String, law: String },
    #[error("{key}: {detail}")]
    Inconsistent { key: String, detail: String },
}

// Every field of the raw types below documents itself for the scene
// reference and the JSON Schema (`ribbar schema scene`): its meaning, then
// `(unit; default …; bounds)` as the last parenthesis of its doc comment.

/// `materials.concrete` as written: Mazars damage (paper §2.3; the elastic
/// law reads only `E` and `nu`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawConcrete {
    /// The concrete's law (choice; default mazars).
    #[schemars(schema_with = "law_schema::<ConcreteLaw>")]
    pub law: Option<String>,
    /// Young's modulus (stress; default 30 GPa; > 0).
    #[serde(rename = "E")]
    pub young_modulus: Option<RawQuantity>,
    /// Poisson's ratio (pure number; default 0.2; in (−1, 0.5)).
    pub nu: Option<RawQuantity>,
    /// Tensile strength; sets ε_D0 = ft / E; give `ft` or `eps_d0`, not both
    /// (stress; default E ε_D0 = 3 MPa; > 0).
    pub ft: Option<RawQuantity>,
    /// Damage threshold ε_D0 (pure number; default 1e-4; > 0).
    pub eps_d0: Option<RawQuantity>,
    /// Shear exponent β of eq. (4) (pure number; default 1.06; > 0).
    pub beta: Option<RawQuantity>,
    /// Fracture energy: Hillerborg tension softening (eq. 9), B_t per
    /// element from its size l (eq. 11); an element too large for it
    /// (l ≥ 2 G_f / (E ε_D0²)) is an error at solve time naming l and the
    /// limit (energy per area; default 130 N/m; > 0).
    #[serde(rename = "Gf")]
    pub gf: Option<RawQuantity>,
    /// A_t of the classic tension softening (eq. 5) instead of `Gf`; needs
    /// `Bt` (pure number; default none; in [0, 1]).
    #[serde(rename = "At")]
    pub a_t: Option<RawQuantity>,
    /// B_t of the classic tension softening (eq. 5) instead of `Gf`; needs
    /// `At` (pure number; default none; > 0).
    #[serde(rename = "Bt")]
    pub b_t: Option<RawQuantity>,
    /// A_c of the compression softening (eq. 5); needs `Bc` (pure number;
    /// default: per element from eqs. (12)–(13); ≥ 0).
    #[serde(rename = "Ac")]
    pub a_c: Option<RawQuantity>,
    /// B_c of the compression softening (eq. 5); needs `Ac` (pure number;
    /// default: per element from eqs. (12)–(13); > 0).
    #[serde(rename = "Bc")]
    pub b_c: Option<RawQuantity>,
    /// The length l of eqs. (11)–(13) for every tet: one law for the whole
    /// concrete, G_f / l dissipated per volume of a damage zone on any mesh,
    /// for mesh-convergence studies where the damage spreads over many
    /// elements. Mazars only; must admit `Gf`, l < 2 G_f / (E ε_D0²)
    /// (length; default: each tet's own size, as the paper; > 0).
    pub regularisation_length: Option<RawQuantity>,
    /// Internal length ℓ of a gradient-enhanced damage: κ follows the
    /// equivalent strain averaged by ε̄ − ℓ²∇²ε̄ = ε_eq, so a damage zone's
    /// width is set by ℓ, not by the elements. Mazars only; needs
    /// `regularisation_length`; runs only with IMPL-EX concrete, which it
    /// takes where `solver.concrete_integration` is unset; resolve ℓ with
    /// h ≲ ℓ where the concrete damages (length; default none: each point's
    /// own strain, as the paper; > 0).
    pub nonlocal_length: Option<RawQuantity>,
    /// Mean compressive strength f_cm, for the design code's bond law that
    /// post draws beside the curve; the solve does not read it (stress;
    /// default from the Mazars tensile strength by MC2010's f_ctm; > 0).
    pub fcm: Option<RawQuantity>,
}

/// `materials.steel` as written.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawSteel {
    /// The steel's law: von Mises perfectly plastic (`j2`) or `elastic`
    /// (choice; default j2).
    #[schemars(schema_with = "law_schema::<SteelLaw>")]
    pub law: Option<String>,
    /// Young's modulus (stress; default 200 GPa; > 0).
    #[serde(rename = "E")]
    pub young_modulus: Option<RawQuantity>,
    /// Poisson's ratio (pure number; default 0.3; in (−1, 0.5)).
    pub nu: Option<RawQuantity>,
    /// Yield stress, `j2` only (stress; default 365 MPa; > 0).
    pub sigma_y: Option<RawQuantity>,
}

/// `materials.interface` as written: the law of the adhesive zone.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawInterface {
    /// The interface's law: the frictional cohesive zone (`fczm`, §3.1),
    /// `tvergaard` (Appendix A), `coulomb` (Appendix B) or `elastic`
    /// (choice; default fczm).
    #[schemars(schema_with = "law_schema::<InterfaceLawChoice>")]
    pub law: Option<String>,
    /// Interface tensile strength (eq. 27); fczm, tvergaard, coulomb (for
    /// coulomb required, 0 ≤ ft ≤ C / tan φ) (stress; default ξ f_t of a
    /// Mazars concrete; > 0).
    pub ft: Option<RawQuantity>,
    /// Interface fracture energy (eq. 28); fczm, tvergaard (energy per area;
    /// default ξ G_f of a Mazars concrete with `Gf`; > 0).
    #[serde(rename = "Gf")]
    pub gf: Option<RawQuantity>,
    /// Damage threshold λ_0, K_n = ft / λ_0 (A.7); fczm, tvergaard (length;
    /// default 5e-5 m; > 0).
    pub lambda0: Option<RawQuantity>,
    /// Stiffness ratio K_n / K_s; fczm, tvergaard (pure number; default
    /// eq. (29), 1 − 0.3889e-6 ft in Pa; > 0).
    pub delta_s: Option<RawQuantity>,
    /// Friction coefficient; fczm (pure number; default 0.3; ≥ 0).
    pub mu: Option<RawQuantity>,
    /// ζ of eq. (22); fczm (pure number; default 8; > 0).
    pub zeta: Option<RawQuantity>,
    /// γ of eq. (26), a compressive stress; fczm (stress; default −1 MPa;
    /// < 0).
    pub gamma: Option<RawQuantity>,
    /// Half-width δ of a quadratic smoothing of the open/closed contact
    /// switch, eqs. (16), (25), (26), over |u_n| < δ; 0 is the paper's sharp
    /// switch; fczm (length; default 0; in [0, lambda0)).
    pub contact_smoothing: Option<RawQuantity>,
    /// Calibration ratio ξ of eqs. (27)–(28), used only for `ft` and `Gf`
    /// not given; fczm, tvergaard (pure number; default 0.72; in (0, 1]).
    pub xi: Option<RawQuantity>,
    /// Normal stiffness; coulomb, elastic (stiffness per area; required by
    /// those laws; > 0).
    #[serde(rename = "Kn")]
    pub kn: Option<RawQuantity>,
    /// Shear stiffness; coulomb, elastic (stiffness per area; required by
    /// those laws; > 0).
    #[serde(rename = "Ks")]
    pub ks: Option<RawQuantity>,
    /// Cohesion; coulomb (stress; required by coulomb; > 0).
    #[serde(rename = "C")]
    pub cohesion: Option<RawQuantity>,
    /// Friction angle; coulomb (angle; required by coulomb; in [0, 90°)).
    pub phi: Option<RawQuantity>,
}

/// The `materials` section as written.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawMaterials {
    /// The concrete: Mazars damage or elastic.
    #[serde(default)]
    pub concrete: RawConcrete,
    /// The steel bar: J2 plasticity or elastic.
    #[serde(default)]
    pub steel: RawSteel,
    /// The steel/concrete interface of the bonded zone.
    #[serde(default)]
    pub interface: RawInterface,
}

/// Resolved concrete.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "law", rename_all = "snake_case")]
pub enum ConcreteModel {
    Mazars(MazarsMaterial),
    Elastic(LinearElastic),
}

impl ConcreteModel {
    /// The law of an element of characteristic size `l` (m, eq. 11).
    pub fn at_size(&self, l: f64) -> Result<AnyBulkLaw, MazarsSizeError> {
        match self {
            ConcreteModel::Mazars(m) => m.at_size(l).map(AnyBulkLaw::Mazars),
            ConcreteModel::Elastic(e) => Ok(AnyBulkLaw::Elastic(*e)),
        }
    }
}

/// Resolved steel.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "law", rename_all = "snake_case")]
pub enum SteelModel {
    J2(J2),
    Elastic(LinearElastic),
}

impl SteelModel {
    pub fn law(&self) -> AnyBulkLaw {
        match self {
            SteelModel::J2(j) => AnyBulkLaw::J2(*j),
            SteelModel::Elastic(e) => AnyBulkLaw::Elastic(*e),
        }
    }
}

/// Resolved interface of the adhesive zone (explicit or calibrated values).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct InterfaceModel {
    pub law: AnyInterfaceLaw,
}

impl InterfaceModel {
    /// The no-tension frictionless contact (SPEC §2 option for the
    /// non-adhesive zone) with the adhesive law's normal stiffness K_n.
    pub fn contact_law(&self) -> AnyInterfaceLaw {
        use crate::laws::InterfaceLaw;
        AnyInterfaceLaw::contact(self.law.elastic_stiffness()[(0, 0)])
    }
}

/// The resolved `materials` section (SI).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Materials {
    pub concrete: ConcreteModel,
    pub steel: SteelModel,
    pub interface: InterfaceModel,
    /// `materials.concrete.fcm`, Pa: read by post alone (the design code's
    /// bond law), so it is kept out of the concrete law and out of the
    /// serialised scene when not given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub concrete_fcm: Option<f64>,
}

/// What the interface of the non-adhesive zone z ∈ [l_adh, L] does
/// (`specimen.non_adhesive`: the geometry is the same either way, only the
/// law the solver puts there differs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum NonAdhesive {
    /// Duplicated nodes and no interface element: no interaction at all.
    #[default]
    Free,
    /// No-tension, frictionless contact interface.
    Contact,
}

/// A concrete tet whose size the concrete law cannot be regularised for.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("materials.concrete: concrete tet {tet} (size l = {size_mm:.3} mm): {source}")]
pub struct ElementLawError {
    pub tet: usize,
    pub size_mm: f64,
    #[source]
    pub source: MazarsSizeError,
}

impl Materials {
    /// The law of every element of `model`: concrete per tet size (eq. 11),
    /// steel, the adhesive interface law, and in the non-adhesive zone
    /// nothing (`free`) or the contact law (`contact`).
    pub fn element_laws(
        &self,
        model: &Model,
        non_adhesive: NonAdhesive,
    ) -> Result<ElementLaws, ElementLawError> {
        let free = match non_adhesive {
            NonAdhesive::Free => None,
            NonAdhesive::Contact => Some(self.interface.contact_law()),
        };
        ElementLaws::sized(
            model,
            |l| self.concrete.at_size(l),
            self.steel.law(),
            self.interface.law,
            free,
        )
        .map(|laws| ElementLaws {
            nonlocal_length: match self.concrete {
                ConcreteModel::Mazars(m) => m.nonlocal_length,
                ConcreteModel::Elastic(_) => None,
            },
            ..laws
        })
        .map_err(|(tet, source)| ElementLawError {
            tet,
            size_mm: model.tet_size.get(tet).copied().unwrap_or(f64::NAN) * 1e3,
            source,
        })
    }
}

/// Reads optional quantities under a dotted prefix.
pub(crate) struct Keys<'a> {
    pub prefix: &'a str,
    pub law: &'a str,
}

impl Keys<'_> {
    pub fn key(&self, name: &str) -> String {
        format!("{}.{name}", self.prefix)
    }
    fn get(
        &self,
        q: &Option<RawQuantity>,
        name: &str,
        dim: Dim,
    ) -> Result<Option<f64>, MaterialsSpecError> {
        q.as_ref()
            .map(|q| q.to_si(dim, &self.key(name)))
            .transpose()
            .map_err(Into::into)
    }
    fn req(
        &self,
        q: &Option<RawQuantity>,
        name: &str,
        dim: Dim,
    ) -> Result<f64, MaterialsSpecError> {
        self.get(q, name, dim)?
            .ok_or_else(|| MaterialsSpecError::Missing {
                key: self.key(name),
                law: self.law.to_string(),
            })
    }
    fn not_for(&self, set: &[(&str, bool)]) -> Result<(), MaterialsSpecError> {
        match set.iter().find(|(_, present)| *present) {
            Some((name, _)) => Err(MaterialsSpecError::NotForLaw {
                key: self.key(name),
                law: self.law.to_string(),
            }),
            None => Ok(()),
        }
    }
    fn check(
        &self,
        name: &str,
        value: f64,
        ok: bool,
        bound: &str,
    ) -> Result<f64, MaterialsSpecError> {
        if ok {
            Ok(value)
        } else {
            Err(MaterialsSpecError::OutOfRange {
                key: self.key(name),
                value,
                bound: bound.to_string(),
            })
        }
    }
    fn positive(&self, name: &str, v: f64) -> Result<f64, MaterialsSpecError> {
        self.check(name, v, v > 0.0, "> 0")
    }
    fn poisson(&self, v: f64) -> Result<f64, MaterialsSpecError> {
        self.check("nu", v, v > -1.0 && v < 0.5, "in (-1, 0.5)")
    }
}

/// The laws a material section accepts (`law:`), by their spec names;
/// the first is the default.
trait LawChoice: Copy + Sized + 'static {
    const ACCEPTED: &'static [Self];
    fn name(self) -> &'static str;
}

macro_rules! law_choice {
    ($(#[$doc:meta])* $ty:ident { $($variant:ident => $name:literal),+ $(,)? }) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        enum $ty { $($variant),+ }
        impl LawChoice for $ty {
            const ACCEPTED: &'static [Self] = &[$($ty::$variant),+];
            fn name(self) -> &'static str {
                match self { $($ty::$variant => $name),+ }
            }
        }
    };
}

law_choice!(
    /// `materials.concrete.law`.
    ConcreteLaw { Mazars => "mazars", Elastic => "elastic" }
);
law_choice!(
    /// `materials.steel.law`.
    SteelLaw { J2 => "j2", Elastic => "elastic" }
);
law_choice!(
    /// `materials.interface.law`.
    InterfaceLawChoice { Fczm => "fczm", Tvergaard => "tvergaard", Coulomb => "coulomb", Elastic => "elastic" }
);

/// The law `raw` names (the default when absent), or an error listing the
/// accepted ones.
fn law_kind<L: LawChoice>(raw: &Option<String>, prefix: &str) -> Result<L, MaterialsSpecError> {
    let Some(name) = raw else {
        return Ok(L::ACCEPTED[0]);
    };
    L::ACCEPTED
        .iter()
        .copied()
        .find(|k| k.name() == name)
        .ok_or_else(|| MaterialsSpecError::UnknownLaw {
            key: format!("{prefix}.law"),
            law: name.clone(),
            accepted: L::ACCEPTED
                .iter()
                .map(|k| k.name())
                .collect::<Vec<_>>()
                .join(", "),
        })
}

/// The schema of a `law:` key: one of the law choice's names (absent or
/// null for its default).
fn law_schema<L: LawChoice>(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
    let mut names: Vec<serde_json::Value> = L::ACCEPTED.iter().map(|k| k.name().into()).collect();
    names.push(serde_json::Value::Null);
    schemars::json_schema!({ "enum": names })
}

/// Resolves `raw` as concrete under `prefix` (e.g. `materials.concrete`).
pub fn resolve_concrete(
    raw: &RawConcrete,
    prefix: &str,
) -> Result<ConcreteModel, MaterialsSpecError> {
    let law = law_kind::<ConcreteLaw>(&raw.law, prefix)?;
    let k = Keys {
        prefix,
        law: law.name(),
    };
    let e = k.positive(
        "E",
        k.get(&raw.young_modulus, "E", Dim::Stress)?.unwrap_or(30e9),
    )?;
    let nu = k.poisson(k.get(&raw.nu, "nu", Dim::Dimensionless)?.unwrap_or(0.2))?;
    if law == ConcreteLaw::Elastic {
        k.not_for(&[
            ("ft", raw.ft.is_some()),
            ("eps_d0", raw.eps_d0.is_some()),
            ("beta", raw.beta.is_some()),
            ("Gf", raw.gf.is_some()),
            ("At", raw.a_t.is_some()),
            ("Bt", raw.b_t.is_some()),
            ("Ac", raw.a_c.is_some()),
            ("Bc", raw.b_c.is_some()),
            ("regularisation_length", raw.regularisation_length.is_some()),
            ("nonlocal_length", raw.nonlocal_length.is_some()),
        ])?;
        return Ok(ConcreteModel::Elastic(LinearElastic {
            young_modulus: e,
            poisson_ratio: nu,
        }));
    }
    let eps_d0 = match (
        k.get(&raw.ft, "ft", Dim::Stress)?,
        k.get(&raw.eps_d0, "eps_d0", Dim::Dimensionless)?,
    ) {
        (Some(_), Some(_)) => {
            return Err(MaterialsSpecError::Inconsistent {
                key: k.key("eps_d0"),
                detail: "give ft or eps_d0 (= ft/E), not both".into(),
            })
        }
        (Some(ft), None) => k.positive("ft", ft)? / e,
        (None, Some(e0)) => k.positive("eps_d0", e0)?,
        (None, None) => DEFAULT_EPS_D0,
    };
    let beta = k.positive(
        "beta",
        k.get(&raw.beta, "beta", Dim::Dimensionless)?
            .unwrap_or(DEFAULT_SHEAR_EXPONENT),
    )?;
    let tension = if raw.a_t.is_some() || raw.b_t.is_some() {
        k.not_for(&[("Gf", raw.gf.is_some())])
            .map_err(|_| MaterialsSpecError::Inconsistent {
                key: k.key("Gf"),
                detail: "give Gf (regularised tension) or At and Bt (classic), not both".into(),
            })?;
        let a_t = k.req(&raw.a_t, "At", Dim::Dimensionless)?;
        let a_t = k.check("At", a_t, (0.0..=1.0).contains(&a_t), "in [0, 1]")?;
        let b_t = k.positive("Bt", k.req(&raw.b_t, "Bt", Dim::Dimensionless)?)?;
        TensionSoftening::Classic { a_t, b_t }
    } else {
        let gf = k.positive(
            "Gf",
            k.get(&raw.gf, "Gf", Dim::EnergyPerArea)?.unwrap_or(130.0),
        )?;
        TensionSoftening::Regularised {
            fracture_energy: gf,
        }
    };
    let compression = if raw.a_c.is_some() || raw.b_c.is_some() {
        let a_c = k.req(&raw.a_c, "Ac", Dim::Dimensionless)?;
        let a_c = k.check("Ac", a_c, a_c >= 0.0, ">= 0")?;
        let b_c = k.positive("Bc", k.req(&raw.b_c, "Bc", Dim::Dimensionless)?)?;
        CompressionSoftening::Classic { a_c, b_c }
    } else {
        CompressionSoftening::SizeFit
    };
    let (regularisation_length, nonlocal_length) = mazars_lengths(&k, raw)?;
    let material = MazarsMaterial {
        young_modulus: e,
        poisson_ratio: nu,
        eps_d0,
        shear_exponent: beta,
        tension,
        compression,
        regularisation_length,
        nonlocal_length,
    };
    // A fixed length must admit the law (the element sizes are checked
    // per tet when the mesh is known).
    if let Some(l) = regularisation_length {
        material
            .at_size(l)
            .map_err(|e| MaterialsSpecError::Inconsistent {
                key: k.key("regularisation_length"),
                detail: e.to_string(),
            })?;
    }
    Ok(ConcreteModel::Mazars(material))
}

/// Mazars' `regularisation_length` and `nonlocal_length`, m.
fn mazars_lengths(
    k: &Keys<'_>,
    raw: &RawConcrete,
) -> Result<(Option<f64>, Option<f64>), MaterialsSpecError> {
    let length = |value: &Option<RawQuantity>, name: &str| {
        k.get(value, name, Dim::Length)?
            .map(|l| k.positive(name, l))
            .transpose()
    };
    let regularisation_length = length(&raw.regularisation_length, "regularisation_length")?;
    let nonlocal_length = length(&raw.nonlocal_length, "nonlocal_length")?;
    // An averaged damage zone is as wide as the length makes it, not one
    // element: the element-size law would change its energy per volume
    // with the mesh.
    if nonlocal_length.is_some() && regularisation_length.is_none() {
        return Err(MaterialsSpecError::Inconsistent {
            key: k.key("nonlocal_length"),
            detail: "needs regularisation_length (the width the softening law's energy \
                     per volume is set for), not each tet's own size"
                .into(),
        });
    }
    Ok((regularisation_length, nonlocal_length))
}

/// Resolves `raw` as steel under `prefix`.
pub fn resolve_steel(raw: &RawSteel, prefix: &str) -> Result<SteelModel, MaterialsSpecError> {
    let law = law_kind::<SteelLaw>(&raw.law, prefix)?;
    let k = Keys {
        prefix,
        law: law.name(),
    };
    let e = k.positive(
        "E",
        k.get(&raw.young_modulus, "E", Dim::Stress)?
            .unwrap_or(200e9),
    )?;
    let nu = k.poisson(k.get(&raw.nu, "nu", Dim::Dimensionless)?.unwrap_or(0.3))?;
    if law == SteelLaw::Elastic {
        k.not_for(&[("sigma_y", raw.sigma_y.is_some())])?;
        return Ok(SteelModel::Elastic(LinearElastic {
            young_modulus: e,
            poisson_ratio: nu,
        }));
    }
    let sy = k.positive(
        "sigma_y",
        k.get(&raw.sigma_y, "sigma_y", Dim::Stress)?
            .unwrap_or(365e6),
    )?;
    Ok(SteelModel::J2(J2 {
        young_modulus: e,
        poisson_ratio: nu,
        yield_stress: sy,
    }))
}

/// Resolves `raw` as the interface under `prefix`; `concrete` (if any) feeds
/// the calibration rule f_t = ξ f_t,con, G_f = ξ G_f,con (eqs. 27–28) for
/// values not given.
pub fn resolve_interface(
    raw: &RawInterface,
    concrete: Option<&ConcreteModel>,
    prefix: &str,
) -> Result<InterfaceModel, MaterialsSpecError> {
    let kind = law_kind::<InterfaceLawChoice>(&raw.law, prefix)?;
    let k = Keys {
        prefix,
        law: kind.name(),
    };
    let law = match kind {
        InterfaceLawChoice::Fczm | InterfaceLawChoice::Tvergaard => {
            cohesive_interface(raw, concrete, &k, kind)?
        }
        InterfaceLawChoice::Coulomb => coulomb_interface(raw, &k)?,
        InterfaceLawChoice::Elastic => elastic_interface(raw, &k)?,
    };
    Ok(InterfaceModel { law })
}

/// The FCZM or Tvergaard interface (`law`), calibrated from `concrete`
/// where f_t or G_f are not given.
fn cohesive_interface(
    raw: &RawInterface,
    concrete: Option<&ConcreteModel>,
    k: &Keys,
    law: InterfaceLawChoice,
) -> Result<AnyInterfaceLaw, MaterialsSpecError> {
    k.not_for(&[
        ("Kn", raw.kn.is_some()),
        ("Ks", raw.ks.is_some()),
        ("C", raw.cohesion.is_some()),
        ("phi", raw.phi.is_some()),
    ])?;
    let xi = k
        .get(&raw.xi, "xi", Dim::Dimensionless)?
        .unwrap_or(DEFAULT_XI);
    let xi = k.check("xi", xi, xi > 0.0 && xi <= 1.0, "in (0, 1]")?;
    let con = match concrete {
        Some(ConcreteModel::Mazars(m)) => Some(m),
        _ => None,
    };
    let calibrated = |name: &str, what: &str, from: Option<f64>| {
        from.map(|v| xi * v)
            .ok_or_else(|| MaterialsSpecError::Missing {
                key: k.key(name),
                law: format!("{} (no Mazars concrete {what} to calibrate from)", k.law),
            })
    };
    let ft = match k.get(&raw.ft, "ft", Dim::Stress)? {
        Some(v) => v,
        None => calibrated("ft", "ft", con.map(|m| m.tensile_strength()))?,
    };
    let ft = k.positive("ft", ft)?;
    let gf = match k.get(&raw.gf, "Gf", Dim::EnergyPerArea)? {
        Some(v) => v,
        None => calibrated(
            "Gf",
            "Gf",
            con.and_then(|m| match m.tension {
                TensionSoftening::Regularised { fracture_energy } => Some(fracture_energy),
                TensionSoftening::Classic { .. } => None,
            }),
        )?,
    };
    let gf = k.positive("Gf", gf)?;
    let lambda0 = k.positive(
        "lambda0",
        k.get(&raw.lambda0, "lambda0", Dim::Length)?
            .unwrap_or(DEFAULT_LAMBDA0),
    )?;
    let delta_s = match k.get(&raw.delta_s, "delta_s", Dim::Dimensionless)? {
        Some(v) => k.positive("delta_s", v)?,
        None => {
            let v = delta_s_eq29(ft);
            if v <= 0.0 {
                return Err(MaterialsSpecError::Inconsistent {
                    key: k.key("delta_s"),
                    detail: format!("eq. (29) gives {v} <= 0 for ft = {ft} Pa; give delta_s"),
                });
            }
            v
        }
    };
    Ok(if law == InterfaceLawChoice::Tvergaard {
        k.not_for(&[
            ("mu", raw.mu.is_some()),
            ("zeta", raw.zeta.is_some()),
            ("gamma", raw.gamma.is_some()),
            ("contact_smoothing", raw.contact_smoothing.is_some()),
        ])?;
        AnyInterfaceLaw::Tvergaard(Tvergaard {
            tensile_strength: ft,
            fracture_energy: gf,
            lambda0,
            delta_s,
        })
    } else {
        let mu = k
            .get(&raw.mu, "mu", Dim::Dimensionless)?
            .unwrap_or(DEFAULT_MU);
        let mu = k.check("mu", mu, mu >= 0.0, ">= 0")?;
        let zeta = k.positive(
            "zeta",
            k.get(&raw.zeta, "zeta", Dim::Dimensionless)?
                .unwrap_or(DEFAULT_ZETA),
        )?;
        let gamma = k
            .get(&raw.gamma, "gamma", Dim::Stress)?
            .unwrap_or(DEFAULT_GAMMA);
        let gamma = k.check("gamma", gamma, gamma < 0.0, "< 0 (a compressive stress)")?;
        let contact_smoothing = k
            .get(&raw.contact_smoothing, "contact_smoothing", Dim::Length)?
            .unwrap_or(DEFAULT_CONTACT_SMOOTHING);
        let contact_smoothing = k.check(
            "contact_smoothing",
            contact_smoothing,
            (0.0..lambda0).contains(&contact_smoothing),
            "in [0, lambda0)",
        )?;
        AnyInterfaceLaw::Fczm(Fczm {
            tensile_strength: ft,
            fracture_energy: gf,
            lambda0,
            delta_s,
            friction: mu,
            zeta,
            gamma,
            min_damage: 0.0,
            contact_smoothing,
        })
    })
}

/// The Coulomb interface (elastic springs, tension cut-off, friction).
fn coulomb_interface(raw: &RawInterface, k: &Keys) -> Result<AnyInterfaceLaw, MaterialsSpecError> {
    k.not_for(&[
        ("Gf", raw.gf.is_some()),
        ("lambda0", raw.lambda0.is_some()),
        ("delta_s", raw.delta_s.is_some()),
        ("mu", raw.mu.is_some()),
        ("zeta", raw.zeta.is_some()),
        ("gamma", raw.gamma.is_some()),
        ("contact_smoothing", raw.contact_smoothing.is_some()),
        ("xi", raw.xi.is_some()),
    ])?;
    let kn = k.positive("Kn", k.req(&raw.kn, "Kn", Dim::StiffnessPerArea)?)?;
    let ks = k.positive("Ks", k.req(&raw.ks, "Ks", Dim::StiffnessPerArea)?)?;
    let c = k.req(&raw.cohesion, "C", Dim::Stress)?;
    let c = k.check("C", c, c >= 0.0, ">= 0")?;
    let phi = k.req(&raw.phi, "phi", Dim::Angle)?;
    let phi = k.check(
        "phi",
        phi,
        (0.0..std::f64::consts::FRAC_PI_2).contains(&phi),
        "in [0, 90 deg)",
    )?;
    let ft = k.req(&raw.ft, "ft", Dim::Stress)?;
    let limit = if phi > 0.0 {
        c / phi.tan()
    } else {
        f64::INFINITY
    };
    let ft = k.check(
        "ft",
        ft,
        ft >= 0.0 && ft <= limit,
        &format!("in [0, C/tan(phi)] = [0, {limit}] Pa (eq. B.2)"),
    )?;
    Ok(AnyInterfaceLaw::Coulomb(Coulomb {
        normal_stiffness: kn,
        shear_stiffness: ks,
        tensile_strength: ft,
        cohesion: c,
        friction_angle: phi,
    }))
}

/// The linear elastic interface.
fn elastic_interface(raw: &RawInterface, k: &Keys) -> Result<AnyInterfaceLaw, MaterialsSpecError> {
    k.not_for(&[
        ("ft", raw.ft.is_some()),
        ("Gf", raw.gf.is_some()),
        ("lambda0", raw.lambda0.is_some()),
        ("delta_s", raw.delta_s.is_some()),
        ("mu", raw.mu.is_some()),
        ("zeta", raw.zeta.is_some()),
        ("gamma", raw.gamma.is_some()),
        ("contact_smoothing", raw.contact_smoothing.is_some()),
        ("xi", raw.xi.is_some()),
        ("C", raw.cohesion.is_some()),
        ("phi", raw.phi.is_some()),
    ])?;
    let kn = k.positive("Kn", k.req(&raw.kn, "Kn", Dim::StiffnessPerArea)?)?;
    let ks = k.positive("Ks", k.req(&raw.ks, "Ks", Dim::StiffnessPerArea)?)?;
    Ok(AnyInterfaceLaw::Elastic(ElasticInterface {
        normal_stiffness: kn,
        shear_stiffness: ks,
    }))
}

/// `materials.concrete.fcm`, Pa: above the 8 MPa by which MC2010's f_ck
/// falls short of it.
fn resolve_fcm(raw: &RawConcrete) -> Result<Option<f64>, MaterialsSpecError> {
    let k = Keys {
        prefix: "materials.concrete",
        law: raw.law.as_deref().unwrap_or("mazars"),
    };
    k.get(&raw.fcm, "fcm", Dim::Stress)?
        .map(|fcm| k.check("fcm", fcm, fcm > 8e6, "> 8 MPa (f_ck = f_cm - 8 MPa > 0)"))
        .transpose()
}

impl RawMaterials {
    /// Resolves units, defaults, bounds and the interface calibration.
    pub fn resolve(&self) -> Result<Materials, MaterialsSpecError> {
        let concrete = resolve_concrete(&self.concrete, "materials.concrete")?;
        let steel = resolve_steel(&self.steel, "materials.steel")?;
        let interface = resolve_interface(&self.interface, Some(&concrete), "materials.interface")?;
        Ok(Materials {
            concrete,
            steel,
            interface,
            concrete_fcm: resolve_fcm(&self.concrete)?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn resolve(yaml: &str) -> Result<Materials, MaterialsSpecError> {
        serde_yaml::from_str::<RawMaterials>(yaml)
            .unwrap()
            .resolve()
    }

    fn err(yaml: &str) -> String {
        resolve(yaml).unwrap_err().to_string()
    }

    /// `fcm` resolves to Pa for any concrete law, is checked against
    /// MC2010's f_ck > 0, and leaves the serialised materials (the solve's
    /// key) as they were when absent.
    #[test]
    fn fcm_is_read_for_the_design_code_only() {
        let m = resolve("concrete: {fcm: 38 MPa}").unwrap();
        assert_eq!(m.concrete_fcm, Some(38e6));
        let elastic =
            resolve("concrete: {law: elastic, fcm: 38 MPa}\ninterface: {ft: 2 MPa, Gf: 90 N/m}")
                .unwrap();
        assert_eq!(elastic.concrete_fcm, Some(38e6));
        let err = err("concrete: {fcm: 6 MPa}");
        assert!(
            err.contains("materials.concrete.fcm") && err.contains("8 MPa"),
            "{err}"
        );
        let plain = serde_json::to_value(resolve("{}").unwrap()).unwrap();
        assert!(plain.get("concrete_fcm").is_none(), "{plain}");
        assert_eq!(
            serde_json::to_value(m.concrete).unwrap(),
            serde_json::to_value(resolve("{}").unwrap().concrete).unwrap()
        );
    }

    /// `nonlocal_length` reads a positive length, needs a fixed
    /// `regularisation_length` and belongs to Mazars only; absent, the
    /// resolved concrete serialises as before.
    #[test]
    fn nonlocal_length_is_read_and_checked() {
        let m = resolve("concrete: {regularisation_length: 2 mm, nonlocal_length: 1 mm}").unwrap();
        let ConcreteModel::Mazars(c) = m.concrete else {
            panic!()
        };
        assert!((c.nonlocal_length.unwrap() - 1e-3).abs() < 1e-15);
        let text = serde_json::to_string(&resolve("{}").unwrap().concrete).unwrap();
        assert!(!text.contains("nonlocal_length"), "{text}");
        for (yaml, words) in [
            (
                "concrete: {nonlocal_length: 1 mm}",
                "materials.concrete.nonlocal_length: needs regularisation_length",
            ),
            (
                "concrete: {regularisation_length: 2 mm, nonlocal_length: 0 mm}",
                "materials.concrete.nonlocal_length",
            ),
            (
                "concrete: {law: elastic, nonlocal_length: 1 mm}",
                "nonlocal_length",
            ),
        ] {
            let e = err(yaml);
            assert!(e.contains(words), "{yaml}: {e}");
        }
    }

    /// `regularisation_length` reads a length, must be positive and admit
    /// the regularised tension, and belongs to Mazars only; absent, the
    /// resolved (serialised) concrete is as before, so stage keys stay.
    #[test]
    fn regularisation_length_is_read_and_checked() {
        let m = resolve("concrete: {regularisation_length: 0.66 mm}").unwrap();
        let ConcreteModel::Mazars(c) = m.concrete else {
            panic!()
        };
        assert!((c.regularisation_length.unwrap() - 0.66e-3).abs() < 1e-15);
        let plain = resolve("{}").unwrap();
        let text = serde_json::to_string(&plain.concrete).unwrap();
        assert!(!text.contains("regularisation_length"), "{text}");
        for (yaml, words) in [
            (
                "concrete: {regularisation_length: -1 mm}",
                "materials.concrete.regularisation_length",
            ),
            ("concrete: {regularisation_length: 2 m}", "too large"),
            (
                "concrete: {law: elastic, regularisation_length: 1 mm}",
                "regularisation_length",
            ),
        ] {
            let e = err(yaml);
            assert!(e.contains(words), "{yaml}: {e}");
        }
    }

    /// Defaults are the paper's: Mazars R1 concrete, J2 steel, FCZM calibrated by
    /// ξ = 0.72 with δ_s from eq. (29) (SPEC §5, Tables 3–4).
    #[test]
    fn defaults_follow_the_calibration_rule() {
        let m = resolve("{}").unwrap();
        let ConcreteModel::Mazars(c) = m.concrete else {
            panic!()
        };
        assert_eq!(c.young_modulus, 30e9);
        assert!((c.tensile_strength() - 3e6).abs() < 1e-6);
        assert_eq!(m.steel, SteelModel::J2(J2::default()));
        let AnyInterfaceLaw::Fczm(f) = m.interface.law else {
            panic!()
        };
        assert!((f.tensile_strength - 2.16e6).abs() < 1e-6);
        assert!((f.fracture_energy - 0.72 * 130.0).abs() < 1e-9);
        // Eq. (29) at 2.16 MPa gives R1's 0.16 (Table 3).
        assert!((f.delta_s - 0.16).abs() < 1e-3);
        assert_eq!(
            (f.lambda0, f.friction, f.zeta, f.gamma),
            (5e-5, 0.3, 8.0, -1e6)
        );
    }

    /// The suggested explicit form resolves to SI with ε_D0 = f_t/E.
    #[test]
    fn explicit_values_resolve_to_si() {
        let m = resolve(
            r#"
concrete: {law: mazars, E: "30 GPa", nu: 0.2, ft: "3 MPa", Gf: "130 N/m"}
steel: {law: j2, E: "200 GPa", nu: 0.3, sigma_y: "365 MPa"}
interface: {law: fczm, ft: "2.16 MPa", Gf: "97 N/m", lambda0: "5e-5 m", delta_s: 0.16, mu: 0.3, zeta: 8}
"#,
        )
        .unwrap();
        let ConcreteModel::Mazars(c) = m.concrete else {
            panic!()
        };
        assert!((c.eps_d0 - 1e-4).abs() < 1e-18);
        assert_eq!(
            c.tension,
            TensionSoftening::Regularised {
                fracture_energy: 130.0
            }
        );
        let AnyInterfaceLaw::Fczm(f) = m.interface.law else {
            panic!()
        };
        assert_eq!((f.fracture_energy, f.delta_s), (97.0, 0.16));
        assert!((f.normal_stiffness() - 2.16e6 / 5e-5).abs() < 1.0);
    }

    /// Other laws resolve, each with its own keys (SPEC §5).
    #[test]
    fn other_laws_resolve() {
        let m = resolve(
            r#"
concrete: {law: elastic, E: "25 GPa"}
steel: {law: elastic}
interface: {law: coulomb, Kn: "1e11 N/m^3", Ks: 1e11, ft: "3 MPa", C: "3 MPa", phi: "45 deg"}
"#,
        )
        .unwrap();
        assert!(matches!(m.concrete, ConcreteModel::Elastic(_)));
        assert!(matches!(m.interface.law, AnyInterfaceLaw::Coulomb(_)));
        let m = resolve("interface: {law: tvergaard, lambda0: \"0.01 mm\"}").unwrap();
        let AnyInterfaceLaw::Tvergaard(t) = m.interface.law else {
            panic!()
        };
        assert!((t.lambda0 - 1e-5).abs() < 1e-18);
        let m = resolve("interface: {law: elastic, Kn: 1e12, Ks: 5e11}").unwrap();
        assert!(matches!(m.interface.law, AnyInterfaceLaw::Elastic(_)));
        let m = resolve("concrete: {At: 0.8, Bt: 17000, Ac: 1.4, Bc: 1900}\ninterface: {Gf: 97}")
            .unwrap();
        let ConcreteModel::Mazars(c) = m.concrete else {
            panic!()
        };
        assert_eq!(
            c.compression,
            CompressionSoftening::Classic {
                a_c: 1.4,
                b_c: 1900.0
            }
        );
    }

    /// Bad values name the dotted key and the bound (SPEC §8).
    #[test]
    fn errors_name_the_key_and_the_bound() {
        let cases = [
            ("interface: {mu: -0.1}", "materials.interface.mu", ">= 0"),
            (
                "interface: {law: fczm, gamma: \"1 MPa\"}",
                "materials.interface.gamma",
                "< 0",
            ),
            ("concrete: {nu: 0.5}", "materials.concrete.nu", "(-1, 0.5)"),
            (
                "steel: {sigma_y: \"-1 MPa\"}",
                "materials.steel.sigma_y",
                "> 0",
            ),
            ("concrete: {E: \"30 mm\"}", "materials.concrete.E", "stress"),
            (
                "concrete: {law: concrete}",
                "materials.concrete.law",
                "mazars",
            ),
            (
                "concrete: {ft: 3e6, eps_d0: 1e-4}",
                "materials.concrete.eps_d0",
                "not both",
            ),
            (
                "concrete: {Gf: 80, At: 0.8, Bt: 1e4}",
                "materials.concrete.Gf",
                "not both",
            ),
            ("concrete: {At: 0.8}", "materials.concrete.Bt", "missing"),
            (
                "steel: {law: elastic, sigma_y: 1e8}",
                "materials.steel.sigma_y",
                "not a parameter",
            ),
            (
                "interface: {law: coulomb, Kn: 1e11, Ks: 1e11, ft: 4e6, C: 3e6, phi: \"45 deg\"}",
                "materials.interface.ft",
                "C/tan(phi)",
            ),
            (
                "interface: {law: coulomb, Kn: 1e11, Ks: 1e11, C: 3e6, phi: 0.5}",
                "materials.interface.ft",
                "missing",
            ),
            (
                "interface: {law: tvergaard, mu: 0.3}",
                "materials.interface.mu",
                "not a parameter",
            ),
            (
                "concrete: {law: elastic}",
                "materials.interface.ft",
                "calibrate",
            ),
            (
                "interface: {ft: \"3 MPa\"}",
                "materials.interface.delta_s",
                "eq. (29)",
            ),
        ];
        for (yaml, key, bound) in cases {
            let msg = err(yaml);
            assert!(msg.contains(key) && msg.contains(bound), "{yaml}: {msg}");
        }
        let unknown = serde_yaml::from_str::<RawMaterials>("interface: {muu: 0.3}").unwrap_err();
        assert!(unknown.to_string().contains("muu"));
    }

    /// Per-element Mazars laws come from the concrete model and l (eq. 11).
    #[test]
    fn concrete_law_at_size() {
        let m = resolve("{}").unwrap();
        assert!(m.concrete.at_size(0.4e-3).is_ok());
        assert!(matches!(
            m.concrete.at_size(2.0),
            Err(MazarsSizeError::TooLarge { .. })
        ));
    }
}
