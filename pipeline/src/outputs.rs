//! The `outputs` section of a scene spec: which fields, plots and summary
//! quantities are produced. Only `outputs.fields` is read by the solve stage
//! (fields need the state at their step, which only exists while solving);
//! everything else is read by post alone, so changing it reruns post only.

use crate::post::BondConditions;
use geom::units::{Dim, RawQuantity};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// The `outputs` section as written. Every field's doc comment ends with
/// `(unit; default …; bounds)`: the scene reference and `ribbar schema
/// scene` are generated from them.
#[derive(Debug, Clone, Default, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawOutputs {
    /// Which converged states the solve writes as VTU fields; read by the
    /// solve stage (a field needs the state at its step), so changing it
    /// reruns the solve.
    pub fields: Option<RawFields>,
    /// FED up to which the energy under the σ_mb–FED curve is integrated,
    /// `summary.json`'s `curve.energy` (length; default 1 mm; > 0).
    pub energy_fed_limit: Option<RawQuantity>,
    /// The residual σ_mb is the mean over this last fraction of the final
    /// FED (pure number; default 0.2; in (0, 1]).
    pub residual_fraction: Option<f64>,
    /// Formats of `plots/bond_slip.*` and `plots/interface_profile.*`; an
    /// empty list writes none (list of png, svg; default [png, svg]).
    pub plots: Option<Vec<PlotFormat>>,
    /// fib Model Code 2010's bond conditions of the design code's law drawn
    /// beside the curve: `good` or `other` (choice; default good).
    pub bond_conditions: Option<BondConditions>,
    /// Points of the piecewise-linear bond law fitted to the curve
    /// (`bond_law.json`), the origin included (count; default 8; 2 to 64).
    pub bond_law_points: Option<usize>,
}

/// `outputs.fields` as written.
#[derive(Debug, Clone, Default, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawFields {
    /// Converged step numbers at which the fields are written
    /// (`fields/stepNNNN_bulk.vtu`, `…_interface.vtu`) and the interface
    /// traction profile is sampled (list of counts; default []).
    pub steps: Option<Vec<usize>>,
    /// Also at the step of the first peak of the bond stress,
    /// `fields/peak_*.vtu` (bool; default true).
    pub at_peak: Option<bool>,
    /// Also at the last converged step, `fields/end_*.vtu` (bool; default
    /// true).
    pub at_end: Option<bool>,
    /// A half or quarter model's fields on the whole specimen: the model and
    /// its images, displacements reflected, cell values copied (the
    /// interface's t_h and s_h signed with the image's frame); the curve and
    /// the profiles are the same either way; no effect on a whole model
    /// (bool; default false).
    pub whole_specimen: Option<bool>,
}

/// A plot file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum PlotFormat {
    /// PNG image.
    Png,
    /// SVG drawing.
    Svg,
}

/// What the solve stage writes besides the curve.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FieldRequest {
    pub steps: Vec<usize>,
    pub at_peak: bool,
    pub at_end: bool,
    /// Left out of the stage key when false, so scenes that do not ask for
    /// it keep their stored solves.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub whole_specimen: bool,
}

/// What post produces.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PostRequest {
    /// m
    pub energy_fed_limit: f64,
    pub residual_fraction: f64,
    pub plots: Vec<PlotFormat>,
    pub bond_conditions: BondConditions,
    pub bond_law_points: usize,
}

/// Default points of the piecewise-linear bond law: enough for an adhesion
/// peak, its fall and a frictional rise.
pub const DEFAULT_BOND_LAW_POINTS: usize = 8;

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Outputs {
    pub fields: FieldRequest,
    pub post: PostRequest,
}

#[derive(Debug, thiserror::Error)]
pub enum OutputsError {
    #[error(transparent)]
    Unit(#[from] geom::units::UnitError),
    #[error("{key}: {value} is out of range: {bound}")]
    OutOfRange {
        key: &'static str,
        value: String,
        bound: &'static str,
    },
}

impl RawOutputs {
    pub fn resolve(&self) -> Result<Outputs, OutputsError> {
        let fields = self.fields.clone().unwrap_or_default();
        let mut steps = fields.steps.unwrap_or_default();
        steps.sort_unstable();
        steps.dedup();
        let energy_fed_limit = match &self.energy_fed_limit {
            Some(q) => q.to_si(Dim::Length, "outputs.energy_fed_limit")?,
            None => 1e-3,
        };
        if energy_fed_limit <= 0.0 {
            return Err(OutputsError::OutOfRange {
                key: "outputs.energy_fed_limit",
                value: format!("{energy_fed_limit} m"),
                bound: "must be > 0",
            });
        }
        let residual_fraction = self.residual_fraction.unwrap_or(0.2);
        if !(residual_fraction > 0.0 && residual_fraction <= 1.0) {
            return Err(OutputsError::OutOfRange {
                key: "outputs.residual_fraction",
                value: residual_fraction.to_string(),
                bound: "must be in (0, 1]",
            });
        }
        let bond_law_points = self.bond_law_points.unwrap_or(DEFAULT_BOND_LAW_POINTS);
        if !(2..=64).contains(&bond_law_points) {
            return Err(OutputsError::OutOfRange {
                key: "outputs.bond_law_points",
                value: bond_law_points.to_string(),
                bound: "must be in [2, 64] (the origin and at least one more point)",
            });
        }
        let mut plots = self
            .plots
            .clone()
            .unwrap_or(vec![PlotFormat::Png, PlotFormat::Svg]);
        plots.dedup();
        Ok(Outputs {
            fields: FieldRequest {
                steps,
                at_peak: fields.at_peak.unwrap_or(true),
                at_end: fields.at_end.unwrap_or(true),
                whole_specimen: fields.whole_specimen.unwrap_or(false),
            },
            post: PostRequest {
                energy_fed_limit,
                residual_fraction,
                plots,
                bond_conditions: self.bond_conditions.unwrap_or_default(),
                bond_law_points,
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_and_bounds() {
        let o = RawOutputs::default().resolve().unwrap();
        assert_eq!(o.post.energy_fed_limit, 1e-3);
        assert!(o.fields.at_peak && o.fields.at_end);
        let raw: RawOutputs = serde_yaml::from_str("residual_fraction: 1.5").unwrap();
        let err = raw.resolve().unwrap_err().to_string();
        assert!(err.contains("outputs.residual_fraction"), "{err}");
        assert!(serde_yaml::from_str::<RawOutputs>("plot: [png]").is_err());
        assert_eq!(o.post.bond_conditions, BondConditions::Good);
        assert_eq!(o.post.bond_law_points, DEFAULT_BOND_LAW_POINTS);
        let raw: RawOutputs =
            serde_yaml::from_str("{bond_conditions: other, bond_law_points: 1}").unwrap();
        let err = raw.resolve().unwrap_err().to_string();
        assert!(err.contains("outputs.bond_law_points"), "{err}");
        assert!(serde_yaml::from_str::<RawOutputs>("bond_conditions: poor").is_err());
    }
}
