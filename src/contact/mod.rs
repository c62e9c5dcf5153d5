//! The frictionless particle contact of Vignjevic, De Vuyst & Campbell, "A Frictionless Contact
//! Algorithm for Meshless Methods", CMES 13(1) 35–48 (2006), eq. (5).
//!
//! Particles of different bodies never meet through the conservation equations (the paper's
//! W(x_A − x_B) = 0 across bodies). They meet through a contact force, the gradient of a
//! contact potential built from the kernel on the neighbour list SPH already has. Eq. (5):
//!
//!   f_c,i = − Σ_{j ∈ C_i} V_i V_j K n (W_ij / W(Δp_avg))^(n−1) ∇_i W_ij ,
//!
//! the gradient of Φ = Σ_pairs V_i V_j K W(Δp_avg) (W_ij/W(Δp_avg))^n. As printed, eq. (5) has
//! W(Δp_avg)^n in the denominator and is a force only for K in N/m⁵; multiplying by W(Δp_avg)
//! makes K a stress (Pa), and gives exactly the shape of Monaghan's (2000) artificial stress
//! that the paper names as its inspiration. ∇_i W_ij = (dW/dr) x_ij/r_ij points from i to j, so
//! the minus sign makes the force repulsive; it is antisymmetric in i, j (linear momentum is
//! conserved to round-off) and vanishes once r_ij ≥ 2 h_ij, so bodies part with no tension.
//!
//! strike has this form as the paper prints it (`law = "paper"`, [`pair`]) and a form of its
//! own, the default (`law = "colour"`, [`colour`]). Both keep the paper's construction — a
//! contact potential of kernel sums over the other body's particles on the existing neighbour
//! list, its gradient the force — and they differ where the printed form fails:
//!
//! 1. **Interdigitation at hypervelocity.** The paper's force acts along the line of centres,
//!    and (W_ij/W0)^n with n = 4 is sharply peaked: two lattices pressed together feel the
//!    corrugation of each other's surface as strongly as the pressure. At 7 km/s (97.6 GPa)
//!    the facing layers slide into each other's gaps after 0.5 µs and mix 2–3 Δp deep; the
//!    interface layer, held at the natural spacing by K while the bulk compresses to 0.65 Δp,
//!    collapses onto the layer behind it, and the pressure overshoots by 75 %. The colour form
//!    takes the power of the *sum* of kernel values (the other body's colour, smooth along a
//!    surface to 0.05–1 %), applies each pair's force along the contact normal with only half
//!    its tangential part where the interface is pressed hard (all of it under light loads,
//!    [`colour::tangential_share`]; the paper's CN-SPH contact "has the direction of normal to
//!    the contact surface"), and sizes the stiffness by the material's own compression curve, so
//!    that the interface compresses as the bodies do. The potential alone is conservative: the
//!    facing layers of a 7 km/s impact bounce off it as off a spring (closing to 0.44 Δp); the
//!    colour form gives the interface the bulk's shock viscosity on its normal closing speed
//!    ([`colour::damping`]), as the shock it is part of.
//! 2. **Load.** The paper's K is one number per pair of bodies, sized (by strike) from the 1D
//!    impact pressure; a Hertz contact's pressure is set by geometry, 30 × that, and crushes
//!    the contact layer. The colour form's traction is the material's σ_u(ε) at the interface
//!    strain: it follows whatever load the contact carries, from gravity to a shock.
//! 3. **Range.** The paper's potential reaches 2h ≈ 2.4 Δp, so bodies built touching (facing
//!    layers Δp apart) already push each other, and after unloading the faces go on pushing
//!    until they are 2.4 Δp apart: slow bars part 37 % too fast and a striker bounces back.
//!    The colour form is offset to vanish at the colour of two bodies that merely touch (a
//!    "potential offset" tied to Δp): no force at rest, none once the faces part.
//!
//! Measured (tests/contact_fidelity.rs and tests/verification_contact.rs): 7 km/s planar
//! impact at Δp = 0.1 and 0.05 mm to 1.5 µs with no particle past the other's surface, the
//! closest pair 0.58 Δp apart and the peak pressure +6 % of the Hugoniot's at both (paper's
//! form: 2.3 Δp deep, +75 %); Hertz spheres' peak force +7.1 / +4.7 % and duration −6.0 /
//! −4.3 % at R/Δp = 20 / 30; slow bars parting at 9.60 and 9.72 m/s of 10 (paper's form
//! 12.6); a striker at rest within 0.8 / 0.4 %.
//!
//! **Default stiffness of the paper's form.** DESIGN.md suggests K of the order of the larger
//! bulk modulus. That is wrong for bodies that start touching at the lattice spacing: the
//! contact then holds a traction ≈ 0.15 n K at t = 0 with nothing to balance it, and the stored
//! potential (≈ 0.1 K Δp per unit area) launches the bodies apart (≈ 170 m/s for Al bars at
//! Δp = 0.1 mm). strike instead sizes K so that the contact carries the *expected* interface
//! pressure p_c at the natural spacing, K = p_c / (τ n), where p_c is the larger of the
//! Hugoniot impact pressure at the bodies' relative speed and the weight of the heavier body on
//! its footprint (gravity), with a floor of 10⁻⁴ of the smaller bulk modulus, and τ the traction
//! per n K that the kernel carries across a lattice interface at the natural spacing
//! ([`lattice_traction_per_nk`]: 0.15–0.23 in 3D, more in 2D). For the paper's 7 km/s Al case
//! this gives K ≈ 2 × the bulk modulus, i.e. DESIGN's own estimate.

pub mod colour;

use crate::kernel::Kernel;

/// Which form of eq. (5) a pair of bodies meets through.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContactLaw {
    /// The colour form (the default, see [`colour`]).
    Colour,
    /// Eq. (5) as printed: pairwise (W_ij/W(Δp))^n over the support 2h, along the line of
    /// centres, K from the expected interface pressure.
    Paper,
}

/// Contact settings of a body pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactParams {
    pub law: ContactLaw,
    /// Paper law: stiffness K (Pa).
    pub stiffness: f64,
    /// Paper law: exponent n.
    pub exponent: f64,
    /// Mean initial particle spacing Δp_avg of the two bodies (m).
    pub spacing: f64,
}

/// One pair's contact term: returns (coefficient c such that f_c,i += c ∇_i W_ij, pair potential
/// Φ_ij, pair stiffness |∂²Φ_ij/∂r²|) for r = r_ij, h = h_ij, dw = dW/dr(r, h).
#[inline(always)]
pub fn pair<const D: usize, K: Kernel>(
    kernel: K,
    params: &ContactParams,
    vol_i: f64,
    vol_j: f64,
    r: f64,
    h: f64,
    dw: f64,
) -> (f64, f64, f64) {
    let w0 = kernel.w::<D>(params.spacing, h);
    let f = kernel.w::<D>(r, h) / w0;
    let n = params.exponent;
    let scale = vol_i * vol_j * params.stiffness;
    let f_nm1 = f.powf(n - 1.0);
    let coef = -scale * n * f_nm1;
    let potential = scale * w0 * f_nm1 * f;
    // d²Φ/dr² = scale n [ (n−1) f^(n−2) (dW/dr)² / W0 + f^(n−1) d²W/dr² ]; its magnitude bounds
    // the pair's spring constant for the time step.
    let f_nm2 = if f > 0.0 { f_nm1 / f } else { 0.0 };
    let stiffness =
        scale * n * ((n - 1.0) * f_nm2 * dw * dw / w0 + f_nm1 * kernel.d2w::<D>(r, h).abs());
    (coef, potential, stiffness)
}

/// Default stiffness K = p_c / (τ n) for an expected interface pressure p_c, with τ the
/// traction per n K of [`lattice_traction_per_nk`] (see the module doc).
pub fn default_stiffness<const D: usize, K: Kernel>(
    kernel: K,
    smoothing_ratio: f64,
    expected_pressure: f64,
    exponent: f64,
) -> f64 {
    expected_pressure
        / (lattice_traction_per_nk::<D, K>(kernel, smoothing_ratio, exponent) * exponent)
}

/// Traction τ (per n K) that eq. (5) carries across a plane interface between two square (2D)
/// or simple-cubic (3D) lattices of spacing Δp whose facing layers are Δp apart, with
/// h = smoothing_ratio · Δp: the contact force on one column of particles of the lower body
/// from the whole upper body, per column area Δp^(D−1), divided by n K. Exact lattice sum
/// (DESIGN.md quotes ≈ 0.15–0.23 for n = 6…2 in 3D with the cubic spline and h = 1.2 Δp; in 2D
/// it is larger, ≈ 0.25, which a 3D constant would miss).
pub fn lattice_traction_per_nk<const D: usize, K: Kernel>(
    kernel: K,
    smoothing_ratio: f64,
    exponent: f64,
) -> f64 {
    let dp = 1.0;
    let h = smoothing_ratio * dp;
    let vol = dp.powi(D as i32);
    let w0 = kernel.w::<D>(dp, h);
    let reach = (2.0 * h / dp).ceil() as i64 + 1;
    let lateral = if D == 3 { reach } else { 0 };
    let mut force = 0.0;
    // Lower column at (0, 0, −a Δp), a ≥ 0; upper lattice at (k, l, b Δp), b ≥ 1.
    for a in 0..=reach {
        for b in 1..=reach {
            let dz = (a + b) as f64 * dp;
            for k in -reach..=reach {
                for l in -lateral..=lateral {
                    let d2 = ((k * k + l * l) as f64) * dp * dp;
                    let r = (d2 + dz * dz).sqrt();
                    let f = kernel.w::<D>(r, h) / w0;
                    if f > 0.0 {
                        force +=
                            vol * vol * f.powf(exponent - 1.0) * (-kernel.dw::<D>(r, h)) * dz / r;
                    }
                }
            }
        }
    }
    force / dp.powi(D as i32 - 1)
}

/// Interface pressure of a planar impact of two materials at relative speed v, each with a
/// linear shock Hugoniot U_s = c + s u_p (the acoustic ρ c v/2 at low speed): the particle
/// velocities u_a + u_b = v balance ρ_a (c_a + s_a u_a) u_a = ρ_b (c_b + s_b u_b) u_b, solved by
/// bisection.
pub fn impact_pressure(v: f64, a: (f64, f64, f64), b: (f64, f64, f64)) -> f64 {
    let p = |(rho, c, s): (f64, f64, f64), u: f64| rho * (c + s * u) * u;
    let (mut lo, mut hi) = (0.0, v.abs());
    for _ in 0..100 {
        let ua = 0.5 * (lo + hi);
        if p(a, ua) > p(b, v.abs() - ua) {
            hi = ua;
        } else {
            lo = ua;
        }
    }
    p(a, 0.5 * (lo + hi))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::CubicSpline;
    use approx::assert_relative_eq;

    #[test]
    fn force_is_minus_the_potential_gradient_and_repulsive() {
        let p = ContactParams {
            law: ContactLaw::Paper,
            stiffness: 2e9,
            exponent: 4.0,
            spacing: 1.0,
        };
        let h = 1.2;
        for r in [0.3, 0.8, 1.0, 1.7, 2.3] {
            let dw = CubicSpline.dw::<3>(r, h);
            let (coef, _, _) = pair::<3, _>(CubicSpline, &p, 1.0, 1.0, r, h, dw);
            // Radial force on i from j along x_ij (positive = away from j): coef · dW/dr.
            let radial = coef * dw;
            let d = 1e-6;
            let phi = |r: f64| pair::<3, _>(CubicSpline, &p, 1.0, 1.0, r, h, 0.0).1;
            let fd = -(phi(r + d) - phi(r - d)) / (2.0 * d);
            assert_relative_eq!(radial, fd, max_relative = 1e-6);
            assert!(radial >= 0.0, "repulsive");
        }
        assert_eq!(pair::<3, _>(CubicSpline, &p, 1.0, 1.0, 2.4, h, 0.0).1, 0.0);
    }

    /// DESIGN.md §2: 3D, cubic spline, h = 1.2 Δp → τ ≈ 0.15 (n = 6) … 0.23 (n = 2).
    #[test]
    fn lattice_traction_matches_design_figures() {
        let t6 = lattice_traction_per_nk::<3, _>(CubicSpline, 1.2, 6.0);
        let t2 = lattice_traction_per_nk::<3, _>(CubicSpline, 1.2, 2.0);
        let t2d = lattice_traction_per_nk::<2, _>(CubicSpline, 1.2, 4.0);
        println!("τ(3D, n=6) = {t6:.4}, τ(3D, n=2) = {t2:.4}, τ(2D, n=4) = {t2d:.4}");
        assert!((t6 / 0.15 - 1.0).abs() < 0.15, "{t6}");
        assert!((t2 / 0.23 - 1.0).abs() < 0.15, "{t2}");
        assert!(t2d > 0.2 && t2d < 0.3, "{t2d}");
    }

    #[test]
    fn impact_pressure_limits() {
        let al = (2785.0, 5328.0, 1.338);
        // Acoustic limit: ρ c v/2 for like materials.
        assert_relative_eq!(
            impact_pressure(1.0, al, al),
            2785.0 * 5328.0 * 0.5,
            max_relative = 1e-3
        );
        // Symmetric strong impact: u_p = v/2, p = ρ (c + s v/2) v/2 ≈ 83.6 GPa at 7 km/s.
        let p = impact_pressure(7000.0, al, al);
        assert_relative_eq!(
            p,
            2785.0 * (5328.0 + 1.338 * 3500.0) * 3500.0,
            max_relative = 1e-9
        );
    }
}
