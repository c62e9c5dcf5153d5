//! The contact's verification cases (VALIDATION.md §B–§D), each in both formulations (issue 12)
//! with the same tolerances: planar impact, bars at ±400 m/s, bars at ±10 m/s, a striker,
//! frictionless sliding, the incline, the rubber rings, Hertz's spheres, the 7 km/s planar
//! impact and the paper's demonstration at a coarse spacing; and its hypervelocity cousin, a
//! sphere cratering a thick block (issue 13).
//!
//! Coarse runs each deck's spacing; `fine` adds half of it (the README's two resolutions), and
//! where a case is held to converge, a check that the error did not grow. The verification
//! tests (`tests/verification_contact.rs`, `tests/contact_fidelity.rs`, `tests/sphere_plate.rs`)
//! call these functions.

use super::{
    converges, example, formulation_label, front, profile, variant, Check, Figure, Outcome,
};
use crate::case::{Case, ContactLaw, Formulation, InteractionKind, Shape};
use crate::error::{Error, Result};
use crate::simulation::{Diagnostics, Simulation};

const FORMULATIONS: [Formulation; 2] = [Formulation::Conventional, Formulation::Corrected];

/// One step: its diagnostics, and each body's mass-weighted mean velocity and centre of mass
/// after it.
pub struct Row {
    pub d: Diagnostics,
    pub v: Vec<[f64; 3]>,
    pub x: Vec<[f64; 3]>,
}

/// Each body's mass-weighted mean velocity and centre of mass.
pub fn body_means<const D: usize>(sim: &Simulation<D>) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let nb = sim.body_names.len();
    let p = &sim.particles;
    let (mut m, mut v, mut x) = (vec![0.0; nb], vec![[0.0; 3]; nb], vec![[0.0; 3]; nb]);
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

/// Steps `sim` to `until`, recording every step; `each` sees the simulation after each.
pub fn record<const D: usize>(
    sim: &mut Simulation<D>,
    until: f64,
    mut each: impl FnMut(&Simulation<D>),
) -> Result<Vec<Row>> {
    let mut rows = Vec::new();
    while sim.state.time < until * (1.0 - 1e-12) {
        let d = sim.step(until - sim.state.time)?;
        each(sim);
        let (v, x) = body_means(sim);
        rows.push(Row { d, v, x });
    }
    Ok(rows)
}

/// Runs a case to its end time.
fn run<const D: usize>(case: &Case) -> Result<Vec<Row>> {
    let mut sim = Simulation::<D>::new(case)?;
    record(&mut sim, case.simulation.end_time, |_| {})
}

/// The spacing factors of a case: the deck's, and half of it with `fine`.
fn factors(fine: bool) -> &'static [f64] {
    if fine {
        &[1.0, 0.5]
    } else {
        &[1.0]
    }
}

/// Every contact between bodies through the paper's form of eq. (5), exponent `n` (its
/// default if `None`).
pub fn paper_law(case: &mut Case, n: Option<f64>) {
    for i in &mut case.interactions {
        if let InteractionKind::Contact { .. } = i.kind {
            i.kind = InteractionKind::Contact {
                law: ContactLaw::Paper,
                stiffness: None,
                exponent: n,
            };
        }
    }
}

/// "conventional SPH, Δp = 0.1 mm" and the like.
fn setting(case: &Case, resolution: &str) -> String {
    format!(
        "{}, {resolution}",
        formulation_label(case.simulation.formulation)
    )
}

fn spacing_mm(case: &Case) -> String {
    format!("Δp = {} mm", case.bodies[0].spacing * 1e3)
}

/// Largest |E − E0| over the run, over `scale`.
fn energy_dev(rows: &[Row], scale: f64) -> f64 {
    let e0 = rows[0].d.total;
    rows.iter()
        .map(|r| (r.d.total - e0).abs())
        .fold(0.0, f64::max)
        / scale
}

/// The largest energy in play over the run: kinetic + |internal| + contact potential.
fn energy_in_play(rows: &[Row]) -> f64 {
    rows.iter()
        .map(|r| r.d.kinetic + r.d.internal.abs() + r.d.contact)
        .fold(0.0, f64::max)
}

/// Largest |p − p0| along any axis over the run, over Σ m|v|.
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

/// Smallest distance between particles of different bodies over the run (Δp); infinite if
/// they never came within reach.
fn closest(rows: &[Row]) -> f64 {
    rows.iter()
        .filter_map(|r| r.d.min_interbody_distance)
        .fold(f64::INFINITY, f64::min)
}

/// Deepest penetration past the other body's surface layer (Δp) and most particles mixed.
fn mixing(rows: &[Row]) -> (f64, u64) {
    rows.iter()
        .flat_map(|r| r.d.mixing.iter())
        .fold((0.0, 0), |(p, m), x| (p.max(x.penetration), m.max(x.mixed)))
}

/// The checks every contact run shares: momentum to round-off (where no external force acts
/// along the motion) and no two bodies' particles closer than half a spacing.
fn contact_checks(checks: &mut Vec<Check>, rows: &[Row], setting: &str, momentum: bool) {
    if momentum {
        checks.push(momentum_check(rows, setting));
    }
    checks.push(closest_check(rows, setting));
}

const OF_KINETIC: &str = "of the initial kinetic energy";
const IN_PLAY: &str = "of the largest kinetic + internal + contact energy";

/// The energy error at most `limit`, relative to what `source` says.
fn energy_check(setting: &str, error: f64, limit: f64, source: &'static str) -> Check {
    Check::new("energy error", setting, error, "", source).at_most(limit)
}

/// Momentum to 1e-10 of Σ m|v| along every axis.
fn momentum_check(rows: &[Row], setting: &str) -> Check {
    Check::new(
        "momentum error",
        setting,
        momentum_dev(rows),
        "",
        "no external force along the motion",
    )
    .at_most(1e-10)
}

/// Momentum along z to 1e-10 of its initial value: the impact's axis, along which a quarter
/// model's symmetry planes exert no force.
fn z_momentum_check(rows: &[Row], setting: &str) -> Check {
    let pz0 = rows[0].d.momentum[2];
    let pz = rows
        .iter()
        .map(|r| (r.d.momentum[2] - pz0).abs())
        .fold(0.0, f64::max)
        / pz0.abs();
    Check::new(
        "z momentum error",
        setting,
        pz,
        "",
        "no external force along z",
    )
    .at_most(1e-10)
}

/// No particle past the other body's surface layer by more than `depth` (Δp), and at most
/// `count` particles past it.
fn mixing_checks(
    checks: &mut Vec<Check>,
    rows: &[Row],
    setting: &str,
    (depth, count): (f64, f64),
    source: &'static str,
) {
    let (pen, mixed) = mixing(rows);
    checks.push(
        Check::new(
            "deepest penetration past the other's surface",
            setting,
            pen,
            "Δp",
            source,
        )
        .at_most(depth),
    );
    checks.push(Check::new("particles mixed", setting, mixed as f64, "", source).at_most(count));
}

/// No two bodies' particles closer than half a spacing over the run.
fn closest_check(rows: &[Row], setting: &str) -> Check {
    Check::new(
        "closest approach of the bodies",
        setting,
        closest(rows),
        "Δp",
        "the contact keeps the bodies' particles apart (VALIDATION.md §B)",
    )
    .at_least(0.5)
}

/// The longitudinal (uniaxial-strain) wave speed of the bars' elastic aluminium, √((K + 4G/3)/ρ).
fn bar_wave_speed(case: &Case) -> f64 {
    let m = &case.materials[case.bodies[0].material];
    ((m.eos.bulk_modulus(m.density) + 4.0 / 3.0 * m.strength.shear_modulus()) / m.density).sqrt()
}

/// Length along x and width along y of a rectangular body.
fn box_size(case: &Case, body: usize) -> Result<(f64, f64)> {
    match case.bodies[body].shape {
        Shape::Box { min, max } => Ok((max[0] - min[0], max[1] - min[1])),
        _ => Err(Error::Invalid(format!(
            "{}: body {body} is not a rectangle",
            case.name
        ))),
    }
}

/// A history figure: series against time (µs), one panel.
fn history(name: String, t: &[f64], label: &str, series: Vec<(String, Vec<f64>)>) -> Figure {
    Figure {
        name,
        x_label: "time (µs)".into(),
        x: t.iter().map(|t| t * 1e6).collect(),
        panels: vec![(label.into(), series)],
    }
}

fn tag(f: Formulation) -> &'static str {
    match f {
        Formulation::Conventional => "conventional",
        Formulation::Corrected => "cn",
    }
}

// ---------------------------------------------------------------------------------------------
// Planar impact at 1 km/s

/// The Rankine–Hugoniot state of Al 2024-T4 (ρ0 2785, U_s = 5328 + 1.338 u_p) struck by
/// itself at `v`: (u_p, U_s, p, ρ/ρ0).
fn hugoniot(v: f64) -> (f64, f64, f64, f64) {
    let (rho0, c0, s1) = (2785.0, 5328.0, 1.338);
    let up = v / 2.0;
    let us = c0 + s1 * up;
    (up, us, rho0 * us * up, us / (us - up))
}

const HUGONIOT: &str = "Rankine–Hugoniot, U_s = 5328 + 1.338 u_p (Al 2024-T4, Steinberg 1996)";

/// A 1 km/s planar impact (`examples/planar_impact_{contact,welded}.toml`): the interface
/// pressure (the contact force over the width; welded, the target's mean pressure behind the
/// shock), the particle velocity and the shock speed within 5 % of the Rankine–Hugoniot state;
/// momentum to 1e-10; the contact's bodies never closer than Δp/2. Figures: the target's
/// pressure at 1.2 µs against the Hugoniot's.
pub fn planar_impact(fine: bool) -> Result<Outcome> {
    let (up, us, p, _) = hugoniot(1000.0);
    let mut checks = Vec::new();
    let mut figures = Vec::new();
    for name in ["planar_impact_contact", "planar_impact_welded"] {
        let base = example(name)?;
        let contact = name.ends_with("contact");
        for f in FORMULATIONS {
            let mut last = None;
            for &k in factors(fine) {
                let case = variant(&base, k, f);
                let run = planar_run(&case)?;
                let s = format!(
                    "{}, {}",
                    if contact { "contact" } else { "welded" },
                    setting(&case, &spacing_mm(&case))
                );
                let what = if contact {
                    "interface pressure"
                } else {
                    "pressure behind the shock"
                };
                checks.push(Check::new(what, &s, run.pressure, "Pa", HUGONIOT).within(p, 0.05));
                checks.push(
                    Check::new("particle velocity", &s, run.up, "m/s", HUGONIOT).within(up, 0.05),
                );
                checks
                    .push(Check::new("shock speed", &s, run.us, "m/s", HUGONIOT).within(us, 0.05));
                let rows = &run.rows;
                if contact {
                    contact_checks(&mut checks, rows, &s, true);
                } else {
                    checks.push(momentum_check(rows, &s));
                }
                last = Some(run.profile);
            }
            if let Some((x, pr)) = last {
                let mut figure = pressure_figure(f, &x, &pr, p, "1.2 µs");
                figure.name = format!(
                    "pressure_{}_{}",
                    if contact { "contact" } else { "welded" },
                    tag(f)
                );
                figures.push(figure);
            }
        }
    }
    Ok(Outcome { checks, figures })
}

/// The target's pressure along x (m) at `when` against the Hugoniot's `p_h`: `pressure_<tag>`.
fn pressure_figure(f: Formulation, x: &[f64], pressure: &[f64], p_h: f64, when: &str) -> Figure {
    Figure {
        name: format!("pressure_{}", tag(f)),
        x_label: "x (mm)".into(),
        x: x.iter().map(|x| x * 1e3).collect(),
        panels: vec![(
            format!("target pressure at {when} (GPa)"),
            vec![
                (
                    format!("strike, {}", formulation_label(f)),
                    pressure.iter().map(|p| p * 1e-9).collect(),
                ),
                ("Hugoniot".into(), vec![p_h * 1e-9; x.len()]),
            ],
        )],
    }
}

struct PlanarRun {
    pressure: f64,
    up: f64,
    us: f64,
    rows: Vec<Row>,
    /// The target's pressure along x at the end.
    profile: (Vec<f64>, Vec<f64>),
}

/// Runs a planar impact to 0.6 and 1.2 µs: the shock front at each (where the target's
/// velocity, averaged over each lattice column, crosses u_p/2, interpolated between the columns
/// on either side: the farthest particle above it alone moves in steps of Δp), the plateau
/// (target particles from 0.5 mm behind the interface to 0.5 mm behind the front), and the
/// interface pressure from the contact force after 0.3 µs.
fn planar_run(case: &Case) -> Result<PlanarRun> {
    let (_, width) = box_size(case, 0)?;
    let half = 0.5 * case.bodies[0].velocity[0] / 2.0;
    let mut sim = Simulation::<2>::new(case)?;
    let mut rows = Vec::new();
    let mut fronts = Vec::new();
    let (mut p_sum, mut u_sum, mut n_sum) = (0.0, 0.0, 0.0);
    let dp = case.bodies[1].spacing;
    for t_stop in [0.6e-6, 1.2e-6] {
        rows.extend(record(&mut sim, t_stop, |_| {})?);
        let front = front(&sim, half, dp)?;
        fronts.push((sim.state.time, front));
        let p = &sim.particles;
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
        .map(|r| -r.d.body_contact_force[0][0] / width)
        .collect();
    let pressure = if contact.iter().all(|&f| f == 0.0) {
        p_sum / n_sum
    } else {
        contact.iter().sum::<f64>() / contact.len() as f64
    };
    let hi = fronts[1].1 + 1.0e-3;
    let p = &sim.particles;
    let profile = profile(&sim, (0.0, hi, 2.0 * dp), |i| p.p[i]);
    Ok(PlanarRun {
        pressure,
        up: u_sum / n_sum,
        us,
        rows,
        profile,
    })
}

// ---------------------------------------------------------------------------------------------
// Bars

/// What a head-on bars run shows, from body 0's contact force (x).
struct Pulse {
    /// First to last step with a non-zero force (s).
    duration: f64,
    /// Time of the first non-zero force.
    start: f64,
    /// Mean force over the middle half of the contact.
    plateau: f64,
    /// Largest x force on body 0 (> 0 pulls it toward body 1).
    tensile: f64,
    /// |force| at the last step.
    at_end: f64,
}

fn pulse(rows: &[Row]) -> Result<Pulse> {
    let f: Vec<f64> = rows.iter().map(|r| r.d.body_contact_force[0][0]).collect();
    let first = f
        .iter()
        .position(|&x| x != 0.0)
        .ok_or_else(|| Error::Invalid("the bodies never touch".into()))?;
    let last = f.iter().rposition(|&x| x != 0.0).unwrap_or(first);
    let t0 = rows[first].d.time;
    let t1 = rows[(last + 1).min(rows.len() - 1)].d.time;
    let duration = t1 - t0;
    let (a, b) = (t0 + 0.25 * duration, t0 + 0.75 * duration);
    let plat: Vec<f64> = rows
        .iter()
        .filter(|r| r.d.time >= a && r.d.time <= b)
        .map(|r| -r.d.body_contact_force[0][0])
        .collect();
    Ok(Pulse {
        duration,
        start: t0,
        plateau: plat.iter().sum::<f64>() / plat.len().max(1) as f64,
        tensile: f.iter().copied().fold(0.0, f64::max),
        at_end: f[f.len() - 1].abs(),
    })
}

/// The checks of a contact pulse that must end: exactly zero at the end, never tensile.
fn release_checks(
    checks: &mut Vec<Check>,
    (tensile, at_end): (f64, f64),
    unit: &'static str,
    s: &str,
) {
    checks.push(
        Check::new(
            "contact force at the end",
            s,
            at_end,
            unit,
            "the bodies have parted",
        )
        .at_most(0.0),
    );
    checks.push(
        Check::new(
            "most tensile contact force",
            s,
            tensile,
            unit,
            "a contact only pushes (VALIDATION.md §B)",
        )
        .at_most(0.0),
    );
}

/// The interface stress on body 0 (its x contact force over the `width`) against the ideal
/// rectangular pulse (start, duration, ρcv), in the unit (scale, name) given.
fn stress_figure(
    f: Formulation,
    rows: &[Row],
    width: f64,
    (t0, duration, sigma): (f64, f64, f64),
    (scale, unit): (f64, &str),
) -> Figure {
    let t: Vec<f64> = rows.iter().map(|r| r.d.time).collect();
    let ideal = t
        .iter()
        .map(|&t| {
            if t >= t0 && t < t0 + duration {
                sigma * scale
            } else {
                0.0
            }
        })
        .collect();
    history(
        format!("stress_{}", tag(f)),
        &t,
        &format!("interface stress ({unit})"),
        vec![
            (
                format!("strike, {}", formulation_label(f)),
                rows.iter()
                    .map(|r| -r.d.body_contact_force[0][0] / width * scale)
                    .collect(),
            ),
            ("ρ c v for 2L/c".into(), ideal),
        ],
    )
}

/// Makes each bar `length` long (the left one ending, the right one starting, where the deck
/// has them), scales the end time with it, and sets the speeds to ±`v`.
fn bars_at(case: &mut Case, length: f64, v: f64) -> Result<()> {
    let (old, _) = box_size(case, 0)?;
    if let Shape::Box { min, .. } = &mut case.bodies[0].shape {
        min[0] += old - length;
    }
    if let Shape::Box { max, .. } = &mut case.bodies[1].shape {
        max[0] += length - old;
    }
    case.simulation.end_time *= length / old;
    case.bodies[0].velocity[0] = v;
    case.bodies[1].velocity[0] = -v;
    Ok(())
}

/// Bars at ±400 m/s, L = 100 mm (`examples/bars_contact.toml` lengthened), L/Δp = 200 (and
/// 400): the contact lasts 2L/c within 5 %, carries ρcv within 10 %, and the bars leave at
/// ∓v within 5 %; the force is never tensile and zero at the end; energy within 1 % of the
/// kinetic, momentum to 1e-10.
///
/// At 400 m/s the strain is 6.3 %, where the linear EOS and Jaumann-rate elasticity stiffen
/// (σ(ε) = K(1/(1−ε) − 1) + (4G/3) ln(1/(1−ε))): the front is a shock at 6318 m/s carrying
/// 6.82 GPa, the release comes back at 6494 m/s, so the finite-strain contact time is
/// 31.2–31.6 µs rather than the acoustic 32.53 µs (the slow bars hold the acoustic figures
/// exactly). The welded twin at ±10 m/s is still joined at 1.8 × 2L/c, the left bar pulled
/// back by the tension across the weld.
pub fn bars(fine: bool) -> Result<Outcome> {
    let (v, length) = (400.0, 0.1);
    let mut checks = Vec::new();
    let mut figures = Vec::new();
    let mut base = example("bars_contact")?;
    bars_at(&mut base, length, v)?;
    let c = bar_wave_speed(&base);
    let rho = base.materials[base.bodies[0].material].density;
    let (_, width) = box_size(&base, 0)?;
    let source = "acoustic: 2L/c, ρ c v (VALIDATION.md §B)";
    for f in FORMULATIONS {
        let mut last = None;
        for &k in factors(fine) {
            let case = variant(&base, k, f);
            let rows = run::<2>(&case)?;
            let pl = pulse(&rows)?;
            let s = setting(
                &case,
                &format!("L/Δp = {:.0}", length / case.bodies[0].spacing),
            );
            checks.push(
                Check::new("contact time", &s, pl.duration, "s", source)
                    .within(2.0 * length / c, 0.05),
            );
            checks.push(
                Check::new("interface stress", &s, pl.plateau / width, "Pa", source)
                    .within(rho * c * v, 0.10),
            );
            let end = rows[rows.len() - 1].v.clone();
            let momentum = "momentum exchange of equal bars: they swap velocities";
            checks.push(
                Check::new("left bar's speed after", &s, end[0][0], "m/s", momentum)
                    .within(-v, 0.05),
            );
            checks.push(
                Check::new("right bar's speed after", &s, end[1][0], "m/s", momentum)
                    .within(v, 0.05),
            );
            release_checks(&mut checks, (pl.tensile, pl.at_end), "N/m", &s);
            checks.push(energy_check(
                &s,
                energy_dev(&rows, rows[0].d.kinetic),
                0.01,
                OF_KINETIC,
            ));
            contact_checks(&mut checks, &rows, &s, true);
            last = Some((rows, pl.start));
        }
        if let Some((rows, t0)) = last {
            let pulse = (t0, 2.0 * length / c, rho * c * v);
            figures.push(stress_figure(f, &rows, width, pulse, (1e-9, "GPa")));
        }
    }
    for f in FORMULATIONS {
        let mut case = example("bars_welded")?;
        case.simulation.formulation = f;
        let rows = run::<2>(&case)?;
        let s = setting(
            &case,
            &format!("welded, ±{} m/s", case.bodies[0].velocity[0]),
        );
        let end = &rows[rows.len() - 1];
        let source = "the weld holds: tension pulls the bars back together";
        checks.push(
            Check::new(
                "left bar's velocity at 1.8 × 2L/c",
                &s,
                end.v[0][0],
                "m/s",
                source,
            )
            .at_least(0.0),
        );
        checks.push(
            Check::new(
                "right bar's velocity at 1.8 × 2L/c",
                &s,
                end.v[1][0],
                "m/s",
                source,
            )
            .at_most(0.0),
        );
        checks.push(momentum_check(&rows, &s));
        let contact = rows
            .iter()
            .flat_map(|r| r.d.body_contact_force.iter())
            .map(|f| f[0].abs().max(f[1].abs()).max(f[2].abs()))
            .fold(0.0, f64::max);
        checks.push(
            Check::new(
                "contact force between welded bodies",
                &s,
                contact,
                "N/m",
                "welded bodies are one body",
            )
            .at_most(0.0),
        );
    }
    Ok(Outcome { checks, figures })
}

/// The contact pulse on body 0 at half its plateau (the ideal pulse is a rectangle, so this is
/// its length; the plateau is the median force over the steps in contact, not the peak, which
/// the first instants of the impact raise to about 1.6 times the plateau): (duration, first
/// time above half, plateau, most tensile x force on body 0, |force| at the end).
fn half_pulse(rows: &[Row]) -> Result<(f64, f64, f64, f64, f64)> {
    let mut forces: Vec<f64> = rows
        .iter()
        .map(|r| r.d.body_contact_force[0][0].abs())
        .filter(|&f| f > 0.0)
        .collect();
    if forces.is_empty() {
        return Err(Error::Invalid("the bodies never touch".into()));
    }
    forces.sort_by(f64::total_cmp);
    let plateau = forces[forces.len() / 2];
    let on: Vec<f64> = rows
        .iter()
        .filter(|r| r.d.body_contact_force[0][0].abs() > 0.5 * plateau)
        .map(|r| r.d.time)
        .collect();
    let tensile = rows
        .iter()
        .map(|r| r.d.body_contact_force[0][0])
        .fold(f64::NEG_INFINITY, f64::max);
    let at_end = rows[rows.len() - 1].d.body_contact_force[0][0].abs();
    Ok((on[on.len() - 1] - on[0], on[0], plateau, tensile, at_end))
}

/// Bars at ±10 m/s (`examples/bars_contact.toml`, to 40 µs), L/Δp = 100 (and 200): they part
/// at ∓10 m/s within 5 %, the pulse lasts 2L/c within 5 % at half its plateau, is never
/// tensile and exactly zero once they part; energy within 1 %, in both formulations, and the
/// speed's error held to shrink with refinement. Until the viscosity's limiter and the mid-step
/// material update (2026-11-28), CN-SPH's bars parted 5.3 % slow at L/Δp = 100 (∓9.47 m/s)
/// and were held only from L/Δp = 200.
pub fn slow_bars(fine: bool) -> Result<Outcome> {
    let mut base = example("bars_contact")?;
    base.simulation.end_time = 40.0e-6;
    let (length, width) = box_size(&base, 0)?;
    let v = base.bodies[0].velocity[0];
    let c = bar_wave_speed(&base);
    let rho = base.materials[base.bodies[0].material].density;
    let two_l_c = 2.0 * length / c;
    let mut checks = Vec::new();
    let mut figures = Vec::new();
    for f in FORMULATIONS {
        let mut previous: Option<f64> = None;
        let mut last = None;
        for &k in factors(fine) {
            let case = variant(&base, k, f);
            let rows = run::<2>(&case)?;
            let per = length / case.bodies[0].spacing;
            let s = setting(&case, &format!("L/Δp = {per:.0}"));
            let source = "momentum exchange of equal bars: they swap velocities";
            let end = rows[rows.len() - 1].v.clone();
            for (what, got, want) in [
                ("left bar's speed after", end[0][0], -v),
                ("right bar's speed after", end[1][0], v),
            ] {
                checks.push(Check::new(what, &s, got, "m/s", source).within(want, 0.05));
            }
            let error = (end[1][0] / v - 1.0).abs();
            converges(
                &mut checks,
                &mut previous,
                error,
                "speed error, finer against coarser",
                &s,
            );
            let (span, start, _, tensile, at_end) = half_pulse(&rows)?;
            checks.push(
                Check::new("contact time at half the plateau", &s, span, "s", "2L/c")
                    .within(two_l_c, 0.05),
            );
            release_checks(&mut checks, (tensile, at_end), "N/m", &s);
            checks.push(energy_check(
                &s,
                energy_dev(&rows, energy_in_play(&rows)),
                0.01,
                IN_PLAY,
            ));
            last = Some((rows, start));
        }
        if let Some((rows, t0)) = last {
            let pulse = (t0, two_l_c, rho * c * v);
            figures.push(stress_figure(f, &rows, width, pulse, (1e-6, "MPa")));
        }
    }
    Ok(Outcome { checks, figures })
}

/// A striker half the bar's length (`examples/striker.toml`, 10 m/s), Δp = 0.5 (and 0.25) mm:
/// the striker ends at rest within 2 % of its speed, the bar carries the momentum at v0/2
/// within 2 %, the contact lasts 2 L1/c within 5 % at half its plateau, never tensile, zero at
/// the end. Figure: the bodies' mean velocities.
pub fn striker(fine: bool) -> Result<Outcome> {
    let base = example("striker")?;
    let (l1, _) = box_size(&base, 0)?;
    let v0 = base.bodies[0].velocity[0];
    let c = bar_wave_speed(&base);
    let mut checks = Vec::new();
    let mut figures = Vec::new();
    for f in FORMULATIONS {
        let mut last = None;
        for &k in factors(fine) {
            let case = variant(&base, k, f);
            let rows = run::<2>(&case)?;
            let s = setting(&case, &spacing_mm(&case));
            let end = rows[rows.len() - 1].v.clone();
            let source = "a striker on a bar twice its length stops dead (elastic waves)";
            checks.push(
                Check::new(
                    "striker's velocity after / v0",
                    &s,
                    end[0][0].abs() / v0,
                    "",
                    source,
                )
                .at_most(0.02),
            );
            checks.push(
                Check::new(
                    "bar's velocity after",
                    &s,
                    end[1][0],
                    "m/s",
                    "v0/2 (momentum)",
                )
                .within(0.5 * v0, 0.02),
            );
            let (span, _, _, tensile, at_end) = half_pulse(&rows)?;
            checks.push(
                Check::new("contact time at half the plateau", &s, span, "s", "2 L1/c")
                    .within(2.0 * l1 / c, 0.05),
            );
            release_checks(&mut checks, (tensile, at_end), "N/m", &s);
            last = Some(rows);
        }
        if let Some(rows) = last {
            let t: Vec<f64> = rows.iter().map(|r| r.d.time).collect();
            figures.push(history(
                format!("velocity_{}", tag(f)),
                &t,
                "mean velocity (m/s)",
                vec![
                    (
                        format!("striker, {}", formulation_label(f)),
                        rows.iter().map(|r| r.v[0][0]).collect(),
                    ),
                    (
                        format!("bar, {}", formulation_label(f)),
                        rows.iter().map(|r| r.v[1][0]).collect(),
                    ),
                    ("v0/2".into(), vec![0.5 * v0; t.len()]),
                ],
            ));
        }
    }
    Ok(Outcome { checks, figures })
}

// ---------------------------------------------------------------------------------------------
// Sliding and the incline

/// (slider's largest |Δv_x/v0|, base's largest x momentum over the slider's initial, share of
/// steps in contact).
fn sliding_figures(rows: &[Row], case: &Case) -> Result<(f64, f64, f64)> {
    let v0 = case.bodies[0].velocity[0];
    let area = |b| box_size(case, b).map(|(l, w)| l * w);
    let mass_ratio = area(1)? / area(0)?;
    let slider = rows
        .iter()
        .map(|r| (r.v[0][0] / v0 - 1.0).abs())
        .fold(0.0, f64::max);
    let base = rows
        .iter()
        .map(|r| (r.v[1][0] * mass_ratio / v0).abs())
        .fold(0.0, f64::max);
    let touching = rows
        .iter()
        .filter(|r| r.d.min_interbody_distance.is_some())
        .count() as f64
        / rows.len() as f64;
    Ok((slider, base, touching))
}

/// The slider's largest relative change of tangential velocity, to be bounded.
fn slider_change(setting: &str, change: f64, source: &'static str) -> Check {
    Check::new(
        "slider's tangential velocity change",
        setting,
        change,
        "",
        source,
    )
}

/// The slider stays on the base: in contact at 99 % of the steps or more.
fn in_contact(setting: &str, share: f64) -> Check {
    Check::new(
        "share of steps in contact",
        setting,
        share,
        "",
        "the slider rests on the base",
    )
    .at_least(0.99)
}

/// Frictionless sliding (`examples/sliding_{contact,welded}.toml`, soft blocks, Δp = 0.05 and
/// 0.025 m): through the contact the slider keeps its tangential velocity within 1 % and the
/// base takes under 1 % of its momentum, x momentum to 1e-10 (gravity and the symmetry plane
/// act along y), in contact throughout; welded, the blocks exchange over 10 %. The paper's form
/// of eq. (5) with n = 4 and 6: in CN-SPH it acts along the contact normal and the slider
/// keeps 99 % of its velocity (issue 12); in conventional SPH (reported, not held) the other
/// body's lattice corrugation acts as friction.
pub fn sliding(fine: bool) -> Result<Outcome> {
    let base = example("sliding_contact")?;
    let welded = example("sliding_welded")?;
    let mut checks = Vec::new();
    let mut figures = Vec::new();
    let frictionless = "frictionless contact: no tangential force (VALIDATION.md §B)";
    for f in FORMULATIONS {
        let mut last = None;
        for &k in factors(fine) {
            let case = variant(&base, k, f);
            let rows = run::<2>(&case)?;
            let (slider, moved, touching) = sliding_figures(&rows, &case)?;
            let s = setting(&case, &format!("Δp = {} m", case.bodies[0].spacing));
            checks.push(slider_change(&s, slider, frictionless).at_most(0.01));
            checks.push(
                Check::new(
                    "base's tangential momentum / slider's",
                    &s,
                    moved,
                    "",
                    frictionless,
                )
                .at_most(0.01),
            );
            checks.push(in_contact(&s, touching));
            let p0 = rows[0].d.momentum[0];
            let px = rows
                .iter()
                .map(|r| (r.d.momentum[0] - p0).abs())
                .fold(0.0, f64::max)
                / rows[0].d.momentum_scale;
            checks.push(
                Check::new("x momentum error", &s, px, "", "no external force along x")
                    .at_most(1e-10),
            );
            checks.push(closest_check(&rows, &s));
            last = Some(rows);
        }
        for &k in factors(fine) {
            let case = variant(&welded, k, f);
            let rows = run::<2>(&case)?;
            let (slider, _, _) = sliding_figures(&rows, &case)?;
            let s = setting(&case, &format!("welded, Δp = {} m", case.bodies[0].spacing));
            checks.push(slider_change(&s, slider, "a weld transmits shear").at_least(0.10));
        }
        for n in [4.0, 6.0] {
            let ks: &[f64] = match f {
                Formulation::Corrected => factors(fine),
                Formulation::Conventional => &[1.0],
            };
            for &k in ks {
                let mut case = variant(&base, k, f);
                paper_law(&mut case, Some(n));
                let rows = run::<2>(&case)?;
                let (slider, _, touching) = sliding_figures(&rows, &case)?;
                let s = setting(
                    &case,
                    &format!(
                        "eq. (5) as printed, n = {n}, Δp = {} m",
                        case.bodies[0].spacing
                    ),
                );
                let source = "frictionless: the slider keeps its velocity (issue 12: 99 %)";
                checks.push(match f {
                    Formulation::Corrected => slider_change(&s, slider, source).at_most(0.01),
                    // The corrugation's friction: shown, not held.
                    Formulation::Conventional => Check::new(
                        "slider's velocity kept at the end",
                        &s,
                        rows[rows.len() - 1].v[0][0] / case.bodies[0].velocity[0],
                        "",
                        source,
                    )
                    .reported(1.0),
                });
                checks.push(in_contact(&s, touching));
            }
        }
        if let Some(rows) = last {
            let t: Vec<f64> = rows.iter().map(|r| r.d.time).collect();
            let v0 = base.bodies[0].velocity[0];
            figures.push(Figure {
                name: format!("slider_{}", tag(f)),
                x_label: "time (s)".into(),
                x: t.clone(),
                panels: vec![(
                    "slider's mean x velocity (m/s)".into(),
                    vec![
                        (
                            format!("strike, {}", formulation_label(f)),
                            rows.iter().map(|r| r.v[0][0]).collect(),
                        ),
                        ("v0".into(), vec![v0; t.len()]),
                    ],
                )],
            });
        }
    }
    Ok(Outcome { checks, figures })
}

/// A block sliding down a frictionless 30° incline (`examples/incline.toml`, gravity turned
/// into the incline's frame, the incline fixed), Δp = 0.05 (and 0.025) m: the distance slid
/// follows ½ g_x t² within 5 % from 0.3 s (before, the block settles onto the incline), its
/// particles never closer than Δp/2 to the incline's.
pub fn incline(fine: bool) -> Result<Outcome> {
    let base = example("incline")?;
    let g = base.simulation.gravity[0];
    let mut checks = Vec::new();
    let mut figures = Vec::new();
    let source = "½ g sin θ t², frictionless";
    for f in FORMULATIONS {
        let mut last = None;
        for &k in factors(fine) {
            let case = variant(&base, k, f);
            let rows = run::<2>(&case)?;
            let s = setting(&case, &format!("Δp = {} m", case.bodies[0].spacing));
            let x0 = rows[0].x[0][0];
            let worst = rows
                .iter()
                .filter(|r| r.d.time >= 0.3)
                .map(|r| ((r.x[0][0] - x0) / (0.5 * g * r.d.time * r.d.time) - 1.0).abs())
                .fold(0.0, f64::max);
            let end = &rows[rows.len() - 1];
            checks.push(
                Check::new(
                    "distance slid at the end",
                    &s,
                    end.x[0][0] - x0,
                    "m",
                    source,
                )
                .within(0.5 * g * end.d.time * end.d.time, 0.05),
            );
            checks.push(
                Check::new("largest relative error from 0.3 s", &s, worst, "", source)
                    .at_most(0.05),
            );
            checks.push(closest_check(&rows, &s));
            last = Some(rows);
        }
        if let Some(rows) = last {
            let t: Vec<f64> = rows.iter().map(|r| r.d.time).collect();
            let x0 = rows[0].x[0][0];
            figures.push(Figure {
                name: format!("distance_{}", tag(f)),
                x_label: "time (s)".into(),
                x: t.clone(),
                panels: vec![(
                    "distance slid (m)".into(),
                    vec![
                        (
                            format!("strike, {}", formulation_label(f)),
                            rows.iter().map(|r| r.x[0][0] - x0).collect(),
                        ),
                        (
                            "½ g sin θ t²".into(),
                            t.iter().map(|t| 0.5 * g * t * t).collect(),
                        ),
                    ],
                )],
            });
        }
    }
    Ok(Outcome { checks, figures })
}

// ---------------------------------------------------------------------------------------------
// Rubber rings

/// Particles with a particle of their own body closer than `r`.
fn within_own_body<const D: usize>(sim: &Simulation<D>, r: f64) -> usize {
    let p = &sim.particles;
    (0..p.n_real)
        .filter(|&i| {
            (0..p.n_real).any(|j| j != i && p.body[j] == p.body[i] && (p.x[i] - p.x[j]).norm() < r)
        })
        .count()
}

/// Particles of the simulation, how many pair up (a particle of their own body closer than
/// Δp/2: the tensile instability; the rings' conformed surface starts with 64) and how many
/// are isolated (none of their own body within 1.5 Δp: fracture).
pub fn pairing<const D: usize>(sim: &Simulation<D>, dp: f64) -> (usize, usize) {
    let paired = within_own_body(sim, 0.5 * dp);
    let isolated = sim.particles.n_real - within_own_body(sim, 1.5 * dp);
    (paired, isolated)
}

/// Gray, Monaghan & Swift's (2001) rubber rings at ±50.3 m/s (`examples/rubber_rings.toml`,
/// artificial stress ε = 0.3), Δp = 1 mm, to 3 ms (CN-SPH's rings touch to 2.33 ms): they meet,
/// part and move apart; no particle isolated (fracture), none paired beyond the 64 the
/// conformed surface starts with (tensile instability); energy within 2 % of the kinetic,
/// momentum to 1e-10, the bodies never closer than Δp/2. One resolution at either setting: at
/// 0.5 mm the rings, whose rebound depends more on their own artificial-stress dynamics than
/// on the contact, are still touching at 2 ms (README).
pub fn rubber_rings(_fine: bool) -> Result<Outcome> {
    let mut base = example("rubber_rings")?;
    base.simulation.end_time = 3.0e-3;
    let mut checks = Vec::new();
    for f in FORMULATIONS {
        let case = variant(&base, 1.0, f);
        let mut sim = Simulation::<2>::new(&case)?;
        let rows = record(&mut sim, case.simulation.end_time, |_| {})?;
        let s = setting(&case, &spacing_mm(&case));
        let end = &rows[rows.len() - 1];
        let at_end = end.d.body_contact_force[0]
            .iter()
            .fold(0.0_f64, |m, x| m.max(x.abs()));
        let source = "elastic rings rebound (Gray et al. 2001)";
        checks.push(Check::new("contact force at the end", &s, at_end, "N/m", source).at_most(0.0));
        checks.push(
            Check::new(
                "left ring's velocity at the end",
                &s,
                end.v[0][0],
                "m/s",
                source,
            )
            .at_most(0.0),
        );
        checks.push(
            Check::new(
                "right ring's velocity at the end",
                &s,
                end.v[1][0],
                "m/s",
                source,
            )
            .at_least(0.0),
        );
        let (paired, isolated) = pairing(&sim, case.bodies[0].spacing);
        checks.push(
            Check::new(
                "isolated particles (fracture)",
                &s,
                isolated as f64,
                "",
                "the rings stay whole",
            )
            .at_most(0.0),
        );
        checks.push(
            Check::new(
                "particles paired closer than Δp/2",
                &s,
                paired as f64,
                "",
                "no tensile instability: at most the 64 of the conformed surface at t = 0",
            )
            .at_most(64.0),
        );
        checks.push(energy_check(
            &s,
            energy_dev(&rows, rows[0].d.kinetic),
            0.02,
            OF_KINETIC,
        ));
        contact_checks(&mut checks, &rows, &s, true);
    }
    Ok(Outcome {
        checks,
        figures: Vec::new(),
    })
}

// ---------------------------------------------------------------------------------------------
// Hertz

/// Hertz's impact of two equal elastic spheres: the force against time from contact,
/// m* δ'' = −(4/3) E* √R* δ^{3/2}, δ'(0) = v (RK4, 4000 steps over the contact).
fn hertz_force(m: f64, es: f64, rs: f64, v: f64, t_c: f64) -> Vec<(f64, f64)> {
    let k = 4.0 / 3.0 * es * rs.sqrt();
    let acc = |d: f64| -k * d.max(0.0).powf(1.5) / m;
    let n = 4000;
    let h = 1.1 * t_c / n as f64;
    let (mut d, mut u) = (0.0, v);
    let mut out = vec![(0.0, 0.0)];
    for s in 1..=n {
        let (k1d, k1u) = (u, acc(d));
        let (k2d, k2u) = (u + 0.5 * h * k1u, acc(d + 0.5 * h * k1d));
        let (k3d, k3u) = (u + 0.5 * h * k2u, acc(d + 0.5 * h * k2d));
        let (k4d, k4u) = (u + h * k3u, acc(d + h * k3d));
        d += h / 6.0 * (k1d + 2.0 * k2d + 2.0 * k3d + k4d);
        u += h / 6.0 * (k1u + 2.0 * k2u + 2.0 * k3u + k4u);
        out.push((s as f64 * h, k * d.max(0.0).powf(1.5)));
    }
    out
}

/// Two equal elastic aluminium spheres at ±50 m/s (`examples/hertz_spheres.toml`, quarter
/// model), R/Δp = 16 and 20 (`fine`: 20 and 30): the peak force and the contact time within
/// 10 % of Hertz's, the error not growing with refinement; the force released and never
/// tensile; restitution above 0.95; no mixing; energy within 1 %. Conventional SPH's total
/// (contact potential Φ included) is held throughout; CN-SPH's contact exchanges with the
/// motion only the normal part of Φ's gradient, so during the contact its total counts the
/// rest of Φ too (+2 % at the deepest compression at R/Δp = 20), and what is held is the drift
/// once the spheres part (Φ = 0).
/// Each run ends at 1.12 t_c of Hertz (the deck's end time at most): a contact within the 10 %
/// tolerance has ended by then, and the spheres have flown apart for a sixth of it (about
/// 4 µs) to show that it stays released. Figure: the force against Hertz's.
///
/// Below R/Δp = 16 the contact is barely resolved: Hertz's contact radius is 2.0 mm and the
/// approach 0.82 mm, so at R/Δp = 12 the patch is 2.4 spacings in radius and the approach one
/// spacing. The error is not monotone there: 7.3 % at 12 against 9.0 % at 14 (CN-SPH 6.4 /
/// 7.6 %); from 14 on it shrinks, 9.0 / 8.6 / 7.3 / 4.8 % at 14 / 16 / 20 / 30 (CN-SPH 7.6 /
/// 7.4 / 6.6 / 5.3 %; measured 2026-12-01). Why 12 reads better is not known.
pub fn hertz(fine: bool) -> Result<Outcome> {
    let base = example("hertz_spheres")?;
    let (r, dp0) = match base.bodies[0].shape {
        Shape::Sphere { radius, .. } => (radius, base.bodies[0].spacing),
        _ => {
            return Err(Error::Invalid(
                "the Hertz deck's bodies are not spheres".into(),
            ))
        }
    };
    let m = &base.materials[base.bodies[0].material];
    let (k, g, rho) = (
        m.eos.bulk_modulus(m.density),
        m.strength.shear_modulus(),
        m.density,
    );
    let e = 9.0 * k * g / (3.0 * k + g);
    let nu = (3.0 * k - 2.0 * g) / (2.0 * (3.0 * k + g));
    // The approach speed: body 0 below moves up, body 1 above moves down.
    let v = base.bodies[0].velocity[2] - base.bodies[1].velocity[2];
    let es = e / (2.0 * (1.0 - nu * nu));
    let rs = r / 2.0;
    let ms = rho * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3) / 2.0;
    let dmax = (15.0 * ms * v * v / (16.0 * es * rs.sqrt())).powf(0.4);
    let f_hertz = 4.0 / 3.0 * es * rs.sqrt() * dmax.powf(1.5);
    let t_hertz = 2.868 * (ms * ms / (rs * es * es * v)).powf(0.2);
    let source = "Hertz (Johnson 1985, §11.4)";
    let mut checks = Vec::new();
    let mut figures = Vec::new();
    let per_radius: &[f64] = if fine { &[20.0, 30.0] } else { &[16.0, 20.0] };
    for f in FORMULATIONS {
        let mut previous: Option<f64> = None;
        let mut last = None;
        for &n in per_radius {
            let mut case = variant(&base, (r / dp0) / n, f);
            case.simulation.end_time = case.simulation.end_time.min(1.12 * t_hertz);
            let mut sim = Simulation::<3>::new(&case)?;
            let rows = record(&mut sim, case.simulation.end_time, |_| {})?;
            let s = setting(&case, &format!("R/Δp = {n}"));
            // The quarter model carries a quarter of the force.
            let force: Vec<(f64, f64)> = rows
                .iter()
                .map(|r| (r.d.time, 4.0 * r.d.body_contact_force[1][2]))
                .collect();
            let f_max = force.iter().map(|f| f.1).fold(0.0, f64::max);
            let on: Vec<f64> = force.iter().filter(|f| f.1 != 0.0).map(|f| f.0).collect();
            let (t_on, t_c) = match (on.first(), on.last()) {
                (Some(a), Some(b)) => (*a, b - a),
                _ => return Err(Error::Invalid("the spheres never touch".into())),
            };
            checks.push(Check::new("peak force", &s, f_max, "N", source).within(f_hertz, 0.10));
            checks.push(Check::new("contact time", &s, t_c, "s", source).within(t_hertz, 0.10));
            let error = (f_max / f_hertz - 1.0)
                .abs()
                .max((t_c / t_hertz - 1.0).abs());
            converges(
                &mut checks,
                &mut previous,
                error,
                "larger error, finer against coarser",
                &s,
            );
            // Tensile: the most negative force, as a positive number.
            let tensile = 0.0 - force.iter().map(|f| f.1).fold(0.0, f64::min);
            release_checks(
                &mut checks,
                (tensile, force[force.len() - 1].1.abs()),
                "N",
                &s,
            );
            let end = &rows[rows.len() - 1];
            checks.push(
                Check::new(
                    "restitution",
                    &s,
                    (end.v[1][2] - end.v[0][2]) / v,
                    "",
                    "elastic spheres",
                )
                .at_least(0.95),
            );
            mixing_checks(
                &mut checks,
                &rows,
                &s,
                (0.0, 0.0),
                "no mixing (VALIDATION.md §D)",
            );
            let energy = match f {
                Formulation::Conventional => energy_dev(&rows, energy_in_play(&rows)),
                Formulation::Corrected => {
                    (end.d.total - rows[0].d.total).abs() / energy_in_play(&rows)
                }
            };
            checks.push(energy_check(&s, energy, 0.01, IN_PLAY));
            last = Some((force, t_on));
        }
        if let Some((force, t_on)) = last {
            let reference = hertz_force(ms, es, rs, v, t_hertz);
            let h = reference[1].0;
            let at = |t: f64| {
                let x = (t - t_on) / h;
                if x < 0.0 || x >= (reference.len() - 1) as f64 {
                    return 0.0;
                }
                let i = x as usize;
                let w = x - i as f64;
                reference[i].1 * (1.0 - w) + reference[i + 1].1 * w
            };
            let t: Vec<f64> = force.iter().map(|f| f.0).collect();
            figures.push(history(
                format!("force_{}", tag(f)),
                &t,
                "contact force (kN)",
                vec![
                    (
                        format!("strike, {}", formulation_label(f)),
                        force.iter().map(|f| f.1 * 1e-3).collect(),
                    ),
                    ("Hertz".into(), t.iter().map(|&t| at(t) * 1e-3).collect()),
                ],
            ));
        }
    }
    Ok(Outcome { checks, figures })
}

// ---------------------------------------------------------------------------------------------
// 7 km/s

/// 7 km/s Al on Al through the colour contact (`examples/planar_7kms_contact.toml`), Δp = 0.1
/// (and 0.05) mm to 1.5 µs: no particle past the other body's surface layer, the interface flat
/// within one spacing, the peak pressure under 1.25 times the Hugoniot's, the Rankine–Hugoniot
/// state on the plateau within 5 %, energy within 1 %, the bodies never closer than Δp/2
/// (VALIDATION.md §D). Figure: the target's pressure at the end against the Hugoniot's.
pub fn planar_7kms(fine: bool) -> Result<Outcome> {
    let base = example("planar_7kms_contact")?;
    let (up, us, p_h, compression) = hugoniot(base.bodies[0].velocity[0]);
    let rho0 = base.materials[base.bodies[1].material].density;
    let (_, width) = box_size(&base, 0)?;
    let mut checks = Vec::new();
    let mut figures = Vec::new();
    for f in FORMULATIONS {
        let mut last = None;
        for &k in factors(fine) {
            let case = variant(&base, k, f);
            let dp = case.bodies[0].spacing;
            let rows_n = (width / dp).round() as usize;
            let mut roughness: f64 = 0.0;
            let mut fronts = Vec::new();
            let sample = [0.9e-6, 1.4e-6];
            let mut sim = Simulation::<2>::new(&case)?;
            let rows = record(&mut sim, case.simulation.end_time, |sim| {
                let p = &sim.particles;
                let mut front = vec![f64::NEG_INFINITY; rows_n];
                let mut rear = vec![f64::INFINITY; rows_n];
                for i in 0..p.n_real {
                    let row = ((p.x[i][1] / dp).max(0.0) as usize).min(rows_n - 1);
                    if p.body[i] == 0 {
                        front[row] = front[row].max(p.x[i][0]);
                    } else {
                        rear[row] = rear[row].min(p.x[i][0]);
                    }
                }
                let spread = |v: &[f64]| {
                    v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                        - v.iter().copied().fold(f64::INFINITY, f64::min)
                };
                roughness = roughness.max(spread(&front).max(spread(&rear)) / dp);
                if fronts.len() < sample.len() && sim.state.time >= sample[fronts.len()] {
                    // The shock front: the farthest target particle faster than 1 km/s.
                    let x = (0..p.n_real)
                        .filter(|&i| p.body[i] == 1 && p.v[i][0] > 1000.0)
                        .map(|i| p.x[i][0])
                        .fold(f64::NEG_INFINITY, f64::max);
                    fronts.push((sim.state.time, x));
                }
            })?;
            if fronts.len() < 2 {
                return Err(Error::Invalid("the 7 km/s run ended before 1.4 µs".into()));
            }
            let p = &sim.particles;
            let front = fronts[1].1;
            // The plateau: target particles from 1 mm behind the interface to 1 mm behind the
            // front.
            let interface = (0..p.n_real)
                .filter(|&i| p.body[i] == 1)
                .map(|i| p.x[i][0])
                .fold(f64::INFINITY, f64::min);
            let plateau: Vec<usize> = (0..p.n_real)
                .filter(|&i| {
                    p.body[i] == 1 && p.x[i][0] > interface + 1.0e-3 && p.x[i][0] < front - 1.0e-3
                })
                .collect();
            let mean = |g: &dyn Fn(usize) -> f64| {
                plateau.iter().map(|&i| g(i)).sum::<f64>() / plateau.len().max(1) as f64
            };
            let s = setting(&case, &spacing_mm(&case));
            mixing_checks(
                &mut checks,
                &rows,
                &s,
                (0.0, 0.0),
                "no interdigitation (VALIDATION.md §D)",
            );
            checks.push(
                Check::new(
                    "interface roughness",
                    &s,
                    roughness,
                    "Δp",
                    "a flat interface (VALIDATION.md §D)",
                )
                .at_most(1.0),
            );
            let peak = rows.iter().map(|r| r.d.max_pressure).fold(0.0, f64::max);
            checks.push(
                Check::new(
                    "peak pressure",
                    &s,
                    peak,
                    "Pa",
                    "1.25 × the Hugoniot pressure (VALIDATION.md §D)",
                )
                .at_most(1.25 * p_h),
            );
            checks.push(
                Check::new(
                    "particle velocity",
                    &s,
                    mean(&|i| p.v[i][0]),
                    "m/s",
                    HUGONIOT,
                )
                .within(up, 0.05),
            );
            checks.push(
                Check::new(
                    "shock speed",
                    &s,
                    (fronts[1].1 - fronts[0].1) / (fronts[1].0 - fronts[0].0),
                    "m/s",
                    HUGONIOT,
                )
                .within(us, 0.05),
            );
            checks.push(
                Check::new(
                    "pressure behind the shock",
                    &s,
                    mean(&|i| p.p[i]),
                    "Pa",
                    HUGONIOT,
                )
                .within(p_h, 0.05),
            );
            checks.push(
                Check::new(
                    "compression ρ/ρ0",
                    &s,
                    mean(&|i| p.rho[i]) / rho0,
                    "",
                    HUGONIOT,
                )
                .within(compression, 0.05),
            );
            checks.push(energy_check(
                &s,
                energy_dev(&rows, energy_in_play(&rows)),
                0.01,
                IN_PLAY,
            ));
            contact_checks(&mut checks, &rows, &s, false);
            last = Some(profile(&sim, (interface, front + 1.0e-3, 2.0 * dp), |i| {
                p.p[i]
            }));
        }
        if let Some((x, pr)) = last {
            figures.push(pressure_figure(f, &x, &pr, p_h, "1.5 µs"));
        }
    }
    Ok(Outcome { checks, figures })
}

// ---------------------------------------------------------------------------------------------
// The paper's demonstration

/// The paper's 7 km/s sphere on a plate (`examples/sphere_plate.toml` and its CN-SPH twin,
/// quarter model, the library's failure on) to 0.2 µs, at Δp = 50 µm (coarse; with `fine` the
/// decks' 20 µm): stable; no particle past the other body's surface layer at any step (rubble,
/// and an intact fragment amid its own rubble, are no body: see `mixing`); energy within 5 %;
/// z momentum to 1e-10; the sphere's rear and the plate under it moving on at over 2 km/s,
/// and over half of that plug past the plate's rear face. Figure: the energies.
pub fn sphere_plate(fine: bool) -> Result<Outcome> {
    let mut checks = Vec::new();
    let mut figures = Vec::new();
    for name in ["sphere_plate", "sphere_plate_cn"] {
        let mut case = example(name)?;
        if !fine {
            for b in &mut case.bodies {
                b.spacing = 50e-6;
            }
        }
        let dp = case.bodies[0].spacing;
        let mut sim = Simulation::<3>::new(&case)?;
        // The sphere's rear: the particles that started in its upper quarter (above 1.5 R).
        let (centre, radius) = match case.bodies[0].shape {
            Shape::Sphere { center, radius } => (center, radius),
            _ => {
                return Err(Error::Invalid(
                    "the demo's projectile is not a sphere".into(),
                ))
            }
        };
        let rear_z0 = centre[2] + 0.5 * radius;
        let z0: Vec<f64> = sim.particles.x.iter().map(|x| x[2]).collect();
        let rows = record(&mut sim, case.simulation.end_time, |_| {})?;
        let s = setting(&case, &format!("Δp = {} µm", (dp * 1e6).round()));
        let p = &sim.particles;
        let e0 = rows[0].d.total;
        let energy = rows
            .iter()
            .map(|r| (r.d.total - e0).abs())
            .fold(0.0, f64::max)
            / e0;
        let rear: Vec<usize> = (0..p.n_real)
            .filter(|&i| p.body[i] == 0 && z0[p.id[i] as usize] > rear_z0)
            .collect();
        let plug: Vec<usize> = (0..p.n_real)
            .filter(|&i| p.body[i] == 1 && p.x[i][0].hypot(p.x[i][1]) < 0.5 * radius)
            .collect();
        let mean_vz =
            |set: &[usize]| set.iter().map(|&i| p.v[i][2]).sum::<f64>() / set.len().max(1) as f64;
        let rear_face = match case.bodies[1].shape {
            Shape::Cylinder { base, .. } => base[2],
            _ => return Err(Error::Invalid("the demo's plate is not a cylinder".into())),
        };
        let below = plug.iter().filter(|&&i| p.x[i][2] < rear_face).count() as f64
            / plug.len().max(1) as f64;
        let demo = "the paper's demonstration (VALIDATION.md §C)";
        mixing_checks(
            &mut checks,
            &rows,
            &s,
            (0.0, 0.0),
            "no mixing (issue 12, item 6; VALIDATION.md §D)",
        );
        checks.push(energy_check(
            &s,
            energy,
            0.05,
            "of the initial energy (VALIDATION.md §C)",
        ));
        checks.push(z_momentum_check(&rows, &s));
        checks.push(
            Check::new("sphere's rear v_z", &s, mean_vz(&rear), "m/s", demo).at_most(-2000.0),
        );
        checks.push(
            Check::new(
                "plug's v_z (plate within R/2 of the axis)",
                &s,
                mean_vz(&plug),
                "m/s",
                demo,
            )
            .at_most(-2000.0),
        );
        checks.push(
            Check::new(
                "share of the plug past the plate's rear face",
                &s,
                below,
                "",
                "the plate is perforated",
            )
            .at_least(0.5),
        );
        let t: Vec<f64> = rows.iter().map(|r| r.d.time).collect();
        figures.push(history(
            format!("energy_{}", tag(case.simulation.formulation)),
            &t,
            "energy of the quarter model (J)",
            vec![
                ("kinetic".into(), rows.iter().map(|r| r.d.kinetic).collect()),
                (
                    "internal".into(),
                    rows.iter().map(|r| r.d.internal).collect(),
                ),
                ("contact".into(), rows.iter().map(|r| r.d.contact).collect()),
                ("total".into(), rows.iter().map(|r| r.d.total).collect()),
            ],
        ));
    }
    Ok(Outcome { checks, figures })
}

/// The Cour-Palais crater depth in a thick metal target as NASA's single-wall ballistic limit
/// uses it (Christiansen 1991, JSC SN3-91-42; Christiansen et al. 2009, NASA/TM-2009-214785; the
/// form of Cour-Palais 1987, Int. J. Impact Eng. 5, 221, whose thin targets perforate at 1.8
/// times it): P∞ = 5.24 d^(19/18) HB^(−1/4) (ρp/ρt)^(1/2) (V/C)^(2/3) in cm, with the
/// projectile's diameter d in cm, V and the target's speed of sound C = √(E/ρ) alike (km/s in
/// the source; only their ratio enters) and HB its Brinell hardness. Here d in m, P∞ in m.
pub fn cour_palais_depth(d: f64, v_over_c: f64, rho_p_over_t: f64, hb: f64) -> f64 {
    let d_cm = d * 100.0;
    5.24 * d_cm.powf(19.0 / 18.0) * hb.powf(-0.25) * rho_p_over_t.sqrt() * v_over_c.powf(2.0 / 3.0)
        / 100.0
}

/// What [`crater_run`] measures (m).
pub struct CraterRun {
    /// Depth of the crater's floor on the impact axis below the target's original surface.
    pub depth: f64,
    /// The crater's diameter at the target's original surface (m; [`crater_run`]).
    pub diameter: f64,
    /// The diameter of the sphere of the projectile's particles' mass, (6 m / π ρ0)^(1/3).
    pub d_eq: f64,
    /// How far the floor moves between [`FLOOR_LOOSE`] and [`FLOOR_DENSE`] of a lattice's count
    /// asked under it ([`floor_spread`]).
    pub floor_spread: f64,
    pub rows: Vec<Row>,
}

/// Runs a crater deck (`examples/crater.toml`: body 0 the sphere, body 1 the block below z = 0,
/// the impact along −z through x = y = 0, symmetry planes through the axis) to its end and
/// measures the crater's depth on the axis: among the block's particles within 0.4 d of the axis,
/// the highest that has at least [`FLOOR_FILL`] of two layers' worth of them (2 A/Δp² for the
/// column's section A) within 2 Δp below it, so that loose debris in the crater does not count;
/// its depth below the original surface (the top layer's centres plus Δp/2), less the half
/// spacing it stands for. The crater's diameter is read the same way across the axis at the
/// original surface: among the block's particles in the layer just below it (centres less than
/// 3Δp/2 under it), the nearest to the axis that has at least half a lattice's worth of them
/// (π r/Δp for a quarter annulus 2 Δp wide and Δp high at radius r, which the symmetry planes
/// scale) within 2 Δp outside it, less the half spacing it stands for.
/// The projectile's size is its particles' mass as a sphere's diameter, with every
/// symmetry plane's mirror counted: the lattice's sphere is not the deck's (1.06 / 1.01 / 1.02
/// mm for the deck's 1 mm at d/Δp = 6 / 8 / 10, up to 20 % in mass).
pub fn crater_run(case: &Case) -> Result<CraterRun> {
    let mut sim = Simulation::<3>::new(case)?;
    let p = &sim.particles;
    let dp = case.bodies[1].spacing;
    let rho0 = case.materials[case.bodies[0].material].density;
    let mirrors = 2.0_f64.powi(case.symmetry.len() as i32);
    let mass: f64 = (0..p.n_real)
        .filter(|&i| p.body[i] == 0)
        .map(|i| p.m[i])
        .sum();
    let d_eq = (6.0 * mass * mirrors / (std::f64::consts::PI * rho0)).cbrt();
    let surface = (0..p.n_real)
        .filter(|&i| p.body[i] == 1)
        .map(|i| p.x[i][2])
        .fold(f64::NEG_INFINITY, f64::max)
        + 0.5 * dp;
    let rows = record(&mut sim, case.simulation.end_time, |_| {})?;
    let p = &sim.particles;
    let block: Vec<[f64; 3]> = (0..p.n_real)
        .filter(|&i| p.body[i] == 1)
        .map(|i| [p.x[i][0], p.x[i][1], p.x[i][2]])
        .collect();
    let (depth, diameter) = crater_shape(&block, (dp, surface, mirrors), 0.4 * d_eq)?;
    let floor_spread = floor_spread(&block, (dp, mirrors), 0.4 * d_eq)?;
    Ok(CraterRun {
        depth,
        diameter,
        d_eq,
        floor_spread,
        rows,
    })
}

/// The share of a full lattice's particles that a column 2 Δp deep under the crater's floor
/// must hold ([`crater_shape`]). A whole lattice's count (1, until 2026-12-04) is a knife edge:
/// a 2 Δp window holds exactly two layers only where it lies on the lattice's planes, and the
/// floor's material, stretched (0.97 ρ0 on the axis) and sheared by the flow, holds a little
/// less, so that the floor was read where the column happened to be full, spacings down. In
/// one run at d/Δp = 8 (`examples/crater.toml`, by hand) the whole count read the floor 2.21
/// and 2.05 mm deep at 3 and 6 µs, three quarters 1.96 mm at both; and from one run to the
/// next the whole count's floor jumped as the output times moved the steps (2.05 and 2.28 mm at
/// 6 µs). Three quarters and nine tenths read the same floor at 6 µs at d/Δp = 6 and 8; a half
/// takes the loose failed layer lying in the crater for floor at d/Δp = 6 (1.87 against 1.97 mm).
/// `crater_measure_reads_a_known_bowl` (tests/verification_materials.rs) holds the measure on a
/// bowl in a lattice stretched by 3 %, which the whole count read 5.9 spacings too deep.
pub const FLOOR_FILL: f64 = 0.75;

/// The crater's depth on the axis and its diameter at the original surface (m), as
/// [`crater_run`] reads them from the block's particle centres `block`, on a lattice of
/// spacing `dp` whose original surface is at z = `surface`, in the part of the whole that
/// `mirrors` symmetry images complete (4 for a quarter model), the floor looked for within
/// `reach` of the axis.
pub fn crater_shape(
    block: &[[f64; 3]],
    (dp, surface, mirrors): (f64, f64, f64),
    reach: f64,
) -> Result<(f64, f64)> {
    let radius = |x: &[f64; 3]| x[0].hypot(x[1]);
    let floor = floor_at(block, (dp, mirrors), reach, FLOOR_FILL)?;
    let mut ring: Vec<f64> = block
        .iter()
        .filter(|x| (0.0..1.5 * dp).contains(&(surface - x[2])))
        .map(radius)
        .collect();
    ring.sort_by(f64::total_cmp);
    // How many quarters of the full annulus the symmetry planes leave (one for two planes).
    let quarters = 4.0 / mirrors;
    let edge = ring
        .iter()
        .enumerate()
        .find(|&(k, &r)| {
            let want = 0.5 * quarters * std::f64::consts::PI * (r.max(dp) / dp);
            ring[k..].iter().take_while(|&&w| w < r + 2.0 * dp).count() as f64 >= want
        })
        .map(|(_, &r)| r)
        .ok_or_else(|| Error::Invalid("no crater wall at the surface".into()))?;
    Ok((surface - (floor + 0.5 * dp), 2.0 * (edge - 0.5 * dp)))
}

/// The height of the crater's floor on the axis (m): the highest of the block's particles within
/// `reach` of the axis with at least `fill` of a lattice's count (2 A/Δp² for the column's
/// section A, which `mirrors` symmetry images complete) within 2 Δp below it.
fn floor_at(block: &[[f64; 3]], (dp, mirrors): (f64, f64), reach: f64, fill: f64) -> Result<f64> {
    let mut column: Vec<f64> = block
        .iter()
        .filter(|x| x[0].hypot(x[1]) < reach)
        .map(|x| x[2])
        .collect();
    column.sort_by(|a, b| b.total_cmp(a));
    let area = std::f64::consts::PI * reach * reach / mirrors;
    let layers = (fill * 2.0 * area / (dp * dp)).round().max(2.0) as usize;
    column
        .iter()
        .enumerate()
        .find(|&(k, &z)| {
            column[k + 1..]
                .iter()
                .take_while(|&&w| w >= z - 2.0 * dp)
                .count()
                >= layers
        })
        .map(|(_, &z)| z)
        .ok_or_else(|| Error::Invalid("no crater floor on the axis".into()))
}

/// The shares of a lattice's count between which [`floor_spread`] looks for a plateau: a half
/// takes a loose layer of failed particles lying in the crater for floor where nine tenths do
/// not (by hand on 2026-12-04: 1.87 against 1.97 mm at d/Δp = 6).
pub const FLOOR_LOOSE: f64 = 0.5;
pub const FLOOR_DENSE: f64 = 0.9;

/// How far down the crater's floor on the axis moves (m) from [`FLOOR_LOOSE`] to [`FLOOR_DENSE`]
/// of a lattice's count asked under it (the block's particles, the spacing and the symmetry
/// images as [`crater_shape`] takes them). On a floor of intact material the two read the same
/// layer; where a loose layer (rubble, a failed layer lifting off) lies on the floor they part,
/// and the depth that [`FLOOR_FILL`] reads between them is the measure's choice, not the
/// crater's. In `examples/crater.toml` at 6 µs (by hand on 2026-12-04, within 0.4 mm of the
/// axis) they read 1.865 and 1.966 mm deep at d/Δp = 6 (0.6 Δp apart), 1.961 and 1.961 mm at
/// 8, and 2.030 and 2.208 mm at 10 (1.8 Δp apart); within 0.4 d_eq, as [`crater`] reads them,
/// 0.58 and 0.71 Δp apart at d/Δp = 6 and 8 (`strike validate --case crater`, 2026-12-04).
pub fn floor_spread(block: &[[f64; 3]], (dp, mirrors): (f64, f64), reach: f64) -> Result<f64> {
    let loose = floor_at(block, (dp, mirrors), reach, FLOOR_LOOSE)?;
    let dense = floor_at(block, (dp, mirrors), reach, FLOOR_DENSE)?;
    Ok(loose - dense)
}

/// Hypervelocity cratering (issue 13, item 6; `examples/crater.toml`): a 1 mm Al 6061-T6 sphere
/// at 6 km/s into a thick 6061-T6 block, the library's material (Steinberg's elastic–perfectly
/// plastic 6061-T6 with its spall strength), against the Cour-Palais crater depth
/// ([`cour_palais_depth`]) with HB = 95 and C = √(E/ρ) = √(68.9 GPa / 2700 kg/m³) = 5.05 km/s
/// (ASM handbook values as NASA's BLE tool pyBLOSSUM tabulates them): 1.66 mm for d = 1 mm.
/// The equation is an empirical fit without a published scatter band in the sources at hand, so
/// the depth is reported against it, not held; held are that refinement does not move the depth
/// away from it, that the floor is read on a plateau ([`floor_spread`] within a spacing: a depth
/// read off a loose layer is the measure's, not the crater's), no mixing and momentum. Reported
/// beside the depth: the depth over the crater's diameter at the surface, against the 0.56–0.60
/// of LDEF's aluminium craters (Love, Brownlee, King & Hörz 1993, LPSC 24, 809: normal impacts
/// above 5 km/s, the ratio independent of size, speed and hardness). Coarse: d/Δp = 6 and 8 (5
/// minutes on 2 cores, measured 2026-12-04); `fine`: 8 and 10 (18 minutes). Measured on
/// 2026-12-04 with the floor's three quarters of a lattice ([`FLOOR_FILL`]): depth 1.965 / 1.961
/// / 2.071 mm at d/Δp = 6 / 8 / 10, +11.2 / +16.6 / +22.8 % of the fit at each lattice's
/// sphere, diameter 3.60 / 3.53 / 3.14 mm, depth over diameter 0.546 / 0.555 / 0.659: both
/// pairs fail their convergence check (README, Not yet). With the whole lattice's count the
/// same runs read 1.965 / 2.283 / 2.140 mm (+11.2 / +35.7 / +26.8 %), the fine pair passing by
/// the knife edge's jump at d/Δp = 8. At d/Δp = 10 the floor's spread would fail too (1.8 Δp
/// by hand within 0.4 mm of the axis; `--fine` not run since): there the depth is read off a
/// failed layer lifting off the floor. Those runs' coarse spheres were 20 / 4.4 % heavy at
/// d/Δp = 6 / 8; since the sphere keeps its mass (`setup::shapes::lattice`, 2026-12-04,
/// latest) the case reads 2.047 / 1.963 mm (+24.0 / +18.5 %), the floor's spread 6.5 / 3.5 Δp,
/// failing at both, and with `fine` 1.963 / 1.997 mm (+18.5 / +19.6 %), the spread 3.5 / 1.46
/// Δp: the failed layer's place on the axis, not the crater, sets the reading.
pub fn crater(fine: bool) -> Result<Outcome> {
    let source = "Cour-Palais crater depth (Christiansen 1991, NASA/TM-2009-214785)";
    let (hb, c) = (95.0, (68.9e9_f64 / 2700.0).sqrt());
    let mut checks = Vec::new();
    let mut previous = None;
    let ratios: &[f64] = if fine { &[8.0, 10.0] } else { &[6.0, 8.0] };
    for &ratio in ratios {
        let mut case = example("crater")?;
        let d = match case.bodies[0].shape {
            Shape::Sphere { radius, .. } => 2.0 * radius,
            _ => {
                return Err(Error::Invalid(
                    "the crater's projectile is not a sphere".into(),
                ))
            }
        };
        for b in &mut case.bodies {
            b.spacing = d / ratio;
        }
        let v = case.bodies[0]
            .velocity
            .iter()
            .map(|u| u * u)
            .sum::<f64>()
            .sqrt();
        let r = crater_run(&case)?;
        let s = setting(&case, &format!("d/Δp = {ratio}"));
        let reference = cour_palais_depth(r.d_eq, v / c, 1.0, hb);
        checks.push(
            Check::new("crater depth on the axis", &s, r.depth, "m", source).reported(reference),
        );
        checks.push(
            Check::new(
                "crater floor's spread between a half and nine tenths of a lattice's count",
                &s,
                r.floor_spread,
                "m",
                "the floor's measure stands on a plateau: within one spacing (validate::contact::floor_spread)",
            )
            .at_most(case.bodies[1].spacing),
        );
        checks.push(
            Check::new(
                "crater depth over its diameter at the surface",
                &s,
                r.depth / r.diameter,
                "",
                "Love, Brownlee, King & Hörz 1993 (LPSC 24, 809): 0.56–0.60 for normal impacts on LDEF's aluminium above 5 km/s",
            )
            .reported(0.58),
        );
        let error = (r.depth / reference - 1.0).abs();
        converges(
            &mut checks,
            &mut previous,
            error,
            "crater depth's error, finer against coarser",
            &s,
        );
        mixing_checks(
            &mut checks,
            &r.rows,
            &s,
            (0.0, 0.0),
            "no mixing (issue 12, item 6; VALIDATION.md §D)",
        );
        checks.push(z_momentum_check(&r.rows, &s));
    }
    Ok(Outcome {
        checks,
        figures: Vec::new(),
    })
}
