//! `strike validate`: verification cases with their references and tolerances, run and
//! reported (Markdown with PNG plots, and one self-contained HTML page), and the README's table
//! of them written from the same results.
//!
//! Each case is a function of the resolution (coarse: the CI's; `--fine`: the README's) that
//! runs one or more decks and returns its [`Check`]s — a measured figure against a reference
//! with a relative tolerance, or against a limit ([`Bound`]) — and [`Figure`]s against the
//! reference where one fits. Here: the engine's and the materials' cases; [`contact`]: the
//! contact's; [`blocks`]: the building blocks (kernel, consistency, contact direction). The
//! verification tests call the same functions, so the command and the tests measure alike.
//! The decks are built into the program (the `examples/` files), so the command runs from any
//! folder.

use crate::case::{Case, Formulation, StrengthSpec};
use crate::error::{Error, Result};
use crate::output::{atomic, picture};
use crate::simulation::{Diagnostics, Simulation};
use std::fmt::Write as _;
use std::path::Path;

pub mod blocks;
pub mod contact;

/// How a check holds its measured figure against its reference.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub enum Bound {
    /// |measured/reference − 1| ≤ tolerance.
    #[default]
    Relative,
    /// measured ≤ reference: a drift, a penetration, a tensile force (the reference is the
    /// limit).
    AtMost,
    /// measured ≥ reference: a closest approach, a restitution.
    AtLeast,
    /// Shown beside the checks, not held: a figure at a resolution where the case is not yet
    /// asked to meet its tolerance (the setting says which is), or a known deficiency of a form
    /// the case compares with.
    Reported,
}

/// One measured figure against its reference.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Check {
    /// What is measured, and at which setting (resolution, formulation).
    pub quantity: String,
    pub setting: String,
    pub measured: f64,
    pub reference: f64,
    pub unit: &'static str,
    pub bound: Bound,
    /// Largest |measured/reference − 1| ([`Bound::Relative`] only).
    pub tolerance: f64,
    /// Where the reference comes from.
    pub source: &'static str,
}

impl Check {
    /// A measured figure, to be held by [`Check::within`], [`Check::at_most`],
    /// [`Check::at_least`] or [`Check::reported`].
    pub fn new(
        quantity: impl Into<String>,
        setting: impl Into<String>,
        measured: f64,
        unit: &'static str,
        source: &'static str,
    ) -> Self {
        Check {
            quantity: quantity.into(),
            setting: setting.into(),
            measured,
            unit,
            source,
            ..Default::default()
        }
    }

    /// Within `tolerance` (relative) of `reference`.
    pub fn within(self, reference: f64, tolerance: f64) -> Self {
        Check {
            reference,
            tolerance,
            bound: Bound::Relative,
            ..self
        }
    }

    /// At most `limit`.
    pub fn at_most(self, limit: f64) -> Self {
        Check {
            reference: limit,
            bound: Bound::AtMost,
            ..self
        }
    }

    /// At least `limit`.
    pub fn at_least(self, limit: f64) -> Self {
        Check {
            reference: limit,
            bound: Bound::AtLeast,
            ..self
        }
    }

    /// Shown against `reference`, not held.
    pub fn reported(self, reference: f64) -> Self {
        Check {
            reference,
            bound: Bound::Reported,
            ..self
        }
    }

    /// measured/reference − 1.
    pub fn error(&self) -> f64 {
        self.measured / self.reference - 1.0
    }

    /// Within the tolerance times `factor`? A positive limit of a bound is loosened by the
    /// factor too (an upper one multiplied, a lower one divided); a zero or negative limit
    /// (no penetration, no tension) is held as it is.
    pub fn passes(&self, factor: f64) -> bool {
        let r = self.reference;
        match self.bound {
            Bound::Relative => self.error().abs() <= self.tolerance * factor,
            Bound::AtMost => self.measured <= if r > 0.0 { r * factor } else { r },
            Bound::AtLeast => self.measured >= if r > 0.0 { r / factor } else { r },
            Bound::Reported => true,
        }
    }

    /// The error column: relative for a relative check or a reported figure, none for a bound.
    fn error_text(&self) -> String {
        match self.bound {
            Bound::Relative | Bound::Reported if self.reference != 0.0 => {
                format!("{:+.2} %", 100.0 * self.error())
            }
            _ => "–".into(),
        }
    }

    /// The tolerance column, with `factor` applied.
    fn tolerance_text(&self, factor: f64) -> String {
        let scaled = |r: f64, up: bool| {
            if r <= 0.0 {
                r
            } else if up {
                r * factor
            } else {
                r / factor
            }
        };
        match self.bound {
            Bound::Relative => format!("{} %", 100.0 * self.tolerance * factor),
            Bound::AtMost => format!("≤ {}", show(scaled(self.reference, true), self.unit)),
            Bound::AtLeast => format!("≥ {}", show(scaled(self.reference, false), self.unit)),
            Bound::Reported => "not held".into(),
        }
    }

    /// The last column.
    fn verdict(&self, factor: f64) -> &'static str {
        match (self.bound, self.passes(factor)) {
            (Bound::Reported, _) => "reported",
            (_, true) => "pass",
            (_, false) => "**FAIL**",
        }
    }
}

/// A named series of values at a figure's x.
pub type Series = (String, Vec<f64>);
/// A panel: its y label and its series.
pub type Panel = (String, Vec<Series>);

/// A plot of a case: series against a common x, in panels.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// File name stem (`<case>_<name>.png`).
    pub name: String,
    pub x_label: String,
    pub x: Vec<f64>,
    /// (y label, series (name, values at x)).
    pub panels: Vec<Panel>,
}

/// What a case gave.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    pub checks: Vec<Check>,
    pub figures: Vec<Figure>,
}

/// A verification case: its name (for `--case`), title, and how to run it.
pub struct CaseDef {
    pub name: &'static str,
    pub title: &'static str,
    pub run: fn(fine: bool) -> Result<Outcome>,
}

/// Every case, in the order of the report.
pub fn cases() -> Vec<CaseDef> {
    vec![
        CaseDef {
            name: "kernel",
            title: "Kernel normalisation and support (VALIDATION.md §A)",
            run: blocks::kernel,
        },
        CaseDef {
            name: "consistency",
            title: "CN-SPH's first-order consistency at the interior, a face and a corner (VALIDATION.md §A, §E)",
            run: blocks::consistency,
        },
        CaseDef {
            name: "contact_direction",
            title: "CN-SPH's contact force along the surface normal (VALIDATION.md §E)",
            run: blocks::contact_direction,
        },
        CaseDef {
            name: "elastic_wave",
            title: "Elastic wave in uniaxial strain (VALIDATION.md §A)",
            run: elastic_wave,
        },
        CaseDef {
            name: "hel",
            title: "Hugoniot elastic limit (VALIDATION.md §A)",
            run: hel,
        },
        CaseDef {
            name: "energy",
            title: "Energy of an elastic impact: a flyer welded to a column (VALIDATION.md §A)",
            run: energy,
        },
        CaseDef {
            name: "planar_impact",
            title: "Planar impact at 1 km/s, contact and welded: the Rankine–Hugoniot state (VALIDATION.md §B)",
            run: contact::planar_impact,
        },
        CaseDef {
            name: "bars",
            title: "Elastic bars at ±400 m/s through the contact; welded bars at ±10 m/s (VALIDATION.md §B)",
            run: contact::bars,
        },
        CaseDef {
            name: "slow_bars",
            title: "Elastic bars at ±10 m/s part at their speed (VALIDATION.md §D)",
            run: contact::slow_bars,
        },
        CaseDef {
            name: "striker",
            title: "A striker on a bar twice its length stops dead (VALIDATION.md §D)",
            run: contact::striker,
        },
        CaseDef {
            name: "sliding",
            title: "Frictionless sliding; the paper's form with n = 4 and 6 (VALIDATION.md §B, §E)",
            run: contact::sliding,
        },
        CaseDef {
            name: "incline",
            title: "A block sliding down a frictionless 30° incline (VALIDATION.md §B)",
            run: contact::incline,
        },
        CaseDef {
            name: "rubber_rings",
            title: "Rubber rings rebound and part without fracture (VALIDATION.md §B)",
            run: contact::rubber_rings,
        },
        CaseDef {
            name: "hertz",
            title: "Hertz impact of two elastic spheres (VALIDATION.md §D)",
            run: contact::hertz,
        },
        CaseDef {
            name: "planar_7kms",
            title: "7 km/s planar impact through the contact: no interdigitation (VALIDATION.md §D)",
            run: contact::planar_7kms,
        },
        CaseDef {
            name: "sphere_plate",
            title: "The paper's demonstration: 7 km/s sphere on a plate (VALIDATION.md §C)",
            run: contact::sphere_plate,
        },
        CaseDef {
            name: "crater",
            title: "Hypervelocity cratering: a 1 mm Al sphere at 6 km/s into a thick Al block, against the Cour-Palais crater depth (issue 13)",
            run: contact::crater,
        },
        CaseDef {
            name: "spall",
            title: "Flyer-plate spall: pull-back against the set spall strength (VALIDATION.md §F), the free face and the spall plane against an independent 1D Lagrangian solution",
            run: spall,
        },
        CaseDef {
            name: "shocked_strength",
            title: "Steinberg–Guinan strength behind a 14 GPa shock (issue 13)",
            run: shocked_strength,
        },
        CaseDef {
            name: "taylor",
            title: "Taylor bar, 42CrMo4, Johnson–Cook (VALIDATION.md §F)",
            run: taylor,
        },
        CaseDef {
            name: "taylor_ofhc",
            title: "Taylor tests, OFHC copper, Johnson–Cook, against Johnson & Cook's rods and the model's continuum (VALIDATION.md §F)",
            run: taylor_ofhc,
        },
        CaseDef {
            name: "taylor_walls",
            title: "Taylor bars (steel, copper) on a wall, a symmetry plane, a fixed wall and their twin (VALIDATION.md §F)",
            run: taylor_walls,
        },
    ]
}

/// The example decks the cases run, built in.
fn example(name: &str) -> Result<Case> {
    let text = match name {
        "elastic_wave" => include_str!("../examples/elastic_wave.toml"),
        "hugoniot_elastic_limit" => include_str!("../examples/hugoniot_elastic_limit.toml"),
        "shocked_strength" => include_str!("../examples/shocked_strength.toml"),
        "spall" => include_str!("../examples/spall.toml"),
        "taylor_bar" => include_str!("../examples/taylor_bar.toml"),
        "taylor_copper" => include_str!("../examples/taylor_copper.toml"),
        "taylor_ofhc" => include_str!("../examples/taylor_ofhc.toml"),
        "planar_impact_contact" => include_str!("../examples/planar_impact_contact.toml"),
        "planar_impact_welded" => include_str!("../examples/planar_impact_welded.toml"),
        "bars_contact" => include_str!("../examples/bars_contact.toml"),
        "bars_welded" => include_str!("../examples/bars_welded.toml"),
        "striker" => include_str!("../examples/striker.toml"),
        "sliding_contact" => include_str!("../examples/sliding_contact.toml"),
        "sliding_welded" => include_str!("../examples/sliding_welded.toml"),
        "incline" => include_str!("../examples/incline.toml"),
        "rubber_rings" => include_str!("../examples/rubber_rings.toml"),
        "hertz_spheres" => include_str!("../examples/hertz_spheres.toml"),
        "planar_7kms_contact" => include_str!("../examples/planar_7kms_contact.toml"),
        "sphere_plate" => include_str!("../examples/sphere_plate.toml"),
        "sphere_plate_cn" => include_str!("../examples/sphere_plate_cn.toml"),
        "crater" => include_str!("../examples/crater.toml"),
        other => return Err(Error::Invalid(format!("no built-in deck `{other}`"))),
    };
    crate::deck::parse(text, &format!("examples/{name}.toml"))
}

/// Runs to `t`, returning every step's diagnostics.
fn run_to<const D: usize>(sim: &mut Simulation<D>, t: f64) -> Result<Vec<Diagnostics>> {
    let mut out = Vec::new();
    while sim.state.time < t * (1.0 - 1e-12) {
        out.push(sim.step(t - sim.state.time)?);
    }
    Ok(out)
}

fn formulation_label(f: Formulation) -> &'static str {
    match f {
        Formulation::Conventional => "conventional SPH",
        Formulation::Corrected => "CN-SPH",
    }
}

/// A column case's runs: (formulation, spacing factor, whether it is the finest run, whose
/// figure is drawn), both formulations at the deck's spacing and, with `fine`, at half of it.
fn column_runs(fine: bool) -> Vec<(Formulation, f64, bool)> {
    let factors: &[f64] = if fine { &[1.0, 0.5] } else { &[1.0] };
    [Formulation::Conventional, Formulation::Corrected]
        .into_iter()
        .flat_map(|f| {
            factors
                .iter()
                .map(move |&k| (f, k, k == factors[factors.len() - 1]))
        })
        .collect()
}

/// `case` with every spacing times `factor`, in `formulation`.
fn variant(case: &Case, factor: f64, formulation: Formulation) -> Case {
    let mut c = case.clone();
    for b in &mut c.bodies {
        b.spacing *= factor;
    }
    c.simulation.formulation = formulation;
    c
}

/// "conventional SPH, Δp = 0.5 mm": a column case's formulation and the spacing of its column
/// (body 1).
fn column_setting(case: &Case) -> String {
    format!(
        "{}, Δp = {} mm",
        formulation_label(case.simulation.formulation),
        case.bodies[1].spacing * 1e3
    )
}

/// A profile along x (m, shown in mm) of one formulation's run against a reference.
fn profile_figure(
    f: Formulation,
    x: &[f64],
    y_label: &str,
    measured: Vec<f64>,
    (reference, values): (&str, Vec<f64>),
) -> Figure {
    let tag = match f {
        Formulation::Conventional => "conventional",
        Formulation::Corrected => "cn",
    };
    Figure {
        name: format!("profile_{tag}"),
        x_label: "x (mm)".into(),
        x: x.iter().map(|x| x * 1e3).collect(),
        panels: vec![(
            y_label.into(),
            vec![
                (format!("strike, {}", formulation_label(f)), measured),
                (reference.into(), values),
            ],
        )],
    }
}

/// (ρ, K, G) of body 1's material.
fn elastic_constants(case: &Case) -> (f64, f64, f64) {
    let m = &case.materials[case.bodies[1].material];
    (
        m.density,
        m.eos.bulk_modulus(m.density),
        m.strength.shear_modulus(),
    )
}

/// The mean of `value` over body 1's particles in bins of `width` along x, from `lo` to `hi`.
fn profile(
    sim: &Simulation<2>,
    (lo, hi, width): (f64, f64, f64),
    value: impl Fn(usize) -> f64,
) -> (Vec<f64>, Vec<f64>) {
    let bins = ((hi - lo) / width).ceil().max(1.0) as usize;
    let (mut sum, mut n) = (vec![0.0; bins], vec![0.0; bins]);
    let p = &sim.particles;
    for i in (0..p.n_real).filter(|&i| p.body[i] == 1) {
        let k = ((p.x[i][0] - lo) / width).floor();
        if k >= 0.0 && (k as usize) < bins {
            sum[k as usize] += value(i);
            n[k as usize] += 1.0;
        }
    }
    let x = (0..bins).map(|k| lo + (k as f64 + 0.5) * width).collect();
    let v = sum
        .iter()
        .zip(&n)
        .map(|(s, n)| if *n > 0.0 { s / n } else { f64::NAN })
        .collect();
    (x, v)
}

/// Where body 1's x velocity, averaged over each lattice column (spacing `dp`), last crosses
/// `v`, interpolated between the columns on either side: the front of a wave moving along +x.
/// (The farthest particle above `v` alone moves in steps of Δp, which over the few centimetres
/// a front is followed is 0.5–1 % of its speed.)
fn front(sim: &Simulation<2>, v: f64, dp: f64) -> Result<f64> {
    let p = &sim.particles;
    let mut columns = std::collections::BTreeMap::<i64, (f64, f64, f64)>::new();
    for i in (0..p.n_real).filter(|&i| p.body[i] == 1) {
        let c = columns.entry((p.x[i][0] / dp).round() as i64).or_default();
        *c = (c.0 + p.x[i][0], c.1 + p.v[i][0], c.2 + 1.0);
    }
    let profile: Vec<(f64, f64)> = columns.values().map(|c| (c.0 / c.2, c.1 / c.2)).collect();
    let k = profile
        .iter()
        .rposition(|c| c.1 > v)
        .filter(|&k| k + 1 < profile.len())
        .ok_or_else(|| Error::Invalid(format!("no front at {v} m/s inside the column")))?;
    let ((x0, v0), (x1, v1)) = (profile[k], profile[k + 1]);
    Ok(x0 + (v0 - v) / (v0 - v1) * (x1 - x0))
}

/// Elastic wave (`examples/elastic_wave.toml`): a piston at 10 m/s drives a wave into an
/// elastic column in uniaxial strain. The front (where v_x passes half the piston's speed)
/// moves at c_L = √((K + 4G/3)/ρ), within 2 %, and the stress behind it is −ρ c_L v, within
/// 2 %. Both formulations, at the deck's spacing and half of it with `fine`; the front, where
/// the column-averaged velocity crosses half the piston's, is measured between 4 and 12 µs,
/// so its spread cancels.
pub fn elastic_wave(fine: bool) -> Result<Outcome> {
    let mut checks = Vec::new();
    let mut figures = Vec::new();
    for (f, factor, finest) in column_runs(fine) {
        let case = variant(&example("elastic_wave")?, factor, f);
        let (rho, k, g) = elastic_constants(&case);
        let c = ((k + 4.0 / 3.0 * g) / rho).sqrt();
        let v = case.bodies[0].velocity[0];
        let mut sim = Simulation::<2>::new(&case)?;
        run_to(&mut sim, 4e-6)?;
        let dp = case.bodies[1].spacing;
        let (t1, x1) = (sim.state.time, front(&sim, 0.5 * v, dp)?);
        run_to(&mut sim, 12e-6)?;
        let (t2, x2) = (sim.state.time, front(&sim, 0.5 * v, dp)?);
        let setting = column_setting(&case);
        checks.push(
            Check::new(
                "front speed",
                setting.clone(),
                (x2 - x1) / (t2 - t1),
                "m/s",
                "c_L = √((K + 4G/3)/ρ)",
            )
            .within(c, 0.02),
        );
        let p = &sim.particles;
        let stress = |i: usize| p.s[i].get(0, 0) - p.p[i];
        let behind: Vec<f64> = (0..p.n_real)
            .filter(|&i| p.body[i] == 1 && p.x[i][0] > 0.02 && p.x[i][0] < 0.05)
            .map(stress)
            .collect();
        checks.push(
            Check::new(
                "σ_xx behind the front",
                setting,
                behind.iter().sum::<f64>() / behind.len().max(1) as f64,
                "Pa",
                "−ρ c_L v (uniaxial strain)",
            )
            .within(-rho * c * v, 0.02),
        );
        let (x, s) = profile(&sim, (0.0, 0.1, 1e-3), stress);
        let exact: Vec<f64> = x
            .iter()
            .map(|&x| if x < c * t2 { -rho * c * v } else { 0.0 })
            .collect();
        if finest {
            figures.push(profile_figure(
                f,
                &x,
                "σ_xx at 12 µs (MPa)",
                s.iter().map(|s| s * 1e-6).collect(),
                ("exact", exact.iter().map(|s| s * 1e-6).collect()),
            ));
        }
    }
    Ok(Outcome { checks, figures })
}

/// Hugoniot elastic limit (`examples/hugoniot_elastic_limit.toml`): a piston at 100 m/s into an
/// elastic–perfectly plastic column in uniaxial strain; the elastic precursor carries
/// σ_HEL = Y (1 − ν)/(1 − 2ν), within 5 %. Both formulations, at the deck's spacing and half
/// of it with `fine`.
pub fn hel(fine: bool) -> Result<Outcome> {
    let mut checks = Vec::new();
    let mut figures = Vec::new();
    for (f, factor, finest) in column_runs(fine) {
        let case = variant(&example("hugoniot_elastic_limit")?, factor, f);
        let (_, k, g) = elastic_constants(&case);
        let y = match case.materials[case.bodies[1].material].strength {
            StrengthSpec::VonMises { yield_stress, .. } => yield_stress,
            _ => {
                return Err(Error::Invalid(
                    "the HEL deck's column is not von Mises".into(),
                ))
            }
        };
        let nu = (3.0 * k - 2.0 * g) / (2.0 * (3.0 * k + g));
        let hel = y * (1.0 - nu) / (1.0 - 2.0 * nu);
        let mut sim = Simulation::<2>::new(&case)?;
        run_to(&mut sim, case.simulation.end_time)?;
        let p = &sim.particles;
        let compression = |i: usize| p.p[i] - p.s[i].get(0, 0);
        // The precursor's peak. (Its plateau is not flat enough to measure here: the median of
        // the unyielded particles above half the peak reads −11.6 / −4.6 % at Δp = 0.1 /
        // 0.05 mm, the ramp of the smeared precursor; the peak carries the front's overshoot,
        // +0.7 / +1.0 %, which does not shrink with refinement.)
        let precursor = (0..p.n_real)
            .filter(|&i| p.body[i] == 1 && p.eps_p[i] == 0.0)
            .map(compression)
            .fold(0.0, f64::max);
        // Behind the plastic wave (the first 10 mm) every particle has yielded.
        let behind: Vec<usize> = (0..p.n_real)
            .filter(|&i| p.body[i] == 1 && p.x[i][0] < 10e-3)
            .collect();
        let yielded = behind.iter().filter(|&&i| p.eps_p[i] > 0.0).count();
        checks.push(
            Check::new(
                "share yielded behind the plastic wave",
                column_setting(&case),
                yielded as f64 / behind.len().max(1) as f64,
                "",
                "elastic–plastic uniaxial strain: the plastic wave follows the precursor",
            )
            .within(1.0, 0.0),
        );
        checks.push(
            Check::new(
                "elastic precursor",
                column_setting(&case),
                precursor,
                "Pa",
                "Y (1 − ν)/(1 − 2ν)",
            )
            .within(hel, 0.05),
        );
        let hi = (0..p.n_real)
            .filter(|&i| p.body[i] == 1)
            .map(|i| p.x[i][0])
            .fold(0.0, f64::max);
        let (x, s) = profile(&sim, (0.0, hi, 2.0 * case.bodies[1].spacing), compression);
        if finest {
            figures.push(profile_figure(
                f,
                &x,
                "−σ_xx at the end (GPa)",
                s.iter().map(|s| s * 1e-9).collect(),
                ("σ_HEL", vec![hel * 1e-9; x.len()]),
            ));
        }
    }
    Ok(Outcome { checks, figures })
}

/// The state behind a steady shock driven at `up` into `m` in uniaxial strain, by integrating
/// the material along the shock's Rayleigh line: in a steady shock every state lies on the
/// line from the state at rest to the end state, σ_xx + q = ρ0 U_s² (1 − 1/η) with q the
/// viscosity, and the energy equation gives e = ½ U_s² (1 − 1/η)² along it (the Rankine–
/// Hugoniot jump e = ½ u_p² at its end). The deviator is loaded in uniaxial strain,
/// −dS_xx = (4/3) G d ln η, and returned radially onto Y(εp, p, η, e); U_s is found where the
/// material's own σ_xx = p − S_xx meets the line at η = U_s/(U_s − u_p). Returns
/// (η, p, von Mises stress, εp) at the end.
pub fn rayleigh_line_state(m: &crate::material::Material, up: f64) -> (f64, f64, f64, f64) {
    use crate::material::StrengthState;
    let rho0 = m.rho0;
    let path = |us: f64, steps: usize| {
        let eta_f = us / (us - up);
        let at = |eta: f64| {
            let e = 0.5 * us * us * (1.0 - 1.0 / eta).powi(2);
            (e, m.eos.pressure(rho0 * eta, e))
        };
        let (mut s, mut eps, mut eta) = (0.0_f64, 0.0_f64, 1.0_f64);
        let mut end = (0.0, 0.0);
        let d = (eta_f - 1.0) / steps as f64;
        for _ in 0..steps {
            let mid = eta + 0.5 * d;
            let (e_mid, p_mid) = at(mid);
            let st = |eps_p: f64, eta: f64, e: f64, p: f64| StrengthState {
                eps_p,
                rate: 0.0,
                e,
                w_p: 0.0,
                eta,
                p,
            };
            let g = m.strength.shear_modulus(&st(eps, mid, e_mid, p_mid));
            let next = eta + d;
            let (e, p) = at(next);
            // −S_xx: the von Mises stress is 3/2 of it in uniaxial strain.
            let trial = s + 4.0 / 3.0 * g * (next / eta).ln();
            let y = m.strength.yield_stress(&st(eps, next, e, p));
            if 1.5 * trial > y {
                eps += (1.5 * trial - y) / (3.0 * g);
                s = m.strength.yield_stress(&st(eps, next, e, p)) / 1.5;
            } else {
                s = trial;
            }
            eta = next;
            end = (p, s);
        }
        (
            eta_f,
            end.0,
            1.5 * end.1,
            eps,
            end.0 + end.1 - rho0 * us * up,
        )
    };
    // The material's σ_xx falls below the line's end as U_s grows (a stiffer line).
    let (mut lo, mut hi) = (0.5 * m.sound_speed(rho0, 0.0).max(up), 20.0 * up + 2e4);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if path(mid, 2000).4 > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let (eta, p, vm, eps, _) = path(0.5 * (lo + hi), 20_000);
    (eta, p, vm, eps)
}

/// Steinberg–Guinan in a run (`examples/shocked_strength.toml`): the HEL column driven at
/// 800 m/s, a 14 GPa shock into Al 6061-T6 with Steinberg's constants. Behind the shock (6 to
/// 14 mm at 3 µs) the compression within 1 % and the flow stress (the particles' von Mises
/// stress) within 10 % of the steady shock's state integrated by hand along its Rayleigh line
/// ([`rayleigh_line_state`]): 0.600 GPa, twice Y0 (work hardening +28 %, the pressure's
/// hardening +84 %, the shock heat's softening −22 %). The deviator ends 5–6 % inside the yield
/// surface (the same 35–45 MPa as with von Mises, where that is −15 %: the smeared shock's
/// overshoot unloads it elastically), hence 10 %. Both formulations, the deck's spacing and
/// half of it with `fine`.
pub fn shocked_strength(fine: bool) -> Result<Outcome> {
    let mut checks = Vec::new();
    for (f, factor, _) in column_runs(fine) {
        let case = variant(&example("shocked_strength")?, factor, f);
        let up = case.bodies[0].velocity[0];
        let mut sim = Simulation::<2>::new(&case)?;
        let material = sim.model.material_of(1);
        let (eta, _, vm_ref, _) = rayleigh_line_state(material, up);
        let rho0 = material.rho0;
        run_to(&mut sim, case.simulation.end_time)?;
        let p = &sim.particles;
        let behind: Vec<usize> = (0..p.n_real)
            .filter(|&i| p.body[i] == 1 && (6e-3..14e-3).contains(&p.x[i][0]))
            .collect();
        let mean = |v: &dyn Fn(usize) -> f64| {
            behind.iter().map(|&i| v(i)).sum::<f64>() / behind.len().max(1) as f64
        };
        let vm = mean(&|i| crate::tensor::von_mises(&p.s[i].full()));
        let compression = mean(&|i| p.rho[i] / rho0);
        checks.push(
            Check::new(
                "compression behind the shock",
                column_setting(&case),
                compression,
                "",
                "the steady shock's end state (Rayleigh line, Rankine–Hugoniot)",
            )
            .within(eta, 0.01),
        );
        checks.push(
            Check::new(
                "flow stress behind the shock",
                column_setting(&case),
                vm,
                "Pa",
                "Steinberg–Guinan integrated along the shock's Rayleigh line",
            )
            .within(vm_ref, 0.10),
        );
    }
    Ok(Outcome {
        checks,
        figures: Vec::new(),
    })
}

/// Energy of an elastic impact with no external work (`examples/elastic_wave.toml` with its
/// piston set free: a flyer welded to the column), to 12 µs at the formulation's default
/// Courant number: kinetic + internal energy within 1 % of the initial, x momentum to 1e-10,
/// and over a fifth of the energy moved into the column's internal energy (so the exchange
/// really happened). Both formulations, at the deck's spacing and half of it with `fine`.
/// Figure: the energies.
pub fn energy(fine: bool) -> Result<Outcome> {
    let mut checks = Vec::new();
    let mut figures = Vec::new();
    for (f, factor, finest) in column_runs(fine) {
        let mut case = variant(&example("elastic_wave")?, factor, f);
        case.bodies[0].motion = crate::case::Motion::Free;
        let mut sim = Simulation::<2>::new(&case)?;
        let hist = run_to(&mut sim, 12e-6)?;
        let e0 = hist[0].total;
        let drift = hist
            .iter()
            .map(|d| (d.total - e0).abs())
            .fold(0.0, f64::max)
            / e0;
        let p0 = hist[0].momentum[0];
        let px = hist
            .iter()
            .map(|d| (d.momentum[0] - p0).abs())
            .fold(0.0, f64::max)
            / hist[0].momentum_scale;
        let setting = column_setting(&case);
        checks.push(
            Check::new(
                "energy error",
                setting.clone(),
                drift,
                "",
                "no external work",
            )
            .at_most(0.01),
        );
        checks.push(
            Check::new(
                "x momentum error",
                setting.clone(),
                px,
                "",
                "no external force",
            )
            .at_most(1e-10),
        );
        let moved = hist.last().map_or(0.0, |d| d.internal) / e0;
        checks.push(
            Check::new(
                "share of the energy in internal energy at the end",
                setting,
                moved,
                "",
                "the flyer's energy went into the column",
            )
            .at_least(0.2),
        );
        let t: Vec<f64> = hist.iter().map(|d| d.time * 1e6).collect();
        if finest {
            figures.push(Figure {
                name: format!(
                    "energies_{}",
                    match f {
                        Formulation::Conventional => "conventional",
                        Formulation::Corrected => "cn",
                    }
                ),
                x_label: "time (µs)".into(),
                x: t,
                panels: vec![(
                    format!("energy, {} (J/m)", formulation_label(f)),
                    vec![
                        ("kinetic".into(), hist.iter().map(|d| d.kinetic).collect()),
                        ("internal".into(), hist.iter().map(|d| d.internal).collect()),
                        ("total".into(), hist.iter().map(|d| d.total).collect()),
                    ],
                )],
            });
        }
    }
    Ok(Outcome { checks, figures })
}

/// What a flyer-plate run shows: the target's free-face velocity history (t, u_fs), where its
/// failed particles started along x (their material coordinate, which does not move as the
/// spalled layers open and fly apart), and the largest relative momentum error along x.
pub struct SpallRun {
    pub free_face: Vec<(f64, f64)>,
    pub failed_x0: Vec<f64>,
    pub momentum_error: f64,
}

/// Runs a flyer-plate deck (2D, target body 1): the free face is the mean velocity of the
/// target's last particle layer.
pub fn spall_run(case: &Case) -> Result<SpallRun> {
    let mut sim = Simulation::<2>::new(case)?;
    let target: u32 = 1;
    let dp = case.bodies[target as usize].spacing;
    let end = case.simulation.end_time;
    let mut free_face = Vec::new();
    let mut momentum_error: f64 = 0.0;
    let mut p0 = None;
    let ids = sim.particles.id.iter().max().map_or(0, |&m| m as usize + 1);
    let mut start = vec![0.0; ids];
    for i in 0..sim.particles.n_real {
        start[sim.particles.id[i] as usize] = sim.particles.x[i][0];
    }
    while sim.state.time < end * (1.0 - 1e-12) {
        let d = sim.step(end - sim.state.time)?;
        let p0 = *p0.get_or_insert(d.momentum);
        momentum_error = momentum_error.max((d.momentum[0] - p0[0]).abs() / d.momentum_scale);
        let p = &sim.particles;
        let back = (0..p.n_real)
            .filter(|&i| p.body[i] == target)
            .map(|i| p.x[i][0])
            .fold(f64::NEG_INFINITY, f64::max);
        let (mut sum, mut n) = (0.0, 0.0);
        for i in (0..p.n_real).filter(|&i| p.body[i] == target && p.x[i][0] > back - 0.5 * dp) {
            sum += p.v[i][0];
            n += 1.0;
        }
        free_face.push((sim.state.time, sum / n));
    }
    let p = &sim.particles;
    let failed_x0 = (0..p.n_real)
        .filter(|&i| p.body[i] == target && p.damage[i] >= 1.0)
        .map(|i| start[p.id[i] as usize])
        .collect();
    Ok(SpallRun {
        free_face,
        failed_x0,
        momentum_error,
    })
}

/// (u_max, the pull-back minimum after it): the plateau is the running maximum until the
/// velocity first falls 5 % below it; the minimum is the lowest velocity after that before
/// the spall's recompression brings the free face back up by a tenth of the drop.
pub fn pull_back(free_face: &[(f64, f64)]) -> (f64, f64) {
    let mut u_max = f64::NEG_INFINITY;
    let mut k = 0;
    while k < free_face.len() {
        let u = free_face[k].1;
        if u < 0.95 * u_max {
            break;
        }
        u_max = u_max.max(u);
        k += 1;
    }
    let mut u_min = u_max;
    for &(_, u) in &free_face[k.min(free_face.len())..] {
        u_min = u_min.min(u);
        if u > u_min + 0.1 * (u_max - u_min) {
            break;
        }
    }
    (u_max, u_min)
}

/// The converged solution of `examples/spall.toml` by an independent code,
/// `examples/spall_lagrangian_1d.py` (1D Lagrangian finite differences, the same EOS, strength
/// and spall strength, a cell failing the instant σ_xx passes σ_s) at 1 µm cells; 0.5–5 µm
/// cells give the same to 0.3 %: the free face's peak and pull-back minimum (m/s, as
/// [`pull_back`] reads them) and the spall plane, the failed cells' mean material coordinate
/// from the impact face (m).
pub const SPALL_LAGRANGIAN_1D: (f64, f64, f64) = (386.4, 265.3, 2.4625e-3);

/// The mean of the failed particles' material coordinates (where they started) along x, or
/// NaN when none failed: the spall plane. Their current places are no measure of it, since
/// the spalled layers open and fly apart at speeds that depend on how the cracks open.
pub fn spall_plane(run: &SpallRun) -> f64 {
    run.failed_x0.iter().sum::<f64>() / run.failed_x0.len() as f64
}

/// Spall (`examples/spall.toml`: Al 6061-T6, σ_s = 1.0 GPa, a 0.5 mm flyer at 400 m/s on a
/// 3 mm target), at Δp = 20 µm, and 10 µm with `fine`:
/// - the free-face pull-back gives back the set strength, ½ ρ0 c_L Δu_fs, within 10 %
///   (VALIDATION.md; the acoustic relation's speed is c_L: a 1 GPa decrement lies in the
///   elastic release range, see the test). The relation itself reads +4.9 % on the converged
///   independent solution, so this check bounds the relation's error and SPH's together;
/// - SPH's solution itself against the independent one ([`SPALL_LAGRANGIAN_1D`]): the free
///   face's peak and pull-back minimum within 10 % at 20 µm and 8 % at 10 µm (the test also
///   holds them converging), and the spall plane, the failed particles' mean material
///   coordinate, within 2 % (the acoustic estimate, one flyer thickness inside the free face,
///   is 2.5 mm). At 20 µm the kernel rounds the short peak off: −8.4 % since the material
///   update at the step's middle (2026-11-28; `integrate`), −5.6 % before, when the
///   whole-step update's negative damping sharpened the pulse.
pub fn spall(fine: bool) -> Result<Outcome> {
    let (rho0, sigma_s) = (2703.0, 1.0e9);
    let c0 = ((rho0 * 5240.0f64.powi(2) + 4.0 / 3.0 * 27.6e9) / rho0).sqrt();
    let (u_max_ref, u_min_ref, plane_ref) = SPALL_LAGRANGIAN_1D;
    let reference = "examples/spall_lagrangian_1d.py, 1 µm cells";
    let mut checks = Vec::new();
    let mut figures = Vec::new();
    let base = example("spall")?;
    let factors: &[f64] = if fine { &[1.0, 0.5] } else { &[1.0] };
    for &f in factors {
        let mut case = base.clone();
        for b in &mut case.bodies {
            b.spacing *= f;
        }
        let dp = case.bodies[1].spacing;
        let run = spall_run(&case)?;
        let (u_max, u_min) = pull_back(&run.free_face);
        let setting = format!("Δp = {} µm", dp * 1e6);
        let face_tolerance = if dp > 15e-6 { 0.10 } else { 0.08 };
        checks.push(
            Check::new(
                "spall strength from the pull-back",
                setting.clone(),
                0.5 * rho0 * c0 * (u_max - u_min),
                "Pa",
                "the deck's σ_s; ½ ρ0 c_L Δu_fs (Novikov et al. 1966)",
            )
            .within(sigma_s, 0.10),
        );
        checks.push(
            Check::new("free-face peak", setting.clone(), u_max, "m/s", reference)
                .within(u_max_ref, face_tolerance),
        );
        checks.push(
            Check::new(
                "free-face pull-back minimum",
                setting.clone(),
                u_min,
                "m/s",
                reference,
            )
            .within(u_min_ref, face_tolerance),
        );
        checks.push(
            Check::new(
                "spall plane (failed particles' material coordinate)",
                setting,
                spall_plane(&run),
                "m",
                reference,
            )
            .within(plane_ref, 0.02),
        );
        let t: Vec<f64> = run.free_face.iter().map(|r| r.0 * 1e6).collect();
        let u: Vec<f64> = run.free_face.iter().map(|r| r.1).collect();
        let expected_min = u_max - 2.0 * sigma_s / (rho0 * c0);
        figures.push(Figure {
            name: format!("free_face_{}um", (dp * 1e6).round()),
            x_label: "time (µs)".into(),
            x: t.clone(),
            panels: vec![(
                "free-face velocity (m/s)".into(),
                vec![
                    (format!("strike, Δp = {} µm", dp * 1e6), u),
                    (
                        "pull-back of σ_s (acoustic)".into(),
                        vec![expected_min; t.len()],
                    ),
                    ("1D Lagrangian peak".into(), vec![u_max_ref; t.len()]),
                    ("1D Lagrangian minimum".into(), vec![u_min_ref; t.len()]),
                ],
            )],
        });
    }
    Ok(Outcome { checks, figures })
}

/// With a coarser run's error in `previous`, a check that this finer run's `error` is no
/// larger (refinement does not move away from the answer); then `previous` becomes `error`.
fn converges(
    checks: &mut Vec<Check>,
    previous: &mut Option<f64>,
    error: f64,
    quantity: &str,
    setting: &str,
) {
    if let Some(e) = *previous {
        checks.push(
            Check::new(
                quantity,
                setting,
                error,
                "",
                "refinement does not move away from the answer",
            )
            .at_most(e),
        );
    }
    *previous = Some(error);
}

/// A Taylor-bar run at 80 µs, measured by [`taylor_measure`].
pub fn taylor_run(case: &Case) -> Result<TaylorRun> {
    let mut sim = Simulation::<3>::new(case)?;
    run_to(&mut sim, case.simulation.end_time)?;
    let dp = case.bodies[0].spacing;
    let p = &sim.particles;
    let ids: Vec<usize> = (0..p.n_real).filter(|&i| p.body[i] == 0).collect();
    let rod: Vec<[f64; 2]> = ids
        .iter()
        .map(|&i| [p.x[i][2], p.x[i][0].hypot(p.x[i][1])])
        .collect();
    let eps = ids.iter().map(|&i| p.eps_p[i]).fold(0.0, f64::max);
    Ok(TaylorRun {
        eps,
        ..taylor_measure(&rod, dp)
    })
}

/// A rod's final length, impact-face diameter and profile from its particles' (height z,
/// distance from the axis r) at spacing `dp` (m; `eps` is left 0). The rod runs from its foot's
/// level to its top's plus one spacing (each particle stands for a cell Δp across; the
/// flattened lowest layer makes it up to Δp/2 long). The face diameter is twice the largest r
/// within [`FACE_LAYER`] of the foot's level, plus one spacing. The profile is the largest
/// r + Δp/2 in bins of one spacing from the foot's level.
///
/// Each level is a [`LEVEL_QUANTILE`] of the particles within two spacings of the rod's end
/// (the lowest tenth for the foot), not that end's single particle: one particle off its layer
/// must not carry the measure with it. Until 2026-12-03 the foot was the lowest particle; at
/// R0/Δp = 16 the copper twin's (CN-SPH) lay 0.046 mm below the plane between the rods, 0.42 Δp
/// under the next, where the two faces undulate into each other near the axis, and its rim
/// 1.35 Δp above it fell out of the face: 14.02 mm read for the 14.29 of its layer (−2.07 %
/// of the wall's for −0.2 %).
pub fn taylor_measure(rod: &[[f64; 2]], dp: f64) -> TaylorRun {
    let mut z: Vec<f64> = rod.iter().map(|p| p[0]).collect();
    z.sort_by(f64::total_cmp);
    let (Some(&lowest), Some(&highest)) = (z.first(), z.last()) else {
        return TaylorRun::default();
    };
    // The LEVEL_QUANTILE of the heights within two spacings of an end, from that end.
    let level = |from_end: &mut dyn Iterator<Item = f64>, end: f64| {
        let near: Vec<f64> = from_end
            .take_while(|&v| (v - end).abs() < 2.0 * dp)
            .collect();
        near[(LEVEL_QUANTILE * (near.len() - 1) as f64).round() as usize]
    };
    let foot = level(&mut z.iter().copied(), lowest);
    let top = level(&mut z.iter().rev().copied(), highest);
    let r_face = rod
        .iter()
        .filter(|p| p[0] < foot + FACE_LAYER * dp)
        .map(|p| p[1])
        .fold(0.0, f64::max);
    let bins = ((highest - lowest) / dp).ceil() as usize + 1;
    let mut prof = vec![0.0_f64; bins];
    for p in rod {
        let k = (((p[0] - foot) / dp).floor().max(0.0) as usize).min(bins - 1);
        prof[k] = prof[k].max(p[1] + 0.5 * dp);
    }
    let profile = prof
        .iter()
        .enumerate()
        .map(|(k, r)| (foot + (k as f64 + 0.5) * dp, *r))
        .collect();
    TaylorRun {
        length: top - foot + dp,
        face: 2.0 * r_face + dp,
        eps: 0.0,
        profile,
    }
}

/// The quantile of the particles within two spacings of a rod's end that [`taylor_measure`]
/// takes for that end's level: the lowest tenth at the foot, the highest at the top. Within two
/// spacings of the foot lie two layers of the face, some 170 particles each at R0/Δp = 8 in
/// the quarter model, so a tenth lies inside the lowest layer and a few particles off it do
/// not move it.
pub const LEVEL_QUANTILE: f64 = 0.1;

/// How far above the foot's level [`taylor_measure`] looks for the face's rim, in spacings: one
/// whole spacing, the height of a particle's cell, so that the lowest layer's particles are in
/// it where the layer is not flat. Until 2026-11-29 it was 0.6 Δp, and a single particle
/// pressed onto the wall on the axis (the copper benchmark's on its `[[wall]]` at R0/Δp = 16,
/// 0.2 µm off it) put the rim, 0.68 Δp above that particle, out of reach: the face read
/// 14.02 mm for a rim at 14.40, and the walls' disagreement −1.95 % for −4.5 %. From 0.75 Δp
/// to 2 Δp the copper benchmark's three faces read the same at R0/Δp = 8 and 16.
pub const FACE_LAYER: f64 = 1.0;

/// What [`taylor_run`] measures (m).
#[derive(Clone, Debug, Default)]
pub struct TaylorRun {
    pub length: f64,
    pub face: f64,
    /// Peak plastic strain.
    pub eps: f64,
    /// (z, largest radius) in bins of one spacing.
    pub profile: Vec<(f64, f64)>,
}

/// The steel Taylor bar's published final length and impact-face diameter (m), the middles of
/// the finite-element results' ranges (26.52–26.56 and 11.15–11.22 mm).
const STEEL_BAR: (f64, f64) = (26.54e-3, 11.185e-3);
const STEEL_BAR_SOURCE: &str = "DynELA and Abaqus (Pantalé et al.), VALIDATION.md §F";

/// The steel bar's impact-face diameter (m) in `examples/taylor_fe_axisymmetric.py` on a wall
/// it may leave, as strike's: 11.343 / 11.377 / 11.390 mm at 0.4 / 0.2 / 0.1 mm elements, the
/// continuum's converged face, which a converging run approaches (the published 11.15–11.22
/// mm are 0.4 mm elements held on the plane; the same script reads 11.262 / 11.286 / 11.286 mm
/// so).
const STEEL_FACE_ON_THE_WALL: f64 = 11.390e-3;

/// The Taylor bar (`examples/taylor_bar.toml`): 42CrMo4 at 287 m/s onto a frictionless rigid
/// wall (`[[wall]]`), quarter model, with the tensor smoothing length and the artificial
/// stress, against the published finite-element results (DynELA and Abaqus): final length
/// 26.52–26.56 mm within 2 % and impact-face diameter 11.15–11.22 mm within 5 %, at R0/Δp = 8
/// and (`fine`) 16, the face's error against the converged face on the same wall
/// ([`STEEL_FACE_ON_THE_WALL`]) no larger at 16 than at 8. Measured 2026-12-05: 26.763 /
/// 26.560 / 26.569 mm and 11.256 / 11.295 / 11.529 mm at R0/Δp = 8 / 12 / 16, so that last
/// check fails narrowly (−1.18 / +1.22 %). With the round kernel the face moved away
/// with refinement, 10.747 / 11.725 / 12.531 mm at 8 / 16 / 24 (−3.9 / +4.8 / +12.0 % of the
/// published): the foot's lattice folds (README, "Large plastic flow"; docs/open-problems.md).
pub fn taylor(fine: bool) -> Result<Outcome> {
    let (length, face) = STEEL_BAR;
    let source = STEEL_BAR_SOURCE;
    let mut checks = Vec::new();
    let mut figures = Vec::new();
    let spacings: &[f64] = if fine { &[0.4e-3, 0.2e-3] } else { &[0.4e-3] };
    let mut previous = None;
    for &dp in spacings {
        let mut case = example("taylor_bar")?;
        case.bodies[0].spacing = dp;
        let TaylorRun {
            length: l,
            face: d,
            profile,
            ..
        } = taylor_run(&case)?;
        let ratio = (3.2e-3 / dp).round();
        let setting = format!("R0/Δp = {ratio}");
        checks.push(Check {
            quantity: "final length".into(),
            setting: setting.clone(),
            measured: l,
            reference: length,
            unit: "m",
            tolerance: 0.02,
            source,
            ..Default::default()
        });
        checks.push(Check {
            quantity: "impact-face diameter".into(),
            setting,
            measured: d,
            reference: face,
            unit: "m",
            tolerance: 0.05,
            source,
            ..Default::default()
        });
        converges(
            &mut checks,
            &mut previous,
            (d / STEEL_FACE_ON_THE_WALL - 1.0).abs(),
            "impact-face diameter error against the converged face on the same wall, finer against coarser",
            &format!("R0/Δp = {ratio}"),
        );
        let z: Vec<f64> = profile.iter().map(|r| r.0 * 1e3).collect();
        figures.push(Figure {
            name: format!("profile_r0_{ratio}"),
            x_label: "height above the wall (mm)".into(),
            x: z.clone(),
            panels: vec![(
                "radius at 80 µs (mm)".into(),
                vec![
                    (
                        format!("strike, R0/Δp = {ratio}"),
                        profile.iter().map(|r| r.1 * 1e3).collect(),
                    ),
                    ("FE face radius".into(), vec![0.5 * face * 1e3; z.len()]),
                    ("initial radius".into(), vec![3.2; z.len()]),
                ],
            )],
        });
    }
    Ok(Outcome { checks, figures })
}

/// A rod's profile: (height, radius) pairs from its face up.
type Profile = &'static [(f64, f64)];

/// Johnson & Cook's copper rods: impact speed (m/s), L_f/L0 and D_f/D0 as tabulated by Zerilli
/// & Armstrong (1987), and the recovered rod's profile, (height above the face, radius) in mm,
/// the 190 m/s rod digitised from Zerilli & Armstrong (1987, p. 1822), the others from Johnson
/// & Cook (1983, p. 546), by B. Banerjee (github.com/bbanerjee/HighRateExptData,
/// TaylorData/DAT), rounded to 1 µm.
const OFHC_RODS: [(f64, f64, f64, Profile); 3] = [
    (
        190.0,
        0.638,
        1.78,
        &[
            (0.0, 6.842),
            (0.584, 6.408),
            (1.137, 6.011),
            (1.657, 5.615),
            (2.014, 5.396),
            (3.214, 5.107),
            (4.061, 5.074),
            (5.782, 5.0),
            (7.536, 4.892),
            (8.639, 4.748),
            (9.970, 4.529),
            (11.464, 4.314),
            (12.797, 4.099),
            (13.868, 3.917),
            (15.005, 3.880),
            (16.205, 3.810),
        ],
    ),
    (
        146.0,
        0.736,
        1.40,
        &[
            (0.0, 5.147),
            (2.055, 4.716),
            (4.075, 4.664),
            (6.216, 4.620),
            (8.107, 4.514),
            (10.300, 4.391),
            (12.363, 4.215),
            (14.634, 4.039),
            (16.706, 3.907),
            (18.873, 3.810),
        ],
    ),
    (
        130.0,
        0.770,
        1.30,
        &[
            (0.0, 4.765),
            (2.067, 4.593),
            (4.099, 4.464),
            (6.037, 4.455),
            (8.181, 4.446),
            (10.075, 4.360),
            (12.012, 4.266),
            (13.993, 4.214),
            (15.818, 4.077),
            (17.755, 3.819),
            (19.649, 3.810),
        ],
    ),
];

/// A profile's radius at height z, linear between its points (its first below them, 0 above).
fn profile_at(profile: &[(f64, f64)], z: f64) -> f64 {
    match profile.iter().position(|p| p.0 >= z) {
        Some(0) => profile[0].1,
        Some(k) => {
            let (a, b) = (profile[k - 1], profile[k]);
            a.1 + (b.1 - a.1) * (z - a.0) / (b.0 - a.0)
        }
        None => 0.0,
    }
}

/// Johnson & Cook's copper rods in the continuum of the same model on the same wall
/// (`examples/taylor_fe_axisymmetric.py --material ofhc`, axisymmetric finite elements, a
/// frictionless wall the face may leave): final length and impact-face diameter (m) at 190,
/// 146 and 130 m/s with 32 elements across R0 (0.119 mm), measured 2026-12-06. With 8 / 16 /
/// 32 elements: lengths 17.320 / 17.340 / 17.355, 19.794 / 19.804 / 19.813 and 20.655 /
/// 20.662 / 20.669 mm; faces 14.532 / 14.670 / 14.744, 12.012 / 12.086 / 12.133 and 11.235 /
/// 11.294 / 11.325 mm, still widening by 0.3–0.6 % (extrapolated). Against the recovered
/// rods the model itself is 5.7–7.1 % long and 8.7–14.3 % wide: Johnson & Cook's constants on
/// a frictionless anvil, not the numerics.
const OFHC_RODS_ON_THE_WALL: [(f64, f64); 3] = [
    (17.355e-3, 14.744e-3),
    (19.813e-3, 12.133e-3),
    (20.669e-3, 11.325e-3),
];

/// Johnson & Cook's (1983) cylinder-impact tests of OFHC copper (`examples/taylor_ofhc.toml`:
/// L0 = 25.4 mm, D0 = 7.62 mm onto a hardened anvil, here the wall z = 0), with the
/// library's `ofhc_copper` and its Johnson–Cook constants from the same paper, failure off (the
/// recovered rods were whole). The tests as tabulated by Zerilli & Armstrong (1987, J. Appl.
/// Phys. 61, 1816): at 190, 146 and 130 m/s, final length L_f/L0 = 0.638, 0.736, 0.770 and
/// impact-face diameter D_f/D0 = 1.78, 1.40, 1.30 (B. Banerjee's compilation,
/// github.com/bbanerjee/HighRateExptData; its digitised profiles of the same rods read faces
/// 3.5–4 % narrower, the uncertainty of the face). The model was fitted to torsion and
/// Hopkinson-bar data, not to these rods, so the check is a prediction: the final length
/// within 12 % of the test's at the finest spacing.
///
/// Convergence is judged against the continuum of the same model on the same wall
/// ([`OFHC_RODS_ON_THE_WALL`]), not against the tests: that continuum is itself 5.7–7.1 % long
/// and 8.7–14.3 % wide of them, so a run that converges moves its face away from the test's
/// (until 2026-12-06 the faces at 146 and 130 m/s, widening with refinement past the tests',
/// were read as strike's error). Against the continuum the length is held within 5 % and the
/// face within 12 % at the finest spacing (8 % with `fine`), each error no larger than at the
/// coarser one; the faces against the tests are reported. Measured 2026-12-06 against the
/// continuum, R0/Δp = 8 / 16: lengths +6.8 / +2.6 %, +3.5 / +1.0 %, +2.7 / +0.6 % and faces
/// −14.3 / −5.9 %, −10.3 / −5.2 %, −8.7 / −4.8 % at 190 / 146 / 130 m/s (at 12, 190 m/s:
/// +3.7 % and −10.3 %). The figures draw each run's profile over the recovered rod's
/// (`OFHC_RODS`) and the continuum's face. Coarse: 190 m/s at R0/Δp = 8 and 12 (about a
/// minute and a half on 2 cores); `fine`: all three speeds at 8 and 16 (about ten minutes).
pub fn taylor_ofhc(fine: bool) -> Result<Outcome> {
    const L0: f64 = 25.4e-3;
    const D0: f64 = 7.62e-3;
    let source = "Johnson & Cook 1983 tests (Zerilli & Armstrong 1987)";
    let continuum = "axisymmetric finite elements, same model and wall (taylor_fe_axisymmetric.py)";
    let speeds = if fine { 3 } else { 1 };
    let ratios: &[f64] = if fine { &[8.0, 16.0] } else { &[8.0, 12.0] };
    let face_tolerance = if fine { 0.08 } else { 0.12 };
    let finest = ratios[ratios.len() - 1];
    let mut checks = Vec::new();
    let mut figures = Vec::new();
    for (&(speed, length, face, rod), &(fe_length, fe_face)) in
        OFHC_RODS.iter().zip(&OFHC_RODS_ON_THE_WALL).take(speeds)
    {
        let (mut prev_l, mut prev_d) = (None, None);
        let mut profiles = Vec::new();
        for &ratio in ratios {
            let mut case = example("taylor_ofhc")?;
            case.bodies[0].spacing = 0.5 * D0 / ratio;
            case.bodies[0].velocity = [0.0, 0.0, -speed];
            let r = taylor_run(&case)?;
            let s = format!("{speed} m/s, R0/Δp = {ratio}");
            let hold = |c: Check, want: f64, tol: f64| {
                if ratio == finest {
                    c.within(want, tol)
                } else {
                    c.reported(want)
                }
            };
            checks.push(hold(
                Check::new("final length", &s, r.length, "m", source),
                length * L0,
                0.12,
            ));
            checks.push(
                Check::new("impact-face diameter", &s, r.face, "m", source).reported(face * D0),
            );
            for (what, got, want, tol, previous) in [
                ("final length", r.length, fe_length, 0.05, &mut prev_l),
                (
                    "impact-face diameter",
                    r.face,
                    fe_face,
                    face_tolerance,
                    &mut prev_d,
                ),
            ] {
                checks.push(hold(
                    Check::new(
                        format!("{what} against the continuum"),
                        &s,
                        got,
                        "m",
                        continuum,
                    ),
                    want,
                    tol,
                ));
                converges(
                    &mut checks,
                    previous,
                    (got / want - 1.0).abs(),
                    &format!("{what} error against the continuum, finer against coarser"),
                    &s,
                );
            }
            profiles.push((ratio, r.profile));
        }
        // Every profile on the coarsest run's heights (mm).
        let z: Vec<f64> = profiles[0].1.iter().map(|r| r.0 * 1e3).collect();
        let mut series: Vec<(String, Vec<f64>)> = profiles
            .iter()
            .map(|(ratio, prof)| {
                let mm: Vec<(f64, f64)> = prof.iter().map(|b| (b.0 * 1e3, b.1 * 1e3)).collect();
                let radius = z.iter().map(|&zz| profile_at(&mm, zz)).collect();
                (format!("strike, R0/Δp = {ratio}"), radius)
            })
            .collect();
        series.push((
            "recovered rod (digitised)".into(),
            z.iter().map(|&zz| profile_at(rod, zz)).collect(),
        ));
        series.push((
            "test face radius".into(),
            vec![0.5 * face * D0 * 1e3; z.len()],
        ));
        series.push((
            "continuum face radius".into(),
            vec![0.5 * fe_face * 1e3; z.len()],
        ));
        series.push(("initial radius".into(), vec![0.5 * D0 * 1e3; z.len()]));
        figures.push(Figure {
            name: format!("profile_{speed}"),
            x_label: "height above the anvil (mm)".into(),
            x: z,
            panels: vec![(format!("radius at 80 µs, {speed} m/s (mm)"), series)],
        });
    }
    Ok(Outcome { checks, figures })
}

/// The Taylor bar of `deck` at `spacing` on its wall (the deck's `[[wall]]` z = 0) and on the
/// same wall made three more ways: a symmetry plane, the rod meeting its mirror twin through
/// the contact, and a fixed steel body four spacings thick through the contact.
pub fn taylor_variants(deck: &str, spacing: f64) -> Result<Vec<(&'static str, Case)>> {
    let mut wall = example(deck)?;
    wall.bodies[0].spacing = spacing;
    if !wall.symmetry.iter().any(|s| s.wall && s.axis == 2) {
        return Err(Error::Invalid(format!("{deck}: no wall z = 0")));
    }
    let mut sym = wall.clone();
    for s in &mut sym.symmetry {
        s.wall = false;
    }
    let mut twin = wall.clone();
    twin.symmetry.retain(|s| s.axis != 2);
    let mut other = twin.bodies[0].clone();
    other.name = "twin".into();
    other.velocity[2] = -other.velocity[2];
    match &mut other.shape {
        crate::case::Shape::Cylinder { base, length, .. } => base[2] = -*length,
        _ => return Err(Error::Invalid(format!("{deck}: the rod is not a cylinder"))),
    }
    twin.bodies.push(other);
    let mut fixed = twin.clone();
    fixed.bodies[1] = crate::case::BodySpec {
        name: "wall".into(),
        velocity: [0.0; 3],
        motion: crate::case::Motion::Prescribed,
        shape: crate::case::Shape::Box {
            min: [0.0, 0.0, -4.0 * spacing],
            max: [9.0e-3, 9.0e-3, 0.0],
        },
        ..twin.bodies[1].clone()
    };
    Ok(vec![
        ("wall", wall),
        ("symmetry plane", sym),
        ("twin", twin),
        ("fixed wall", fixed),
    ])
}

/// The round kernel of the decks' defaults, without the artificial stress: the walls were
/// measured so in CN-SPH (2026-12-04), before `examples/taylor_bar.toml` took the ellipsoid
/// and the artificial stress (2026-12-05) and before CN-SPH took the ellipsoid (2026-12-06);
/// with it they have not been measured.
fn round_kernel(case: &mut Case) {
    case.simulation.tensor_smoothing = false;
    case.simulation.smoothing_stretch = 1.25;
    for m in &mut case.materials {
        m.artificial_stress = None;
    }
}

/// The walls and the copper bar (VALIDATION.md §F, issue 13 items 5 and 6): the steel bar
/// (`examples/taylor_bar.toml`) and the copper one with linear hardening
/// (`examples/taylor_copper.toml`, 227 m/s; the benchmark of Kamoulakos 1990, Zhu & Cescotto
/// 1995, Camacho & Ortiz 1997: final length 21.42–21.47 mm, mushroom diameter 14.0–14.4 mm).
///
/// The walls are compared in CN-SPH: each bar on its `[[wall]]`, against its twin through the
/// contact and on a fixed wall through the contact agree within 2 % in final length and face
/// diameter at R0/Δp = 16 (`fine`), and the face's disagreement does not grow with
/// refinement; at 8 the figures are reported. CN-SPH's contact acts along the face's normal
/// (`contact::colour::normal`), and through it the faces came out within 1.1 % of the wall's
/// at 16 (by hand, 2026-12-02 and 03) while the wall met the foot wherever a pair closed within
/// the support. Met from touching (`boundary::wall_share`, 2026-12-04) the wall's faces are
/// wider and the steel twin's face reads −3.19 / −2.77 % of the wall's at R0/Δp = 8 / 16 (by
/// hand, the same functions): **the steel bar fails the 2 % at 16** (README, Not yet).
/// Conventional SPH's contact does worse: its tangential part pushes the rim of a face
/// inwards, the copper twin's face −4.5 % of the wall's and the fixed wall's −4.9 % at 16
/// (2026-11-29; README, Not yet), so it is not the formulation to compare walls in. On a
/// symmetry plane, held the same way: the rod moves into it, so the plane meets it as the
/// wall (`boundary`) and the runs are the same to the bit. Until 2026-12-04 a symmetry plane
/// also pulled, held the face in tension where the radial release meets on the axis, and read
/// faces 3.2–3.9 % narrower than the wall's at R0/Δp = 8 and 16.
///
/// The copper bar against the published results is run in conventional SPH on its wall
/// (length within 4 % and face within 5 % at R0/Δp = 16, reported at 8): CN-SPH's rod comes
/// out +4.4 % long there. About 12 minutes at R0/Δp = 8 and three hours more with
/// `fine` on 2 cores.
pub fn taylor_walls(fine: bool) -> Result<Outcome> {
    let copper = (21.445e-3, 14.2e-3);
    let source = "Kamoulakos 1990; Zhu & Cescotto 1995; Camacho & Ortiz 1997";
    let mut checks = Vec::new();
    let spacings: &[f64] = if fine { &[0.4e-3, 0.2e-3] } else { &[0.4e-3] };
    for (deck, published, cited) in [
        ("taylor_bar", STEEL_BAR, STEEL_BAR_SOURCE),
        ("taylor_copper", copper, source),
    ] {
        // Each variant's face disagreement at the coarser spacing, for the convergence check
        // (the variants come in the same order at every spacing).
        let mut previous: Vec<Option<f64>> = Vec::new();
        for &dp in spacings {
            let ratio = (3.2e-3 / dp).round();
            let held = ratio >= 16.0;
            let variants = taylor_variants(deck, dp)?;
            if deck == "taylor_copper" {
                let (label, case) = &variants[0];
                let r = taylor_run(case)?;
                let s = format!("{deck}, {label}, conventional SPH, R0/Δp = {ratio}");
                for (what, got, want, tol) in [
                    ("final length", r.length, copper.0, 0.04),
                    ("impact-face diameter", r.face, copper.1, 0.05),
                ] {
                    let c = Check::new(what, &s, got, "m", source);
                    checks.push(if held {
                        c.within(want, tol)
                    } else {
                        c.reported(want)
                    });
                }
            }
            previous.resize(variants.len(), None);
            let mut on_wall = None;
            for (k, (label, mut case)) in variants.into_iter().enumerate() {
                case.simulation.formulation = Formulation::Corrected;
                round_kernel(&mut case);
                let r = taylor_run(&case)?;
                let s = format!("{deck}, {label}, CN-SPH, R0/Δp = {ratio}");
                let Some((l0, d0)) = on_wall else {
                    on_wall = Some((r.length, r.face));
                    for (what, got, want) in [
                        ("final length", r.length, published.0),
                        ("impact-face diameter", r.face, published.1),
                    ] {
                        checks.push(Check::new(what, &s, got, "m", cited).reported(want));
                    }
                    continue;
                };
                let walls = "the same wall three ways (VALIDATION.md §F)";
                for (what, got, want) in [
                    ("final length against the wall's", r.length, l0),
                    ("face diameter against the wall's", r.face, d0),
                ] {
                    let c = Check::new(what, &s, got, "m", walls);
                    checks.push(if held {
                        c.within(want, 0.02)
                    } else {
                        c.reported(want)
                    });
                }
                converges(
                    &mut checks,
                    &mut previous[k],
                    (r.face / d0 - 1.0).abs(),
                    "face diameter against the wall's, finer against coarser",
                    &s,
                );
            }
        }
    }
    Ok(Outcome {
        checks,
        figures: Vec::new(),
    })
}

/// A case's result as the report holds it.
pub struct CaseReport {
    pub name: &'static str,
    pub title: &'static str,
    /// The checks, or why the case could not run.
    pub outcome: std::result::Result<Outcome, String>,
    /// The figures' files, relative to the report.
    pub images: Vec<String>,
}

impl CaseReport {
    /// Every check within its tolerance (times `factor`), and the case ran.
    pub fn passes(&self, factor: f64) -> bool {
        self.outcome
            .as_ref()
            .is_ok_and(|o| o.checks.iter().all(|c| c.passes(factor)))
    }
}

/// Runs the cases named (all if empty), draws their figures into `out_dir`.
pub fn run(names: &[String], fine: bool, out_dir: &Path) -> Result<Vec<CaseReport>> {
    let all = cases();
    for n in names {
        if !all.iter().any(|c| c.name == n) {
            let known: Vec<&str> = all.iter().map(|c| c.name).collect();
            return Err(Error::Invalid(format!(
                "no verification case `{n}` (the cases are {})",
                known.join(", ")
            )));
        }
    }
    std::fs::create_dir_all(out_dir).map_err(|e| Error::io(out_dir, e))?;
    let mut reports = Vec::new();
    for c in all
        .iter()
        .filter(|c| names.is_empty() || names.iter().any(|n| n == c.name))
    {
        tracing::info!(
            "validating {} ({})",
            c.name,
            if fine { "fine" } else { "coarse" }
        );
        let outcome = (c.run)(fine).map_err(|e| e.to_string());
        let mut images = Vec::new();
        if let Ok(o) = &outcome {
            for f in &o.figures {
                let file = format!("{}_{}.png", c.name, f.name);
                let panels: Vec<picture::HistoryPanel<'_>> = f
                    .panels
                    .iter()
                    .map(|(label, series)| {
                        (
                            label.as_str(),
                            series
                                .iter()
                                .map(|(n, v)| (n.as_str(), v.clone()))
                                .collect(),
                        )
                    })
                    .collect();
                picture::plot_lines(&out_dir.join(&file), &f.x_label, &f.x, &panels, false)?;
                images.push(file);
            }
        }
        reports.push(CaseReport {
            name: c.name,
            title: c.title,
            outcome,
            images,
        });
    }
    Ok(reports)
}

/// A figure in its unit, shortest readable form.
fn show(x: f64, unit: &str) -> String {
    let (v, u) = match unit {
        "Pa" if x.abs() >= 1e8 => (x / 1e9, "GPa"),
        "Pa" => (x / 1e6, "MPa"),
        "m" => (x * 1e3, "mm"),
        "s" if x.abs() < 1e-2 => (x * 1e6, "µs"),
        "N" if x.abs() >= 1e3 => (x * 1e-3, "kN"),
        u => (x, u),
    };
    let number = if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e7) {
        format!("{v:.2e}")
    } else {
        format!("{v:.4}")
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string()
    };
    format!("{number} {u}").trim_end().to_string()
}

/// The table of every check: case, quantity, setting, measured, reference, error, tolerance,
/// pass — the README's verification summary and the report's table.
pub fn table(reports: &[CaseReport], factor: f64) -> String {
    let mut s = String::from(
        "| case | quantity | setting | measured | reference | error | tolerance | |\n|---|---|---|---|---|---|---|---|\n",
    );
    for r in reports {
        match &r.outcome {
            Ok(o) => {
                for c in &o.checks {
                    let _ = writeln!(
                        s,
                        "| {} | {} | {} | {} | {} | {} | {} | {} |",
                        r.name,
                        cell(&c.quantity),
                        cell(&c.setting),
                        show(c.measured, c.unit),
                        show(c.reference, c.unit),
                        c.error_text(),
                        c.tolerance_text(factor),
                        c.verdict(factor)
                    );
                }
            }
            Err(e) => {
                let _ = writeln!(
                    s,
                    "| {} | – | – | – | – | – | – | **FAIL**: {} |",
                    r.name,
                    e.replace('|', "/")
                );
            }
        }
    }
    s
}

/// The README's verification summary: one row per case and quantity, every setting's figure
/// side by side (so two resolutions read as a convergence study), the reference, the
/// tolerance and the verdict over them all. The full table is [`table`]'s.
pub fn summary(reports: &[CaseReport], factor: f64) -> String {
    let mut s = String::from(
        "| case | quantity | reference | tolerance | measured (error) | |\n|---|---|---|---|---|---|\n",
    );
    for r in reports {
        let o = match &r.outcome {
            Ok(o) => o,
            Err(e) => {
                let _ = writeln!(
                    s,
                    "| {} | – | – | – | – | **FAIL**: {} |",
                    r.name,
                    e.replace('|', "/")
                );
                continue;
            }
        };
        let mut groups: Vec<(&str, Bound, Vec<&Check>)> = Vec::new();
        for c in &o.checks {
            match groups
                .iter_mut()
                .find(|g| g.0 == c.quantity && g.1 == c.bound)
            {
                Some(g) => g.2.push(c),
                None => groups.push((&c.quantity, c.bound, vec![c])),
            }
        }
        for (quantity, _, checks) in groups {
            let first = checks[0];
            let same_reference = checks.iter().all(|c| c.reference == first.reference);
            let same_tolerance = checks
                .iter()
                .all(|c| c.tolerance_text(factor) == first.tolerance_text(factor));
            let figures: Vec<String> = checks
                .iter()
                .map(|c| {
                    let mut f = format!("{}: {}", cell(&c.setting), show(c.measured, c.unit));
                    let err = c.error_text();
                    if err != "–" {
                        let _ = write!(f, " ({err})");
                    }
                    if !same_reference {
                        let _ = write!(f, " against {}", show(c.reference, c.unit));
                    }
                    if !same_tolerance {
                        let _ = write!(f, ", {}", c.tolerance_text(factor));
                    }
                    if c.bound == Bound::Reported {
                        f.push_str(", not held");
                    } else if !c.passes(factor) {
                        f.push_str(", **FAIL**");
                    }
                    f
                })
                .collect();
            let verdict = if checks.iter().all(|c| c.bound == Bound::Reported) {
                "reported"
            } else if checks.iter().all(|c| c.passes(factor)) {
                "pass"
            } else {
                "**FAIL**"
            };
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} |",
                r.name,
                cell(quantity),
                if same_reference {
                    show(first.reference, first.unit)
                } else {
                    "see each".into()
                },
                if same_tolerance {
                    first.tolerance_text(factor)
                } else {
                    "see each".into()
                },
                figures.join("; "),
                verdict
            );
        }
    }
    s
}

/// Writes `report.md` (the table, each case's references and figures) and `report.html` (the
/// same, its pictures inside it) into `out_dir`.
pub fn write_report(reports: &[CaseReport], fine: bool, factor: f64, out_dir: &Path) -> Result<()> {
    let resolution = if fine {
        "fine (the README's resolutions)"
    } else {
        "coarse"
    };
    let passed = reports.iter().filter(|r| r.passes(factor)).count();
    let mut md = format!(
        "# strike validation report\n\nstrike {}, {resolution}: {passed} of {} cases pass.\n\n{}\n",
        env!("CARGO_PKG_VERSION"),
        reports.len(),
        table(reports, factor)
    );
    let mut html = format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>strike validation report</title>\n<style>body{{font-family:sans-serif;max-width:70em;margin:auto}}table{{border-collapse:collapse}}td,th{{border:1px solid #bbb;padding:2px 6px}}.fail{{color:#b00;font-weight:bold}}img{{max-width:100%}}</style></head><body>\n<h1>strike validation report</h1>\n<p>strike {}, {resolution}: {passed} of {} cases pass.</p>\n<table><tr><th>case</th><th>quantity</th><th>setting</th><th>measured</th><th>reference</th><th>error</th><th>tolerance</th><th></th></tr>\n",
        env!("CARGO_PKG_VERSION"),
        reports.len()
    );
    for r in reports {
        let _ = writeln!(md, "## {}\n\n{}\n", r.name, r.title);
        match &r.outcome {
            Ok(o) => {
                for c in &o.checks {
                    let _ = writeln!(
                        md,
                        "- {} ({}): {} against {} (error {}, tolerance {}, {}); reference: {}",
                        c.quantity,
                        c.setting,
                        show(c.measured, c.unit),
                        show(c.reference, c.unit),
                        c.error_text(),
                        c.tolerance_text(factor),
                        c.verdict(factor).trim_matches('*'),
                        c.source
                    );
                    let _ = writeln!(
                        html,
                        "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td{}>{}</td></tr>",
                        escape(r.name),
                        escape(&c.quantity),
                        escape(&c.setting),
                        escape(&show(c.measured, c.unit)),
                        escape(&show(c.reference, c.unit)),
                        escape(&c.error_text()),
                        escape(&c.tolerance_text(factor)),
                        if c.passes(factor) { "" } else { " class=\"fail\"" },
                        c.verdict(factor).trim_matches('*')
                    );
                }
            }
            Err(e) => {
                let _ = writeln!(md, "**The case failed to run**: {e}");
                let _ = writeln!(
                    html,
                    "<tr><td>{}</td><td colspan=\"6\">{}</td><td class=\"fail\">FAIL</td></tr>",
                    escape(r.name),
                    escape(e)
                );
            }
        }
        md.push('\n');
        for img in &r.images {
            let _ = writeln!(md, "![{img}]({img})\n");
        }
    }
    html.push_str("</table>\n");
    for r in reports {
        let _ = writeln!(
            html,
            "<h2>{}</h2>\n<p>{}</p>",
            escape(r.name),
            escape(r.title)
        );
        for img in &r.images {
            let bytes =
                std::fs::read(out_dir.join(img)).map_err(|e| Error::io(out_dir.join(img), e))?;
            use base64::Engine as _;
            let _ = writeln!(
                html,
                "<p><img alt=\"{}\" src=\"data:image/png;base64,{}\"></p>",
                escape(img),
                base64::engine::general_purpose::STANDARD.encode(bytes)
            );
        }
    }
    html.push_str("</body></html>\n");
    atomic::write(&out_dir.join("report.md"), md.as_bytes())?;
    atomic::write(&out_dir.join("report.html"), html.as_bytes())
}

/// Text for a Markdown table's cell: a `|` would end it.
fn cell(s: &str) -> String {
    s.replace('|', "\\|")
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The README's text with its generated verification summary (between the markers
/// `<!-- strike validate: begin -->` and `<!-- strike validate: end -->`) replaced by `table`.
pub fn replace_readme_block(readme: &str, table: &str, note: &str) -> Result<String> {
    const BEGIN: &str = "<!-- strike validate: begin -->";
    const END: &str = "<!-- strike validate: end -->";
    let (Some(a), Some(b)) = (readme.find(BEGIN), readme.find(END)) else {
        return Err(Error::Invalid(format!(
            "the README has no `{BEGIN}` … `{END}` block to write the table into"
        )));
    };
    if b < a {
        return Err(Error::Invalid(format!(
            "`{END}` comes before `{BEGIN}` in the README"
        )));
    }
    Ok(format!(
        "{}{BEGIN}\n{note}\n\n{table}{}",
        &readme[..a],
        &readme[b..]
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(measured: f64) -> Check {
        Check::new("q", "s", measured, "m", "src")
    }

    /// The Rayleigh-line state: a fluid's is the Mie–Grüneisen Hugoniot's jump (U_s = C + S1
    /// u_p), and with von Mises the deviator ends on Y0 with σ_xx = p + ⅔ Y0 on the line.
    #[test]
    fn rayleigh_line_state_is_the_jump() {
        let case = example("shocked_strength").unwrap();
        let mut spec = case.materials[case.bodies[1].material].clone();
        let up = 800.0;
        let (c0, s1) = (5240.0, 1.40);
        spec.strength = StrengthSpec::Hydrodynamic;
        let fluid = crate::material::Material::from_spec(&spec);
        let (eta, p, vm, eps) = rayleigh_line_state(&fluid, up);
        let us = c0 + s1 * up;
        assert!((eta / (us / (us - up)) - 1.0).abs() < 1e-6, "{eta}");
        assert!((p / (2703.0 * us * up) - 1.0).abs() < 1e-6, "{p}");
        assert_eq!((vm, eps), (0.0, 0.0));
        spec.strength = StrengthSpec::VonMises {
            shear_modulus: 27.6e9,
            yield_stress: 0.29e9,
            hardening_modulus: 0.0,
        };
        let solid = crate::material::Material::from_spec(&spec);
        let (eta, p, vm, eps) = rayleigh_line_state(&solid, up);
        assert!((vm / 0.29e9 - 1.0).abs() < 1e-9, "{vm}");
        let us = up * eta / (eta - 1.0);
        let sxx = p + vm / 1.5;
        assert!((sxx / (2703.0 * us * up) - 1.0).abs() < 1e-4, "{sxx}");
        assert!(eps > 0.05 && eps < (2.0 / 3.0) * eta.ln(), "{eps}");
    }

    /// Each bound holds what it says, the factor loosens a positive limit and leaves a zero
    /// one, and a reported figure always passes.
    #[test]
    fn bounds_and_the_tolerance_factor() {
        assert!(check(1.04).within(1.0, 0.05).passes(1.0));
        assert!(!check(1.06).within(1.0, 0.05).passes(1.0));
        assert!(check(1.06).within(1.0, 0.05).passes(2.0));
        assert!(check(0.01).at_most(0.01).passes(1.0));
        assert!(!check(0.011).at_most(0.01).passes(1.0));
        assert!(check(0.011).at_most(0.01).passes(2.0));
        assert!(!check(1e-30).at_most(0.0).passes(1e6));
        assert!(check(0.0).at_most(0.0).passes(1.0));
        assert!(check(0.5).at_least(0.5).passes(1.0));
        assert!(!check(0.4).at_least(0.5).passes(1.0));
        assert!(check(0.4).at_least(0.5).passes(2.0));
        assert!(!check(-1e-30).at_least(0.0).passes(1e6));
        let r = check(2.0).reported(1.0);
        assert!(r.passes(1.0));
        assert_eq!(r.verdict(1.0), "reported");
        assert_eq!(check(0.2).at_most(0.1).verdict(1.0), "**FAIL**");
        assert_eq!(check(1.0).at_most(0.01).tolerance_text(2.0), "≤ 20 mm");
        assert_eq!(check(1.0).at_most(0.01).error_text(), "–");
        assert_eq!(check(1.1).within(1.0, 0.05).error_text(), "+10.00 %");
    }

    /// The summary puts one row per case and quantity with each setting's figure; a failing
    /// setting fails its row and is marked where it stands.
    #[test]
    fn the_summary_groups_settings_and_names_a_failure() {
        let mut a = Check::new("length", "R/Δp = 8", 1.01, "m", "src").within(1.0, 0.02);
        let mut b = a.clone();
        b.setting = "R/Δp = 16".into();
        b.measured = 1.03;
        a.quantity = "length".into();
        let c = Check::new("gap", "R/Δp = 8", 0.6, "Δp", "src").at_least(0.5);
        let report = CaseReport {
            name: "demo",
            title: "t",
            outcome: Ok(Outcome {
                checks: vec![a, b, c],
                figures: Vec::new(),
            }),
            images: Vec::new(),
        };
        let s = summary(&[report], 1.0);
        let rows: Vec<&str> = s.lines().skip(2).collect();
        assert_eq!(rows.len(), 2, "{s}");
        assert_eq!(
            rows[0],
            "| demo | length | 1000 mm | 2 % | R/Δp = 8: 1010 mm (+1.00 %); R/Δp = 16: 1030 mm (+3.00 %), **FAIL** | **FAIL** |"
        );
        assert_eq!(
            rows[1],
            "| demo | gap | 0.5 Δp | ≥ 0.5 Δp | R/Δp = 8: 0.6 Δp | pass |"
        );
    }
}
