//! The paper's demonstration at a coarse resolution (VALIDATION.md §C): a 7 km/s Al sphere on an
//! Al plate, quarter model, contact between the bodies.

use std::path::Path;
use strike::deck;
use strike::run::{run, RunOptions};
use strike::simulation::Simulation;

mod support;
use support::validated;

/// In both formulations (examples/sphere_plate.toml and its CN-SPH twin,
/// examples/sphere_plate_cn.toml) at Δp = 50 µm (`strike validate --case sphere_plate`): no
/// particle of one body passes the other's surface layer at any step (none at the example's
/// 20 µm either, see the README); energy within 5 %, z momentum to 1e-10; the sphere's rear
/// and the plug under it moving on at km/s, the plate perforated. The closest approach, 0.4 Δp
/// here, is no measure of mixing (see `mixing`).
#[test]
fn coarse_sphere_plate_impact() {
    validated(strike::validate::contact::sphere_plate(false));
}

/// The same coarse case through the run driver: the summary reports the momentum error over the
/// components parallel to both symmetry planes (z), the energy error and the closest approach.
#[test]
fn coarse_sphere_plate_summary() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/sphere_plate.toml");
    let mut case = deck::load(&path).unwrap();
    for b in &mut case.bodies {
        b.spacing = 50e-6;
    }
    let opts = RunOptions {
        out_dir: Path::new(env!("CARGO_TARGET_TMPDIR")).join("sphere_plate_summary"),
        progress: false,
        max_steps: Some(60),
        write_fields: false,
        overwrite: true,
        ..Default::default()
    };
    let s = run(&case, &opts).unwrap();
    println!("{s:?}");
    assert_eq!(s.status, "max_steps");
    assert_eq!(s.steps, 60);
    assert!(
        s.momentum_error < 1e-10,
        "momentum error {}",
        s.momentum_error
    );
    assert!(s.energy_error < 0.05, "energy error {}", s.energy_error);
    assert!(s
        .mixing
        .iter()
        .all(|m| m.max_penetration == 0.0 && m.max_mixed == 0));
}

/// Past 0.2 µs the debris leaves the plate (the issue asks for runs to 1 µs): no particle ever
/// crosses a symmetry plane (a crossed particle would meet ghosts beyond the ghost layer and
/// break the balance of forces along the plane), z-momentum stays conserved.
#[test]
fn coarse_debris_stays_on_the_model_side() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/sphere_plate.toml");
    let mut case = deck::load(&path).unwrap();
    for b in &mut case.bodies {
        b.spacing = 50e-6;
    }
    let mut sim = Simulation::<3>::new(&case).unwrap();
    let first = sim.step(1.0).unwrap();
    let mut worst_momentum: f64 = 0.0;
    let mut worst_depth = f64::INFINITY;
    while sim.state.time < 0.6e-6 {
        let d = sim.step(1.0).unwrap();
        worst_momentum = worst_momentum.max((d.momentum[2] / first.momentum[2] - 1.0).abs());
        let p = &sim.particles;
        for i in 0..p.n_real {
            worst_depth = worst_depth.min(p.x[i][0].min(p.x[i][1]));
        }
    }
    println!(
        "coarse sphere-plate to 0.6 µs: {} steps, closest approach to a plane {worst_depth:.3e} m, z-momentum {worst_momentum:.3e}",
        sim.state.step
    );
    assert!(
        worst_depth >= 0.0,
        "a particle crossed a symmetry plane: {worst_depth}"
    );
    assert!(worst_momentum < 1e-10);
}
