//! The points of a sampled or sensitivity study: space-filling samples,
//! Saltelli's design for Sobol' indices, Morris trajectories. Each point
//! is checked as a scene before it becomes a case; a point outside the
//! design bounds that the spec checks is recorded with the reason and
//! replaced by the next draw of the sequence (for Saltelli's design, the
//! whole base row; for Morris, the whole trajectory), so the design keeps
//! its size and its structure.

use super::sequence::{generator, Method, Stream, SOBOL_MAX_POINTS};
use super::space::{Axis, AxisValue};
use rand::seq::SliceRandom;
use rand::Rng;

/// What a point of the design is for.
#[derive(Debug, Clone, PartialEq)]
pub enum Role {
    /// A sampled design: the accepted draw's index in its sequence.
    Sample {
        draw: usize,
    },
    /// Saltelli's design: the base row's matrices A and B, and A with
    /// column `parameter` taken from B.
    SobolA {
        row: usize,
    },
    SobolB {
        row: usize,
    },
    SobolAB {
        row: usize,
        parameter: usize,
    },
    /// A Morris trajectory's `step`-th point; from the second point on,
    /// the parameter that moved and its signed step in the unit cube.
    Morris {
        trajectory: usize,
        step: usize,
        moved: Option<(usize, f64)>,
    },
}

impl Role {
    /// The role in words, as designs.csv names it.
    pub fn label(&self, axes: &[Axis]) -> String {
        match self {
            Role::Sample { draw } => format!("draw {draw}"),
            Role::SobolA { row } => format!("row {row} A"),
            Role::SobolB { row } => format!("row {row} B"),
            Role::SobolAB { row, parameter } => {
                format!("row {row} AB({})", axes[*parameter].key)
            }
            Role::Morris {
                trajectory,
                step,
                moved,
            } => match moved {
                None => format!("trajectory {trajectory} start"),
                Some((p, d)) => format!(
                    "trajectory {trajectory} step {step}: {} {}{:.3}",
                    axes[*p].key,
                    if *d > 0.0 { "+" } else { "-" },
                    d.abs()
                ),
            },
        }
    }
}

/// One point of the design.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignPoint {
    pub role: Role,
    /// Its coordinates in the unit cube, one per axis.
    pub unit: Vec<f64>,
    pub values: Vec<AxisValue>,
}

/// A draw that was not a valid scene, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct RejectedDraw {
    /// Which draw, in words ("draw 5", "row 3 AB(bar.ribs.angle)").
    pub draw: String,
    pub values: Vec<AxisValue>,
    pub reason: String,
}

/// How a candidate point fared as a scene.
pub enum Verdict {
    Valid,
    /// Outside the design bounds: replaced.
    OutOfBounds(String),
}

/// Checks the values of a point as a scene; `Err` stops the whole study
/// (an error that no other draw would escape, such as an unknown key).
pub type Check<'a> = dyn Fn(&[AxisValue]) -> Result<Verdict, String> + 'a;

/// The accepted points and the rejected draws.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Points {
    pub points: Vec<DesignPoint>,
    pub rejected: Vec<RejectedDraw>,
}

/// Rejections allowed before a design whose space is mostly outside the
/// bounds is given up, for a design of `n` accepted draws.
fn rejection_budget(n: usize) -> usize {
    100 + 20 * n
}

fn values(axes: &[Axis], unit: &[f64]) -> Vec<AxisValue> {
    axes.iter().zip(unit).map(|(a, &u)| a.value(u)).collect()
}

impl Points {
    fn reject(
        &mut self,
        draw: String,
        values: Vec<AxisValue>,
        reason: String,
        n: usize,
    ) -> Result<(), String> {
        self.rejected.push(RejectedDraw {
            draw,
            values,
            reason,
        });
        if self.rejected.len() > rejection_budget(n) {
            let first = &self.rejected[0];
            return Err(format!(
                "{} draws were outside the design bounds before {} of {n} were valid: \
                 narrow the ranges; the first was {} ({})",
                self.rejected.len(),
                self.points.len(),
                first.draw,
                first.reason
            ));
        }
        Ok(())
    }
}

/// The first `n` draws of `method` (seeded) that are valid scenes.
pub fn sample(
    axes: &[Axis],
    method: Method,
    n: usize,
    seed: u64,
    check: &Check,
) -> Result<Points, String> {
    let mut stream = Stream::new(method, axes.len(), n, seed)?;
    let mut out = Points::default();
    while out.points.len() < n {
        let draw = stream.drawn();
        let unit = stream
            .next_point()
            .ok_or_else(|| exhausted(method, draw, &out))?;
        let v = values(axes, &unit);
        match check(&v)? {
            Verdict::Valid => out.points.push(DesignPoint {
                role: Role::Sample { draw },
                unit,
                values: v,
            }),
            Verdict::OutOfBounds(reason) => out.reject(format!("draw {draw}"), v, reason, n)?,
        }
    }
    Ok(out)
}

fn exhausted(method: Method, drawn: usize, out: &Points) -> String {
    format!(
        "the {} sequence ended after {drawn} draws ({} valid, {} outside the design bounds)",
        method.name(),
        out.points.len(),
        out.rejected.len()
    )
}

/// The points of a Saltelli row or a Morris trajectory, which is kept whole
/// or not at all: all its candidates when each is in the design bounds,
/// else the first that is not (its role's label, its values, why).
type WholeOrRejected = Result<Vec<DesignPoint>, (String, Vec<AxisValue>, String)>;

fn accept_whole(
    axes: &[Axis],
    candidates: Vec<(Role, Vec<f64>)>,
    check: &Check,
) -> Result<WholeOrRejected, String> {
    let mut accepted = Vec::with_capacity(candidates.len());
    for (role, unit) in candidates {
        let v = values(axes, &unit);
        match check(&v)? {
            Verdict::Valid => accepted.push(DesignPoint {
                role,
                unit,
                values: v,
            }),
            Verdict::OutOfBounds(reason) => return Ok(Err((role.label(axes), v, reason))),
        }
    }
    Ok(Ok(accepted))
}

/// Saltelli's design for `n` base rows: from 2d-dimensional Sobol' points
/// (seeded), A the first d coordinates, B the last d, and for every
/// parameter i the point A with its i-th coordinate from B; N (d + 2)
/// points, each row's A, B, AB(1) … AB(d) in turn.
pub fn saltelli(axes: &[Axis], n: usize, seed: u64, check: &Check) -> Result<Points, String> {
    let d = axes.len();
    let mut stream = Stream::new(Method::Sobol, 2 * d, n, seed)?;
    let mut out = Points::default();
    let mut row = 0;
    while row < n {
        let draw = stream.drawn();
        let u = stream
            .next_point()
            .ok_or_else(|| exhausted(Method::Sobol, draw.min(SOBOL_MAX_POINTS), &out))?;
        let (a, b) = (u[..d].to_vec(), u[d..].to_vec());
        let mut candidates = vec![
            (Role::SobolA { row }, a.clone()),
            (Role::SobolB { row }, b.clone()),
        ];
        for i in 0..d {
            let mut ab = a.clone();
            ab[i] = b[i];
            candidates.push((Role::SobolAB { row, parameter: i }, ab));
        }
        let rejected = accept_whole(axes, candidates, check)?;
        match rejected {
            Ok(accepted) => {
                out.points.extend(accepted);
                row += 1;
            }
            Err((which, v, reason)) => {
                out.reject(format!("Sobol' point {draw} (as {which})"), v, reason, n)?
            }
        }
    }
    Ok(out)
}

/// `r` Morris trajectories on a grid of `levels` levels (seeded): each
/// starts on the grid and moves every parameter once, in a random order,
/// by Δ = levels / (2 (levels − 1)) up or down (Morris 1991).
pub fn morris(
    axes: &[Axis],
    r: usize,
    levels: usize,
    seed: u64,
    check: &Check,
) -> Result<Points, String> {
    let d = axes.len();
    let step = levels as f64 / (2.0 * (levels as f64 - 1.0));
    let mut rng = generator(seed);
    let mut out = Points::default();
    let mut drawn = 0;
    while out.points.len() < r * (d + 1) {
        let trajectory = out.points.len() / (d + 1);
        let start: Vec<f64> = (0..d)
            .map(|_| rng.random_range(0..levels / 2) as f64 / (levels as f64 - 1.0))
            .collect();
        let up: Vec<bool> = (0..d).map(|_| rng.random::<bool>()).collect();
        let mut order: Vec<usize> = (0..d).collect();
        order.shuffle(&mut rng);
        let mut x: Vec<f64> = (0..d)
            .map(|i| if up[i] { start[i] } else { start[i] + step })
            .collect();
        let mut candidates = vec![(
            Role::Morris {
                trajectory,
                step: 0,
                moved: None,
            },
            x.clone(),
        )];
        for (k, &i) in order.iter().enumerate() {
            let delta = if up[i] { step } else { -step };
            x[i] += delta;
            candidates.push((
                Role::Morris {
                    trajectory,
                    step: k + 1,
                    moved: Some((i, delta)),
                },
                x.clone(),
            ));
        }
        let rejected = accept_whole(axes, candidates, check)?;
        match rejected {
            Ok(accepted) => out.points.extend(accepted),
            Err((which, v, reason)) => out.reject(
                format!("trajectory draw {drawn} (at its {which})"),
                v,
                reason,
                r,
            )?,
        }
        drawn += 1;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn axes(n: usize) -> Vec<Axis> {
        (0..n)
            .map(|i| {
                Axis::parse(
                    &format!("k{i}"),
                    &serde_yaml::from_str("{range: [0, 1]}").unwrap(),
                )
                .unwrap()
            })
            .collect()
    }

    fn all_valid(_: &[AxisValue]) -> Result<Verdict, String> {
        Ok(Verdict::Valid)
    }

    /// A draw outside the bounds is recorded and replaced by the next draw
    /// of the sequence: the valid draws are the sequence's valid points in
    /// order, none dropped silently.
    #[test]
    fn rejected_draws_are_recorded_and_replaced_in_order() {
        let a = axes(2);
        let check = |v: &[AxisValue]| -> Result<Verdict, String> {
            let x = v[0].table.as_f64().unwrap();
            Ok(if x > 0.7 {
                Verdict::OutOfBounds(format!("k0 = {x} > 0.7"))
            } else {
                Verdict::Valid
            })
        };
        let got = sample(&a, Method::Sobol, 16, 5, &check).unwrap();
        assert_eq!(got.points.len(), 16);
        assert!(!got.rejected.is_empty());
        let mut stream = Stream::new(Method::Sobol, 2, 16, 5).unwrap();
        let total = got.points.len() + got.rejected.len();
        let sequence: Vec<Vec<f64>> = (0..total).map(|_| stream.next_point().unwrap()).collect();
        let valid: Vec<&Vec<f64>> = sequence.iter().filter(|u| u[0] <= 0.7).collect();
        let kept: Vec<&Vec<f64>> = got.points.iter().map(|p| &p.unit).collect();
        assert_eq!(kept, valid);
        assert!(got.rejected.iter().all(|r| r.reason.contains("> 0.7")));
        // A space entirely outside the bounds is given up, saying why.
        let none = |_: &[AxisValue]| Ok(Verdict::OutOfBounds("never".into()));
        let err = sample(&a, Method::Random, 4, 1, &none).unwrap_err();
        assert!(
            err.contains("narrow the ranges") && err.contains("never"),
            "{err}"
        );
    }

    /// Saltelli's rows are A, B and each A with one column of B; Morris
    /// trajectories move each parameter once by ±Δ on the grid.
    #[test]
    fn saltelli_rows_and_morris_trajectories_have_their_structure() {
        let a = axes(3);
        let s = saltelli(&a, 4, 2, &all_valid).unwrap();
        assert_eq!(s.points.len(), 4 * 5);
        for row in s.points.chunks(5) {
            let (pa, pb) = (&row[0].unit, &row[1].unit);
            for (i, ab) in row[2..].iter().enumerate() {
                for j in 0..3 {
                    assert_eq!(ab.unit[j], if j == i { pb[j] } else { pa[j] });
                }
            }
        }
        let m = morris(&a, 5, 4, 9, &all_valid).unwrap();
        assert_eq!(m.points.len(), 5 * 4);
        for t in m.points.chunks(4) {
            let mut moved = Vec::new();
            for w in t.windows(2) {
                let Role::Morris {
                    moved: Some((i, d)),
                    ..
                } = w[1].role
                else {
                    panic!("{:?}", w[1].role)
                };
                assert!((d.abs() - 2.0 / 3.0).abs() < 1e-12);
                assert!((w[1].unit[i] - w[0].unit[i] - d).abs() < 1e-12);
                moved.push(i);
            }
            moved.sort_unstable();
            assert_eq!(moved, [0, 1, 2]);
            assert!(t
                .iter()
                .flat_map(|p| &p.unit)
                .all(|u| (-1e-12..=1.0 + 1e-12).contains(u)));
        }
    }
}
