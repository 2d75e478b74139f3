//! Everything needed to restart a run from a converged step, saved
//! atomically as one framed file: a header with the format, the key of the
//! run it belongs to and the SHA-256 of the payload, then the payload
//! (bincode). A file whose checksum or key does not match is refused
//! whole, so a resumed run never starts from flipped bytes or another
//! model's state.

use super::policy::{ConvergedPath, PolicyState};
use super::summary::Summary;
use crate::elements::interface::INTERFACE_POINTS;
use crate::energy::EnergyRow;
use crate::fields::ProfileRow;
use crate::spec::solver::REBUILD_COST_ITERATIONS;
use mesh::Model;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::path::Path;

/// Everything a run carries from one step to the next: its converged
/// path, the stepping policy's state and the summary so far.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunState {
    pub path: ConvergedPath,
    pub policy: PolicyState,
    pub summary: Summary,
}

/// Everything needed to restart from a converged step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    pub n_nodes: usize,
    pub n_tets: usize,
    pub n_interfaces: usize,
    /// The run's state, whole: a run resumed from it takes the decisions
    /// the uninterrupted run takes.
    pub state: RunState,
    /// The matrix whose factor preconditions the next linear solves (PCG
    /// and GMRES keep one across steps); a resumed run factorises exactly
    /// these values, so its iterates equal the uninterrupted run's bit for
    /// bit. `None` when no factor is kept (Cholesky mode, or none yet).
    pub preconditioner: Option<PreconditionerState>,
    /// Energy balance, one row per converged step (empty when it could not
    /// be evaluated, see `RunResult::energy`).
    pub energy: Vec<EnergyRow>,
    /// What the run's caller recorded up to this step; it travels with the
    /// state so that a resumed run continues it (the solver leaves it
    /// empty, the caller fills it before saving).
    pub record: ObserverRecord,
}

/// What an [`Observer`](super::Observer) recorded of a run up to a checkpoint.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ObserverRecord {
    /// Interface traction profiles of the field steps so far.
    pub profile: Vec<ProfileRow>,
    /// The profile of the current adhesion peak (replaced by each new one).
    pub peak_profile: Vec<ProfileRow>,
}

/// The kept preconditioner of a run: the lower-triangle values (N/m) that
/// were factorised, and whether the solver had decided to refactorise at
/// its next correction.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PreconditionerState {
    pub values: Vec<f64>,
    pub refactor: bool,
    pub wear: HierarchyWear,
}

/// The wear of a kept multigrid hierarchy that `solver.expert.multigrid_rebuild:
/// amortised` counts: the GMRES iterations of the first solve with it,
/// those the solves after it needed beyond that, and whether the last
/// rebuilds for wear paid.
///
/// A rebuild pays when the first solve with the new hierarchy needs
/// clearly fewer iterations per decade of residual than the old one's
/// solves after its first ([`REBUILD_PAID`]). Past a peak the solves'
/// iteration counts scatter with the right-hand side whatever the
/// hierarchy, and that scatter, counted against the first solve, looks
/// like wear: each rebuild that does not pay doubles the wear the next
/// one waits for (up to [`MAX_WEAR_DOUBLINGS`] times), and one that pays
/// resets it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct HierarchyWear {
    first: Option<usize>,
    excess: usize,
    /// GMRES iterations and decades of relative residual of the solves
    /// after the first.
    later_iterations: usize,
    later_decades: f64,
    /// Iterations per decade of the worn hierarchy's later solves, while
    /// the first solve with its replacement is awaited.
    replaced_rate: Option<f64>,
    /// Rebuilds for wear in a row that did not pay.
    doublings: u32,
}

/// A rebuild for wear pays when the new hierarchy's first solve needs at
/// most this share of the worn one's iterations per decade.
pub const REBUILD_PAID: f64 = 0.75;
/// The wear a rebuild waits for doubles at most this many times (40 → 640
/// iterations).
pub const MAX_WEAR_DOUBLINGS: u32 = 4;

impl HierarchyWear {
    /// Counts a solve of `iterations` that reached `relative_residual`
    /// with the hierarchy; returns whether it is now worn.
    pub(crate) fn after_solve(&mut self, iterations: usize, relative_residual: f64) -> bool {
        let decades = decades_of(relative_residual);
        match self.first {
            None => {
                self.first = Some(iterations);
                if let (Some(old), Some(d)) = (self.replaced_rate.take(), decades) {
                    let paid = (iterations as f64) / d <= REBUILD_PAID * old;
                    self.doublings = if paid {
                        0
                    } else {
                        (self.doublings + 1).min(MAX_WEAR_DOUBLINGS)
                    };
                }
            }
            Some(first) => {
                self.excess += iterations.saturating_sub(first);
                if let Some(d) = decades {
                    self.later_iterations += iterations;
                    self.later_decades += d;
                }
            }
        }
        self.worn()
    }

    /// The wear has passed what a build costs ([`REBUILD_COST_ITERATIONS`],
    /// doubled for each rebuild in a row that did not pay).
    fn worn(&self) -> bool {
        self.excess > REBUILD_COST_ITERATIONS << self.doublings
    }

    /// The wear of a new hierarchy. When the old one is replaced because
    /// it wore, the new one's first solve is judged against it.
    pub(crate) fn rebuilt(self) -> Self {
        if self.first.is_none() {
            // Built again before a solve (the secant after an indefinite
            // matrix): the judgement waits for the first solve still.
            return self;
        }
        let replaced_rate = (self.worn() && self.later_decades > 0.0)
            .then(|| self.later_iterations as f64 / self.later_decades);
        Self {
            replaced_rate,
            doublings: self.doublings,
            ..Self::default()
        }
    }
}

/// Decades of residual reduction of a solve that reached
/// `relative_residual` (none for an empty right-hand side).
fn decades_of(relative_residual: f64) -> Option<f64> {
    (relative_residual > 0.0 && relative_residual < 1.0).then(|| -relative_residual.log10())
}

/// A checkpoint file that cannot be written or read.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error("checkpoint {path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("checkpoint {path}: damaged or of another version ({detail})")]
    Corrupt { path: String, detail: String },
    /// A whole, undamaged checkpoint of another run (another model, other
    /// inputs): resuming from it would continue someone else's curve.
    #[error("checkpoint {path}: belongs to the run with key {found}, not to {expected}")]
    Foreign {
        path: String,
        found: String,
        expected: String,
    },
}

/// The file's first bytes: what it is.
const CHECKPOINT_MAGIC: &[u8; 8] = b"RIBBARCP";
/// Version of the framing and of the payload's layout; a checkpoint of
/// another version is refused (a run starts over rather than misread it).
const CHECKPOINT_FORMAT: u32 = 2;
/// The longest key a header may carry, bytes (keys are 32 hex digits).
const MAX_KEY_BYTES: usize = 256;

/// The framed file: magic, format (u32), key length (u32) and key, payload
/// length (u64), SHA-256 of the payload, payload; integers little-endian.
fn frame(key: &str, payload: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(payload.len() + key.len() + 64);
    out.extend_from_slice(CHECKPOINT_MAGIC);
    out.extend_from_slice(&CHECKPOINT_FORMAT.to_le_bytes());
    out.extend_from_slice(&(key.len() as u32).to_le_bytes());
    out.extend_from_slice(key.as_bytes());
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&Sha256::digest(payload));
    out.extend_from_slice(payload);
    out
}

/// The key and the checked payload of a framed file, or what is wrong
/// with it.
fn unframe(bytes: &[u8]) -> Result<(&str, &[u8]), String> {
    let mut rest = bytes;
    let mut take = |n: usize, what: &str| -> Result<&[u8], String> {
        if rest.len() < n {
            return Err(format!("truncated in its {what}"));
        }
        let (head, tail) = rest.split_at(n);
        rest = tail;
        Ok(head)
    };
    if take(8, "header")? != CHECKPOINT_MAGIC {
        return Err("not a ribbar checkpoint (no RIBBARCP header)".into());
    }
    let format = u32::from_le_bytes(take(4, "header")?.try_into().expect("4 bytes"));
    if format != CHECKPOINT_FORMAT {
        return Err(format!(
            "format {format}, this ribbar reads format {CHECKPOINT_FORMAT}"
        ));
    }
    let key_len = u32::from_le_bytes(take(4, "header")?.try_into().expect("4 bytes")) as usize;
    if key_len > MAX_KEY_BYTES {
        return Err(format!("a key of {key_len} bytes in its header"));
    }
    let key = std::str::from_utf8(take(key_len, "header")?)
        .map_err(|_| "a key that is not text in its header".to_string())?;
    let len = u64::from_le_bytes(take(8, "header")?.try_into().expect("8 bytes"));
    let checksum = take(32, "header")?;
    if rest.len() as u64 != len {
        return Err(format!(
            "{} bytes of state where its header says {len}",
            rest.len()
        ));
    }
    if Sha256::digest(rest).as_slice() != checksum {
        return Err("its SHA-256 does not match the one in its header".into());
    }
    Ok((key, rest))
}

impl Checkpoint {
    /// Writes atomically (temporary file then rename) with the key of the
    /// run it belongs to (`key`, e.g. the solve stage's key) and the
    /// payload's checksum.
    pub fn save(&self, path: &Path, key: &str) -> Result<(), CheckpointError> {
        let shown = || path.display().to_string();
        let payload = bincode::serialize(self).map_err(|e| CheckpointError::Corrupt {
            path: shown(),
            detail: e.to_string(),
        })?;
        geom::fsutil::write_atomic(path, &frame(key, &payload)).map_err(|source| {
            CheckpointError::Io {
                path: shown(),
                source,
            }
        })
    }

    /// Reads a checkpoint saved with `key`; one whose checksum fails, of
    /// another format, or saved with another key is an error that says so.
    pub fn load(path: &Path, key: &str) -> Result<Self, CheckpointError> {
        let shown = || path.display().to_string();
        let bytes = std::fs::read(path).map_err(|source| CheckpointError::Io {
            path: shown(),
            source,
        })?;
        let corrupt = |detail: String| CheckpointError::Corrupt {
            path: shown(),
            detail,
        };
        let (found, payload) = unframe(&bytes).map_err(corrupt)?;
        if found != key {
            return Err(CheckpointError::Foreign {
                path: shown(),
                found: found.to_string(),
                expected: key.to_string(),
            });
        }
        bincode::deserialize(payload).map_err(|e| corrupt(e.to_string()))
    }

    /// `Err` with what differs when this checkpoint was not taken on
    /// `model` (with `n_dofs` global DOFs).
    pub(crate) fn check_matches(&self, model: &Model, n_dofs: usize) -> Result<(), String> {
        let path = &self.state.path;
        let increment = path.last_increment.len();
        if self.n_nodes != model.nodes.len()
            || self.n_tets != model.tets.len()
            || self.n_interfaces != model.interfaces.len()
            || path.u.len() != n_dofs
            || !(increment == 0 || increment == n_dofs)
            || path.states.bulk.len() != model.tets.len()
            || path.states.interface.len() != INTERFACE_POINTS * model.interfaces.len()
        {
            return Err(format!(
                "checkpoint has {} nodes, {} tets, {} interface elements; model has {}, {}, {}",
                self.n_nodes,
                self.n_tets,
                self.n_interfaces,
                model.nodes.len(),
                model.tets.len(),
                model.interfaces.len()
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A framed payload reads back whole; every flipped byte (header,
    /// checksum or state) and every truncation is refused, never read as
    /// a state.
    #[test]
    fn every_flipped_byte_and_truncation_of_a_frame_is_refused() {
        let payload: Vec<u8> = (0..200u8).collect();
        let bytes = frame("0123abcd", &payload);
        assert_eq!(unframe(&bytes), Ok(("0123abcd", payload.as_slice())));
        for i in 0..bytes.len() {
            let mut flipped = bytes.clone();
            flipped[i] ^= 0x40;
            // A flip inside the key can only give another key, which
            // `load` refuses as foreign; anything else fails here.
            if let Ok((key, data)) = unframe(&flipped) {
                assert!(key != "0123abcd" && data == payload, "byte {i}");
            }
        }
        for n in 0..bytes.len() {
            assert!(unframe(&bytes[..n]).is_err(), "truncated to {n} bytes");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(unframe(&longer).unwrap_err().contains("header says"));
    }

    /// `load` names the file and tells a foreign checkpoint (another key)
    /// from a damaged one.
    #[test]
    fn load_tells_foreign_from_damaged() {
        let dir = std::env::temp_dir().join(format!("ribbar-cp-frame-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("checkpoint.bin");
        std::fs::write(&path, frame("other", b"not a state")).unwrap();
        let err = Checkpoint::load(&path, "mine").unwrap_err();
        assert!(matches!(err, CheckpointError::Foreign { .. }), "{err}");
        assert!(err.to_string().contains("checkpoint.bin") && err.to_string().contains("other"));
        let err = Checkpoint::load(&path, "other").unwrap_err();
        assert!(matches!(err, CheckpointError::Corrupt { .. }), "{err}");
        std::fs::write(&path, b"RIBBARCP\x01\x00\x00\x00").unwrap();
        let err = Checkpoint::load(&path, "mine").unwrap_err().to_string();
        assert!(err.contains("format 1"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Solves of `iterations` each reaching `residual` until the wear
    /// passes a build (40 iterations); returns how many it took.
    fn solves_until_worn(wear: &mut HierarchyWear, iterations: usize, residual: f64) -> usize {
        (1..=100)
            .find(|_| wear.after_solve(iterations, residual))
            .expect("the wear passes the build's cost")
    }

    fn close(a: Option<f64>, b: f64) -> bool {
        a.is_some_and(|a| (a - b).abs() <= 1e-12 * b)
    }

    #[test]
    fn a_rebuild_that_does_not_pay_doubles_the_wear_awaited() {
        let mut wear = HierarchyWear::default();
        assert!(!wear.after_solve(10, 1e-3));
        // 20 beyond the first each: the third later solve passes 40.
        assert_eq!(solves_until_worn(&mut wear, 30, 1e-3), 3);
        // The new hierarchy's first solve needs as many iterations per
        // decade as the worn one's (10): the rebuild did not pay.
        let mut wear = wear.rebuilt();
        assert!(!wear.after_solve(30, 1e-3));
        assert_eq!(wear.doublings, 1);
        assert_eq!(solves_until_worn(&mut wear, 50, 1e-3), 5, "80 awaited");
        // A build before any solve (the secant's) keeps the judgement.
        let wear = wear.rebuilt();
        assert!(close(wear.replaced_rate, 50.0 / 3.0));
        let mut wear = wear.rebuilt();
        assert!(close(wear.replaced_rate, 50.0 / 3.0));
        // 8 per decade against 16.7: this one paid, the next waits for 40.
        assert!(!wear.after_solve(24, 1e-3));
        assert_eq!(wear.doublings, 0);
        assert_eq!(solves_until_worn(&mut wear, 45, 1e-3), 2);
    }

    #[test]
    fn rebuilds_that_do_not_pay_wait_at_most_sixteen_builds() {
        // First solves of 16 iterations per decade after later ones of 21:
        // no rebuild pays.
        let mut wear = HierarchyWear::default();
        wear.after_solve(32, 1e-2);
        for doublings in 1..=6 {
            solves_until_worn(&mut wear, 42, 1e-2);
            wear = wear.rebuilt();
            wear.after_solve(32, 1e-2);
            assert_eq!(wear.doublings, doublings.min(MAX_WEAR_DOUBLINGS));
        }
        // 10 beyond the first a solve: 640 iterations wait for 65 solves.
        assert_eq!(solves_until_worn(&mut wear, 42, 1e-2), 65);
    }

    /// A rebuild for another reason (GMRES failed, the half limit) with
    /// the hierarchy unworn is not judged; an empty right-hand side
    /// (relative residual 0) counts no decades.
    #[test]
    fn only_rebuilds_for_wear_are_judged() {
        let mut wear = HierarchyWear::default();
        wear.after_solve(10, 1e-3);
        wear.after_solve(0, 0.0);
        assert_eq!(wear.later_decades, 0.0);
        wear.after_solve(30, 1e-3);
        let mut wear = wear.rebuilt();
        assert_eq!(wear.replaced_rate, None);
        wear.after_solve(30, 1e-3);
        assert_eq!(wear.doublings, 0);
    }
}
