//! Materials: an equation of state and a strength model behind traits, so that Tillotson,
//! Johnson–Cook and others can be added without touching the solver. The paper's material is
//! the "elastic-plastic hydrodynamic" model with a Mie–Grüneisen EOS (LS-DYNA MAT_010 +
//! EOS_GRUNEISEN).

pub mod eos;
pub mod strength;

use crate::case::{EosSpec, MaterialSpec, StrengthSpec};
pub use eos::{Eos, LinearEos, MieGruneisen};
pub use strength::{radial_return, Strength, VonMises};

/// A material as the solver sees it.
#[derive(Debug)]
pub struct Material {
    pub name: String,
    /// Reference density ρ0 (kg/m³).
    pub rho0: f64,
    pub eos: Box<dyn Eos>,
    pub strength: Box<dyn Strength>,
    /// Pressure cut-off p_min (Pa): p = max(p, p_min); −∞ when off.
    pub p_min: f64,
    /// Artificial stress ε (Monaghan 2000), None when off.
    pub artificial_stress: Option<f64>,
}

impl Material {
    /// Build from a validated spec.
    pub fn from_spec(spec: &MaterialSpec) -> Self {
        let rho0 = spec.density;
        let eos: Box<dyn Eos> = match spec.eos {
            EosSpec::Linear { bulk_modulus } => Box::new(LinearEos { rho0, bulk_modulus }),
            EosSpec::MieGruneisen {
                c0,
                s1,
                s2,
                s3,
                gamma0,
                a,
            } => Box::new(MieGruneisen {
                rho0,
                c0,
                s1,
                s2,
                s3,
                gamma0,
                a,
            }),
        };
        let strength: Box<dyn Strength> = match spec.strength {
            StrengthSpec::Hydrodynamic => Box::new(VonMises {
                shear_modulus: 0.0,
                yield_stress: 0.0,
                hardening_modulus: 0.0,
            }),
            StrengthSpec::Elastic { shear_modulus } => Box::new(VonMises {
                shear_modulus,
                yield_stress: f64::INFINITY,
                hardening_modulus: 0.0,
            }),
            StrengthSpec::VonMises {
                shear_modulus,
                yield_stress,
                hardening_modulus,
            } => Box::new(VonMises {
                shear_modulus,
                yield_stress,
                hardening_modulus,
            }),
        };
        Material {
            name: spec.name.clone(),
            rho0,
            eos,
            strength,
            p_min: spec.pressure_cutoff.unwrap_or(f64::NEG_INFINITY),
            artificial_stress: spec.artificial_stress,
        }
    }

    /// Pressure with the cut-off applied.
    pub fn pressure(&self, rho: f64, e: f64) -> f64 {
        self.eos.pressure(rho, e).max(self.p_min)
    }

    /// Sound speed c = √((K_s + 4G/3)/ρ), the longitudinal wave speed used for the time step and
    /// the viscosity. K_s is floored at 1 % of its reference value so that a particle in deep
    /// tension still has a finite signal speed.
    pub fn sound_speed(&self, rho: f64, e: f64) -> f64 {
        let k0 = self.eos.bulk_modulus(self.rho0, 0.0);
        let ks = self.eos.bulk_modulus(rho, e).max(0.01 * k0);
        ((ks + 4.0 / 3.0 * self.strength.shear_modulus()) / rho).sqrt()
    }

    /// Reference bulk modulus K0 = ρ0 c0².
    pub fn bulk_modulus0(&self) -> f64 {
        self.eos.bulk_modulus(self.rho0, 0.0)
    }

    /// Reference longitudinal sound speed.
    pub fn sound_speed0(&self) -> f64 {
        self.sound_speed(self.rho0, 0.0)
    }
}
