//! Materials and failure (VALIDATION.md §F; issue 13), each case at two resolutions.

use strike::case::Case;
use strike::simulation::Simulation;
use strike::validate::{pull_back, spall_run};

fn load(name: &str) -> Case {
    let path = format!("{}/examples/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    strike::deck::load(std::path::Path::new(&path)).unwrap_or_else(|e| panic!("{path}: {e:?}"))
}

/// The deck, and the deck with every spacing halved.
fn two_resolutions(name: &str) -> [Case; 2] {
    let coarse = load(name);
    let mut fine = coarse.clone();
    for b in &mut fine.bodies {
        b.spacing *= 0.5;
    }
    [coarse, fine]
}

/// Issue 13, item 6 (spall): a flyer-plate impact spalls the target, and the free-face pull-back
/// gives back the spall strength set in the deck, σ_s = ½ ρ0 c Δu_fs, within 10 %, at two
/// resolutions (`examples/spall.toml`: a thin flyer, so that the pulse is triangular).
///
/// The wave speed of the acoustic relation is that of the release that carries the tension:
/// here the elastic one, c_L = √((K0 + 4G/3)/ρ0) = 6409 m/s, because the tension at the spall
/// plane is the incident pulse's stress decrement, and a decrement of 1 GPa lies inside the
/// elastic release range 2 HEL ≈ 1.2 GPa of Al 6061-T6 (Kanel 2010, Int. J. Fract. 163, 173,
/// on the acoustic approximation). With the bulk speed 5240 m/s the same runs read 0.81 GPa.
///
/// The spall plane lies where the free face's reflected release meets the pulse's tail, about
/// one flyer thickness (0.5 mm) inside the free face. The same run with damage off shows the
/// diagnostic sees the difference: the free face then falls back towards rest.
#[test]
fn flyer_plate_spall_gives_back_the_spall_strength() {
    let (rho0, sigma_s) = (2703.0, 1.0e9);
    let c0 = ((rho0 * 5240.0f64.powi(2) + 4.0 / 3.0 * 27.6e9) / rho0).sqrt();
    let plane_expected = 2.5e-3;
    let mut results = Vec::new();
    for case in two_resolutions("spall") {
        let dp = case.bodies[1].spacing;
        let run = spall_run(&case).unwrap();
        let (u_max, u_min) = pull_back(&run.free_face);
        let sigma = 0.5 * rho0 * c0 * (u_max - u_min);
        let plane = run.failed_x.iter().sum::<f64>() / run.failed_x.len().max(1) as f64;
        println!(
            "spall, Δp = {dp:.1e} m: u_fs max {u_max:.1} m/s, pull-back to {u_min:.1} m/s, ½ ρ0 c0 Δu = {:.3} GPa (set {:.3}), {:+.2} %; {} failed particles, spall plane at {:.3} mm (expected {:.3}); momentum {:.1e}",
            sigma * 1e-9,
            sigma_s * 1e-9,
            100.0 * (sigma / sigma_s - 1.0),
            run.failed_x.len(),
            plane * 1e3,
            plane_expected * 1e3,
            run.momentum_error
        );
        results.push((u_max, sigma, plane, run));
    }
    for (u_max, sigma, plane, run) in results {
        // 2 u_p = 400 m/s, less what the elastic release took off the pulse's peak.
        assert!(u_max > 340.0 && u_max < 410.0, "free face peak {u_max}");
        assert!(
            (sigma / sigma_s - 1.0).abs() < 0.10,
            "spall strength from the pull-back {sigma:.3e} vs {sigma_s:.3e}"
        );
        assert!(!run.failed_x.is_empty(), "the target did not spall");
        assert!(
            (plane - plane_expected).abs() < 0.25e-3,
            "spall plane at {plane}"
        );
        assert!(
            run.momentum_error < 1e-10,
            "momentum {}",
            run.momentum_error
        );
    }
    // Without damage the target holds the tension and the free face falls back to rest.
    let mut intact = load("spall");
    intact.materials[0].damage = Default::default();
    let run = spall_run(&intact).unwrap();
    let (u_max, u_min) = pull_back(&run.free_face);
    println!("no damage: u_fs {u_max:.1} → {u_min:.1} m/s");
    assert!(run.failed_x.is_empty());
    assert!(
        u_min < 0.3 * u_max,
        "no spall, yet the free face stays at {u_min}"
    );
}

/// (final length, face diameter, peak εp) of a Taylor-bar run (`strike::validate::taylor_run`).
fn taylor_run(case: &Case) -> (f64, f64, f64) {
    let r = strike::validate::taylor_run(case).unwrap();
    (r.length, r.face, r.eps)
}

/// The Taylor bar on a wall made three ways: a symmetry plane (the deck), the rod meeting its
/// twin through the contact, and a fixed steel body through the contact.
fn taylor_variants(deck: &str, spacing: f64) -> Vec<(&'static str, Case)> {
    let mut sym = load(deck);
    sym.bodies[0].spacing = spacing;
    let mut twin = sym.clone();
    twin.symmetry.retain(|s| s.axis != 2);
    let mut other = twin.bodies[0].clone();
    other.name = "twin".into();
    other.velocity[2] = -other.velocity[2];
    if let strike::case::Shape::Cylinder { base, .. } = &mut other.shape {
        base[2] = -32.4e-3;
    }
    twin.bodies.push(other);
    let mut wall = twin.clone();
    wall.bodies[1] = strike::case::BodySpec {
        name: "wall".into(),
        velocity: [0.0; 3],
        motion: strike::case::Motion::Prescribed,
        shape: strike::case::Shape::Box {
            min: [0.0, 0.0, -4.0 * spacing],
            max: [9.0e-3, 9.0e-3, 0.0],
        },
        ..twin.bodies[1].clone()
    };
    vec![
        ("symmetry plane", sym),
        ("twin", twin),
        ("fixed wall", wall),
    ]
}

/// A Taylor bar's published finite-element results: (final length, impact-face diameter, peak
/// plastic strain), the middles of their ranges.
struct TaylorReference {
    length: f64,
    face: f64,
    eps: f64,
}

/// 42CrMo4 at 287 m/s, Johnson–Cook (DynELA and Abaqus; VALIDATION.md §F): final length
/// 26.52–26.56 mm, impact-face diameter 11.15–11.22 mm, peak plastic strain 1.78–1.84.
const STEEL: TaylorReference = TaylorReference {
    length: 26.54e-3,
    face: 11.185e-3,
    eps: 1.81,
};

/// Copper at 227 m/s with linear hardening (`examples/taylor_copper.toml`; the benchmark of
/// Kamoulakos 1990, Zhu & Cescotto 1995, Camacho & Ortiz 1997): final length 21.42–21.47 mm,
/// mushroom radius 7.0–7.2 mm, peak plastic strain 2.7–3.2 across the published codes.
const COPPER: TaylorReference = TaylorReference {
    length: 21.445e-3,
    face: 14.2e-3,
    eps: 2.95,
};

fn taylor_report(
    label: &str,
    reference: &TaylorReference,
    spacing: f64,
    (l, d, eps): (f64, f64, f64),
) {
    println!(
        "Taylor bar, {label}, Δp = {:.1} mm: length {:.3} mm ({:+.2} %), face diameter {:.3} mm ({:+.2} %), peak εp {eps:.3} ({:+.1} %)",
        spacing * 1e3,
        l * 1e3,
        100.0 * (l / reference.length - 1.0),
        d * 1e3,
        100.0 * (d / reference.face - 1.0),
        100.0 * (eps / reference.eps - 1.0)
    );
}

/// Issue 13, item 6 (Taylor bar, Johnson–Cook): 42CrMo4 at 287 m/s on a frictionless rigid
/// wall (the symmetry plane z = 0), quarter model, R0/Δp = 8, against the finite-element
/// results: the final length within 2 % (27.02 mm, +1.8 %) and the impact-face diameter, which
/// converges to them from below as the lattice is refined (−8.5 % here, −0.2 % at R0/Δp = 16:
/// [`taylor_bars_converge_and_their_walls_agree`]), within 10 % at this coarse resolution.
#[test]
fn taylor_bar_final_length_matches_the_finite_element_results() {
    let spacing = 0.4e-3;
    let (label, case) = taylor_variants("taylor_bar", spacing).swap_remove(0);
    let (l, d, eps) = taylor_run(&case);
    taylor_report(label, &STEEL, spacing, (l, d, eps));
    assert!((l / STEEL.length - 1.0).abs() < 0.02, "length {l}");
    assert!((d / STEEL.face - 1.0).abs() < 0.10, "face diameter {d}");
}

/// Issue 13, items 5 and 6: the steel and the copper Taylor bars at R0/Δp = 8 and 16. On the
/// symmetry plane, the rod's twin through the contact and a fixed steel wall through the
/// contact agree within 2 % in final length and face diameter; both errors shrink with
/// refinement, and at R0/Δp = 16 the final length is within 2 % (steel; the issue's tolerance)
/// and 4 % (copper: the published codes spread by 0.3 %, the rest is our lattice's, half a
/// spacing of it the length's measure) and the face diameter within 5 % of the published
/// results. About an hour on 2 cores:
/// `cargo test --release --test verification_materials -- --ignored`. It fails today on the
/// walls: the twin's face diameter is −1.4 % of the symmetry plane's at R0/Δp = 8 but +3.2 % at
/// 16 (steel; the fixed wall's +3.0 %), and −5.9 % at R0/Δp = 8 for copper; the lengths agree
/// within 0.6 %.
#[test]
#[ignore = "long (the validation command), and failing: the walls disagree on the footprint (README, Not yet)"]
fn taylor_bars_converge_and_their_walls_agree() {
    for (deck, reference, length_tolerance) in [
        ("taylor_bar", &STEEL, 0.02),
        ("taylor_copper", &COPPER, 0.04),
    ] {
        let (mut face_error, mut length_error) = (f64::INFINITY, f64::INFINITY);
        for spacing in [0.4e-3, 0.2e-3] {
            let runs: Vec<(&str, (f64, f64, f64))> = taylor_variants(deck, spacing)
                .into_iter()
                .map(|(label, case)| {
                    let r = taylor_run(&case);
                    taylor_report(label, reference, spacing, r);
                    (label, r)
                })
                .collect();
            let (l0, d0, _) = runs[0].1;
            for (label, (l, d, _)) in &runs[1..] {
                assert!(
                    (l / l0 - 1.0).abs() < 0.02,
                    "{deck}, {label}: length {l} vs {l0}"
                );
                assert!(
                    (d / d0 - 1.0).abs() < 0.02,
                    "{deck}, {label}: face {d} vs {d0}"
                );
            }
            let error = (d0 / reference.face - 1.0).abs();
            assert!(
                error < face_error,
                "{deck}: the face diameter moves away, {d0}"
            );
            face_error = error;
            let dl = (l0 / reference.length - 1.0).abs();
            assert!(dl < length_error, "{deck}: the length moves away, {l0}");
            length_error = dl;
            if spacing < 0.3e-3 {
                assert!(dl < length_tolerance, "{deck}: length {l0}");
                assert!(error < 0.05, "{deck}: face diameter {d0}");
            }
        }
    }
}

/// Rubble keeps its energy and its density. A cube of failed aluminium (every particle at
/// damage 1: it pushes but cannot pull) with random velocities of ±20 m/s and no mean motion:
/// its particles knock into each other and drift apart. Energy must stay within 0.5 % and no
/// particle may be compressed by more than a 20 m/s knock does (Δρ/ρ ≈ v/c ≈ 0.4 %), at
/// most 2 %. With the separating pairs of failed particles dropped from the continuity
/// equation (strike's first rule) the density ratcheted up at every knock: 1.4 ρ0 and 65 GPa
/// in the rubble of `examples/ogive_plate.toml`, and its energy grew by 10 %.
#[test]
fn rubble_keeps_its_energy_and_density() {
    let deck = r#"
[simulation]
dimension = 3
end_time = 3.0e-5

[[body]]
name = "rubble"
material = "al_6061_t6"
spacing = 1.0e-3
shape = { type = "box", min = [0.0, 0.0, 0.0], max = [0.01, 0.01, 0.01] }
"#;
    let case = strike::deck::parse(deck, "rubble.toml").unwrap();
    let mut sim = Simulation::<3>::new(&case).unwrap();
    let rho0 = sim.particles.rho[0];
    let n = sim.particles.n_real;
    let mut seed = 12345u64;
    let mut random = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    for i in 0..n {
        sim.particles.damage[i] = 1.0;
        for k in 0..3 {
            sim.particles.v[i][k] = 20.0 * random();
        }
    }
    // No mean motion.
    let mean: Vec<f64> = (0..3)
        .map(|k| (0..n).map(|i| sim.particles.v[i][k]).sum::<f64>() / n as f64)
        .collect();
    for i in 0..n {
        for (k, m) in mean.iter().enumerate() {
            sim.particles.v[i][k] -= m;
        }
        sim.particles.vh[i] = sim.particles.v[i];
    }
    let end = case.simulation.end_time;
    let (mut e0, mut drift, mut rho_max) = (None, 0.0_f64, 0.0_f64);
    while sim.state.time < end * (1.0 - 1e-12) {
        let d = sim.step(end - sim.state.time).unwrap();
        let e0 = *e0.get_or_insert(d.total);
        drift = drift.max((d.total - e0).abs() / e0);
        rho_max = (0..n).map(|i| sim.particles.rho[i]).fold(rho_max, f64::max);
    }
    println!(
        "rubble: {} steps, energy drift {:.3e}, densest {:.4} ρ0",
        sim.state.step,
        drift,
        rho_max / rho0
    );
    assert!(drift < 5e-3, "energy drift {drift}");
    assert!(rho_max / rho0 < 1.02, "densest {}", rho_max / rho0);
}
