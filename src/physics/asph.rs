//! A smoothing length that follows the material's stretch as a tensor: the adaptive SPH of
//! Owen, Villumsen, Shapiro & Martel (1998, ApJS 116, 155), as Spheral's ASPH, with the
//! kernel's ellipsoid taken from the particle's own left Cauchy–Green tensor b = F Fᵀ
//! (`Particles::stretch`) instead of from its neighbours' second moment.
//!
//! A round kernel sees a flattened lattice: in the foot of a Taylor rod the rows close to
//! half a spacing while the columns open to twice one, so the vertical neighbours sit where
//! the cubic spline's gradient falls to zero (the compressive instability, Swegle et al.
//! 1995, σ W'' > 0) and the lateral ones at its edge. On the plane-strain slab
//! (`examples/taylor_slab_2d.toml`) rows of particles then fold onto the wall between the
//! lowest row's, and the foot spreads more the finer the lattice (docs/open-problems.md).
//! With the ellipsoid, a neighbour at x_ij = F X_ij (an affine deformation of its initial
//! offset X_ij) sits at |G x_ij| = |R X_ij| = |X_ij| in the kernel's own coordinates,
//! G = b^(−½)/h: the deformed lattice looks to the kernel as the initial one did.
//!
//! Particle i's kernel is W_i(x) = det(G_i) w(|G_i x|), w the round kernel with h = 1; its
//! gradient ∇W_i = det(G_i) A_i x w'(q)/q with A_i = G_iᵀ G_i = b_i⁻¹/h_iso,i² and q = |G_i x|. A
//! pair uses the mean metric A_ij = ½ (A_i + A_j), so that ∇_i W_ij = −∇_j W_ji and momentum
//! is conserved: ∇_i W_ij = √(det A_ij) A_ij x_ij w'(q)/q with q² = x_ij·A_ij x_ij. With b = 1
//! this is the round kernel at h_ij = ½ (h_i + h_j) up to the mean of 1/h² instead of h.
//!
//! b's principal stretches are bounded to [1/s, s] with s = `simulation.smoothing_stretch`, so
//! the ellipsoid's longest axis, h_iso max(λ, 1), is the particle's h, which the neighbour
//! lists' support already covers (`integrate::smoothing_length`); its shortest, h_iso λ_min,
//! sets the time step. Materials that do not flow plastically keep b = 1 and a round kernel.

use super::{sym, SYM};
use crate::kernel::Kernel;
use crate::tensor::{symmetric_eigen, Sym};

/// A particle's kernel metric A = b⁻¹/h_iso² (components in [`SYM`] order) and the
/// ellipsoid's shortest half-axis over 2 (the h that bounds the time step).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Metric {
    pub a: [f64; 6],
    pub h_min: f64,
}

impl Metric {
    /// The metric of nothing: the padding record's (every pair with it lies beyond support).
    pub const NONE: Metric = Metric {
        a: [0.0; 6],
        h_min: 0.0,
    };

    /// The metric of a particle with stretch `b` and smoothing length `h` (the ellipsoid's
    /// longest half-axis over 2), its principal stretches bounded to [1/s, s].
    pub fn of<const D: usize>(b: &Sym<f64, D>, h: f64, s: f64) -> Metric {
        let (ev, q) = symmetric_eigen(&b.full());
        let lambda: [f64; D] = std::array::from_fn(|k| ev[k].max(0.0).sqrt().clamp(1.0 / s, s));
        let longest = lambda.iter().copied().fold(1.0_f64, f64::max);
        let shortest = lambda.iter().copied().fold(f64::INFINITY, f64::min);
        let h_iso = h / longest;
        let mut a = [0.0; 6];
        for (k, &(r, c)) in SYM.iter().enumerate() {
            if r < D && c < D {
                let mut v = 0.0;
                for e in 0..D {
                    v += q[(r, e)] * q[(c, e)] / (lambda[e] * lambda[e]);
                }
                a[k] = v / (h_iso * h_iso);
            }
        }
        Metric {
            a,
            h_min: h_iso * shortest,
        }
    }
}

/// The pair's mean metric A_ij = ½ (A_i + A_j), A_ij x_ij and q² = x_ij·A_ij x_ij.
#[inline(always)]
fn quadratic<const D: usize>(
    ai: &[f64; 6],
    aj: &[f64; 6],
    xij: &[f64; D],
) -> ([f64; 6], [f64; D], f64) {
    let a: [f64; 6] = std::array::from_fn(|k| 0.5 * (ai[k] + aj[k]));
    let ax: [f64; D] = std::array::from_fn(|r| {
        let mut s = 0.0;
        for (c, x) in xij.iter().enumerate() {
            s += a[sym(r.min(c), r.max(c))] * x;
        }
        s
    });
    let mut q2 = 0.0;
    for k in 0..D {
        q2 += xij[k] * ax[k];
    }
    (a, ax, q2)
}

/// Whether the pair lies inside its ellipsoid's support, q < 2 ([`pair_gradient`]'s q, to the
/// bit): beyond it every term of the pair is zero. The neighbour lists' round support holds
/// the ellipsoid's longest axis, so a flattened particle's list holds up to s^D times the
/// neighbours its ellipsoid reaches; the passes leave the rest out before their sums.
#[inline(always)]
pub fn within<const D: usize>(ai: &[f64; 6], aj: &[f64; 6], xij: &[f64; D]) -> bool {
    quadratic(ai, aj, xij).2 < 4.0
}

/// The pair's kernel gradient ∇_i W_ij, the pair's h along its line (|x_ij|/q, which the
/// viscosity takes), and the mean metric's isotropic h, det(A_ij)^(−1/(2D)) (which the
/// artificial stress's W(Δp) takes).
#[inline(always)]
pub fn pair_gradient<const D: usize, K: Kernel>(
    kernel: K,
    ai: &[f64; 6],
    aj: &[f64; 6],
    xij: &[f64; D],
) -> ([f64; D], f64, f64) {
    let (a, ax, q2) = quadratic(ai, aj, xij);
    let mut r2 = 0.0;
    for x in xij {
        r2 += x * x;
    }
    let det = determinant::<D>(&a);
    let root = det.max(0.0).sqrt();
    let q = q2.sqrt();
    // The round kernel at h = 1: (1/q) dw/dq, zero beyond q = 2.
    let gf = if q > 0.0 {
        root * kernel.grad_factor::<D>(q, 1.0)
    } else {
        0.0
    };
    let h_line = if q > 0.0 { (r2 / q2).sqrt() } else { 0.0 };
    let h_iso = if root > 0.0 {
        root.powf(-1.0 / D as f64)
    } else {
        0.0
    };
    (std::array::from_fn(|k| ax[k] * gf), h_line, h_iso)
}

/// The pair's kernel value W_ij = √(det A_ij) w(q) (for the tests' sums; the pass takes
/// only the gradient).
#[cfg(test)]
fn pair_value<const D: usize, K: Kernel>(
    kernel: K,
    ai: &[f64; 6],
    aj: &[f64; 6],
    xij: &[f64; D],
) -> f64 {
    let a: [f64; 6] = std::array::from_fn(|k| 0.5 * (ai[k] + aj[k]));
    let mut q2 = 0.0;
    for r in 0..D {
        for c in 0..D {
            q2 += xij[r] * a[sym(r.min(c), r.max(c))] * xij[c];
        }
    }
    determinant::<D>(&a).max(0.0).sqrt() * kernel.w::<D>(q2.sqrt(), 1.0)
}

/// det of the symmetric matrix with components `a` in [`SYM`] order.
#[inline(always)]
fn determinant<const D: usize>(a: &[f64; 6]) -> f64 {
    if D == 2 {
        a[0] * a[1] - a[3] * a[3]
    } else {
        // [[a0, a3, a4], [a3, a1, a5], [a4, a5, a2]]
        a[0] * (a[1] * a[2] - a[5] * a[5]) - a[3] * (a[3] * a[2] - a[5] * a[4])
            + a[4] * (a[3] * a[5] - a[1] * a[4])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::CubicSpline;
    use crate::particles::Tensor;
    use approx::assert_relative_eq;

    /// b = F Fᵀ of a deformation gradient F.
    fn stretch_of<const D: usize>(f: &Tensor<D>) -> Sym<f64, D> {
        Sym::from_full(&(f * f.transpose()))
    }

    /// With b = 1 the pair gradient is the round kernel's at h_ij (equal h: exactly h).
    #[test]
    fn a_round_metric_is_the_round_kernel() {
        let h = 1.3e-3;
        let m = Metric::of::<3>(&Sym::from_full(&Tensor::<3>::identity()), h, 2.0);
        assert_relative_eq!(m.h_min, h, max_relative = 1e-15);
        for r in [0.2e-3, 0.9e-3, 1.6e-3, 2.5e-3] {
            let x = [0.6 * r, -0.48 * r, 0.64 * r];
            let (g, h_line, h_iso) = pair_gradient::<3, _>(CubicSpline, &m.a, &m.a, &x);
            let gf = CubicSpline.grad_factor::<3>(r, h);
            for k in 0..3 {
                assert_relative_eq!(g[k], x[k] * gf, max_relative = 1e-12, epsilon = 1e-300);
            }
            assert_relative_eq!(h_line, h, max_relative = 1e-12);
            assert_relative_eq!(h_iso, h, max_relative = 1e-12);
        }
    }

    /// The kernel's first moment Σ_j V_j x_ji ⊗ ∇_i W_ij (the identity where the gradient is
    /// consistent). On a lattice stretched by F = diag(2, ½) (plane strain, volume kept: the
    /// foot of a Taylor slab) the round kernel at its cap (1.25 h0) reads 0.75 across the
    /// stretch, and its nearest neighbours along the closed rows sit at q = ⅓, where W'' < 0:
    /// under compression σ W'' > 0, Swegle et al.'s (1995) condition for the instability. The
    /// ellipsoid reads the initial lattice's moment to round-off, and those neighbours at
    /// q = ⅚, where W'' > 0.
    #[test]
    fn the_ellipsoid_keeps_the_moment_of_a_stretched_lattice() {
        let dp = 1.0e-3;
        let h0 = 1.2 * dp;
        let f = Tensor::<2>::new(2.0, 0.0, 0.0, 0.5);
        let ellipse = Metric::of::<2>(&stretch_of(&f), h0 * 2.0, 2.0);
        let round_h = h0 * 1.25;
        let id = Sym::from_full(&Tensor::<2>::identity());
        let round = Metric::of::<2>(&id, round_h, 2.0);
        let initial = Metric::of::<2>(&id, h0, 2.0);
        let vol = dp * dp; // F keeps the volume
        let moment = |m: &Metric, stretch: [f64; 2]| {
            let mut s = Tensor::<2>::zeros();
            for a in -8i32..=8 {
                for c in -8i32..=8 {
                    if a == 0 && c == 0 {
                        continue;
                    }
                    // j at x from i at the origin: x_ij = −x.
                    let x = [stretch[0] * a as f64 * dp, stretch[1] * c as f64 * dp];
                    let xij = [-x[0], -x[1]];
                    let (g, _, _) = pair_gradient::<2, _>(CubicSpline, &m.a, &m.a, &xij);
                    for r in 0..2 {
                        for k in 0..2 {
                            s[(r, k)] += vol * x[r] * g[k];
                        }
                    }
                }
            }
            s
        };
        let m0 = moment(&initial, [1.0, 1.0]);
        assert_relative_eq!(m0, Tensor::<2>::identity(), epsilon = 0.01);
        assert_relative_eq!(moment(&ellipse, [2.0, 0.5]), m0, max_relative = 1e-12);
        let r = moment(&round, [2.0, 0.5]);
        assert_relative_eq!(r[(0, 0)], 0.7535, epsilon = 1e-4);
        // The nearest neighbour along the closed rows, 0.5 Δp away.
        let row = [0.0, 0.5 * dp];
        let (_, h_line, _) = pair_gradient::<2, _>(CubicSpline, &ellipse.a, &ellipse.a, &row);
        let q_ellipse = 0.5 * dp / h_line;
        let q_round = 0.5 * dp / round_h;
        assert_relative_eq!(q_ellipse, 5.0 / 6.0, max_relative = 1e-12);
        assert_relative_eq!(q_round, 1.0 / 3.0, max_relative = 1e-12);
        assert!(CubicSpline.d2w::<2>(q_round, 1.0) < 0.0);
        assert!(CubicSpline.d2w::<2>(q_ellipse, 1.0) > 0.0);
        // The shortest half-axis sets the step: h0 ½ (the rows' spacing closed by half).
        assert_relative_eq!(ellipse.h_min, 0.5 * h0, max_relative = 1e-12);
    }

    /// Σ_j V_j W_ij = 1 on a sheared lattice in 3D (the ellipsoid's normalisation), and the
    /// pair gradient is antisymmetric between particles of different metrics.
    #[test]
    fn the_ellipsoid_is_normalised_and_its_pair_gradient_antisymmetric() {
        let dp = 1.0e-3;
        let h0 = 1.2 * dp;
        let f = Tensor::<3>::new(1.6, 0.3, 0.0, 0.0, 0.8, 0.1, 0.0, 0.0, 1.0 / (1.6 * 0.8));
        let b = stretch_of(&f);
        let longest = crate::integrate::largest_stretch(&b.full()).min(2.0);
        let m = Metric::of::<3>(&b, h0 * longest, 2.0);
        let mut sum = 0.0;
        for a in -6i32..=6 {
            for c in -6i32..=6 {
                for d in -6i32..=6 {
                    let x0 = nalgebra::Vector3::new(a as f64, c as f64, d as f64) * dp;
                    let x = f * x0;
                    sum += dp.powi(3)
                        * pair_value::<3, _>(CubicSpline, &m.a, &m.a, &[x[0], x[1], x[2]]);
                }
            }
        }
        assert_relative_eq!(sum, 1.0, epsilon = 2e-3);
        let other = Metric::of::<3>(&Sym::from_full(&Tensor::<3>::identity()), h0, 2.0);
        let x = [0.7e-3, -0.4e-3, 0.3e-3];
        let (g, _, _) = pair_gradient::<3, _>(CubicSpline, &m.a, &other.a, &x);
        let (back, _, _) = pair_gradient::<3, _>(CubicSpline, &other.a, &m.a, &x.map(|v| -v));
        for k in 0..3 {
            assert_eq!(g[k], -back[k]);
        }
    }
}
