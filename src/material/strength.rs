//! Strength models and the radial return.

use crate::particles::Tensor;
use crate::tensor::deviator_norm2;

/// A strength model: elastic shear modulus and the current yield stress.
pub trait Strength: Send + Sync + std::fmt::Debug {
    /// Shear modulus G (Pa); 0 for a fluid.
    fn shear_modulus(&self) -> f64;
    /// Yield stress Y(εp) (Pa); ∞ for an elastic material.
    fn yield_stress(&self, eps_p: f64) -> f64;
    /// Plastic hardening modulus dY/dεp (Pa).
    fn hardening_modulus(&self) -> f64;
}

/// von Mises plasticity with linear isotropic hardening, Y = Y0 + E_h εp (LS-DYNA MAT_010's
/// strength, with E_h the plastic hardening modulus). Y0 = ∞ gives an elastic material,
/// G = 0 a fluid.
#[derive(Debug, Clone, Copy)]
pub struct VonMises {
    pub shear_modulus: f64,
    pub yield_stress: f64,
    pub hardening_modulus: f64,
}

impl Strength for VonMises {
    fn shear_modulus(&self) -> f64 {
        self.shear_modulus
    }

    fn yield_stress(&self, eps_p: f64) -> f64 {
        self.yield_stress + self.hardening_modulus * eps_p
    }

    fn hardening_modulus(&self) -> f64 {
        self.hardening_modulus
    }
}

/// Radial return (Wilkins 1964) of a trial deviator S*: with σ_eq = √(3/2 S*:S*) (plane-strain
/// S_zz included) and Y = Y(εp), if σ_eq > Y the plastic strain grows by
/// Δεp = (σ_eq − Y)/(3G + E_h) and S = S* · (Y + E_h Δεp)/σ_eq, which puts S exactly on the
/// hardened yield surface (for E_h = 0 this is DESIGN.md's S = S* Y/σ_eq). Returns (S, Δεp).
pub fn radial_return<const D: usize>(
    s_trial: &Tensor<D>,
    eps_p: f64,
    strength: &dyn Strength,
) -> (Tensor<D>, f64) {
    let y = strength.yield_stress(eps_p);
    let sigma_eq = (1.5 * deviator_norm2(s_trial)).sqrt();
    if sigma_eq <= y {
        return (*s_trial, 0.0);
    }
    let g = strength.shear_modulus();
    let eh = strength.hardening_modulus();
    let d_eps = (sigma_eq - y) / (3.0 * g + eh);
    let y_new = (y + eh * d_eps).max(0.0);
    (s_trial * (y_new / sigma_eq), d_eps)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tensor::von_mises;
    use approx::assert_relative_eq;

    #[test]
    fn returns_to_the_yield_surface_3d() {
        let m = VonMises {
            shear_modulus: 26e9,
            yield_stress: 0.3e9,
            hardening_modulus: 1e9,
        };
        let s = Tensor::<3>::new(4e8, 1e8, 0.0, 1e8, -1e8, 5e7, 0.0, 5e7, -3e8);
        let (out, d) = radial_return(&s, 0.1, &m);
        let y_new = 0.3e9 + 1e9 * (0.1 + d);
        assert_relative_eq!(von_mises(&out), y_new, max_relative = 1e-12);
        // Consistency: σ_eq* − 3G Δεp equals the new yield stress.
        assert_relative_eq!(von_mises(&s) - 3.0 * 26e9 * d, y_new, max_relative = 1e-12);
        // The direction is kept.
        assert_relative_eq!(out[(0, 1)] / out[(0, 0)], 0.25, max_relative = 1e-12);
    }

    #[test]
    fn elastic_below_yield_and_plane_strain_szz_counts() {
        let m = VonMises {
            shear_modulus: 26e9,
            yield_stress: 1e8,
            hardening_modulus: 0.0,
        };
        // In-plane deviator with S_zz = −(S_xx + S_yy) = −6e7: σ_eq = √(3/2 (4²+2²+6²))e7 ≈ 9.17e7 < Y.
        let s = Tensor::<2>::new(4e7, 0.0, 0.0, 2e7);
        assert_eq!(radial_return(&s, 0.0, &m), (s, 0.0));
        // Doubled it yields, and S_zz enters σ_eq.
        let (out, d) = radial_return(&(s * 2.0), 0.0, &m);
        assert!(d > 0.0);
        assert_relative_eq!(von_mises(&out), 1e8, max_relative = 1e-12);
    }
}
