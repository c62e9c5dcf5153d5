//! The paper's demonstration at a coarse resolution (VALIDATION.md §C): a 7 km/s Al sphere on an
//! Al plate, quarter model, contact between the bodies.

use std::path::Path;
use strike::deck;
use strike::run::{run, RunOptions};
use strike::simulation::Simulation;

/// In both formulations (examples/sphere_plate.toml and its CN-SPH twin,
/// examples/sphere_plate_cn.toml).
#[test]
fn coarse_sphere_plate_impact() {
    for name in ["sphere_plate", "sphere_plate_cn"] {
        coarse_impact(name);
    }
}

fn coarse_impact(name: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("examples/{name}.toml"));
    let mut case = deck::load(&path).unwrap();
    let dp = 50e-6;
    for b in &mut case.bodies {
        b.spacing = dp;
    }
    let mut sim = Simulation::<3>::new(&case).unwrap();
    // Initial height of each particle, by id: the sphere's rear is its upper quarter at t = 0.
    let z0: Vec<f64> = sim.particles.x.iter().map(|x| x[2]).collect();
    let rear_z0 = 3.0e-4 + 0.5 * 3.0e-4;
    let end = case.simulation.end_time;
    let mut hist = Vec::new();
    while sim.state.time < end * (1.0 - 1e-12) {
        match sim.step(end - sim.state.time) {
            Ok(d) => hist.push(d),
            Err(e) => panic!("unstable: {e}"),
        }
    }
    let e0 = hist[0].total;
    let energy_error = hist
        .iter()
        .map(|d| (d.total - e0).abs())
        .fold(0.0, f64::max)
        / e0;
    let pz0 = hist[0].momentum[2];
    let momentum_error = hist
        .iter()
        .map(|d| (d.momentum[2] - pz0).abs())
        .fold(0.0, f64::max)
        / pz0.abs();
    let min_gap = hist
        .iter()
        .filter_map(|d| d.min_interbody_distance)
        .fold(f64::INFINITY, f64::min);
    let (penetration, mixed) = hist
        .iter()
        .flat_map(|d| d.mixing.iter())
        .fold((0.0_f64, 0), |(p, m), x| {
            (p.max(x.penetration), m.max(x.mixed))
        });

    let p = &sim.particles;
    let n = p.n_real;
    // The sphere's rear: the particles that started in its upper quarter (above z = 1.5 R).
    let rear: Vec<usize> = (0..n)
        .filter(|&i| p.body[i] == 0 && z0[p.id[i] as usize] > rear_z0)
        .collect();
    let rear_vz = rear.iter().map(|&i| p.v[i][2]).sum::<f64>() / rear.len() as f64;
    // The plate under the sphere: particles within half a sphere radius of the axis.
    let plug: Vec<usize> = (0..n)
        .filter(|&i| p.body[i] == 1 && (p.x[i][0].powi(2) + p.x[i][1].powi(2)).sqrt() < 1.5e-4)
        .collect();
    let plug_vz = plug.iter().map(|&i| p.v[i][2]).sum::<f64>() / plug.len() as f64;
    let plug_below =
        plug.iter().filter(|&&i| p.x[i][2] < -2.0e-4).count() as f64 / plug.len() as f64;
    println!(
        "{name} Δp = {dp:e} m, {n} particles, {} steps: energy error {energy_error:.3e}, \
         z-momentum error {momentum_error:.3e}, min inter-body distance {min_gap:.3} Δp, \
         penetration {penetration:.2} Δp ({mixed} particles), \
         rear v_z {rear_vz:.0} m/s, plug v_z {plug_vz:.0} m/s, plug below the plate's rear face {:.0} %",
        hist.len(),
        100.0 * plug_below
    );
    // No particle of one body passes the other's surface layer by more than a few hundredths of
    // a spacing at this very coarse resolution (R/Δp = 6; none at the example's 20 µm, see the
    // README). The closest approach, 0.4 Δp here, is no measure of mixing (see `mixing`).
    assert!(
        penetration < 0.1 && mixed <= 2,
        "particles mixed: {penetration} Δp, {mixed}"
    );
    assert!(energy_error < 0.05, "energy error {energy_error}");
    assert!(momentum_error < 1e-10, "momentum error {momentum_error}");
    assert!(
        rear_vz < -2000.0,
        "the sphere's rear should still move forward: {rear_vz}"
    );
    assert!(
        plug_vz < -2000.0,
        "the plate under the sphere should move at km/s: {plug_vz}"
    );
    assert!(
        plug_below > 0.5,
        "the plate should be perforated: {plug_below}"
    );
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
