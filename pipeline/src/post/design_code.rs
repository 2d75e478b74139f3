//! The design code beside a run: fib Model Code 2010's bond–slip law for
//! ribbed bars failing by pull-out (§6.1.1, Table 6.1-1, ε_s < ε_sy), for
//! the scene's concrete strength, bond conditions and clear rib spacing.
//!
//! | | good bond | all other bond conditions |
//! |---|---|---|
//! | τ_max | 2.5 √f_cm | 1.25 √f_cm |
//! | s1 | 1.0 mm | 1.8 mm |
//! | s2 | 2.0 mm | 3.6 mm |
//! | s3 | c_clear | c_clear |
//! | α | 0.4 | 0.4 |
//! | τ_f | 0.4 τ_max | 0.4 τ_max |
//!
//! (f_cm and τ in MPa in the formulas.) Where f_cm is not given it is
//! derived from the concrete's tensile strength by MC2010's (5.1-3a/b),
//! f_ctm = 0.3 f_ck^(2/3) up to C50 and 2.12 ln(1 + f_cm/10) above, with
//! f_ck = f_cm − 8 MPa.
//!
//! ```
//! use pipeline::post::{fcm_from_tensile_strength, mc2010_pull_out_law, BondConditions};
//! // f_ctm = 3 MPa: f_ck = (3 / 0.3)^1.5 = 31.6 MPa, f_cm = 39.6 MPa.
//! let fcm = fcm_from_tensile_strength(3e6);
//! assert!((fcm / 39.62e6 - 1.0).abs() < 1e-3);
//! let law = mc2010_pull_out_law(fcm, BondConditions::Good, 2.75e-3);
//! assert!((law.tau_max / (2.5e6 * 39.62f64.sqrt()) - 1.0).abs() < 1e-3);
//! assert_eq!((law.s1, law.s2, law.s3), (1e-3, 2e-3, 2.75e-3));
//! ```

use super::bond_law::Mc2010Law;
use serde::{Deserialize, Serialize};

/// MC2010's bond conditions (§6.1.3.2): good, or all other.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum BondConditions {
    /// Good bond conditions.
    #[default]
    Good,
    /// All other bond conditions.
    Other,
}

/// f_ck = f_cm − Δf, Δf = 8 MPa.
const DELTA_F: f64 = 8e6;
/// f_ctm at f_ck = 50 MPa by the lower-strength formula, Pa: where (5.1-3a)
/// hands over to (5.1-3b). The upper formula gives 4.064 MPa there, so a
/// strength between the two is read by the lower one.
fn fctm_at_c50() -> f64 {
    0.3e6 * 50f64.powf(2.0 / 3.0)
}

/// MC2010's mean tensile strength of a concrete of mean compressive
/// strength `fcm`, Pa.
pub fn tensile_strength_of(fcm: f64) -> f64 {
    let fck_mpa = (fcm - DELTA_F) / 1e6;
    if fck_mpa <= 50.0 {
        0.3e6 * fck_mpa.max(0.0).powf(2.0 / 3.0)
    } else {
        2.12e6 * (1.0 + fcm / 1e7).ln()
    }
}

/// The f_cm (Pa) whose MC2010 mean tensile strength is `fctm` (Pa): the
/// inverse of [`tensile_strength_of`].
pub fn fcm_from_tensile_strength(fctm: f64) -> f64 {
    if fctm <= fctm_at_c50() {
        DELTA_F + 1e6 * (fctm / 0.3e6).powf(1.5)
    } else {
        1e7 * ((fctm / 2.12e6).exp() - 1.0)
    }
}

/// MC2010's pull-out bond law for ribbed bars (Table 6.1-1), SI. Where the
/// clear rib spacing is shorter than s2 the fall has no length and s3 is
/// s2 (see [`DesignCodeLaw::notes`]).
pub fn mc2010_pull_out_law(
    fcm: f64,
    conditions: BondConditions,
    clear_rib_spacing: f64,
) -> Mc2010Law {
    let root = (fcm / 1e6).max(0.0).sqrt() * 1e6;
    let (factor, s1, s2) = match conditions {
        BondConditions::Good => (2.5, 1.0e-3, 2.0e-3),
        BondConditions::Other => (1.25, 1.8e-3, 3.6e-3),
    };
    let tau_max = factor * root;
    Mc2010Law {
        tau_max,
        s1,
        s2,
        s3: clear_rib_spacing.max(s2),
        alpha: 0.4,
        tau_f: 0.4 * tau_max,
    }
}

/// Where the scene's f_cm comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FcmSource {
    /// `materials.concrete.fcm` as written.
    Given,
    /// From the concrete's tensile strength (`materials.concrete.ft`) by
    /// MC2010's f_ctm(f_cm).
    DerivedFromTensileStrength,
}

/// The design code's law for one scene, with what it was computed from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DesignCodeLaw {
    pub code: String,
    pub bond_conditions: BondConditions,
    /// Mean compressive strength, Pa.
    pub fcm: f64,
    pub fcm_source: FcmSource,
    /// Axial clear distance between consecutive ribs at the core surface,
    /// m: c − b_base / sin β.
    pub clear_rib_spacing: f64,
    #[serde(flatten)]
    pub law: Mc2010Law,
    /// What the reader should know about these values.
    pub notes: Vec<String>,
}

impl DesignCodeLaw {
    /// The MC2010 pull-out law for `fcm` (given or derived), `conditions`
    /// and the ribs' `clear_rib_spacing` (m).
    pub fn new(
        fcm: f64,
        fcm_source: FcmSource,
        conditions: BondConditions,
        clear_rib_spacing: f64,
    ) -> DesignCodeLaw {
        let law = mc2010_pull_out_law(fcm, conditions, clear_rib_spacing);
        let mut notes = Vec::new();
        if fcm_source == FcmSource::DerivedFromTensileStrength {
            notes.push(format!(
                "f_cm = {:.1} MPa derived from materials.concrete.ft = {:.2} MPa by MC2010's \
                 f_ctm = 0.3 (f_cm - 8)^(2/3) (2.12 ln(1 + f_cm/10) above C50); give \
                 materials.concrete.fcm to set it",
                fcm / 1e6,
                tensile_strength_of(fcm) / 1e6
            ));
        }
        if clear_rib_spacing < law.s2 {
            notes.push(format!(
                "the clear rib spacing {:.2} mm is shorter than s2 = {:.1} mm: s3 is taken as s2, \
                 so τ falls to τ_f at s2",
                clear_rib_spacing * 1e3,
                law.s2 * 1e3
            ));
        }
        DesignCodeLaw {
            code: "fib Model Code 2010, 6.1.1, Table 6.1-1: ribbed bars, pull-out, eps_s < eps_sy"
                .into(),
            bond_conditions: conditions,
            fcm,
            fcm_source,
            clear_rib_spacing,
            law,
            notes,
        }
    }

    /// τ_max / (2.5 √f_cm) of a stress `tau` (Pa): its share of the good
    /// bond conditions' pull-out strength.
    pub fn strength_ratio(&self, tau: f64) -> f64 {
        tau / (2.5e6 * (self.fcm / 1e6).sqrt())
    }
}

/// The axial clear distance between consecutive ribs of one side at the
/// core surface, m: the spacing less the rib's axial base width.
pub fn clear_rib_spacing(ribs: &geom::spec::TransverseRibs) -> f64 {
    ribs.spacing - ribs.base_width / ribs.angle.sin()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The derivation of f_cm inverts MC2010's f_ctm on both sides of C50,
    /// and meets C50's value there.
    #[test]
    fn fcm_and_fctm_are_inverse() {
        // Above C50 but below the lower formula's C50 value the inverse
        // takes the lower formula; elsewhere it is exact.
        for fcm in [20e6, 39.6e6, 58e6, 60e6, 70e6, 98e6] {
            let back = fcm_from_tensile_strength(tensile_strength_of(fcm));
            assert!((back / fcm - 1.0).abs() < 1e-12, "{fcm} {back}");
        }
        assert!((tensile_strength_of(58e6) - fctm_at_c50()).abs() < 1e-6);
        // C30/37: f_cm = 38 MPa, f_ctm = 2.9 MPa (MC2010 Table 5.1-2).
        assert!((tensile_strength_of(38e6) / 2.896e6 - 1.0).abs() < 1e-3);
    }

    /// Table 6.1-1's values for both bond conditions, and s3 no shorter
    /// than s2 with a note where the ribs are closer.
    #[test]
    fn the_code_law_follows_table_6_1_1() {
        let other = DesignCodeLaw::new(40e6, FcmSource::Given, BondConditions::Other, 2.75e-3);
        assert!((other.law.tau_max - 1.25e6 * 40f64.sqrt()).abs() < 1.0);
        assert_eq!(
            (other.law.s1, other.law.s2, other.law.s3),
            (1.8e-3, 3.6e-3, 3.6e-3)
        );
        assert!((other.law.tau_f / other.law.tau_max - 0.4).abs() < 1e-12);
        assert!(
            other.notes.iter().any(|n| n.contains("shorter than s2")),
            "{other:?}"
        );
        let good = DesignCodeLaw::new(
            40e6,
            FcmSource::DerivedFromTensileStrength,
            BondConditions::Good,
            5e-3,
        );
        assert_eq!(good.law.s3, 5e-3);
        assert!(good.notes[0].contains("derived"), "{good:?}");
        assert!((good.strength_ratio(good.law.tau_max) - 1.0).abs() < 1e-12);
    }
}
