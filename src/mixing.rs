//! The no-mixing diagnostics: do the particles of two bodies stay apart?
//!
//! The closest approach between particles of different bodies (`min_interbody_distance`) does
//! not see particles that pass *between* each other: two square lattices can interleave with no
//! pair closer than 0.7 Δp. Two figures that do, for every pair of bodies (a, b):
//!
//! - **penetration**: how far a particle i of one body lies past the surface layer of the other,
//!   in Δp_avg. With n̂ the outward normal of body b seen from i — minus the gradient of b's
//!   colour field c_b(x) = Σ_{j∈b} V_j W(x − x_j) at x_i — every particle of b lies behind i
//!   along n̂ while i is outside b, so the height (x_j − x_i)·n̂ of the neighbours j of b is
//!   negative (−Δp for two bodies touching). It is positive for a particle of b beyond i: i has
//!   passed b's outermost layer. The figure is the largest height over Δp_avg (0 when none is
//!   positive), counting the particles of b within Δp_avg of the normal line through i — those
//!   i would have had to pass, not the walls of a notch i sits in. A particle nestled in a gap
//!   of the other lattice stays below 0.
//! - **mixed**: the number of particles with a positive penetration, i.e. lying past the other
//!   body's surface layer.
//!
//! A particle counts only where both bodies are present as bodies: the other body fills a good
//! part of its neighbourhood, c_b(x_i) ≥ ½ c_a(x_i) (its own body's colour, itself included;
//! a particle that has passed the other's surface layer sees ≈ 0.6 c_a, one touching it from
//! outside ≈ 0.27 c_a), and it is itself part of its body, c_a ≥ 0.45 (0.79 at a face, about
//! 0.45 at the corner of a cube, 0.2–0.3 for a detached fragment). Fragments of a debris cloud
//! may overtake each other — that is flow, not interdigitation.
//!
//! A failed particle (damage 1, `material::damage`) is rubble, not part of a body: it is not
//! counted, it does not make up another body's surface layer, and it does not make up its own
//! body around an intact particle either (c_a sums the intact particles only). Rubble of two
//! bodies mixes in a debris cloud as two sands poured together do; in the paper's
//! demonstration with failure, plate rubble at half density near the hole's edge lies past the
//! sphere's rubble by up to 1.3 Δp for a few nanoseconds. An intact particle amid its own
//! body's rubble is a fragment: in the CN-SPH demo at 0.1 µs a sphere particle with 43 failed
//! neighbours (c_a 0.47 with its rubble, 0.22–0.30 without) flew 0.04 Δp past a plate
//! fragment, and counted as mixed while its rubble counted as its body.
//!
//! Both are zero for bodies that touch along a face, at a convex or a concave corner, and grow
//! with the interleaving of two lattices. They are computed for the particles that have a
//! neighbour of another body within the support (in contact or welded), from the state at t_n.

use crate::kernel::Kernel;
use crate::neighbors::NeighborList;
use crate::particles::Particles;
use rayon::prelude::*;

/// The mixing figures of one pair of bodies (a < b).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PairMixing {
    /// Deepest penetration of a particle of one body past the other's surface layer (Δp_avg).
    pub penetration: f64,
    /// Particles whose neighbourhood is dominated by the other body.
    pub mixed: u64,
}

/// Index of the pair (a, b), a ≠ b, among the n(n−1)/2 pairs of n bodies (a < b, row by row).
pub fn pair_index(n: usize, a: usize, b: usize) -> usize {
    let (a, b) = if a < b { (a, b) } else { (b, a) };
    a * (2 * n - a - 1) / 2 + (b - a - 1)
}

/// A particle with less of its own body around it than this is a fragment (see the module doc).
const MIN_OWN_COLOUR: f64 = 0.45;

/// The other bodies a particle meets: at most this many are told apart (more are rare).
const OTHERS: usize = 4;

/// One other body's colour, its gradient and mean spacing, seen from particle i.
#[derive(Clone, Copy)]
struct Other<const D: usize> {
    body: u32,
    colour: f64,
    grad: [f64; D],
    spacing: f64,
}

/// The mixing figures of every pair of bodies, for the real particles in `owned` flagged in
/// `near` (those with a neighbour of another body within the support). `spacing[b]` is body
/// b's lattice spacing.
pub fn mixing<const D: usize, K: Kernel>(
    kernel: K,
    p: &Particles<D>,
    nl: &NeighborList,
    near: impl Fn(usize) -> bool + Sync,
    spacing: &[f64],
    owned: &std::ops::Range<usize>,
) -> Vec<PairMixing> {
    let bodies = spacing.len();
    let pairs = bodies * bodies.saturating_sub(1) / 2;
    let merge = |mut a: Vec<PairMixing>, b: Vec<PairMixing>| {
        for (x, y) in a.iter_mut().zip(&b) {
            x.penetration = x.penetration.max(y.penetration);
            x.mixed += y.mixed;
        }
        a
    };
    // Max and integer counts: the same result in any order (thread count).
    owned
        .clone()
        .into_par_iter()
        .filter(|&i| near(i))
        .fold(
            || vec![PairMixing::default(); pairs],
            |mut acc, i| {
                nl.with_list(i, |list| particle(kernel, p, list, i, spacing, &mut acc));
                acc
            },
        )
        .reduce(|| vec![PairMixing::default(); pairs], merge)
}

/// Particle i's contribution to the figures of its pairs.
fn particle<const D: usize, K: Kernel>(
    kernel: K,
    p: &Particles<D>,
    list: &[u32],
    i: usize,
    spacing: &[f64],
    acc: &mut [PairMixing],
) {
    let bi = p.body[i];
    if p.damage[i] >= 1.0 {
        return;
    }
    let within = |j: usize| (p.x[i] - p.x[j]).norm() < p.h[i] + p.h[j];
    let mut others: [Option<Other<D>>; OTHERS] = [None; OTHERS];
    let mut own = p.m[i] / p.rho[i] * kernel.w::<D>(0.0, p.h[i]);
    for &j in list {
        let j = j as usize;
        if !within(j) {
            continue;
        }
        let xij = p.x[i] - p.x[j];
        let r = xij.norm();
        let hij = 0.5 * (p.h[i] + p.h[j]);
        let vol = p.m[j] / p.rho[j];
        // Rubble is part of no body: neither the other's nor i's own. A wall's image of a
        // body (body ≥ the bodies, see `boundary`) is no body to mix with.
        if p.damage[j] >= 1.0 || p.body[j] as usize >= spacing.len() {
            continue;
        }
        if p.body[j] == bi {
            own += vol * kernel.w::<D>(r, hij);
            continue;
        }
        let gf = if r > 0.0 {
            kernel.dw::<D>(r, hij) / r
        } else {
            0.0
        };
        let slot = others
            .iter()
            .position(|o| o.is_none_or(|o| o.body == p.body[j]));
        if let Some(k) = slot {
            let o = others[k].get_or_insert(Other {
                body: p.body[j],
                colour: 0.0,
                grad: [0.0; D],
                spacing: 0.5 * (spacing[bi as usize] + spacing[p.body[j] as usize]),
            });
            o.colour += vol * kernel.w::<D>(r, hij);
            for a in 0..D {
                o.grad[a] += vol * gf * xij[a];
            }
        }
    }
    for o in others.iter().flatten() {
        // ∇c_b = Σ V_j ∇_i W_ij points into b; n̂ = −∇c_b/|∇c_b| points from b toward i.
        let g = o.grad.iter().map(|x| x * x).sum::<f64>().sqrt();
        if g == 0.0 {
            continue;
        }
        let n: [f64; D] = std::array::from_fn(|a| -o.grad[a] / g);
        let mut height = f64::NEG_INFINITY;
        for &j in list {
            let j = j as usize;
            if p.body[j] != o.body || p.damage[j] >= 1.0 || !within(j) {
                continue;
            }
            let xji = p.x[j] - p.x[i];
            let along: f64 = (0..D).map(|a| xji[a] * n[a]).sum();
            let lateral2 = xji.norm_squared() - along * along;
            if lateral2 < o.spacing * o.spacing {
                height = height.max(along);
            }
        }
        let k = pair_index(spacing.len(), bi as usize, o.body as usize);
        if height > 0.0 && o.colour >= 0.5 * own && own >= MIN_OWN_COLOUR {
            acc[k].penetration = acc[k].penetration.max(height / o.spacing);
            acc[k].mixed += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pair_indices_are_dense_and_symmetric() {
        let n = 5;
        let mut seen = Vec::new();
        for a in 0..n {
            for b in a + 1..n {
                let k = pair_index(n, a, b);
                assert_eq!(k, pair_index(n, b, a));
                seen.push(k);
            }
        }
        assert_eq!(seen, (0..n * (n - 1) / 2).collect::<Vec<_>>());
    }
}
