//! Symmetry planes against the full model, and determinism across thread counts.

use std::collections::HashMap;
use std::path::Path;
use strike::case::{Case, Formulation};
use strike::deck;
use strike::simulation::{Diagnostics, Simulation};

/// A small sphere-on-plate case (2 km/s, coarse) with or without the two symmetry planes.
fn small_case(quarter: bool) -> Case {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/sphere_plate.toml");
    let mut case = deck::load(&path).unwrap();
    for b in &mut case.bodies {
        b.spacing = 50e-6;
    }
    case.bodies[0].velocity = [0.0, 0.0, -2000.0];
    case.simulation.impact_speed = Some(2000.0);
    if let strike::case::Shape::Cylinder { radius, .. } = &mut case.bodies[1].shape {
        *radius = 0.6e-3;
    }
    case.simulation.end_time = 0.06e-6;
    if !quarter {
        case.symmetry.clear();
    }
    case
}

fn run(case: &Case) -> (Simulation<3>, Vec<Diagnostics>) {
    let mut sim = Simulation::<3>::new(case).unwrap();
    let mut hist = Vec::new();
    let end = case.simulation.end_time;
    while sim.state.time < end * (1.0 - 1e-12) {
        hist.push(sim.step(end - sim.state.time).unwrap());
    }
    (sim, hist)
}

/// The quarter model reproduces the full model: energies ×4 and the final position of every
/// particle of the quarter, matched to the full model's particle that started at the same place.
#[test]
fn quarter_model_matches_full_model() {
    for f in [Formulation::Conventional, Formulation::Corrected] {
        quarter_and_full(f);
    }
}

/// Quarter against full model in one formulation (CN-SPH: the ghosts carry their sources'
/// gradient correction seen in the mirror).
fn quarter_and_full(formulation: Formulation) {
    let (mut q_case, mut f_case) = (small_case(true), small_case(false));
    q_case.simulation.formulation = formulation;
    f_case.simulation.formulation = formulation;
    let q0 = Simulation::<3>::new(&q_case).unwrap().particles.x;
    let f0 = Simulation::<3>::new(&f_case).unwrap().particles.x;
    let (q, qh) = run(&q_case);
    let (f, fh) = run(&f_case);
    assert_eq!(
        f.particles.n_real,
        4 * q.particles.n_real,
        "lattices should match"
    );
    // Particles matched by their initial position (to a nanometre: conforming moves the
    // surface shell off the lattice, identically in both models).
    let key = |x: &nalgebra::SVector<f64, 3>| [0, 1, 2].map(|k| (x[k] / 1e-9).round() as i64);
    let full_index: HashMap<[i64; 3], usize> =
        f0.iter().enumerate().map(|(i, x)| (key(x), i)).collect();
    let dp = 50e-6;
    let mut worst: f64 = 0.0;
    for i in 0..q.particles.n_real {
        let id = q.particles.id[i] as usize;
        let j0 = full_index[&key(&q0[id])];
        let j = (0..f.particles.n_real)
            .find(|&j| f.particles.id[j] as usize == j0)
            .unwrap();
        worst = worst.max((q.particles.x[i] - f.particles.x[j]).norm() / dp);
    }
    let (qe, fe) = (qh.last().unwrap(), fh.last().unwrap());
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-300);
    println!(
        "quarter vs full, {formulation:?} ({} vs {} particles, {} steps): worst position difference {worst:.3e} Δp, \
         kinetic {:.3e}, internal {:.3e}, contact {:.3e} relative",
        q.particles.n_real,
        f.particles.n_real,
        qh.len(),
        rel(4.0 * qe.kinetic, fe.kinetic),
        rel(4.0 * qe.internal, fe.internal),
        rel(4.0 * qe.contact, fe.contact)
    );
    assert!(worst < 1e-6, "positions differ by {worst} Δp");
    assert!(rel(4.0 * qe.kinetic, fe.kinetic) < 1e-9);
    assert!(rel(4.0 * qe.internal, fe.internal) < 1e-9);
    assert!(rel(4.0 * qe.contact, fe.contact) < 1e-9);
    assert_eq!(qh.len(), fh.len(), "same time steps");
}

/// The same contact case on 1 and 2 threads gives bit-identical particles and diagnostics.
#[test]
fn bit_identical_on_one_and_two_threads() {
    for f in [Formulation::Conventional, Formulation::Corrected] {
        let mut case = small_case(true);
        case.simulation.formulation = f;
        one_and_two_threads(&case);
    }
}

fn one_and_two_threads(case: &Case) {
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| run(case))
    };
    let (a, ah) = on(1);
    let (b, bh) = on(2);
    assert_eq!(ah, bh, "diagnostics differ");
    let p = (&a.particles, &b.particles);
    assert_eq!(p.0.x, p.1.x);
    assert_eq!(p.0.vh, p.1.vh);
    assert_eq!(p.0.rho, p.1.rho);
    assert_eq!(p.0.eh, p.1.eh);
    assert_eq!(p.0.s, p.1.s);
    assert!(
        ah.iter().any(|d| d.contact > 0.0),
        "the case must exercise the contact"
    );
}

/// The mean velocity of body 0's particles along x (2D) or z (3D) after each step, and their
/// end positions.
fn body0<const D: usize>(case: &Case) -> (Vec<f64>, Vec<[f64; D]>) {
    let mut sim = Simulation::<D>::new(case).unwrap();
    let mut v = Vec::new();
    let axis = if D == 2 { 0 } else { 2 };
    let end = case.simulation.end_time;
    while sim.state.time < end * (1.0 - 1e-12) {
        sim.step(end - sim.state.time).unwrap();
        let p = &sim.particles;
        let (mut m, mut mv) = (0.0, 0.0);
        for i in (0..p.n_real).filter(|&i| p.body[i] == 0) {
            m += p.m[i];
            mv += p.m[i] * p.v[i][axis];
        }
        v.push(mv / m);
    }
    // In the order of the particles' ids (the runs may reorder them differently).
    let p = &sim.particles;
    let mut own: Vec<usize> = (0..p.n_real).filter(|&i| p.body[i] == 0).collect();
    own.sort_by_key(|&i| p.id[i]);
    let x = own
        .iter()
        .map(|&i| std::array::from_fn(|k| p.x[i][k]))
        .collect();
    (v, x)
}

/// Largest difference between two runs' positions, in spacings.
fn apart<const D: usize>(a: &[[f64; D]], b: &[[f64; D]], dp: f64) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| (0..D).map(move |k| (p[k] - q[k]).abs()))
        .fold(0.0, f64::max)
        / dp
}

/// A `[[wall]]` is the body meeting its mirror twin through the contact (a frictionless rigid
/// wall), to round-off; a symmetry plane in its place holds the body. The elastic bars of
/// `examples/bars_contact.toml` (±10 m/s, L/Δp = 100): the left bar alone on a wall at the
/// interface follows its twin's run step by step and leaves at the twin's −9.60 m/s (acoustic:
/// −10 m/s; `tests/contact_fidelity.rs` holds the bars to that); on a symmetry plane it is still
/// held at the end and swings back past +5 m/s. Both formulations.
#[test]
fn a_wall_is_the_twin_through_the_contact_and_a_symmetry_plane_holds_on() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/bars_contact.toml");
    for f in [Formulation::Conventional, Formulation::Corrected] {
        let mut twin = deck::load(&path).unwrap();
        twin.simulation.formulation = f;
        let mut wall = twin.clone();
        wall.bodies.truncate(1);
        wall.interactions.clear();
        wall.symmetry.push(strike::case::SymmetryPlane {
            axis: 0,
            position: 0.0,
            wall: true,
        });
        let mut plane = wall.clone();
        plane.symmetry.last_mut().unwrap().wall = false;
        let dp = twin.bodies[0].spacing;
        let (vt, xt) = body0::<2>(&twin);
        let (vw, xw) = body0::<2>(&wall);
        let (vp, _) = body0::<2>(&plane);
        assert_eq!(vt.len(), vw.len(), "{f:?}: the wall takes other steps");
        let dv = vt
            .iter()
            .zip(&vw)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let dx = apart(&xt, &xw, dp);
        let (end_t, end_w, end_p) = (vt[vt.len() - 1], vw[vw.len() - 1], vp[vp.len() - 1]);
        eprintln!("{f:?}: twin {end_t:.4} m/s, wall {end_w:.4}, plane {end_p:.4}; |Δv| {dv:.2e} m/s, |Δx| {dx:.2e} Δp");
        assert!(dv < 1e-9 && dx < 1e-9, "{f:?}: the wall is not the twin");
        assert!(end_w < -9.0, "{f:?}: left the wall at {end_w} m/s");
        assert!(
            end_p > 5.0,
            "{f:?}: the symmetry plane let go ({end_p} m/s)"
        );
    }
}

/// The same in 3D with symmetry planes beside the wall: a quarter copper rod
/// (`examples/taylor_ofhc.toml`, L0/Δp = 27, R0/Δp ≈ 4) on a wall against the quarter rod and
/// its twin, for 3 µs (the mirror bodies of the corner ghosts, a wall's ghosts mirrored in the
/// symmetry planes, included). A whole number of spacings along the rod, so that the twin's
/// lattice, laid from its far end, is the rod's mirror image.
#[test]
fn a_wall_beside_symmetry_planes_is_the_twin() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/taylor_ofhc.toml");
    let mut wall = deck::load(&path).unwrap();
    wall.bodies[0].spacing = 25.4e-3 / 27.0;
    wall.simulation.end_time = 3e-6;
    let mut twin = wall.clone();
    for s in &mut wall.symmetry {
        s.wall = s.axis == 2;
    }
    twin.symmetry.retain(|s| s.axis != 2);
    let mut other = twin.bodies[0].clone();
    other.name = "twin".into();
    other.velocity[2] = -other.velocity[2];
    if let strike::case::Shape::Cylinder { base, length, .. } = &mut other.shape {
        base[2] = -*length;
    }
    twin.bodies.push(other);
    let (vt, xt) = body0::<3>(&twin);
    let (vw, xw) = body0::<3>(&wall);
    let dx = apart(&xt, &xw, wall.bodies[0].spacing);
    eprintln!(
        "rod: twin {:.3} m/s, wall {:.3} m/s, |Δx| {dx:.2e} Δp",
        vt[vt.len() - 1],
        vw[vw.len() - 1]
    );
    assert_eq!(vt.len(), vw.len());
    assert!(dx < 1e-9, "{dx}");
    assert!(vw[vw.len() - 1] > -180.0, "the rod did not meet the wall");
}
