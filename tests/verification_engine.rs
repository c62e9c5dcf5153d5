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

/// Every check of a `strike validate` case within its tolerance, printed.
fn validated(outcome: strike::Result<strike::validate::Outcome>) {
    let outcome = outcome.expect("the case runs");
    for c in &outcome.checks {
        println!(
            "{} ({}): {:.6e} against {:.6e} {}, {:+.3} % (tolerance {} %)",
            c.quantity,
            c.setting,
            c.measured,
            c.reference,
            c.unit,
            100.0 * c.error(),
            100.0 * c.tolerance
        );
    }
    for c in &outcome.checks {
        assert!(c.passes(1.0), "{c:?}");
    }
}

/// Elastic wave in uniaxial strain (`strike validate --case elastic_wave`): the front moves at
/// c_L = √((K + 4G/3)/ρ) within 2 %; the stress behind it is −ρ c_L v within 2 %. Both
/// formulations.
#[test]
fn elastic_wave_front_speed() {
    validated(strike::validate::elastic_wave(false));
}

/// Uniaxial-strain loading of an elastic–perfectly plastic column (`strike validate --case
/// hel`): the elastic precursor carries σ_HEL = Y (1 − ν)/(1 − 2ν) within 5 %, and the material
/// behind the plastic wave has yielded. Both formulations.
#[test]
fn hugoniot_elastic_limit() {
    validated(strike::validate::hel(false));
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
