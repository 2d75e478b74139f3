//! Post-processing of solved pull-out curves: summary quantities, plots,
//! mesh-convergence estimates (Celik et al. 2008) and study tables.
//!
//! Everything here works from files and small plain structs (the solver's
//! `curve.csv`, interface traction samples, per-case summaries), so it can be
//! run again on old results without the solver.
//!
//! Units: SI inside (m, N, Pa, s, J/m²); plots and human-facing table
//! columns use MPa and mm and say so in their labels.
//!
//! ```
//! use pipeline::post::{summarize, CurveRow, SummaryOptions};
//!
//! // A triangle: σ_mb rises to 10 MPa at FED = 1 mm, falls to 0 at 2 mm.
//! let rows: Vec<CurveRow> = [(0.0, 0.0), (1e-3, 10e6), (2e-3, 0.0)]
//!     .iter()
//!     .enumerate()
//!     .map(|(i, &(fed, s))| CurveRow::new(i, fed, 0.0, fed, s, 1))
//!     .collect();
//! let opts = SummaryOptions { energy_fed_limit: Some(2e-3), residual_fraction: 0.5 };
//! let s = summarize(&rows, &opts).unwrap();
//! assert_eq!(s.peak_bond_stress, 10e6);
//! assert_eq!(s.fed_at_peak, 1e-3);
//! // Area of the triangle: ½ · 2 mm · 10 MPa = 10 kJ/m².
//! assert!((s.energy.unwrap() - 1.0e4).abs() < 1e-6);
//! ```

mod bond_law;
mod cell;
mod convergence;
mod curve;
mod design_code;
mod distance;
mod error;
mod fsutil;
mod plot;
mod plot_study;
mod sensitivity;
mod summary;
mod table;
mod uncertainty;

pub use bond_law::{
    bond_law_entries, fit_mc2010, fit_piecewise, folded_curve, relative_l2, FittedMc2010,
    Mc2010Law, PiecewiseLaw, FIT_BOUNDS,
};
pub use convergence::{
    convergence_study, three_grid_estimate, ConvergenceKind, ConvergenceRow, ConvergenceStudy,
    GridResult, TripletEstimate, GCI_SAFETY_FACTOR,
};
pub use curve::{parse_curve_csv, read_curve_csv, CurveRow, CURVE_COLUMNS};
pub use design_code::{
    clear_rib_spacing, fcm_from_tensile_strength, mc2010_pull_out_law, tensile_strength_of,
    BondConditions, DesignCodeLaw, FcmSource,
};
pub use distance::{curve_distance, CurveAxis, FOLDED_RECESSION_SHARE};
pub use error::PostError;
pub use plot::{
    bond_slip_plot, bond_slip_png, bond_slip_svg, bond_slip_with_laws_png, bond_slip_with_laws_svg,
    ensure_font, error_vs_time_plot, error_vs_time_png, error_vs_time_svg, interface_line_plot,
    interface_line_png, interface_line_svg, ErrorTimeSeries, InterfaceProfile, InterfaceSample,
    ReferenceCurve, FONT_FAMILY,
};
pub use plot_study::{
    sensitivity_plot, trend_line, trend_plot, Measure, SensitivityBars, TrendLine, TrendPanel,
};
pub use sensitivity::{
    morris_indices, morris_table, sobol_indices, sobol_table, MorrisIndex, SobolIndex,
    BOOTSTRAP_RESAMPLES,
};
pub use summary::{
    energy_to_fed, first_peak_bond_stress, peak_bond_stress, residual_bond_stress, summarize,
    CurveSummary, SummaryOptions, FIRST_PEAK_DROP,
};
pub use table::{
    convergence_markdown, convergence_order_table, convergence_table, parameters_label,
    study_table, uncertainty_table, value_label, write_convergence_tables, write_study_tables,
    Cell, StudyCase, Table,
};
pub use uncertainty::{least_squares_uncertainty, ErrorFit, LeastSquaresEstimate};
