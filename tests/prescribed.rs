//! `[[prescribed]]` sets: particles of a body within a region, moving at a set velocity (held
//! fixed by default), as a clamp or a piston. A set is a body of its own, welded to its body,
//! so it must run exactly as the welded prescribed body a deck would otherwise add for it, and
//! drive the wave its speed gives.

use std::path::Path;
use strike::case::Case;
use strike::simulation::Simulation;

fn example(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("examples/{name}.toml"));
    std::fs::read_to_string(path).unwrap()
}

/// `text` with `from` replaced by `to` (which must be there).
fn edit(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "`{from}` not in the deck");
    text.replacen(from, to, 1)
}

fn run<const D: usize>(case: &Case, steps: usize) -> Simulation<D> {
    let mut sim = Simulation::<D>::new(case).unwrap();
    for _ in 0..steps {
        sim.step(f64::INFINITY).unwrap();
    }
    sim
}

/// `examples/plate_2d.toml` clamps its plate by a set: the plate's particles beyond 15 mm
/// held fixed. The same plate 15 mm wide with a prescribed frame body welded to its edge, as
/// decks clamped plates before sets existed, has the same particles in the same order and gives
/// the same run to the bit: every particle's state after 400 steps, the rod through the plate
/// and its failure included.
#[test]
fn a_set_runs_as_the_welded_prescribed_body_it_replaces() {
    let deck = example("plate_2d");
    let set = r#"[[body]]
name = "plate"
material = "al"
spacing = 0.25e-3
shape = { type = "rectangle", min = [0.0, -1.0e-3], max = [17.0e-3, 0.0] }
"#;
    let set_table = r#"[[prescribed]]
name = "frame"
body = "plate"
region = { type = "rectangle", min = [15.0e-3, -2.0e-3], max = [18.0e-3, 1.0e-3] }
"#;
    let frame = r#"[[body]]
name = "plate"
material = "al"
spacing = 0.25e-3
shape = { type = "rectangle", min = [0.0, -1.0e-3], max = [15.0e-3, 0.0] }

[[body]]
name = "frame"
material = "al"
spacing = 0.25e-3
motion = "prescribed"
shape = { type = "rectangle", min = [15.0e-3, -1.0e-3], max = [17.0e-3, 0.0] }

[[interaction]]
bodies = ["plate", "frame"]
type = "welded"
"#;
    let framed = edit(&edit(&deck, set, frame), set_table, "");
    let with_body = strike::deck::parse(&framed, "plate_2d_frame.toml").unwrap();
    let with_set = strike::deck::parse(&deck, "plate_2d.toml").unwrap();
    assert_eq!(with_set.bodies[2].part_of, Some(1));
    assert_eq!(with_body.bodies[2].part_of, None);
    let (a, b) = (run::<2>(&with_body, 400), run::<2>(&with_set, 400));
    let (p, q) = (&a.particles, &b.particles);
    assert_eq!((p.n_real, p.len()), (q.n_real, q.len()));
    assert_eq!(p.body, q.body);
    assert_eq!(p.id, q.id);
    assert_eq!(p.x, q.x);
    assert_eq!(p.v, q.v);
    assert_eq!(p.rho, q.rho);
    assert_eq!(p.e, q.e);
    assert_eq!(p.s, q.s);
    assert_eq!(p.damage, q.damage);
    assert_eq!(a.state.time, b.state.time);
    // The frame held: its particles where they started.
    let frame = (0..q.n_real).filter(|&i| q.body[i] == 2);
    assert!(frame.clone().count() > 0);
    assert!(frame
        .clone()
        .all(|i| q.v[i].norm() == 0.0 && q.x[i][0] > 15.0e-3));
    // Something happened: the rod has hit the plate.
    let plate_moved = (0..q.n_real).any(|i| q.body[i] == 1 && q.v[i].norm() > 10.0);
    assert!(plate_moved);
}

/// A piston made of a column's own end: `examples/elastic_wave.toml` with its welded piston
/// body replaced by the column's first 1.5 mm as a set moving at 10 m/s. Behind the front the
/// column carries σ_xx = −ρ c_L v (uniaxial strain, c_L = √((K + 4G/3)/ρ)), within 2 % at
/// Δp = 0.5 and 0.25 mm (measured on 2026-12-05: −0.03 / −0.16 % of −1.660e8 Pa).
#[test]
fn a_piston_set_drives_the_plane_wave_its_speed_gives() {
    let deck = edit(
        &example("elastic_wave"),
        r#"[[body]]
name = "piston"
material = "elastic_al"
spacing = 0.5e-3
velocity = [10.0, 0.0]
motion = "prescribed"
shape = { type = "rectangle", min = [-1.5e-3, 0.0], max = [0.0, 2.0e-3] }

[[body]]
name = "column"
material = "elastic_al"
spacing = 0.5e-3
shape = { type = "rectangle", min = [0.0, 0.0], max = [0.1, 2.0e-3] }

[[interaction]]
bodies = ["piston", "column"]
type = "welded"
"#,
        r#"[[body]]
name = "column"
material = "elastic_al"
spacing = 0.5e-3
shape = { type = "rectangle", min = [-1.5e-3, 0.0], max = [0.1, 2.0e-3] }

[[prescribed]]
name = "piston"
body = "column"
region = { type = "rectangle", min = [-2.0e-3, -1.0e-3], max = [0.0, 3.0e-3] }
velocity = [10.0, 0.0]
"#,
    );
    let (rho, e, nu, v): (f64, f64, f64, f64) = (2700.0, 68.9e9, 0.33, 10.0);
    let (k, g) = (e / (3.0 * (1.0 - 2.0 * nu)), e / (2.0 * (1.0 + nu)));
    let c = ((k + 4.0 / 3.0 * g) / rho).sqrt();
    let expected = -rho * c * v;
    for dp in [0.5e-3, 0.25e-3] {
        let mut case = strike::deck::parse(&deck, "piston_set.toml").unwrap();
        for b in &mut case.bodies {
            b.spacing = dp;
        }
        assert_eq!(case.bodies[1].name, "piston");
        let mut sim = Simulation::<2>::new(&case).unwrap();
        while sim.state.time < 4.0e-6 {
            sim.step(4.0e-6 - sim.state.time + 1e-12).unwrap();
        }
        let p = &sim.particles;
        let behind: Vec<f64> = (0..p.n_real)
            .filter(|&i| p.body[i] == 0 && (5.0e-3..20.0e-3).contains(&p.x[i][0]))
            .map(|i| p.s[i].get(0, 0) - p.p[i])
            .collect();
        let mean = behind.iter().sum::<f64>() / behind.len() as f64;
        let piston: Vec<usize> = (0..p.n_real).filter(|&i| p.body[i] == 1).collect();
        eprintln!(
            "Δp = {dp:e} m: σ_xx behind the front {mean:.4e} Pa against {expected:.4e} ({:+.2} %), {} piston particles",
            100.0 * (mean / expected - 1.0),
            piston.len()
        );
        assert_eq!(piston.len(), (1.5e-3 / dp * 2.0e-3 / dp).round() as usize);
        assert!(piston.iter().all(|&i| p.v[i][0] == v && p.v[i][1] == 0.0));
        assert!(
            (mean / expected - 1.0).abs() < 0.02,
            "σ_xx {mean:e} against {expected:e}"
        );
    }
}

/// A set whose region holds none of its body's particles, and sets that take every one, are
/// refused at set-up with the set's (or the body's) line and key.
#[test]
fn a_set_without_particles_or_a_body_without_any_left_is_refused() {
    let deck = edit(
        &example("plate_2d"),
        "[output]",
        "[[prescribed]]\nname = \"clamp\"\nbody = \"plate\"\nREGION\n\n[output]",
    );
    let line = deck
        .lines()
        .enumerate()
        .filter(|(_, l)| *l == "[[prescribed]]")
        .last()
        .unwrap()
        .0
        + 1;
    let refused = |region: &str| {
        let case = strike::deck::parse(&deck.replace("REGION", region), "sets.toml").unwrap();
        match Simulation::<2>::new(&case) {
            Err(strike::Error::Deck {
                location,
                key,
                message,
                ..
            }) => (location.line, key, message),
            Err(e) => panic!("not a deck error: {e}"),
            Ok(_) => panic!("the deck was accepted"),
        }
    };
    let (at, key, message) =
        refused("region = { type = \"rectangle\", min = [20e-3, -1e-3], max = [21e-3, 0.0] }");
    assert_eq!(
        (at, key.as_str()),
        (line, "prescribed[1].region"),
        "{message}"
    );
    assert!(message.contains("'clamp' holds no particle"), "{message}");
    let (_, key, message) =
        refused("region = { type = \"rectangle\", min = [-1.0, -1.0], max = [1.0, 1.0] }");
    assert_eq!(key, "body[1].shape", "{message}");
    assert!(message.contains("no particle left"), "{message}");
}
