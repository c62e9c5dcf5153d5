//! Small tensor helpers shared by the material models, the artificial stress and the output.

use crate::particles::Tensor;
use nalgebra::{SMatrix, SVector};

/// A symmetric D × D tensor kept as its diagonal and the components above it (xy, xz, yz in
/// 3D; xy in 2D, whose second slot stays zero): 48 bytes in 3D instead of 72, the same 32 in
/// 2D. [`Sym::from_full`] keeps the upper triangle and [`Sym::full`] mirrors it: a symmetric
/// tensor comes back bit for bit. The particles' S and b = F Fᵀ are symmetric in exact
/// arithmetic, but the products that update them (Ω S − S Ω, ΔF b ΔFᵀ) add their terms in
/// different orders for (a, b) and (b, a), and until 2026-11-29, when they were kept whole,
/// they drifted apart at round-off; kept this way they stay symmetric. The strain rate
/// ½ (L + Lᵀ) is symmetric to the bit.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Sym<T: nalgebra::Scalar, const D: usize> {
    diag: SVector<T, D>,
    off: SVector<T, D>,
}

/// Where component (a, b), a < b, sits among [`Sym`]'s off-diagonal slots.
#[inline(always)]
const fn off_slot(a: usize, b: usize) -> usize {
    a + b - 1
}

impl<T: nalgebra::RealField + Copy, const D: usize> Sym<T, D> {
    /// The zero tensor.
    pub fn zeros() -> Self {
        Sym {
            diag: SVector::zeros(),
            off: SVector::zeros(),
        }
    }

    /// The upper triangle of `t` (symmetric: see the type's doc).
    #[inline]
    pub fn from_full(t: &SMatrix<T, D, D>) -> Self {
        let mut s = Self::zeros();
        for a in 0..D {
            s.diag[a] = t[(a, a)];
            for b in a + 1..D {
                s.off[off_slot(a, b)] = t[(a, b)];
            }
        }
        s
    }

    /// The whole D × D tensor.
    #[inline]
    pub fn full(&self) -> SMatrix<T, D, D> {
        SMatrix::from_fn(|a, b| self.get(a, b))
    }

    /// Component (a, b).
    #[inline]
    pub fn get(&self, a: usize, b: usize) -> T {
        match a.cmp(&b) {
            std::cmp::Ordering::Equal => self.diag[a],
            std::cmp::Ordering::Less => self.off[off_slot(a, b)],
            std::cmp::Ordering::Greater => self.off[off_slot(b, a)],
        }
    }

    /// The stored components, all finite.
    pub fn is_finite(&self) -> bool {
        self.diag
            .iter()
            .chain(self.off.iter())
            .all(|c| c.is_finite())
    }

    /// The tensor seen in the mirror of the plane normal to axis k: M T M with
    /// M = I − 2 e_k e_kᵀ, the components with one index k change sign.
    pub fn mirror(&mut self, k: usize) {
        for a in 0..D {
            for b in a + 1..D {
                if (a == k) != (b == k) {
                    self.off[off_slot(a, b)] = -self.off[off_slot(a, b)];
                }
            }
        }
    }
}

/// Out-of-plane deviatoric component: S_zz = −tr S in 2D plane strain (S is traceless in 3D),
/// 0 in 3D (where it is already part of S).
pub fn out_of_plane<const D: usize>(s: &Tensor<D>) -> f64 {
    if D == 2 {
        -s.trace()
    } else {
        0.0
    }
}

/// S:S including the plane-strain S_zz.
pub fn deviator_norm2<const D: usize>(s: &Tensor<D>) -> f64 {
    let szz = out_of_plane(s);
    s.component_mul(s).sum() + szz * szz
}

/// von Mises equivalent stress σ_eq = √(3/2 S:S), S_zz included in 2D.
pub fn von_mises<const D: usize>(s: &Tensor<D>) -> f64 {
    (1.5 * deviator_norm2(s)).sqrt()
}

/// Equivalent strain rate ε̇ = √(2/3 d′:d′) of a velocity gradient L, with d = (L + Lᵀ)/2 and d′
/// its deviator (in 2D plane strain d_zz = 0, and d′_zz = −tr d/3 counts).
pub fn equivalent_strain_rate<const D: usize>(l: &Tensor<D>) -> f64 {
    let d = (l + l.transpose()) * 0.5;
    let mean = d.trace() / 3.0;
    let dev = d - Tensor::<D>::identity() * mean;
    let zz = if D == 2 { -mean } else { 0.0 };
    (2.0 / 3.0 * (dev.component_mul(&dev).sum() + zz * zz)).sqrt()
}

/// Largest principal value of a symmetric stress σ, the plane-strain σ_zz included in 2D (given
/// as `zz`; ignored in 3D): −λ_min(−σ) in closed form (`physics::correction::min_eigenvalue`).
pub fn max_principal<const D: usize>(sigma: &Tensor<D>, zz: f64) -> f64 {
    let top = -crate::physics::correction::min_eigenvalue(&(-sigma));
    if D == 2 {
        top.max(zz)
    } else {
        top
    }
}

/// An upper bound of [`max_principal`] by Gershgorin's discs, max_a (σ_aa + Σ_{b≠a} |σ_ab|)
/// (and σ_zz in 2D): no square root or trigonometry, for the tests that only ask whether the
/// largest principal stress can pass a threshold.
pub fn max_principal_bound<const D: usize>(sigma: &Tensor<D>, zz: f64) -> f64 {
    let mut top = if D == 2 { zz } else { f64::NEG_INFINITY };
    for a in 0..D {
        let mut disc = sigma[(a, a)];
        for b in 0..D {
            if b != a {
                disc += sigma[(a, b)].abs();
            }
        }
        top = top.max(disc);
    }
    top
}

/// Eigen-decomposition of a symmetric D×D matrix by cyclic Jacobi rotations:
/// returns (eigenvalues, eigenvectors as columns), A = Q diag(λ) Qᵀ. Exact to round-off for
/// the 2×2 and 3×3 stresses it is used on.
pub fn symmetric_eigen<const D: usize>(a: &Tensor<D>) -> ([f64; D], Tensor<D>) {
    let mut a = *a;
    let mut q = Tensor::<D>::identity();
    for _sweep in 0..32 {
        let mut off = 0.0;
        for p in 0..D {
            for r in p + 1..D {
                off += a[(p, r)] * a[(p, r)];
            }
        }
        let scale = a.component_mul(&a).sum();
        if off <= 1e-30 * scale || off == 0.0 {
            break;
        }
        for p in 0..D {
            for r in p + 1..D {
                let apr = a[(p, r)];
                if apr == 0.0 {
                    continue;
                }
                let theta = (a[(r, r)] - a[(p, p)]) / (2.0 * apr);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                let mut rot = Tensor::<D>::identity();
                rot[(p, p)] = c;
                rot[(r, r)] = c;
                rot[(p, r)] = s;
                rot[(r, p)] = -s;
                a = rot.transpose() * a * rot;
                q *= rot;
            }
        }
    }
    let mut lambda = [0.0; D];
    for (k, l) in lambda.iter_mut().enumerate() {
        *l = a[(k, k)];
    }
    (lambda, q)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A symmetric tensor comes back whole, bit for bit, in 2D and 3D; its mirror is M T M
    /// (M = I − 2 e_k e_kᵀ); and the 3D store is two thirds of the tensor's size.
    #[test]
    fn sym_keeps_a_symmetric_tensor() {
        let t3 = Tensor::<3>::new(1.5, -2.25, 3.0, -2.25, 4.0, 0.1, 3.0, 0.1, -5.5);
        let t2 = Tensor::<2>::new(1.5, 0.3, 0.3, -7.0);
        assert_eq!(Sym::from_full(&t3).full(), t3);
        assert_eq!(Sym::from_full(&t2).full(), t2);
        assert_eq!(Sym::from_full(&t3).get(2, 0), 3.0);
        for k in 0..3 {
            let mut m = Tensor::<3>::identity();
            m[(k, k)] = -1.0;
            let mut s = Sym::from_full(&t3);
            s.mirror(k);
            assert_eq!(s.full(), m * t3 * m, "axis {k}");
        }
        let mut s = Sym::from_full(&t2);
        s.mirror(1);
        assert_eq!(s, Sym::from_full(&Tensor::<2>::new(1.5, -0.3, -0.3, -7.0)));
        assert_eq!(std::mem::size_of::<Sym<f64, 3>>(), 48);
        assert_eq!(std::mem::size_of::<Sym<f32, 3>>(), 24);
        assert_eq!(std::mem::size_of::<Sym<f64, 2>>(), 32);
    }

    proptest::proptest! {
        /// Gershgorin's bound is never below the largest principal value, 2D (zz counted) and
        /// 3D, and is it for a diagonal stress.
        #[test]
        fn principal_bound_is_above(c in proptest::collection::vec(-5.0f64..5.0, 7)) {
            let a = Tensor::<3>::new(c[0], c[3], c[4], c[3], c[1], c[5], c[4], c[5], c[2]);
            proptest::prop_assert!(max_principal_bound(&a, 0.0) >= max_principal(&a, 0.0) - 1e-12);
            let b = Tensor::<2>::new(c[0], c[3], c[3], c[1]);
            proptest::prop_assert!(max_principal_bound(&b, c[6]) >= max_principal(&b, c[6]) - 1e-12);
            let d = Tensor::<3>::from_diagonal(&nalgebra::Vector3::new(c[0], c[1], c[2]));
            proptest::prop_assert_eq!(max_principal_bound(&d, 0.0), c[0].max(c[1]).max(c[2]));
        }
    }

    #[test]
    fn largest_principal_value_and_strain_rate() {
        // diag(3, −1, 2) rotated about z by 30°: still 3; in 2D the plane-strain zz counts.
        let (c, s_) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let r = Tensor::<3>::new(c, -s_, 0.0, s_, c, 0.0, 0.0, 0.0, 1.0);
        let a =
            r * Tensor::<3>::from_diagonal(&nalgebra::Vector3::new(3.0, -1.0, 2.0)) * r.transpose();
        approx::assert_relative_eq!(max_principal(&a, 0.0), 3.0, max_relative = 1e-12);
        let b = Tensor::<2>::new(1.0, 0.0, 0.0, -2.0);
        assert_eq!(max_principal(&b, 5.0), 5.0);
        // Uniaxial stretching ε̇ along x (3D): √(2/3 d′:d′) = ε̇ · √(2/3 (4/9 + 1/9 + 1/9)) = 2/3 ε̇.
        let l = Tensor::<3>::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        approx::assert_relative_eq!(equivalent_strain_rate(&l), 2.0 / 3.0, max_relative = 1e-14);
    }
    use approx::assert_relative_eq;

    #[test]
    fn eigen_reconstructs_3d() {
        let a = Tensor::<3>::new(4.0, 1.0, -2.0, 1.0, 3.0, 0.5, -2.0, 0.5, -1.0);
        let (l, q) = symmetric_eigen(&a);
        let d = Tensor::<3>::from_diagonal(&nalgebra::Vector3::new(l[0], l[1], l[2]));
        let back = q * d * q.transpose();
        assert_relative_eq!(back, a, epsilon = 1e-12);
        assert_relative_eq!(l.iter().sum::<f64>(), a.trace(), epsilon = 1e-12);
    }

    #[test]
    fn von_mises_uniaxial_plane_strain() {
        // 3D deviator of uniaxial stress σ along x: S = σ diag(2/3, −1/3, −1/3) → σ_eq = σ.
        let s = Tensor::<2>::new(2.0 / 3.0, 0.0, 0.0, -1.0 / 3.0) * 5.0;
        assert_relative_eq!(von_mises(&s), 5.0, epsilon = 1e-12);
    }
}
