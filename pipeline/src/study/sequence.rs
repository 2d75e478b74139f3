//! Seeded sequences of points in the unit cube [0, 1)^dim, drawn in order:
//! a study takes the first n that make valid scenes, and a draw outside
//! the design bounds is replaced by the next draw of the same sequence.
//!
//! - `sobol`: Owen-scrambled Sobol' points (Burley 2020, Joe–Kuo direction
//!   numbers; `sobol_burley`), the scramble and the shuffle of the index
//!   set by the seed; up to 256 dimensions and 2^16 points. Its balance
//!   holds for runs of 2^k points.
//! - `halton`: the Halton sequence in the first primes (`halton`), started
//!   at an index set by the seed (a random-start Halton sequence, Wang &
//!   Hickernell 2000); up to 54 dimensions.
//! - `lhs`: Latin hypercubes of n points (one point in each of n equal
//!   strata of every axis, a seeded permutation per axis, jittered inside
//!   the stratum); draws beyond the first n come from the next hypercube.
//! - `random`: independent uniform points.
//!
//! The seeded generator is ChaCha8 (`rand_chacha`), the same on every
//! platform.

use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;

/// The sequence a sampled study draws from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Owen-scrambled Sobol' points.
    Sobol,
    /// The Halton sequence, started at an index set by the seed.
    Halton,
    /// A Latin hypercube.
    Lhs,
    /// Independent uniform draws.
    Random,
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::Sobol => "sobol",
            Method::Halton => "halton",
            Method::Lhs => "lhs",
            Method::Random => "random",
        }
    }

    /// The most dimensions the method draws.
    pub fn max_dimensions(self) -> usize {
        match self {
            Method::Sobol => sobol_burley::NUM_DIMENSIONS as usize,
            Method::Halton => PRIMES.len(),
            Method::Lhs | Method::Random => usize::MAX,
        }
    }
}

/// The first 54 primes: the Halton bases up to 251 (the crate's u8).
const PRIMES: [u8; 54] = [
    2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53, 59, 61, 67, 71, 73, 79, 83, 89, 97,
    101, 103, 107, 109, 113, 127, 131, 137, 139, 149, 151, 157, 163, 167, 173, 179, 181, 191, 193,
    197, 199, 211, 223, 227, 229, 233, 239, 241, 251,
];

/// The most points a Sobol' stream gives.
pub const SOBOL_MAX_POINTS: usize = 1 << 16;

/// Points of one sequence, in order.
pub struct Stream {
    method: Method,
    dim: usize,
    /// Points per Latin hypercube.
    block: usize,
    seed: u64,
    index: usize,
    rng: ChaCha8Rng,
    /// The Latin hypercube being drawn from.
    pending: Vec<Vec<f64>>,
    halton_start: usize,
}

impl Stream {
    /// The stream of `method` in `dim` dimensions for a design of `n`
    /// points (the Latin hypercubes' size), from `seed`.
    pub fn new(method: Method, dim: usize, n: usize, seed: u64) -> Result<Stream, String> {
        if dim == 0 || dim > method.max_dimensions() {
            return Err(format!(
                "{} draws at most {} dimensions, the design has {dim}",
                method.name(),
                method.max_dimensions()
            ));
        }
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let halton_start = rng.random_range(1..1usize << 20);
        Ok(Stream {
            method,
            dim,
            block: n.max(1),
            seed,
            index: 0,
            rng,
            pending: Vec::new(),
            halton_start,
        })
    }

    /// How many points were drawn so far.
    pub fn drawn(&self) -> usize {
        self.index
    }

    /// The next point, or `None` past the end of a finite sequence.
    pub fn next_point(&mut self) -> Option<Vec<f64>> {
        let i = self.index;
        let point = match self.method {
            Method::Sobol => {
                if i >= SOBOL_MAX_POINTS {
                    return None;
                }
                // The crate's seed is 32 bits: fold the upper half in.
                let seed = (self.seed ^ (self.seed >> 32)) as u32;
                (0..self.dim)
                    .map(|d| f64::from(sobol_burley::sample(i as u32, d as u32, seed)))
                    .collect()
            }
            Method::Halton => (0..self.dim)
                .map(|d| halton::number(PRIMES[d], self.halton_start + i))
                .collect(),
            Method::Random => (0..self.dim).map(|_| self.rng.random::<f64>()).collect(),
            Method::Lhs => {
                if self.pending.is_empty() {
                    self.pending = latin_hypercube(&mut self.rng, self.block, self.dim);
                    self.pending.reverse();
                }
                self.pending.pop()?
            }
        };
        self.index += 1;
        Some(point)
    }
}

/// `n` points in `dim` dimensions, one in each stratum [k/n, (k+1)/n) of
/// every axis.
fn latin_hypercube(rng: &mut ChaCha8Rng, n: usize, dim: usize) -> Vec<Vec<f64>> {
    let strata: Vec<Vec<usize>> = (0..dim)
        .map(|_| {
            let mut p: Vec<usize> = (0..n).collect();
            p.shuffle(rng);
            p
        })
        .collect();
    (0..n)
        .map(|i| {
            (0..dim)
                .map(|d| (strata[d][i] as f64 + rng.random::<f64>()) / n as f64)
                .collect()
        })
        .collect()
}

/// A seeded generator for the designs and estimators built on this module.
pub fn generator(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn first(method: Method, dim: usize, n: usize, seed: u64) -> Vec<Vec<f64>> {
        let mut s = Stream::new(method, dim, n, seed).unwrap();
        (0..n).map(|_| s.next_point().unwrap()).collect()
    }

    /// Every method gives the same points from the same seed and other
    /// points from another, all inside the unit cube.
    #[test]
    fn the_seed_fixes_the_points() {
        for method in [Method::Sobol, Method::Halton, Method::Lhs, Method::Random] {
            let a = first(method, 5, 16, 7);
            assert_eq!(a, first(method, 5, 16, 7), "{method:?}");
            assert_ne!(a, first(method, 5, 16, 8), "{method:?}");
            assert!(
                a.iter().flatten().all(|u| (0.0..1.0).contains(u)),
                "{method:?}"
            );
        }
    }

    /// A Latin hypercube puts one point in each stratum of every axis, and
    /// so does every 2^k run of the scrambled Sobol' points.
    #[test]
    fn hypercubes_and_sobol_runs_fill_every_stratum() {
        for points in [first(Method::Lhs, 4, 16, 3), first(Method::Sobol, 4, 16, 3)] {
            for d in 0..4 {
                let mut strata: Vec<usize> =
                    points.iter().map(|p| (p[d] * 16.0) as usize).collect();
                strata.sort_unstable();
                assert_eq!(strata, (0..16).collect::<Vec<_>>());
            }
        }
        // The next draws of an LHS stream form another hypercube.
        let mut s = Stream::new(Method::Lhs, 2, 8, 1).unwrap();
        let all: Vec<Vec<f64>> = (0..16).map(|_| s.next_point().unwrap()).collect();
        let mut second: Vec<usize> = all[8..].iter().map(|p| (p[0] * 8.0) as usize).collect();
        second.sort_unstable();
        assert_eq!(second, (0..8).collect::<Vec<_>>());
        assert_ne!(all[..8], all[8..]);
    }

    /// The methods refuse designs with more dimensions than they have.
    #[test]
    fn dimensions_are_bounded() {
        assert!(Stream::new(Method::Halton, 55, 8, 0).is_err());
        assert!(Stream::new(Method::Sobol, 257, 8, 0).is_err());
        assert!(Stream::new(Method::Random, 0, 8, 0).is_err());
    }
}
