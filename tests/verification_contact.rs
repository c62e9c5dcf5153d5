//! Verification of the frictionless contact (VALIDATION.md §B), built from the example decks.
//!
//! Run with `cargo test --release --test verification_contact`.
//!
//! Momentum: total linear momentum is checked to 1e-10 relative along every axis with no
//! external force — in the bars, rings and planar-impact cases (the symmetry planes of the bars
//! and the plates are parallel to the motion and exert no force along it). The sliding case has
//! gravity normal to the sliding and a prescribed base, so there only the tangential momentum is
//! checked; the incline has gravity and a fixed body, so momentum is not conserved there.

use strike::case::{Case, ContactLaw, Formulation, InteractionKind, Shape};
use strike::simulation::{Diagnostics, Simulation};

/// One step's record.
#[allow(dead_code)]
struct Row {
    d: Diagnostics,
    /// Mass-weighted mean velocity and centre of mass of each body (3 components).
    vmean: Vec<[f64; 3]>,
    com: Vec<[f64; 3]>,
}

fn load(name: &str) -> Case {
    let path = format!("{}/examples/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    strike::deck::load(std::path::Path::new(&path)).unwrap_or_else(|e| panic!("{path}: {e:?}"))
}

/// The case in conventional SPH and in CN-SPH: each case is checked in both formulations
/// (issue 12), with the same tolerances.
fn both(case: Case) -> [Case; 2] {
    let mut cn = case.clone();
    cn.simulation.formulation = Formulation::Corrected;
    let mut conventional = case;
    conventional.simulation.formulation = Formulation::Conventional;
    [conventional, cn]
}

/// The formulation's name, for the printed figures.
fn label(case: &Case) -> &'static str {
    match case.simulation.formulation {
        Formulation::Conventional => "conventional",
        Formulation::Corrected => "CN-SPH",
    }
}

/// The deck, and the deck with every spacing halved, each in both formulations: each case is
/// checked at two resolutions.
fn two_resolutions(name: &str) -> Vec<Case> {
    let coarse = load(name);
    let mut fine = coarse.clone();
    for b in &mut fine.bodies {
        b.spacing *= 0.5;
    }
    [coarse, fine].into_iter().flat_map(both).collect()
}

fn body_means<const D: usize>(sim: &Simulation<D>) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let nb = sim.body_names.len();
    let p = &sim.particles;
    let mut m = vec![0.0; nb];
    let mut v = vec![[0.0; 3]; nb];
    let mut x = vec![[0.0; 3]; nb];
    for i in 0..p.n_real {
        let b = p.body[i] as usize;
        m[b] += p.m[i];
        for k in 0..D {
            v[b][k] += p.m[i] * p.v[i][k];
            x[b][k] += p.m[i] * p.x[i][k];
        }
    }
    for b in 0..nb {
        for k in 0..3 {
            v[b][k] /= m[b];
            x[b][k] /= m[b];
        }
    }
    (v, x)
}

/// Run a case to its end time, recording every step (and the final simulation).
fn run<const D: usize>(case: &Case) -> (Vec<Row>, Simulation<D>) {
    let (rows, sim, err) = try_run(case);
    if let Some(e) = err {
        panic!("{}: {e}", case.name);
    }
    (rows, sim)
}

/// Run a case, stopping at the end time or at the first instability (returned as text).
fn try_run<const D: usize>(case: &Case) -> (Vec<Row>, Simulation<D>, Option<String>) {
    let mut sim = Simulation::<D>::new(case).expect("setup");
    let mut rows = Vec::new();
    while sim.state.time < case.simulation.end_time * (1.0 - 1e-12) {
        let (vmean, com) = body_means(&sim);
        match sim.step(case.simulation.end_time - sim.state.time) {
            Ok(d) => rows.push(Row { d, vmean, com }),
            Err(e) => return (rows, sim, Some(format!("{e:?}"))),
        }
    }
    (rows, sim, None)
}

// ---------------------------------------------------------------------------------------------
// Bars

const BAR_RHO: f64 = 2700.0;
const BAR_V: f64 = 10.0;
const BAR_W: f64 = 2.0e-3;

fn bar_c() -> f64 {
    let (e, nu) = (68.9e9, 0.33);
    let k = e / (3.0 * (1.0 - 2.0 * nu));
    let g = e / (2.0 * (1.0 + nu));
    ((k + 4.0 * g / 3.0) / BAR_RHO).sqrt()
}

/// Figures of a bars run.
#[derive(Debug)]
struct BarFigures {
    /// Time from the first to the last step with a non-zero contact force (s).
    duration: f64,
    /// Whether the contact force was zero at the end (the last non-zero step is not the last).
    released: bool,
    /// Mean interface stress, contact force / contact area, over the middle half of the contact.
    plateau_stress: f64,
    /// Mean x velocity of each bar at the end.
    v_after: [f64; 2],
    /// Largest x component of the contact force on the left bar (> 0 would pull the bars
    /// together).
    max_tensile: f64,
    /// Largest |total energy − initial| over the run, / the initial kinetic energy.
    energy_dev: f64,
    /// Largest |momentum − initial| (any axis), / Σ m|v|.
    momentum_dev: f64,
    /// Smallest inter-body distance / Δp over the run.
    min_gap: f64,
}

fn energy_dev(rows: &[Row]) -> f64 {
    let e0 = rows[0].d.total;
    let scale = rows[0].d.kinetic;
    rows.iter()
        .map(|r| (r.d.total - e0).abs())
        .fold(0.0, f64::max)
        / scale
}

fn momentum_dev(rows: &[Row]) -> f64 {
    let p0 = rows[0].d.momentum;
    rows.iter()
        .map(|r| {
            (0..3)
                .map(|k| (r.d.momentum[k] - p0[k]).abs())
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max)
        / rows[0].d.momentum_scale
}

fn min_gap(rows: &[Row]) -> f64 {
    rows.iter()
        .filter_map(|r| r.d.min_interbody_distance)
        .fold(f64::INFINITY, f64::min)
}

fn bar_figures(rows: &[Row]) -> BarFigures {
    let f: Vec<f64> = rows.iter().map(|r| r.d.body_contact_force[0][0]).collect();
    let first = f.iter().position(|&x| x != 0.0).expect("bars never touch");
    let last = f.iter().rposition(|&x| x != 0.0).unwrap();
    let released = last + 1 < rows.len();
    let t0 = rows[first].d.time;
    let t1 = rows[(last + 1).min(rows.len() - 1)].d.time;
    let duration = t1 - t0;
    let (a, b) = (t0 + 0.25 * duration, t0 + 0.75 * duration);
    let plat: Vec<f64> = rows
        .iter()
        .filter(|r| r.d.time >= a && r.d.time <= b)
        .map(|r| -r.d.body_contact_force[0][0] / BAR_W)
        .collect();
    let lastrow = rows.last().unwrap();
    BarFigures {
        duration,
        released,
        plateau_stress: plat.iter().sum::<f64>() / plat.len() as f64,
        v_after: [lastrow.vmean[0][0], lastrow.vmean[1][0]],
        max_tensile: f.iter().copied().fold(0.0, f64::max),
        energy_dev: energy_dev(rows),
        momentum_dev: momentum_dev(rows),
        min_gap: min_gap(rows),
    }
}

/// Make each bar `length` long (the left one ends, the right one starts, where the deck has
/// them) and scale the end time with it.
fn set_bar_length(case: &mut Case, length: f64) {
    let old = match case.bodies[0].shape {
        Shape::Box { min, max } => max[0] - min[0],
        _ => panic!("bars are rectangles"),
    };
    if let Shape::Box { min, .. } = &mut case.bodies[0].shape {
        min[0] += old - length;
    }
    if let Shape::Box { max, .. } = &mut case.bodies[1].shape {
        max[0] += length - old;
    }
    case.simulation.end_time *= length / old;
}

fn set_bar_speed(case: &mut Case, v: f64) {
    case.bodies[0].velocity[0] = v;
    case.bodies[1].velocity[0] = -v;
}

/// Check the §B "separation" figures of a contact run at bar speed v, and return them.
fn check_bars(rows: &[Row], v: f64, length: f64) -> BarFigures {
    let fig = bar_figures(rows);
    let c = bar_c();
    println!(
        "bars at ±{v} m/s: {fig:?}; 2L/c = {:.4e} s, ρcv = {:.4e} Pa",
        2.0 * length / c,
        BAR_RHO * c * v
    );
    assert!(fig.released, "contact force still non-zero at the end");
    let expected = 2.0 * length / c;
    assert!(
        (fig.duration / expected - 1.0).abs() < 0.05,
        "contact duration {:.4e} s vs 2L/c {expected:.4e} s",
        fig.duration
    );
    let sigma = BAR_RHO * c * v;
    assert!(
        (fig.plateau_stress / sigma - 1.0).abs() < 0.10,
        "interface stress {:.4e} Pa vs ρcv {sigma:.4e} Pa",
        fig.plateau_stress
    );
    assert!(
        (fig.v_after[0] / -v - 1.0).abs() < 0.05,
        "left bar leaves at {}",
        fig.v_after[0]
    );
    assert!(
        (fig.v_after[1] / v - 1.0).abs() < 0.05,
        "right bar leaves at {}",
        fig.v_after[1]
    );
    assert!(
        fig.max_tensile <= 0.0,
        "tensile contact force {}",
        fig.max_tensile
    );
    assert!(
        fig.energy_dev < 0.01,
        "energy drifts by {:.3e}",
        fig.energy_dev
    );
    assert!(
        fig.momentum_dev < 1e-10,
        "momentum drifts by {:.3e}",
        fig.momentum_dev
    );
    assert!(
        fig.min_gap >= 0.5,
        "bodies closer than 0.5 Δp: {}",
        fig.min_gap
    );
    fig
}

/// Bars at ±400 m/s, L = 100 mm, at L/Δp = 200 and 400, default (colour) contact: §B's
/// separation figures against the acoustic references 2L/c = 32.53 µs and ρcv = 6.64 GPa.
///
/// At 400 m/s the strain is 6.3 %, where the model's linear EOS and Jaumann-rate elasticity
/// are no longer linear in the strain: σ(ε) = K(1/(1−ε) − 1) + (4G/3) ln(1/(1−ε)) stiffens, so
/// the compression front is a shock at 6318 m/s carrying 6.82 GPa, and the release comes back
/// at 6494 m/s (head) to c. The finite-strain contact time is therefore 31.2–31.6 µs, not
/// 32.53: measured 31.99 and 31.92 µs at the two resolutions, stress 6.789 and 6.790 GPa —
/// refinement moves toward the finite-strain answer. (The slow-bar case, where the strain is
/// small and the acoustic figures exact, is in tests/contact_fidelity.rs.)
#[test]
fn bars_separate_through_the_contact() {
    let (v, length) = (400.0, 0.1);
    for mut case in two_resolutions("bars_contact") {
        set_bar_speed(&mut case, v);
        set_bar_length(&mut case, length);
        let (rows, _) = run::<2>(&case);
        let fig = check_bars(&rows, v, length);
        println!(
            "contact bars, {}, L/Δp = {:.0}: part at {:.2} {:.2} m/s",
            label(&case),
            length / case.bodies[0].spacing,
            fig.v_after[0],
            fig.v_after[1]
        );
    }
}

/// Welded twin at the deck's ±10 m/s: at the end (≈ 1.8 × 2L/c, when a contact pair has long
/// parted) the bars are still joined and the left one moves right again, pulled back by the
/// tension across the weld. (At ±400 m/s the welded bars break apart at 6.6 GPa of tension —
/// SPH's tensile instability — and leave at ∓260 m/s, so the welded check is made at 10 m/s.)
#[test]
fn welded_bars_do_not_part() {
    for case in both(load("bars_welded")) {
        let (wrows, _) = run::<2>(&case);
        let w = wrows.last().unwrap();
        let swing = wrows
            .iter()
            .map(|r| r.vmean[0][0])
            .fold(f64::INFINITY, f64::min);
        println!(
            "welded bars, {}, at ±{BAR_V} m/s: mean velocities at t = {:.3e} s {:.3} {:.3}, slowest left-bar velocity {swing:.3}",
            label(&case),
            w.d.time,
            w.vmean[0][0],
            w.vmean[1][0]
        );
        assert!(
            w.vmean[0][0] > 0.0 && w.vmean[1][0] < 0.0,
            "welded bars parted"
        );
        assert!(momentum_dev(&wrows) < 1e-10);
        assert!(wrows
            .iter()
            .all(|r| r.d.body_contact_force.iter().all(|f| *f == [0.0; 3])));
    }
}

// ---------------------------------------------------------------------------------------------
// Frictionless sliding

/// Slider x velocity relative change (max over the run), base x momentum / slider's initial
/// x momentum (max), fraction of steps in contact.
fn sliding_figures(rows: &[Row], case: &Case) -> (f64, f64, f64) {
    let v0 = case.bodies[0].velocity[0];
    let mass_ratio = {
        // Base area / slider area (same material and spacing).
        let area = |b: &strike::case::BodySpec| match b.shape {
            strike::case::Shape::Box { min, max } => (max[0] - min[0]) * (max[1] - min[1]),
            _ => unreachable!(),
        };
        area(&case.bodies[1]) / area(&case.bodies[0])
    };
    let slider = rows
        .iter()
        .map(|r| (r.vmean[0][0] / v0 - 1.0).abs())
        .fold(0.0, f64::max);
    let base = rows
        .iter()
        .map(|r| (r.vmean[1][0] * mass_ratio / v0).abs())
        .fold(0.0, f64::max);
    let touching = rows
        .iter()
        .filter(|r| r.d.min_interbody_distance.is_some())
        .count() as f64
        / rows.len() as f64;
    (slider, base, touching)
}

/// The slider keeps its tangential momentum with the (colour) contact and loses
/// most of it to the base when welded. Gravity (−y) and the symmetry plane under the base (normal
/// to y) leave the x momentum of the whole conserved, which is checked to 1e-10.
#[test]
fn sliding_keeps_tangential_momentum_only_with_contact() {
    for case in two_resolutions("sliding_contact") {
        let (rows, _) = run::<2>(&case);
        let (slider, base, touching) = sliding_figures(&rows, &case);
        let p0 = rows[0].d.momentum[0];
        let px = rows
            .iter()
            .map(|r| (r.d.momentum[0] - p0).abs())
            .fold(0.0, f64::max)
            / rows[0].d.momentum_scale;
        println!(
            "sliding contact, {}, Δp = {} m: slider |Δv_x/v| ≤ {slider:.3e}, base p_x/p0 ≤ {base:.3e}, in contact {:.1} % of steps, p_x drift {px:.2e}, min gap {:.3}",
            label(&case),
            case.bodies[0].spacing,
            100.0 * touching,
            min_gap(&rows)
        );
        assert!(touching > 0.99, "the slider left the base");
        assert!(
            slider < 0.01,
            "slider tangential momentum changed by {slider:.3e}"
        );
        assert!(
            base < 0.01,
            "base tangential momentum reached {base:.3e} of the slider's"
        );
        assert!(px < 1e-10, "x momentum drifts by {px:.3e}");
        assert!(min_gap(&rows) >= 0.5);
    }
    for welded in two_resolutions("sliding_welded") {
        let (wrows, _) = run::<2>(&welded);
        let (wslider, wbase, _) = sliding_figures(&wrows, &welded);
        println!(
            "sliding welded, {}, Δp = {} m: slider |Δv_x/v| ≤ {wslider:.3e}, base p_x/p0 ≤ {wbase:.3e}",
            label(&welded),
            welded.bodies[0].spacing
        );
        assert!(
            wslider > 0.10 && wbase > 0.10,
            "welded blocks did not exchange momentum"
        );
    }
}

/// The paper's form of eq. (5) with a steep exponent n: in conventional SPH its force follows
/// the line of each pair's centres, and the other body's lattice corrugation acts as friction
/// (the slider loses several per cent of its velocity with n = 4, more with n = 6); in CN-SPH
/// it acts along the contact normal and the slider keeps its velocity within 1 % (VALIDATION.md
/// §E), at both resolutions.
#[test]
fn steep_paper_law_slides_without_friction_in_cn_sph() {
    for n in [4.0, 6.0] {
        for case in two_resolutions("sliding_contact") {
            let mut case = case;
            let fine = case.bodies[0].spacing < 0.04;
            let cn = case.simulation.formulation == Formulation::Corrected;
            if fine && !cn {
                continue;
            }
            for i in &mut case.interactions {
                i.kind = InteractionKind::Contact {
                    law: ContactLaw::Paper,
                    stiffness: None,
                    exponent: Some(n),
                };
            }
            let (rows, _) = run::<2>(&case);
            let (slider, _, touching) = sliding_figures(&rows, &case);
            let v0 = case.bodies[0].velocity[0];
            let kept = rows.last().unwrap().vmean[0][0] / v0;
            println!(
                "paper's form, n = {n}, {}, Δp = {} m: slider |Δv_x/v| ≤ {slider:.3e}, keeps {:.2} % of its velocity, in contact {:.1} % of steps, min gap {:.3}",
                label(&case),
                case.bodies[0].spacing,
                100.0 * kept,
                100.0 * touching,
                min_gap(&rows)
            );
            assert!(touching > 0.99, "the slider left the base");
            if cn {
                assert!(slider < 0.01, "CN-SPH slider lost {slider:.3e}");
            } else {
                assert!(slider > 0.01, "conventional slider lost only {slider:.3e}");
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Incline

/// Distance slid vs ½ g sin θ t² (gravity and a fixed body: momentum is not conserved).
#[test]
fn block_slides_down_the_incline() {
    for case in two_resolutions("incline") {
        let (rows, _) = run::<2>(&case);
        let x0 = rows[0].com[0][0];
        let mut worst: f64 = 0.0;
        for r in rows.iter().filter(|r| r.d.time >= 0.3) {
            let expected = 0.5 * 9.8 * 0.5 * r.d.time * r.d.time;
            worst = worst.max(((r.com[0][0] - x0) / expected - 1.0).abs());
        }
        let last = rows.last().unwrap();
        let t = last.d.time;
        println!(
            "incline, {}, Δp = {} m: slid {:.4} m at t = {t:.4} s vs 2.45 t² = {:.4} m; worst relative error for t ≥ 0.3 s {worst:.3e}; min gap {:.3}",
            label(&case),
            case.bodies[0].spacing,
            last.com[0][0] - x0,
            2.45 * t * t,
            min_gap(&rows)
        );
        assert!(worst < 0.05);
        assert!(min_gap(&rows) >= 0.5);
    }
}

// ---------------------------------------------------------------------------------------------
// Rubber rings

/// Particles with a particle of their own body closer than half a spacing: the pairing of the
/// tensile instability (the rings' conformed surface starts with 64 of them).
fn paired<const D: usize>(sim: &Simulation<D>, dp: f64) -> usize {
    let p = &sim.particles;
    (0..p.n_real)
        .filter(|&i| {
            (0..p.n_real)
                .any(|j| j != i && p.body[j] == p.body[i] && (p.x[i] - p.x[j]).norm() < 0.5 * dp)
        })
        .count()
}

/// One resolution (Δp = 1 mm) here: at 0.5 mm a run to 2 ms takes two minutes, and the rings,
/// whose rebound depends on their own (artificial-stress) dynamics more than on the contact,
/// are still touching at 2 ms with the colour law (see the README).
#[test]
fn rubber_rings_rebound_and_separate_without_fracture() {
    let mut deck = load("rubber_rings");
    // CN-SPH's rings stay in contact to 2.33 ms (conventional SPH's to 1.58 ms at this
    // spacing, and beyond 2 ms at Δp = 0.5 mm): both are followed to 3 ms.
    deck.simulation.end_time = 3.0e-3;
    for case in both(deck) {
        let (rows, sim) = run::<2>(&case);
        let f: Vec<bool> = rows
            .iter()
            .map(|r| r.d.body_contact_force[0] != [0.0; 3])
            .collect();
        let first = f.iter().position(|&x| x).expect("the rings never meet");
        let last = f.iter().rposition(|&x| x).unwrap();
        let end = rows.last().unwrap();
        let gap = |r: &Row| r.com[1][0] - r.com[0][0];
        let closest = rows.iter().map(gap).fold(f64::INFINITY, f64::min);
        let edev = energy_dev(&rows);
        let mdev = momentum_dev(&rows);
        // No fracture: every particle keeps a particle of its own body within 1.5 Δp.
        let p = &sim.particles;
        let dp = case.bodies[0].spacing;
        let isolated = (0..p.n_real)
            .filter(|&i| {
                !(0..p.n_real).any(|j| {
                    j != i && p.body[j] == p.body[i] && (p.x[i] - p.x[j]).norm() < 1.5 * dp
                })
            })
            .count();
        let paired_end = paired(&sim, dp);
        println!(
            "rings, {}, Δp = {} m: contact from {:.3e} s to {:.3e} s; centres {:.4} m apart at closest, {:.4} m at the end, moving apart at {:.2} m/s each; energy {edev:.3e}; momentum {mdev:.2e}; min gap {:.3}; isolated particles {isolated}, paired {paired_end}",
            label(&case),
            case.bodies[0].spacing,
            rows[first].d.time,
            rows[(last + 1).min(rows.len() - 1)].d.time,
            closest,
            gap(end),
            end.vmean[1][0],
            min_gap(&rows)
        );
        assert!(last + 1 < rows.len(), "still in contact at the end");
        assert!(
            end.vmean[0][0] < 0.0 && end.vmean[1][0] > 0.0,
            "not moving apart"
        );
        assert!(gap(end) > closest, "centres not moving apart");
        assert_eq!(
            isolated, 0,
            "fracture: particles with no neighbour of their own body"
        );
        assert!(paired_end <= 64, "{paired_end} particles paired");
        assert!(edev < 0.02, "energy drifts by {edev:.3e}");
        assert!(mdev < 1e-10, "momentum drifts by {mdev:.3e}");
        assert!(min_gap(&rows) >= 0.5);
    }
}

/// Issue 12, item 7: is artificial stress still needed in CN-SPH? Yes. Without it the rings
/// pair up in both formulations as their material goes into tension (the tensile instability:
/// corrected gradients make the kernel consistent, not stable in tension, Belytschko et al.
/// 2000, IJNME 48:1359, whose analysis puts the instability in the Eulerian kernel, which
/// CN-SPH keeps): conventional SPH ends with over 900 particles closer than Δp/2 to one of their
/// own body (64 at the start, none with ε = 0.3), and CN-SPH's rings pair up as fast and blow
/// up at about 0.8 ms.
#[test]
fn rubber_rings_need_artificial_stress_in_both_formulations() {
    let mut deck = load("rubber_rings");
    for m in &mut deck.materials {
        m.artificial_stress = None;
    }
    for case in both(deck) {
        let (rows, sim, err) = try_run::<2>(&case);
        let dp = case.bodies[0].spacing;
        let n = paired(&sim, dp);
        println!(
            "rings without artificial stress, {}: {} at t = {:.3e} s, {n} particles paired",
            label(&case),
            err.as_deref().unwrap_or("running"),
            rows.last().map_or(0.0, |r| r.d.time)
        );
        assert!(
            err.is_some() || n > 4 * 64,
            "no tensile instability: {n} particles paired"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Planar impact

/// Rankine–Hugoniot figures measured on the plateau: (interface pressure from the contact force
/// or, welded, mean target pressure behind the shock; particle velocity; shock speed).
fn planar_figures(case: &Case) -> (f64, f64, f64, Vec<Row>) {
    let w = 0.4e-3;
    let mut sim = Simulation::<2>::new(case).unwrap();
    let mut rows = Vec::new();
    let mut fronts = Vec::new();
    let (mut p_sum, mut u_sum, mut n_sum) = (0.0, 0.0, 0.0);
    for t_stop in [0.6e-6, 1.2e-6] {
        while sim.state.time < t_stop * (1.0 - 1e-12) {
            let (vmean, com) = body_means(&sim);
            let d = sim.step(t_stop - sim.state.time).unwrap();
            rows.push(Row { d, vmean, com });
        }
        let p = &sim.particles;
        // Shock front: where the target's velocity, averaged over each lattice column,
        // crosses u_p/2 = 250 m/s, interpolated between the columns on either side (the
        // farthest particle above 250 m/s alone moves in steps of Δp, 1–3 % of U_s here).
        let dp = case.bodies[1].spacing;
        let mut columns = std::collections::BTreeMap::<i64, (f64, f64, f64)>::new();
        for i in (0..p.n_real).filter(|&i| p.body[i] == 1) {
            let c = columns.entry((p.x[i][0] / dp).round() as i64).or_default();
            *c = (c.0 + p.x[i][0], c.1 + p.v[i][0], c.2 + 1.0);
        }
        let profile: Vec<(f64, f64)> = columns.values().map(|c| (c.0 / c.2, c.1 / c.2)).collect();
        let k = profile
            .iter()
            .rposition(|c| c.1 > 250.0)
            .filter(|&k| k + 1 < profile.len())
            .expect("no shock front inside the target");
        let ((x0, v0), (x1, v1)) = (profile[k], profile[k + 1]);
        let front = x0 + (v0 - 250.0) / (v0 - v1) * (x1 - x0);
        fronts.push((sim.state.time, front));
        // Plateau: target particles from 0.5 mm behind the interface to 0.5 mm behind the front.
        for i in (0..p.n_real)
            .filter(|&i| p.body[i] == 1 && p.x[i][0] > 0.5e-3 && p.x[i][0] < front - 0.5e-3)
        {
            p_sum += p.p[i];
            u_sum += p.v[i][0];
            n_sum += 1.0;
        }
    }
    let us = (fronts[1].1 - fronts[0].1) / (fronts[1].0 - fronts[0].0);
    let contact: Vec<f64> = rows
        .iter()
        .filter(|r| r.d.time > 0.3e-6)
        .map(|r| -r.d.body_contact_force[0][0] / w)
        .collect();
    let p_int = if contact.iter().all(|&f| f == 0.0) {
        p_sum / n_sum
    } else {
        contact.iter().sum::<f64>() / contact.len() as f64
    };
    println!("planar {}, {}, Δp = {} m: interface/plateau pressure {p_int:.4e} Pa (target plateau {:.4e} Pa), u_p {:.2} m/s, U_s {us:.1} m/s", case.name, label(case), case.bodies[0].spacing, p_sum / n_sum, u_sum / n_sum);
    (p_int, u_sum / n_sum, us, rows)
}

#[test]
fn planar_impact_meets_rankine_hugoniot() {
    let (rho0, c0, s1, v) = (2785.0, 5328.0, 1.338, 1000.0);
    let up = v / 2.0;
    let us = c0 + s1 * up;
    let p = rho0 * us * up;
    for (name, case) in ["planar_impact_contact", "planar_impact_welded"]
        .iter()
        .flat_map(|&n| two_resolutions(n).into_iter().map(move |c| (n, c)))
    {
        let (p_m, u_m, us_m, rows) = planar_figures(&case);
        assert!(
            (p_m / p - 1.0).abs() < 0.05,
            "{name}: pressure {p_m:.4e} vs {p:.4e}"
        );
        assert!((u_m / up - 1.0).abs() < 0.05, "{name}: u_p {u_m} vs {up}");
        assert!((us_m / us - 1.0).abs() < 0.05, "{name}: U_s {us_m} vs {us}");
        assert!(momentum_dev(&rows) < 1e-10, "{name}: momentum");
        if name == "planar_impact_contact" {
            // Two bodies throughout: they meet only through the contact, never closer than
            // 0.5 Δp.
            assert!(min_gap(&rows) >= 0.5, "min gap {}", min_gap(&rows));
        }
    }
}
