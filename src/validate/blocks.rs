//! The building blocks' verification cases (VALIDATION.md §A, §E), which need no deck: the
//! kernels' normalisation, CN-SPH's first-order consistency, and the direction of CN-SPH's
//! contact force on a flat face. The unit tests of the kernel, the correction and the contact
//! use the same functions.

use super::{formulation_label, Check, Outcome};
use crate::case::Formulation;
use crate::contact::colour;
use crate::error::Result;
use crate::kernel::{moments, CubicSpline, Kernel, WendlandC2};
use crate::neighbors::NeighborList;
use crate::particles::{Particles, Tensor, Vector};
use crate::physics::correction::{self, corrections, same_body, shepard, Correction, Counts};
use crate::physics::{colour_states, compute_rates, Model, PairRule, Rates};

/// A fixed pseudo-random sequence uniform on [−½, ½) from `seed` (Knuth's MMIX linear
/// congruential generator, its top 53 bits): perturbed lattices that are the same on every run.
pub fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
    move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}

/// ∫W = 1 and ∫∇W = 0 to 1e-6 (∫∇W in units of 1/h) on a lattice of spacing h/40, centred and
/// shifted by 0.3 of its spacing, and W = dW/dr = 0 at r = 2h: the cubic spline and Wendland C2,
/// 2D and 3D (VALIDATION.md §A).
pub fn kernel(_fine: bool) -> Result<Outcome> {
    fn one<const D: usize, K: Kernel>(k: K, name: &str, checks: &mut Vec<Check>) {
        let h = 0.37;
        let source = "a kernel's normalisation (VALIDATION.md §A)";
        for (offset, shifted) in [(0.0, ""), (0.3 * h / 40.0, ", shifted lattice")] {
            let (i, g) = moments::<D, K>(k, h, offset);
            let s = format!("{name}, {D}D{shifted}");
            checks.push(
                Check::new("error of ∫W dV = 1", &s, (i - 1.0).abs(), "", source).at_most(1e-6),
            );
            if offset == 0.0 {
                let g = g.iter().map(|c| c.abs()).fold(0.0, f64::max) * h;
                checks.push(
                    Check::new("largest component of ∫∇W dV, times h", &s, g, "", source)
                        .at_most(1e-6),
                );
            }
        }
        let edge = k.w::<D>(2.0 * h, h).abs() + k.dw::<D>(2.0 * h, h).abs();
        checks.push(
            Check::new(
                "W and dW/dr at r = 2h (sum of magnitudes)",
                format!("{name}, {D}D"),
                edge,
                "",
                "compact support 2h",
            )
            .at_most(0.0),
        );
    }
    let mut checks = Vec::new();
    one::<2, _>(CubicSpline, "cubic spline", &mut checks);
    one::<3, _>(CubicSpline, "cubic spline", &mut checks);
    one::<2, _>(WendlandC2, "Wendland C2", &mut checks);
    one::<3, _>(WendlandC2, "Wendland C2", &mut checks);
    Ok(Outcome {
        checks,
        figures: Vec::new(),
    })
}

/// CN-SPH's first-order consistency (VALIDATION.md §E): on blocks of 9² and 7³ particles,
/// regular and perturbed by ±0.2 Δp, the corrected gradient of a linear field is exact to
/// 1e-12 in the interior, at a face and at a corner, and the Shepard-normalised kernel gives
/// back a constant to 1e-12; plain SPH's gradient is off by more than 30 % at a face and at a
/// corner (it is exact in the regular interior only).
pub fn consistency(_fine: bool) -> Result<Outcome> {
    let mut checks = Vec::new();
    let source = "first-order consistency (Randles & Libersky 1996; Bonet & Lok 1999)";
    for jitter in [0.0, 0.2] {
        let lattice = if jitter > 0.0 {
            "perturbed ±0.2 Δp"
        } else {
            "regular"
        };
        let (n2, n3) = (9, 7);
        let sites: [(&str, usize, usize); 3] = [
            ("interior", 4 + 4 * n2, 3 + 3 * n3 + 3 * n3 * n3),
            ("face", 4, 3 + 3 * n3),
            ("corner", 0, 0),
        ];
        for (place, i2, i3) in sites {
            for (d, e) in [
                (2, linear_field_errors::<2>(n2, jitter, &[i2])),
                (3, linear_field_errors::<3>(n3, jitter, &[i3])),
            ] {
                let s = format!("{d}D, {place}, {lattice}");
                let [corrected, plain, normalised, _] = e;
                checks.push(
                    Check::new(
                        "corrected gradient's error, linear field",
                        &s,
                        corrected,
                        "",
                        source,
                    )
                    .at_most(1e-12),
                );
                checks.push(
                    Check::new(
                        "normalised kernel's error, constant field",
                        &s,
                        normalised,
                        "",
                        source,
                    )
                    .at_most(1e-12),
                );
                if place != "interior" {
                    checks.push(
                        Check::new(
                            "plain SPH gradient's error at the surface",
                            &s,
                            plain,
                            "",
                            "plain SPH is not consistent at a surface (VALIDATION.md §E)",
                        )
                        .at_least(0.3),
                    );
                }
            }
        }
    }
    Ok(Outcome {
        checks,
        figures: Vec::new(),
    })
}

/// The direction of the contact force on a flat face (VALIDATION.md §E, issue 12 item 3): two
/// 3D blocks pressed together, on a regular lattice and one perturbed by ±0.1 Δp, with either
/// contact law. In CN-SPH the force at every particle away from the blocks' edges is along the
/// surface normal within 1°; in conventional SPH it strays by more than 3° on the perturbed
/// lattice; the net contact force vanishes to 1e-12 of the sum of its magnitudes in both.
///
/// A narrower block on a face (`pressed_blocks`' `narrow`): in CN-SPH the force on the pressed
/// layers stays within 1° of the face's normal, on every particle within 5°, the narrower
/// block's edges and corners included (with each side's normal counted alike, as until
/// 2026-12-02, 5.6° and 41°; see [`colour::normal`]).
///
/// And the balance of a face in contact ([`face_layers`]): CN-SPH's two facing layers feel the
/// net force that conventional SPH's do, within 0.05 of a layer's traction, at 5–35 % strain.
pub fn contact_direction(_fine: bool) -> Result<Outcome> {
    let mut checks = Vec::new();
    for strain in [0.05, 0.2, 0.35] {
        for jitter in [0.0, 0.1] {
            let conventional = face_layers(Formulation::Conventional, strain, jitter, Counts::Not)?;
            let corrected = face_layers(Formulation::Corrected, strain, jitter, Counts::Facing)?;
            let worst = (0..2)
                .map(|k| (corrected[k] - conventional[k]).abs())
                .fold(0.0, f64::max);
            let s = format!(
                "CN-SPH against conventional SPH, strain {strain}, lattice {}",
                if jitter > 0.0 {
                    "perturbed ±0.1 Δp"
                } else {
                    "regular"
                }
            );
            checks.push(
                Check::new(
                    "face layers' net force, largest difference",
                    &s,
                    worst,
                    "p A",
                    "the contact's traction meets the face as it does in conventional SPH \
                     (physics::correction::Counts::Facing)",
                )
                .at_most(0.05),
            );
        }
    }
    for law in ["colour", "paper"] {
        for jitter in [0.0, 0.1] {
            for f in [Formulation::Corrected, Formulation::Conventional] {
                let (p, force) = pressed_blocks(f, jitter, law, false)?;
                let biggest = force.iter().map(|f| f.norm()).fold(0.0, f64::max);
                // Two supports from the side faces: nearer, a neighbour's normal sees the edge.
                let inner = |x: f64| (5.0e-3..9.0e-3).contains(&x);
                let worst = (0..p.n_real)
                    .filter(|&i| inner(p.x[i][0]) && inner(p.x[i][1]))
                    .filter(|&i| force[i].norm() > 1e-3 * biggest)
                    .map(|i| {
                        (force[i][2].abs() / force[i].norm())
                            .min(1.0)
                            .acos()
                            .to_degrees()
                    })
                    .fold(0.0, f64::max);
                let net: Vector<3> = force.iter().sum();
                let total: f64 = force.iter().map(|f| f.norm()).sum();
                let s = format!(
                    "{}, {law} law, lattice {}",
                    formulation_label(f),
                    if jitter > 0.0 {
                        "perturbed ±0.1 Δp"
                    } else {
                        "regular"
                    }
                );
                let angle = Check::new(
                    "worst angle of the contact force to the normal",
                    &s,
                    worst,
                    "°",
                    "CN-SPH's contact acts along the surface normal (VALIDATION.md §E)",
                );
                checks.push(match f {
                    Formulation::Corrected => angle.at_most(1.0),
                    Formulation::Conventional if jitter > 0.0 => angle.at_least(3.0),
                    Formulation::Conventional => angle.reported(0.0),
                });
                checks.push(
                    Check::new(
                        "net contact force over the sum of the magnitudes",
                        &s,
                        if total > 0.0 {
                            net.norm() / total
                        } else {
                            f64::INFINITY
                        },
                        "",
                        "pair forces are antisymmetric: momentum is conserved",
                    )
                    .at_most(1e-12),
                );
            }
        }
    }
    // Edges and corners on a face: the contact normal is the face's (`colour::normal`).
    for law in ["colour", "paper"] {
        for jitter in [0.0, 0.1] {
            for f in [Formulation::Corrected, Formulation::Conventional] {
                let (p, force) = pressed_blocks(f, jitter, law, true)?;
                let biggest = force.iter().map(|f| f.norm()).fold(0.0, f64::max);
                let worst = |share: f64| {
                    (0..p.n_real)
                        .filter(|&i| force[i].norm() > share * biggest)
                        .map(|i| {
                            (force[i][2].abs() / force[i].norm())
                                .min(1.0)
                                .acos()
                                .to_degrees()
                        })
                        .fold(0.0, f64::max)
                };
                let s = format!(
                    "{}, {law} law, lattice {}, a narrower block on a face",
                    formulation_label(f),
                    if jitter > 0.0 {
                        "perturbed ±0.1 Δp"
                    } else {
                        "regular"
                    }
                );
                let why = "a frictionless face pushes along its normal, on an edge or a corner too";
                for (share, limit, what) in [
                    (
                        0.1,
                        1.0,
                        "the pressed layers (a tenth of the largest force or more)",
                    ),
                    (1e-3, 5.0, "every particle with a contact force"),
                ] {
                    let angle = Check::new(
                        format!("worst angle of the contact force to the face's normal, {what}"),
                        &s,
                        worst(share),
                        "°",
                        why,
                    );
                    // Conventional SPH's colour law keeps the tangential part of −∇Φ, which
                    // an edge tilts (43–45° on the pressed layers): the measure sees a tilt.
                    checks.push(match f {
                        Formulation::Corrected => angle.at_most(limit),
                        Formulation::Conventional if law == "colour" && share > 0.01 => {
                            angle.at_least(3.0)
                        }
                        Formulation::Conventional => angle.reported(0.0),
                    });
                }
            }
        }
    }
    Ok(Outcome {
        checks,
        figures: Vec::new(),
    })
}

/// A block of n^D particles at spacing 1 (h = 1.2), displaced by up to ±`jitter` along
/// each axis (a fixed pseudo-random sequence), density 1 and mass 1.
pub fn block<const D: usize>(n: usize, jitter: f64) -> Particles<D> {
    let mut p = Particles::<D>::default();
    let mut rnd = uniform(12345u64);
    for k in 0..n.pow(D as u32) {
        let x =
            Vector::<D>::from_fn(|a, _| ((k / n.pow(a as u32)) % n) as f64 + 2.0 * jitter * rnd());
        p.push(x, Vector::<D>::zeros(), 1.0, 1.0, 1.2, 0);
    }
    p
}

/// Gradient of f(x) = g·x + 3 at particle i: Σ_j V_j (f_j − f_i) ∇W, corrected with `b`.
fn gradient<const D: usize>(
    p: &Particles<D>,
    nl: &NeighborList,
    i: usize,
    b: &Tensor<D>,
) -> Vector<D> {
    let g = Vector::<D>::from_fn(|a, _| [0.7, -1.3, 2.1][a]);
    let f = |x: &Vector<D>| g.dot(x) + 3.0;
    let mut sum = Vector::<D>::zeros();
    for j in nl.list(i) {
        let j = j as usize;
        let xij = p.x[i] - p.x[j];
        let (r, h) = (xij.norm(), 0.5 * (p.h[i] + p.h[j]));
        if r > 0.0 && r < 2.0 * h {
            sum +=
                xij * (CubicSpline.dw::<D>(r, h) / r) * (p.volume(j) * (f(&p.x[j]) - f(&p.x[i])));
        }
    }
    b * sum - g
}

/// Worst error of the corrected and of the plain gradient of a linear field, and of the
/// Shepard-normalised and plain interpolation of a constant, over particles picked by
/// `which` (their index on the n^D lattice).
pub fn linear_field_errors<const D: usize>(n: usize, jitter: f64, which: &[usize]) -> [f64; 4] {
    let p = block::<D>(n, jitter);
    let mut nl = NeighborList::default();
    nl.build(&p.x, &p.h, p.n_real, 0.0);
    let mut c = Vec::new();
    // A 9² or 7³ block has no particle whose matrix needs the fallback.
    corrections(
        CubicSpline,
        &p,
        &nl,
        same_body(&p),
        &(0..p.n_real),
        &mut c,
        &[],
    );
    let shepard = shepard(CubicSpline, &p, &nl, same_body(&p));
    let mut e = [0.0_f64; 4];
    for &i in which {
        e[0] = e[0].max(gradient(&p, &nl, i, &c[i].b).norm());
        e[1] = e[1].max(gradient(&p, &nl, i, &Tensor::<D>::identity()).norm());
        // A constant field 1: Σ_j V_j W_ij · 1, normalised by S_i and plain.
        let mut sum = p.volume(i) * CubicSpline.w::<D>(0.0, p.h[i]);
        for j in nl.list(i) {
            let j = j as usize;
            let (r, h) = ((p.x[i] - p.x[j]).norm(), 0.5 * (p.h[i] + p.h[j]));
            if r > 0.0 {
                sum += p.volume(j) * CubicSpline.w::<D>(r, h);
            }
        }
        e[2] = e[2].max((sum / shepard[i] - 1.0).abs());
        e[3] = e[3].max((sum - 1.0).abs());
    }
    e
}

/// Per-particle contact forces of two 3D blocks pressed together across a flat face
/// (facing layers 0.7 Δp apart), in `formulation`, on a lattice perturbed by up to
/// ±`jitter` Δp (the facing layers in their plane only, so that the face stays flat), with
/// the contact `law`. The upper block (body 1) is as wide as the lower one, or, `narrow`,
/// 6 Δp wide over the lower one's middle, so that its edges and corners stand on a face.
pub fn pressed_blocks(
    formulation: Formulation,
    jitter: f64,
    law: &str,
    narrow: bool,
) -> Result<(Particles<3>, Vec<Vector<3>>)> {
    let (lo, hi) = if narrow {
        (4.0e-3, 10.0e-3)
    } else {
        (0.0, 14.0e-3)
    };
    let deck = format!(
        r#"
[simulation]
dimension = 3
end_time = 1.0
[materials.al]
density = 2700.0
eos = {{ type = "linear" }}
strength = {{ type = "elastic", youngs_modulus = 68.9e9, poissons_ratio = 0.33 }}
[[body]]
name = "a"
material = "al"
spacing = 1.0e-3
shape = {{ type = "box", min = [0.0, 0.0, 0.0], max = [14.0e-3, 14.0e-3, 6.0e-3] }}
[[body]]
name = "b"
material = "al"
spacing = 1.0e-3
shape = {{ type = "box", min = [{lo:e}, {lo:e}, 5.7e-3], max = [{hi:e}, {hi:e}, 11.7e-3] }}
[[interaction]]
bodies = ["a", "b"]
type = "contact"
law = "{law}"
"#
    );
    let case = crate::deck::parse(&deck, "pressed.toml")?;
    let (mut p, mut model) = crate::setup::build::<3>(&case)?;
    model.formulation = formulation;
    let mut rnd = uniform(4242u64);
    for i in 0..p.n_real {
        let facing = (p.x[i][2] - 5.5e-3).abs() < 1e-6 || (p.x[i][2] - 6.2e-3).abs() < 1e-6;
        for k in 0..3 {
            let d = 2.0 * jitter * 1e-3 * rnd();
            if !(facing && k == 2) {
                p.x[i][k] += d;
            }
        }
    }
    let mut nl = NeighborList::default();
    nl.build(&p.x, &p.h, p.n_real, 0.0);
    nl.classify(&p.body, false);
    let mut c = Vec::new();
    if formulation == Formulation::Corrected {
        crate::physics::corrections(CubicSpline, &p, &nl, &model, &(0..p.n_real), &mut c);
    }
    let rates = rates_of(&p, &nl, &model, &c);
    let f = rates.contact_force[..p.n_real].to_vec();
    Ok((p, f))
}

/// The net force along the normal on the two facing layers of a flat contact in a uniformly
/// compressed state, per particle, in units of the traction a layer carries (p Δp^(D−1)):
/// two 3D blocks of a fluid (linear EOS, K = 76 GPa) touching at the natural spacing, then
/// compressed together along the normal by `strain` (the facing gap with them), every particle
/// at the pressure of its density, the facing layers perturbed within their planes by up to
/// ±`jitter` Δp. In CN-SPH `facing` says how the other body's particles count in B
/// ([`Counts::Facing`], as strike has it, or [`Counts::Not`], B over the own body alone).
/// Averaged over the lower block's particles two supports away from its sides; positive
/// towards the other body.
pub fn face_layers(
    formulation: Formulation,
    strain: f64,
    jitter: f64,
    facing: Counts,
) -> Result<[f64; 2]> {
    let deck = r#"
[simulation]
dimension = 3
end_time = 1.0
[materials.fluid]
density = 2700.0
eos = { type = "linear", bulk_modulus = 76.0e9 }
strength = { type = "hydrodynamic" }
[[body]]
name = "a"
material = "fluid"
spacing = 1.0e-3
shape = { type = "box", min = [0.0, 0.0, 0.0], max = [14.0e-3, 14.0e-3, 6.0e-3] }
[[body]]
name = "b"
material = "fluid"
spacing = 1.0e-3
shape = { type = "box", min = [0.0, 0.0, 6.0e-3], max = [14.0e-3, 14.0e-3, 12.0e-3] }
[[interaction]]
bodies = ["a", "b"]
type = "contact"
"#;
    let case = crate::deck::parse(deck, "face_layers.toml")?;
    let (mut p, mut model) = crate::setup::build::<3>(&case)?;
    model.formulation = formulation;
    let (dp, face) = (1.0e-3, 6.0e-3);
    let rho = case.materials[0].density / (1.0 - strain);
    let pressure = model.materials[0].pressure(rho, 0.0);
    let mut rnd = uniform(4242u64);
    for i in 0..p.n_real {
        p.x[i][2] = face + (p.x[i][2] - face) * (1.0 - strain);
        for k in 0..2 {
            p.x[i][k] += 2.0 * jitter * dp * rnd();
        }
        p.rho[i] = rho;
        p.p[i] = pressure;
    }
    let mut nl = NeighborList::default();
    nl.build(&p.x, &p.h, p.n_real, 0.0);
    nl.classify(&p.body, false);
    let all = 0..p.n_real;
    let mut c = Vec::new();
    if formulation == Formulation::Corrected {
        let counts = |i: usize, j: usize| {
            let (bi, bj) = (p.body[i], p.body[j]);
            match model.pairs.rule(bi, bj) {
                _ if bi == bj => Counts::Body,
                PairRule::Contact(_) => facing,
                _ => Counts::Not,
            }
        };
        correction::corrections(CubicSpline, &p, &nl, counts, &all, &mut c, &[]);
    }
    let rates = rates_of(&p, &nl, &model, &c);
    let traction = pressure * dp * dp;
    let inner = |x: f64| (5.0e-3..9.0e-3).contains(&x);
    let (mut sum, mut n) = ([0.0; 2], [0usize; 2]);
    for i in 0..p.n_real {
        if p.body[i] != 0 || !inner(p.x[i][0]) || !inner(p.x[i][1]) {
            continue;
        }
        let layer = ((face - p.x[i][2]) / (dp * (1.0 - strain))).floor() as usize;
        if layer < 2 {
            sum[layer] += p.m[i] * rates.particles[i].acc[2] / traction;
            n[layer] += 1;
        }
    }
    Ok([0, 1].map(|k| sum[k] / n[k].max(1) as f64))
}

/// One rate pass over every particle (its colour states first), in CN-SPH with the
/// corrections `c` (empty: conventional SPH).
fn rates_of(
    p: &Particles<3>,
    nl: &NeighborList,
    model: &Model<3>,
    c: &[Correction<3>],
) -> Rates<3> {
    let all = 0..p.n_real;
    let b: Vec<Tensor<3>> = c.iter().map(|c| c.b).collect();
    let lambda: Vec<f64> = c.iter().map(|c| c.lambda_min).collect();
    let surfaces = (!c.is_empty()).then_some(colour::Surfaces { lambda: &lambda });
    let mut states = colour::ColourStates::default();
    colour_states(CubicSpline, p, nl, model, (surfaces, &all), &mut states);
    let mut rates = Rates::default();
    compute_rates(
        CubicSpline,
        p,
        nl,
        model,
        (&states, &b, &[]),
        &all,
        &mut rates,
    );
    rates
}
