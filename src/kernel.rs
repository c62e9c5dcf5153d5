//! Smoothing kernels W(r, h) with support 2h, normalised in D dimensions.
//!
//! Each kernel gives W, dW/dr and d²W/dr² (the last for the contact time step). The gradient
//! used everywhere is ∇_i W_ij = (dW/dr)(r_ij) · x_ij / r_ij, pointing from j towards i times a
//! negative dW/dr, i.e. from i towards j.

use std::f64::consts::PI;

/// A radial smoothing kernel with compact support 2h.
pub trait Kernel: Copy + Send + Sync {
    /// W(r, h) in D dimensions.
    fn w<const D: usize>(&self, r: f64, h: f64) -> f64;
    /// dW/dr.
    fn dw<const D: usize>(&self, r: f64, h: f64) -> f64;
    /// d²W/dr².
    fn d2w<const D: usize>(&self, r: f64, h: f64) -> f64;
    /// (1/r) dW/dr for r > 0, so that ∇_i W_ij = x_ij · grad_factor(r_ij, h): the form the pair
    /// loop uses. Written without branches (selects only) and with a single division, so that
    /// the pair loop, which evaluates it for several neighbours at once, vectorises.
    fn grad_factor<const D: usize>(&self, r: f64, h: f64) -> f64;
    /// [`Kernel::grad_factor`] of `L` pairs at once, bit for bit the same; a kernel may write
    /// it one operation over all pairs at a time, which vectorises where the pairs' chains
    /// one by one do not.
    #[inline(always)]
    fn grad_factors<const D: usize, const L: usize>(&self, r: &[f64; L], h: &[f64; L]) -> [f64; L] {
        std::array::from_fn(|l| self.grad_factor::<D>(r[l], h[l]))
    }
}

/// Cubic B-spline (Monaghan & Lattanzio 1985), q = r/h:
/// W = σ_D/h^D · { 1 − 3/2 q² + 3/4 q³ (q < 1); ¼ (2 − q)³ (1 ≤ q < 2); 0 },
/// σ = 2/3, 10/(7π), 1/π in 1D, 2D, 3D.
#[derive(Debug, Clone, Copy, Default)]
pub struct CubicSpline;

/// Wendland C2 (Wendland 1995; Dehnen & Aly 2012) with support 2h, q = r/h:
/// W = σ_D/h^D (1 − q/2)⁴ (2q + 1), σ = 7/(4π) in 2D, 21/(16π) in 3D.
#[derive(Debug, Clone, Copy, Default)]
pub struct WendlandC2;

/// x^(D+2), by multiplication (the exponent of 1/h in (1/r) dW/dr).
#[inline(always)]
fn pow_d2<const D: usize>(x: f64) -> f64 {
    let x2 = x * x;
    match D {
        1 => x2 * x,
        2 => x2 * x2,
        _ => x2 * x2 * x,
    }
}

fn h_pow<const D: usize>(h: f64) -> f64 {
    match D {
        1 => h,
        2 => h * h,
        _ => h * h * h,
    }
}

impl CubicSpline {
    const fn sigma<const D: usize>() -> f64 {
        match D {
            1 => 2.0 / 3.0,
            2 => 10.0 / (7.0 * PI),
            _ => 1.0 / PI,
        }
    }
}

impl Kernel for CubicSpline {
    #[inline(always)]
    fn w<const D: usize>(&self, r: f64, h: f64) -> f64 {
        let q = r / h;
        let f = if q < 1.0 {
            1.0 - 1.5 * q * q + 0.75 * q * q * q
        } else if q < 2.0 {
            let t = 2.0 - q;
            0.25 * t * t * t
        } else {
            0.0
        };
        Self::sigma::<D>() / h_pow::<D>(h) * f
    }

    #[inline(always)]
    fn dw<const D: usize>(&self, r: f64, h: f64) -> f64 {
        let q = r / h;
        let f = if q < 1.0 {
            -3.0 * q + 2.25 * q * q
        } else if q < 2.0 {
            let t = 2.0 - q;
            -0.75 * t * t
        } else {
            0.0
        };
        Self::sigma::<D>() / (h_pow::<D>(h) * h) * f
    }

    #[inline(always)]
    fn d2w<const D: usize>(&self, r: f64, h: f64) -> f64 {
        let q = r / h;
        let f = if q < 1.0 {
            -3.0 + 4.5 * q
        } else if q < 2.0 {
            1.5 * (2.0 - q)
        } else {
            0.0
        };
        Self::sigma::<D>() / (h_pow::<D>(h) * h * h) * f
    }

    #[inline(always)]
    fn grad_factor<const D: usize>(&self, r: f64, h: f64) -> f64 {
        Self::grad_factor_impl::<D>(r, h)
    }

    /// `CubicSpline::grad_factor_impl`'s operations, each over all `L` pairs.
    #[inline(always)]
    fn grad_factors<const D: usize, const L: usize>(&self, r: &[f64; L], h: &[f64; L]) -> [f64; L] {
        let d: [f64; L] = std::array::from_fn(|l| 1.0 / (r[l] * h[l]));
        let inv_h: [f64; L] = std::array::from_fn(|l| r[l] * d[l]);
        let q: [f64; L] = std::array::from_fn(|l| r[l] * inv_h[l]);
        let inner: [f64; L] = std::array::from_fn(|l| -3.0 + 2.25 * q[l]);
        let t: [f64; L] = std::array::from_fn(|l| (2.0 - q[l]).max(0.0));
        let outer: [f64; L] = std::array::from_fn(|l| -0.75 * t[l] * t[l] * (h[l] * h[l] * d[l]));
        let f: [f64; L] = std::array::from_fn(|l| if q[l] < 1.0 { inner[l] } else { outer[l] });
        std::array::from_fn(|l| Self::sigma::<D>() * pow_d2::<D>(inv_h[l]) * f[l])
    }
}

impl CubicSpline {
    /// (1/r) dW/dr = σ/h^(D+2) · { −3 + 9/4 q (q < 1); −¾ (2 − q)²/q (1 ≤ q < 2); 0 }, with
    /// 1/h and 1/q = h/r both taken from the one division 1/(r h).
    #[inline(always)]
    fn grad_factor_impl<const D: usize>(r: f64, h: f64) -> f64 {
        let d = 1.0 / (r * h);
        let inv_h = r * d;
        let q = r * inv_h;
        let inner = -3.0 + 2.25 * q;
        let t = (2.0 - q).max(0.0);
        let outer = -0.75 * t * t * (h * h * d);
        let f = if q < 1.0 { inner } else { outer };
        Self::sigma::<D>() * pow_d2::<D>(inv_h) * f
    }
}

impl WendlandC2 {
    const fn sigma<const D: usize>() -> f64 {
        match D {
            2 => 7.0 / (4.0 * PI),
            _ => 21.0 / (16.0 * PI),
        }
    }
}

impl Kernel for WendlandC2 {
    #[inline(always)]
    fn w<const D: usize>(&self, r: f64, h: f64) -> f64 {
        let q = r / h;
        if q >= 2.0 {
            return 0.0;
        }
        let t = 1.0 - 0.5 * q;
        let t2 = t * t;
        Self::sigma::<D>() / h_pow::<D>(h) * t2 * t2 * (2.0 * q + 1.0)
    }

    #[inline(always)]
    fn dw<const D: usize>(&self, r: f64, h: f64) -> f64 {
        let q = r / h;
        if q >= 2.0 {
            return 0.0;
        }
        let t = 1.0 - 0.5 * q;
        Self::sigma::<D>() / (h_pow::<D>(h) * h) * (-5.0 * q) * t * t * t
    }

    #[inline(always)]
    fn d2w<const D: usize>(&self, r: f64, h: f64) -> f64 {
        let q = r / h;
        if q >= 2.0 {
            return 0.0;
        }
        let t = 1.0 - 0.5 * q;
        Self::sigma::<D>() / (h_pow::<D>(h) * h * h) * t * t * (10.0 * q - 5.0)
    }

    /// (1/r) dW/dr = −5 σ/h^(D+2) (1 − q/2)³, 0 beyond the support.
    #[inline(always)]
    fn grad_factor<const D: usize>(&self, r: f64, h: f64) -> f64 {
        let inv_h = 1.0 / h;
        let t = (1.0 - 0.5 * r * inv_h).max(0.0);
        -5.0 * Self::sigma::<D>() * pow_d2::<D>(inv_h) * t * t * t
    }
}

/// ∫W dV and ∫∇W dV by a midpoint sum on a lattice of spacing h/40 over the support (160 points
/// across its 4h), shifted by `offset` along x: the normalisation check of VALIDATION.md §A
/// (`strike validate --case kernel`).
pub fn moments<const D: usize, K: Kernel>(k: K, h: f64, offset: f64) -> (f64, [f64; 3]) {
    let n = 160i64; // lattice points across the support
    let dx = 4.0 * h / n as f64;
    let mut integral = 0.0;
    let mut grad = [0.0; 3];
    let range = -(n / 2)..(n / 2);
    let mut visit = |p: [f64; 3]| {
        let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        let dv = dx.powi(D as i32);
        integral += k.w::<D>(r, h) * dv;
        if r > 0.0 {
            for a in 0..3 {
                grad[a] += k.dw::<D>(r, h) * p[a] / r * dv;
            }
        }
    };
    for i in range.clone() {
        for j in range.clone() {
            let x = (i as f64 + 0.5) * dx + offset;
            let y = (j as f64 + 0.5) * dx;
            if D == 2 {
                visit([x, y, 0.0]);
            } else {
                for l in range.clone() {
                    visit([x, y, (l as f64 + 0.5) * dx]);
                }
            }
        }
    }
    (integral, grad)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check<const D: usize, K: Kernel>(k: K) {
        let h = 0.37;
        let (i, g) = moments::<D, K>(k, h, 0.0);
        assert!((i - 1.0).abs() < 1e-6, "∫W = {i}");
        assert!(g.iter().all(|c| c.abs() < 1e-6 / h), "∫∇W = {g:?}");
        // Shifted lattice: still normalised, gradient still odd.
        let (i, _) = moments::<D, K>(k, h, 0.3 * 4.0 * h / 160.0);
        assert!((i - 1.0).abs() < 1e-6, "shifted ∫W = {i}");
        assert_eq!(k.w::<D>(2.0 * h, h), 0.0);
        assert_eq!(k.w::<D>(2.5 * h, h), 0.0);
        assert_eq!(k.dw::<D>(2.0 * h, h), 0.0);
    }

    #[test]
    fn cubic_spline_normalised() {
        check::<2, _>(CubicSpline);
        check::<3, _>(CubicSpline);
    }

    #[test]
    fn wendland_normalised() {
        check::<2, _>(WendlandC2);
        check::<3, _>(WendlandC2);
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let h = 1.3;
        for r in [0.1, 0.7, 1.2, 1.9, 2.4] {
            let d = 1e-6;
            for (dw, d2w, fd1, fd2) in [
                (
                    CubicSpline.dw::<3>(r, h),
                    CubicSpline.d2w::<3>(r, h),
                    (CubicSpline.w::<3>(r + d, h) - CubicSpline.w::<3>(r - d, h)) / (2.0 * d),
                    (CubicSpline.dw::<3>(r + d, h) - CubicSpline.dw::<3>(r - d, h)) / (2.0 * d),
                ),
                (
                    WendlandC2.dw::<2>(r, h),
                    WendlandC2.d2w::<2>(r, h),
                    (WendlandC2.w::<2>(r + d, h) - WendlandC2.w::<2>(r - d, h)) / (2.0 * d),
                    (WendlandC2.dw::<2>(r + d, h) - WendlandC2.dw::<2>(r - d, h)) / (2.0 * d),
                ),
            ] {
                assert!((dw - fd1).abs() < 1e-7, "dW at r={r}: {dw} vs {fd1}");
                let gf = [
                    CubicSpline.grad_factor::<3>(r, h) * r,
                    WendlandC2.grad_factor::<2>(r, h) * r,
                ];
                assert!(
                    gf.iter().any(|g| (g - dw).abs() < 1e-12 * (1.0 + dw.abs())),
                    "grad factor at r={r}"
                );
                assert!((d2w - fd2).abs() < 1e-6, "d²W at r={r}: {d2w} vs {fd2}");
            }
        }
    }

    /// The branch-free (1/r) dW/dr agrees with dW/dr / r everywhere, 0 beyond the support.
    #[test]
    fn grad_factors_are_grad_factor_bit_for_bit() {
        fn check<const D: usize, K: Kernel>(k: K) {
            // q < 1, 1 ≤ q < 2 and q ≥ 2, with h varying from pair to pair.
            let r = [0.1, 0.5, 0.99, 1.0, 1.5, 1.999, 2.0, 3.0];
            let h: [f64; 8] = std::array::from_fn(|l| 0.9 + 0.05 * l as f64);
            let lanes = k.grad_factors::<D, 8>(&r, &h);
            for l in 0..8 {
                assert_eq!(lanes[l].to_bits(), k.grad_factor::<D>(r[l], h[l]).to_bits());
            }
        }
        check::<2, _>(CubicSpline);
        check::<3, _>(CubicSpline);
        check::<2, _>(WendlandC2);
        check::<3, _>(WendlandC2);
    }

    #[test]
    fn grad_factor_is_dw_over_r() {
        fn check<const D: usize, K: Kernel>(k: K) {
            let h = 0.37;
            for i in 1..=260 {
                let r = i as f64 * 0.01 * h;
                let expect = k.dw::<D>(r, h) / r;
                let got = k.grad_factor::<D>(r, h);
                assert!(
                    (got - expect).abs() <= 1e-13 * expect.abs().max(1.0 / h.powi(D as i32 + 2)),
                    "D={D} q={}: {got} vs {expect}",
                    r / h
                );
                if r >= 2.0 * h {
                    assert_eq!(got, 0.0);
                }
            }
        }
        check::<2, _>(CubicSpline);
        check::<3, _>(CubicSpline);
        check::<2, _>(WendlandC2);
        check::<3, _>(WendlandC2);
    }
}
