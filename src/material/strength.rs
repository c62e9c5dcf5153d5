//! Strength models behind one trait, and the radial return. The models: [`VonMises`] (here),
//! [`super::johnson_cook::JohnsonCook`] and [`super::steinberg_guinan::SteinbergGuinan`].

use super::params::{Param, Valid};
use crate::particles::Tensor;
use crate::tensor::deviator_norm2;

/// What a strength model may depend on besides its own parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrengthState {
    /// Equivalent plastic strain εp.
    pub eps_p: f64,
    /// Equivalent (total, deviatoric) strain rate √(2/3 d′:d′) (1/s).
    pub rate: f64,
    /// Specific internal energy e (J/kg): Steinberg–Guinan takes its temperature from it.
    pub e: f64,
    /// Plastic work per unit mass (J/kg): Johnson–Cook takes its temperature from it.
    pub w_p: f64,
    /// Compression η = ρ/ρ0.
    pub eta: f64,
    /// Pressure p (Pa).
    pub p: f64,
}

impl StrengthState {
    /// The reference state: undeformed, at rest, e = 0.
    pub const REFERENCE: StrengthState = StrengthState {
        eps_p: 0.0,
        rate: 0.0,
        e: 0.0,
        w_p: 0.0,
        eta: 1.0,
        p: 0.0,
    };
}

/// A strength model: shear modulus and yield stress at a state.
pub trait Strength: Send + Sync + std::fmt::Debug {
    /// Shear modulus G (Pa); 0 for a fluid.
    fn shear_modulus(&self, st: &StrengthState) -> f64;
    /// Yield stress Y (Pa), ≥ 0; ∞ for an elastic material.
    fn yield_stress(&self, st: &StrengthState) -> f64;
    /// ∂Y/∂εp at the state (Pa); may be infinite (a power law at εp = 0).
    fn hardening_modulus(&self, st: &StrengthState) -> f64;
    /// A factor of Y and ∂Y/∂εp that does not depend on εp (Johnson–Cook's rate and thermal
    /// factors), for [`Strength::yield_and_slope_scaled`]: the radial return's iterations
    /// change only εp, so it is computed once a return instead of once an iteration. 1 by
    /// default (the model has none).
    fn state_factor(&self, _st: &StrengthState) -> f64 {
        1.0
    }
    /// ([`Strength::yield_stress`], [`Strength::hardening_modulus`]) in one call, given the
    /// [`Strength::state_factor`] k of the same rate, temperature and pressure: the same
    /// numbers. A power law's slope follows from its power, εp^(n − 1) = εpⁿ/εp, so that each
    /// iteration of the return costs one `powf`, not two.
    fn yield_and_slope_scaled(&self, st: &StrengthState, _k: f64) -> (f64, f64) {
        (self.yield_stress(st), self.hardening_modulus(st))
    }
    /// A lower bound of Y at the state, below the melt, that costs no transcendental function:
    /// a trial stress under it is elastic without asking Y ([`radial_return`]; Johnson–Cook's
    /// Y asks a logarithm and two powers). 0 by default (no shortcut).
    fn yield_floor(&self, _st: &StrengthState) -> f64 {
        0.0
    }
    /// Homologous temperature T* = (T − T_room)/(T_melt − T_room) in [0, 1] (1: molten, no
    /// deviatoric stress), for the damage models; 0 for a model without temperature.
    fn homologous_temperature(&self, _st: &StrengthState) -> f64 {
        0.0
    }
    /// G in the reference state.
    fn reference_shear_modulus(&self) -> f64 {
        self.shear_modulus(&StrengthState::REFERENCE)
    }
    /// Y in the reference state (εp = 0, at the reference strain rate and temperature).
    fn reference_yield_stress(&self) -> f64 {
        self.yield_stress(&StrengthState::REFERENCE)
    }
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

/// An elastic model's parameter.
pub const ELASTIC_PARAMS: &[Param] = &[Param::required(
    "shear_modulus",
    "the shear modulus G in Pa, e.g. 26e9 for aluminium",
    Valid::Positive,
)];

impl VonMises {
    pub const PARAMS: &'static [Param] = &[
        ELASTIC_PARAMS[0],
        Param::required(
            "yield_stress",
            "the initial yield stress Y0 in Pa, e.g. 0.26e9",
            Valid::Positive,
        ),
        Param::optional(
            "hardening_modulus",
            "the linear hardening modulus E_h in Pa (0: perfectly plastic)",
            Valid::NonNegative,
            0.0,
        ),
    ];
}

impl Strength for VonMises {
    fn shear_modulus(&self, _st: &StrengthState) -> f64 {
        self.shear_modulus
    }

    fn yield_stress(&self, st: &StrengthState) -> f64 {
        self.yield_stress + self.hardening_modulus * st.eps_p
    }

    fn hardening_modulus(&self, _st: &StrengthState) -> f64 {
        self.hardening_modulus
    }
}

/// Radial return (Wilkins 1964) of a trial deviator S* at the state `st` (its rate, energy
/// and pressure held through the step): with σ_eq = √(3/2 S*:S*) (plane-strain S_zz
/// included), if σ_eq > Y(εp) the plastic strain grows by the Δεp that solves
/// σ_eq − 3G Δεp = Y(εp + Δεp) and S = S* · Y(εp + Δεp)/σ_eq, exactly on the hardened yield
/// surface. For linear hardening one Newton step solves it, Δεp = (σ_eq − Y)/(3G + E_h)
/// (DESIGN.md's S = S* Y/σ_eq for E_h = 0); for a power law it is Newton's method kept inside
/// the bracket [0, σ_eq/3G], bisecting where the slope is infinite or a step leaves it. A
/// trial under the model's [`Strength::yield_floor`] is elastic without asking Y. A molten
/// particle (T* = 1) carries no deviator and gains no plastic strain. Returns (S, Δεp).
pub fn radial_return<const D: usize>(
    s_trial: &Tensor<D>,
    st: &StrengthState,
    strength: &dyn Strength,
) -> (Tensor<D>, f64) {
    if strength.homologous_temperature(st) >= 1.0 {
        return (Tensor::<D>::zeros(), 0.0);
    }
    let sigma_eq = (1.5 * deviator_norm2(s_trial)).sqrt();
    if sigma_eq <= strength.yield_floor(st) {
        return (*s_trial, 0.0);
    }
    let k = strength.state_factor(st);
    let (y, slope_y) = strength.yield_and_slope_scaled(st, k);
    if sigma_eq <= y {
        return (*s_trial, 0.0);
    }
    let g = strength.shear_modulus(st);
    if g <= 0.0 {
        return (Tensor::<D>::zeros(), 0.0);
    }
    let at = |d: f64| StrengthState {
        eps_p: st.eps_p + d,
        ..*st
    };
    // f(Δ) = σ_eq − 3GΔ − Y(εp + Δ): f(0) > 0, f(σ_eq/3G) = −Y ≤ 0, f decreasing.
    let (mut lo, mut hi) = (0.0, sigma_eq / (3.0 * g));
    let mut d = 0.0;
    // Y(εp + Δ) and ∂Y/∂εp there at the last Δ tried: the return's end is the last (not asked
    // again: a power law's yield costs a `powf`, and the return asks a handful of them).
    let (mut y_d, mut slope_d) = (y, slope_y);
    let mut f = sigma_eq - y;
    let tol = 1e-12 * sigma_eq;
    // The evaluation before the last (Δ, ∂Y/∂εp), for the curvature Y''.
    let (mut d_before, mut slope_before) = (f64::NAN, f64::NAN);
    for _ in 0..100 {
        let slope = 3.0 * g + slope_d;
        let newton = d + f / slope;
        // The bracket's ends are in it: at hi the yield stress is 0 (a failed particle, or a
        // fluid's), which Newton's step finds at once (bisecting, it took 24 iterations).
        let inside = newton.is_finite() && newton > lo && newton <= hi;
        if inside {
            // A Newton step δ leaves the residual ½ |Y''| δ² of a smooth Y. Y'' is taken from
            // the last two evaluations (NaN until there are two) while the iterates rise, as
            // they do from the left of the root: for a hardening law whose curvature falls
            // with εp (a power law's) that overestimates the curvature ahead. Where the
            // residual is far below the tolerance, the step's linear prediction is the root
            // and Y is not asked again: a power law's return then asks 1.6 `powf` instead of
            // 2.5, its Y off its own value by less than 1e-13 of σ_eq.
            let delta = newton - d;
            let curvature = (slope_d - slope_before) / (d - d_before);
            if delta > 0.0 && d > d_before && 0.5 * curvature.abs() * delta * delta <= 0.1 * tol {
                y_d += slope_d * delta;
                d = newton;
                break;
            }
        }
        (d_before, slope_before) = (d, slope_d);
        d = if inside { newton } else { 0.5 * (lo + hi) };
        (y_d, slope_d) = strength.yield_and_slope_scaled(&at(d), k);
        f = sigma_eq - 3.0 * g * d - y_d;
        if f.abs() <= tol || hi - lo <= 1e-15 * hi {
            break;
        }
        if f > 0.0 {
            lo = d;
        } else {
            hi = d;
        }
    }
    (s_trial * (y_d.max(0.0) / sigma_eq), d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tensor::von_mises;
    use approx::assert_relative_eq;

    pub(crate) fn at(eps_p: f64) -> StrengthState {
        StrengthState {
            eps_p,
            ..StrengthState::REFERENCE
        }
    }

    #[test]
    fn returns_to_the_yield_surface_3d() {
        let m = VonMises {
            shear_modulus: 26e9,
            yield_stress: 0.3e9,
            hardening_modulus: 1e9,
        };
        let s = Tensor::<3>::new(4e8, 1e8, 0.0, 1e8, -1e8, 5e7, 0.0, 5e7, -3e8);
        let (out, d) = radial_return(&s, &at(0.1), &m);
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
        assert_eq!(radial_return(&s, &at(0.0), &m), (s, 0.0));
        // Doubled it yields, and S_zz enters σ_eq.
        let (out, d) = radial_return(&(s * 2.0), &at(0.0), &m);
        assert!(d > 0.0);
        assert_relative_eq!(von_mises(&out), 1e8, max_relative = 1e-12);
    }
}
