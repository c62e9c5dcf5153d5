//! Verification of the engine against analytical values (VALIDATION.md §A), from the example
//! decks, run in-process.

use std::path::Path;
use strike::case::{Case, Formulation, Motion};
use strike::deck;
use strike::simulation::{Diagnostics, Simulation};
use strike::Error;

/// Both formulations: conventional SPH and CN-SPH.
const FORMULATIONS: [Formulation; 2] = [Formulation::Conventional, Formulation::Corrected];

fn example_in(name: &str, formulation: Formulation) -> Case {
    let mut case = example(name);
    case.simulation.formulation = formulation;
    case
}

fn example(name: &str) -> Case {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples")
        .join(name);
    deck::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Run to `t`, returning every step's diagnostics.
fn run_to<const D: usize>(sim: &mut Simulation<D>, t: f64) -> Vec<Diagnostics> {
    let mut out = Vec::new();
    while sim.state.time < t * (1.0 - 1e-12) {
        out.push(sim.step(t - sim.state.time).expect("stable run"));
    }
    out
}

/// Furthest x of a body's particles moving faster than `v` along x.
fn front(sim: &Simulation<2>, body: u32, v: f64) -> f64 {
    let p = &sim.particles;
    (0..p.n_real)
        .filter(|&i| p.body[i] == body && p.v[i][0] > v)
        .map(|i| p.x[i][0])
        .fold(f64::NEG_INFINITY, f64::max)
}

fn elastic_constants(case: &Case) -> (f64, f64, f64) {
    let m = &case.materials[case.bodies[1].material];
    (
        m.density,
        m.eos.bulk_modulus(m.density),
        m.strength.shear_modulus(),
    )
}

/// Elastic wave in uniaxial strain: the front (where v_x passes half the piston's speed) moves
/// at c_L = √((K + 4G/3)/ρ), within 2 %; the stress behind it is −ρ c_L v. Both formulations.
#[test]
fn elastic_wave_front_speed() {
    for f in FORMULATIONS {
        elastic_wave(f);
    }
}

fn elastic_wave(formulation: Formulation) {
    let case = example_in("elastic_wave.toml", formulation);
    let (rho, k, g) = elastic_constants(&case);
    let c = ((k + 4.0 / 3.0 * g) / rho).sqrt();
    let v = case.bodies[0].velocity[0];
    let mut sim = Simulation::<2>::new(&case).unwrap();
    run_to(&mut sim, 4e-6);
    let (t1, x1) = (sim.state.time, front(&sim, 1, 0.5 * v));
    run_to(&mut sim, 12e-6);
    let (t2, x2) = (sim.state.time, front(&sim, 1, 0.5 * v));
    let speed = (x2 - x1) / (t2 - t1);
    let err = speed / c - 1.0;
    println!(
        "elastic wave ({formulation:?}): front {speed:.1} m/s, c_L {c:.1} m/s, error {:.3} %",
        100.0 * err
    );
    assert!(err.abs() < 0.02, "front speed {speed} vs {c}");
    // σ_xx behind the front, away from the piston.
    let p = &sim.particles;
    let behind: Vec<f64> = (0..p.n_real)
        .filter(|&i| p.body[i] == 1 && p.x[i][0] > 0.02 && p.x[i][0] < 0.05)
        .map(|i| p.s[i][(0, 0)] - p.p[i])
        .collect();
    let sxx = behind.iter().sum::<f64>() / behind.len() as f64;
    let expect = -rho * c * v;
    println!("elastic wave ({formulation:?}): σ_xx {sxx:.4e} Pa, −ρ c v {expect:.4e} Pa");
    assert!((sxx / expect - 1.0).abs() < 0.02);
}

/// Uniaxial-strain loading of an elastic–perfectly plastic column: the elastic precursor
/// carries σ_HEL = Y (1 − ν)/(1 − 2ν), within 5 %. Both formulations.
#[test]
fn hugoniot_elastic_limit() {
    for f in FORMULATIONS {
        hel(f);
    }
}

fn hel(formulation: Formulation) {
    let case = example_in("hugoniot_elastic_limit.toml", formulation);
    let (_, k, g) = elastic_constants(&case);
    let y = match case.materials[case.bodies[1].material].strength {
        strike::case::StrengthSpec::VonMises { yield_stress, .. } => yield_stress,
        _ => panic!("von Mises expected"),
    };
    let nu = (3.0 * k - 2.0 * g) / (2.0 * (3.0 * k + g));
    let hel = y * (1.0 - nu) / (1.0 - 2.0 * nu);
    let mut sim = Simulation::<2>::new(&case).unwrap();
    run_to(&mut sim, case.simulation.end_time);
    let p = &sim.particles;
    // The precursor: the largest compression among column particles still elastic.
    let precursor = (0..p.n_real)
        .filter(|&i| p.body[i] == 1 && p.eps_p[i] == 0.0)
        .map(|i| p.p[i] - p.s[i][(0, 0)])
        .fold(0.0, f64::max);
    // Behind the plastic wave the material has yielded.
    let yielded = (0..p.n_real)
        .filter(|&i| p.body[i] == 1 && p.x[i][0] < 10e-3)
        .all(|i| p.eps_p[i] > 0.0);
    println!(
        "HEL ({formulation:?}): precursor {:.4} GPa, Y(1−ν)/(1−2ν) = {:.4} GPa (ν = {nu:.4}), error {:.2} %",
        precursor / 1e9,
        hel / 1e9,
        100.0 * (precursor / hel - 1.0)
    );
    assert!(
        yielded,
        "material behind the plastic wave must have yielded"
    );
    assert!((precursor / hel - 1.0).abs() < 0.05);
}

/// Energy in an elastic case with no external work: the piston of the elastic-wave deck set
/// free as a flyer welded to the column. Kinetic + internal energy drifts < 1 %, and momentum
/// is conserved to round-off. Both formulations.
#[test]
fn elastic_energy_is_conserved() {
    for f in FORMULATIONS {
        elastic_energy(f);
    }
}

fn elastic_energy(formulation: Formulation) {
    let mut case = example_in("elastic_wave.toml", formulation);
    case.bodies[0].motion = Motion::Free;
    let mut sim = Simulation::<2>::new(&case).unwrap();
    let hist = run_to(&mut sim, 12e-6);
    let e0 = hist[0].total;
    let drift = hist
        .iter()
        .map(|d| (d.total - e0).abs())
        .fold(0.0, f64::max)
        / e0;
    let p0 = hist[0].momentum[0];
    let dp = hist
        .iter()
        .map(|d| (d.momentum[0] - p0).abs())
        .fold(0.0, f64::max)
        / hist[0].momentum_scale;
    println!(
        "elastic energy ({formulation:?}): drift {:.3e} over {} steps, x momentum {dp:.1e}",
        drift,
        hist.len()
    );
    assert!(dp < 1e-10, "momentum drift {dp}");
    assert!(drift < 0.01, "energy drift {drift}");
    // The energy really moved: most of the flyer's kinetic energy went into the column.
    assert!(hist.last().unwrap().internal > 0.2 * e0);
}

/// A run that goes unstable stops with the particle, its body, its place and the cause, and
/// leaves the last good state.
#[test]
fn instability_names_particle_body_place_and_cause() {
    let case = example("elastic_wave.toml");
    let mut sim = Simulation::<2>::new(&case).unwrap();
    run_to(&mut sim, 1e-6);
    let victim = 500;
    let id = sim.particles.id[victim];
    sim.particles.v[victim][1] = f64::NAN;
    sim.particles.vh[victim][1] = f64::NAN;
    let before = sim.particles.x.clone();
    let step = sim.state.step;
    match sim.step(1.0) {
        Err(Error::Unstable { step: s, cause, .. }) => {
            println!("{cause}");
            assert_eq!(s, step);
            assert!(cause.contains(&format!("particle {id} ")), "{cause}");
            assert!(cause.contains("body 'column'"), "{cause}");
            assert!(cause.contains("not finite"), "{cause}");
            assert!(cause.contains("m:"), "{cause}");
        }
        other => panic!("expected an instability, got {other:?}"),
    }
    // Nothing moved: the last good state is intact.
    assert_eq!(
        &sim.particles.x[..sim.particles.n_real],
        &before[..sim.particles.n_real]
    );
}
