//! `strike bench`: fixed built-in cases run for a fixed number of steps after a warm-up, on one
//! thread and on all cores, reporting particle-steps/s, particle-neighbour interactions/s per
//! core, mean neighbours and peak memory per particle. Also written to `bench.json`. Under
//! `mpirun` (the `mpi` feature) each case runs on all the ranks with one thread each, and the
//! share of the time spent in the exchanges between ranks is reported. After each case, the
//! halo a domain decomposition would exchange a step (`ranks::Halo`): under MPI each rank's
//! own; on one process for splits into 2 to 1000 ranks along the run's cell order and along
//! Morton's curve (the evidence for the weak-scaling model in the README).

use crate::deck;
use crate::error::{Error, Result};
use crate::ranks::{Curve, Ranks};
use crate::simulation::Simulation;
use serde::Serialize;
use std::time::Instant;

/// One measured case at one thread count.
#[derive(Debug, Clone, Serialize)]
pub struct BenchCase {
    pub name: String,
    pub dimension: usize,
    pub particles: usize,
    /// Threads of each rank.
    pub threads: usize,
    /// MPI ranks (1 without MPI).
    pub ranks: usize,
    pub steps: u64,
    pub wall_seconds: f64,
    pub particle_steps_per_second: f64,
    /// Each particle's neighbours counted once per step (the one pass of a step); the cores
    /// are threads × ranks.
    pub interactions_per_second_per_core: f64,
    /// Share of the wall time the root rank spent in the exchanges between ranks (0 on one).
    pub exchange_share: f64,
    pub mean_neighbors: f64,
    /// Peak resident memory while the case ran (set up + steps), whole process (bytes).
    pub peak_rss_bytes: u64,
    /// Growth of the peak resident memory over the process before the case, per particle.
    pub bytes_per_particle: f64,
    /// What `strike check` estimates per particle for the same deck, for comparison.
    pub estimated_bytes_per_particle: f64,
    /// The halos a domain decomposition would exchange at the end of the timed steps: under
    /// MPI the run's own ranks', on one process splits of its lists into several ranks.
    pub halos: Vec<HaloFigure>,
    /// Where each rank's time went over the timed steps (one entry on one process).
    pub phases: Vec<crate::simulation::PhaseSeconds>,
}

/// The halos of one split into ranks (see [`crate::ranks::Halo`]).
#[derive(Debug, Clone, Serialize)]
pub struct HaloFigure {
    pub ranks: usize,
    /// The order the ranks' ranges are taken along.
    pub curve: Curve,
    /// Whether these are the ranks of the run itself (MPI), not a split of one process's
    /// lists into ranges along `curve`, balanced as a run on that many ranks balances them.
    pub actual: bool,
    pub particles_per_rank: f64,
    /// Halo particles over a rank's own: mean and largest over the ranks.
    pub halo_share_mean: f64,
    pub halo_share_max: f64,
    /// Ranks a rank's halo comes from (its messages a step): mean and largest.
    pub neighbour_ranks_mean: f64,
    pub neighbour_ranks_max: usize,
}

impl HaloFigure {
    fn of(halos: &[crate::ranks::Halo], curve: Curve, actual: bool) -> Option<HaloFigure> {
        let r = halos.len();
        let share = |h: &crate::ranks::Halo| h.halo as f64 / h.own.max(1) as f64;
        (r > 0).then(|| HaloFigure {
            ranks: r,
            curve,
            actual,
            particles_per_rank: halos.iter().map(|h| h.own).sum::<usize>() as f64 / r as f64,
            halo_share_mean: halos.iter().map(share).sum::<f64>() / r as f64,
            halo_share_max: halos.iter().map(share).fold(0.0, f64::max),
            neighbour_ranks_mean: halos.iter().map(|h| h.neighbour_ranks).sum::<usize>() as f64
                / r as f64,
            neighbour_ranks_max: halos.iter().map(|h| h.neighbour_ranks).max().unwrap_or(0),
        })
    }
}

#[derive(Debug, Clone, Serialize)]
pub struct BenchReport {
    pub cases: Vec<BenchCase>,
}

/// Two elastic aluminium cubes (20³ particles each, h = 1.2 Δp) colliding head-on at ±50 m/s.
pub const CUBES_3D: &str = r#"
[simulation]
name = "cubes_3d"
dimension = 3
end_time = 1.0
[materials.al]
density = 2700.0
eos = { type = "linear" }
strength = { type = "elastic", youngs_modulus = 68.9e9, poissons_ratio = 0.33 }
[[body]]
name = "left"
material = "al"
spacing = 1.0e-3
velocity = [50.0, 0.0, 0.0]
shape = { type = "box", min = [-0.02, 0.0, 0.0], max = [0.0, 0.02, 0.02] }
[[body]]
name = "right"
material = "al"
spacing = 1.0e-3
velocity = [-50.0, 0.0, 0.0]
shape = { type = "box", min = [0.001, 0.0, 0.0], max = [0.021, 0.02, 0.02] }
"#;

/// Two 2D elastic plates (200 × 50 particles each) colliding head-on.
pub const PLATES_2D: &str = r#"
[simulation]
name = "plates_2d"
dimension = 2
end_time = 1.0
[materials.al]
density = 2700.0
eos = { type = "linear" }
strength = { type = "elastic", youngs_modulus = 68.9e9, poissons_ratio = 0.33 }
[[body]]
name = "left"
material = "al"
spacing = 1.0e-4
velocity = [50.0, 0.0]
shape = { type = "rectangle", min = [-0.02, 0.0], max = [0.0, 0.005] }
[[body]]
name = "right"
material = "al"
spacing = 1.0e-4
velocity = [-50.0, 0.0]
shape = { type = "rectangle", min = [0.0001, 0.0], max = [0.0201, 0.005] }
"#;

/// A cube of `n`³ particles of the 3D cube material, for the memory and scaling figures.
pub fn cube_deck(n: usize) -> String {
    let l = n as f64 * 1e-3;
    format!(
        r#"
[simulation]
name = "cube_{n}"
dimension = 3
end_time = 1.0
[materials.al]
density = 2700.0
eos = {{ type = "linear" }}
strength = {{ type = "elastic", youngs_modulus = 68.9e9, poissons_ratio = 0.33 }}
[[body]]
name = "cube"
material = "al"
spacing = 1.0e-3
velocity = [10.0, 0.0, 0.0]
shape = {{ type = "box", min = [0.0, 0.0, 0.0], max = [{l}, {l}, {l}] }}
"#
    )
}

/// The sphere-plate demo deck at its default resolution.
pub const SPHERE_PLATE: &str = include_str!("../examples/sphere_plate.toml");

/// Peak and current resident memory of the process (VmHWM, VmRSS), bytes (0 where unknown).
fn rss() -> (u64, u64) {
    (
        crate::machine::peak_resident_memory().unwrap_or(0),
        crate::machine::resident_memory().unwrap_or(0),
    )
}

/// Reset the peak-RSS counter to the current RSS (Linux ≥ 4.0; ignored elsewhere).
fn reset_peak() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// Measure one deck at one thread count (of each of `ranks`): `warmup` steps, then `steps`
/// timed steps; then the halos of `census` ranks each (on one process; under MPI the run's
/// own, whatever `census` holds, unless it is empty).
pub fn measure(
    text: &str,
    label: &str,
    (threads, ranks): (usize, Ranks),
    (warmup, steps): (u64, u64),
    census: &[usize],
) -> Result<BenchCase> {
    let case = deck::parse(text, label)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error::Invalid(format!("cannot start {threads} threads: {e}")))?;
    crate::machine::release_free_memory();
    reset_peak();
    let (_, base) = rss();
    pool.install(|| match case.dimension {
        2 => measure_dim::<2>(&case, (threads, ranks), (warmup, steps), census, base),
        _ => measure_dim::<3>(&case, (threads, ranks), (warmup, steps), census, base),
    })
}

fn measure_dim<const D: usize>(
    case: &crate::case::Case,
    (threads, ranks): (usize, Ranks),
    (warmup, steps): (u64, u64),
    census: &[usize],
    base_rss: u64,
) -> Result<BenchCase> {
    let mut sim = Simulation::<D>::new(case)?;
    sim.distribute(ranks);
    for _ in 0..warmup {
        sim.step(f64::INFINITY)?;
    }
    let exchanged = sim.exchange_seconds();
    let before = sim.phase_seconds();
    let start = Instant::now();
    let mut interactions = 0u64;
    for _ in 0..steps {
        interactions += sim.step(f64::INFINITY)?.interactions as u64;
    }
    let wall = start.elapsed().as_secs_f64();
    let after = sim.phase_seconds();
    let each =
        |f: fn(&crate::simulation::PhaseSeconds) -> f64| ranks.gather_each(f(&after) - f(&before));
    let (search, passes, exchanges) = (
        each(|s| s.search),
        each(|s| s.passes),
        each(|s| s.exchanges),
    );
    let phases = (0..ranks.size())
        .map(|r| crate::simulation::PhaseSeconds {
            search: search[r],
            passes: passes[r],
            exchanges: exchanges[r],
        })
        .collect();
    let n = sim.particles.n_real;
    let (peak, _) = rss();
    let halos = if census.is_empty() {
        Vec::new()
    } else if ranks.size() > 1 {
        let own = sim.own_halo();
        let each = |v: usize| ranks.gather_each(v as f64);
        let (own_all, halo_all, from_all) =
            (each(own.own), each(own.halo), each(own.neighbour_ranks));
        let all: Vec<crate::ranks::Halo> = (0..ranks.size())
            .map(|r| crate::ranks::Halo {
                own: own_all[r] as usize,
                halo: halo_all[r] as usize,
                neighbour_ranks: from_all[r] as usize,
            })
            .collect();
        HaloFigure::of(&all, Curve::Cells, true)
            .into_iter()
            .collect()
    } else {
        [Curve::Cells, Curve::Morton]
            .into_iter()
            .flat_map(|curve| census.iter().map(move |&r| (curve, r)))
            .filter_map(|(curve, r)| HaloFigure::of(&sim.halo_census(r, curve), curve, false))
            .collect()
    };
    Ok(BenchCase {
        name: case.name.clone(),
        dimension: D,
        particles: n,
        threads,
        ranks: ranks.size(),
        steps,
        wall_seconds: wall,
        particle_steps_per_second: (n as u64 * steps) as f64 / wall,
        interactions_per_second_per_core: interactions as f64
            / wall
            / (threads * ranks.size()) as f64,
        exchange_share: (sim.exchange_seconds() - exchanged) / wall,
        mean_neighbors: interactions as f64 / (n as u64 * steps) as f64,
        peak_rss_bytes: peak,
        bytes_per_particle: peak.saturating_sub(base_rss) as f64 / n as f64,
        estimated_bytes_per_particle: crate::particles::estimated_bytes(
            n as f64,
            crate::deck::estimate_ghosts(
                &case.bodies,
                D,
                &crate::setup::symmetry_planes(case),
                case.simulation.smoothing_ratio,
            ),
            D,
            case.simulation.formulation == crate::case::Formulation::Corrected,
            case.may_fail(),
        ) / n as f64,
        halos,
        phases,
    })
}

/// The groups of cases `run_all` can be limited to.
pub const GROUPS: [&str; 8] = [
    "large",
    "scaling",
    "cubes_3d",
    "cubes_3d_cn",
    "cubes_3d_vm",
    "cubes_3d_jc",
    "sphere_plate",
    "plates_2d",
];

/// The cubes in CN-SPH (`formulation = "corrected"`).
fn cubes_3d_cn() -> String {
    CUBES_3D.replace(
        "name = \"cubes_3d\"",
        "name = \"cubes_3d_cn\"\nformulation = \"corrected\"",
    )
}

/// The cubes as 4340 steel at ±300 m/s (an 11 GPa shock: every particle behind it yields),
/// with the library's Johnson–Cook strength and its failure (Johnson–Cook D1–D5 and spall):
/// the cost of the material models, against [`cubes_3d_vm`]. Also the MPI tests' case with
/// failure (`tests/mpi.rs`).
pub fn cubes_3d_jc() -> String {
    steel_cubes("cubes_3d_jc", "library = \"steel_4340\"")
}

/// [`cubes_3d_jc`] with von Mises at Johnson–Cook's A and the same shear modulus and EOS, no
/// damage: the same run with the simplest strength (issue 13 asks Johnson–Cook with damage to
/// cost at most 25 % more a step).
fn cubes_3d_vm() -> String {
    steel_cubes(
        "cubes_3d_vm",
        "library = \"steel_4340\"\nstrength = { type = \"von_mises\", shear_modulus = 77.5e9, yield_stress = 792e6 }\ndamage = { type = \"none\" }",
    )
}

/// [`CUBES_3D`] with material `material` (deck lines) at ±300 m/s, named `name`.
fn steel_cubes(name: &str, material: &str) -> String {
    let deck = CUBES_3D
        .replace("name = \"cubes_3d\"", &format!("name = \"{name}\""))
        .replace("50.0, 0.0, 0.0", "300.0, 0.0, 0.0");
    let (head, bodies) = deck.split_once("[materials.al]").expect("cube deck");
    let bodies = &bodies[bodies.find("[[body]]").expect("cube deck")..];
    format!("{head}[materials.al]\n{material}\n{bodies}")
}

/// Edge of the large cube in particles: 216³ = 10 077 696, the ten million particles of issue
/// 14 (7.7 GB).
pub const LARGE_CUBE: usize = 216;
/// The ranks the halos are counted for: of the large case (10⁶ down to 10⁴ particles a rank),
/// and of the others.
const LARGE_CENSUS: &[usize] = &[2, 10, 100, 1000];
const CENSUS: &[usize] = &[2, 3, 4, 8];

/// The standard benchmark. First the large cube (10⁷ particles, 2 steps; skipped with a warning
/// where the machine has too little memory for it, an error when asked for by name), then the
/// scaling series on all cores — cubes of 100³ (the million-particle memory figure), 50³ and
/// 25³ particles — then every fixed case on 1 thread and on all cores. `quick` runs fewer steps and
/// smaller cubes (a smoke test). `only` limits the run to some of [`GROUPS`] (all when empty).
/// `report` is told of each case as it is measured.
pub fn run_all(
    quick: bool,
    only: &[String],
    ranks: Ranks,
    mut report: impl FnMut(&BenchCase),
) -> Result<BenchReport> {
    if let Some(bad) = only.iter().find(|g| !GROUPS.contains(&g.as_str())) {
        return Err(Error::Invalid(format!(
            "unknown benchmark case `{bad}`: expected one of {}",
            GROUPS.join(", ")
        )));
    }
    let wanted = |g: &str| only.is_empty() || only.iter().any(|o| o == g);
    // Under MPI, one thread a rank (the ranks take the cores).
    let all = if ranks.size() > 1 {
        1
    } else {
        std::thread::available_parallelism().map_or(1, |n| n.get())
    };
    let mut threads = vec![1];
    if all > 1 {
        threads.push(all);
    }
    let mut cases = Vec::new();
    let sizes: &[(usize, u64)] = if quick {
        &[(20, 1), (10, 1)]
    } else {
        &[(100, 3), (50, 10), (25, 40)]
    };
    // Each rank holds the whole state (see `ranks`): the large case is for one process.
    if wanted("large") && !quick && ranks.size() == 1 {
        let deck = cube_deck(LARGE_CUBE);
        let n = LARGE_CUBE.pow(3) as f64;
        let need = crate::particles::estimated_bytes(n, 0.0, 3, false, false);
        match crate::machine::available_memory() {
            Some(have) if have < 1.1 * need => {
                let why = format!(
                    "the large benchmark case ({n:.3e} particles) needs about {:.1} GB; {:.1} GB are available",
                    need / 1e9,
                    have / 1e9
                );
                if !only.is_empty() {
                    return Err(Error::Invalid(why));
                }
                tracing::warn!("skipped: {why}");
            }
            _ => {
                let c = measure(&deck, "bench:cube", (all, ranks), (1, 2), LARGE_CENSUS)?;
                report(&c);
                cases.push(c);
            }
        }
    }
    for &(n, steps) in sizes.iter().filter(|_| wanted("scaling")) {
        let c = measure(&cube_deck(n), "bench:cube", (all, ranks), (1, steps), &[])?;
        report(&c);
        cases.push(c);
    }
    let (warm, steps) = if quick { (1, 2) } else { (5, 60) };
    // The steel cubes are timed after 100 steps, when the shock has crossed most of each cube
    // (at step 160, 96 % of the particles have yielded and 12 % have failed).
    let (warm_steel, steps_steel) = if quick { (1, 2) } else { (100, 60) };
    let decks: [(&str, String, &str, u64, u64); 6] = [
        ("cubes_3d", CUBES_3D.into(), "bench:cubes_3d", warm, steps),
        (
            "cubes_3d_cn",
            cubes_3d_cn(),
            "bench:cubes_3d_cn",
            warm,
            steps,
        ),
        (
            "cubes_3d_vm",
            cubes_3d_vm(),
            "bench:cubes_3d_vm",
            warm_steel,
            steps_steel,
        ),
        (
            "cubes_3d_jc",
            cubes_3d_jc(),
            "bench:cubes_3d_jc",
            warm_steel,
            steps_steel,
        ),
        (
            "sphere_plate",
            SPHERE_PLATE.into(),
            "bench:sphere_plate",
            warm,
            steps / 2,
        ),
        (
            "plates_2d",
            PLATES_2D.into(),
            "bench:plates_2d",
            warm,
            steps,
        ),
    ];
    for (_, text, label, w, s) in decks.into_iter().filter(|d| wanted(d.0)) {
        for &t in &threads {
            // The halos once a case, after its last run.
            let census = if t == all { CENSUS } else { &[] };
            let c = measure(&text, label, (t, ranks), (w, s.max(2)), census)?;
            report(&c);
            cases.push(c);
        }
    }
    Ok(BenchReport { cases })
}

/// Where the time of each rank went (see [`crate::simulation::PhaseSeconds`]), a line after a
/// case's own: what an MPI run's speed-up is bound by (a rank that searches longer than the
/// others keeps them waiting at the halo).
fn phases_line(c: &BenchCase) -> String {
    let rank = |(r, s): (usize, &crate::simulation::PhaseSeconds)| {
        let exchanges = if c.ranks > 1 {
            format!(", exchanges {:.2}", s.exchanges)
        } else {
            String::new()
        };
        let who = if c.ranks > 1 {
            format!("rank {r}: ")
        } else {
            String::new()
        };
        format!(
            "{who}search {:.2}, passes {:.2}{exchanges}",
            s.search, s.passes
        )
    };
    let ranks: Vec<String> = c.phases.iter().enumerate().map(rank).collect();
    if ranks.is_empty() {
        return String::new();
    }
    format!("\n  seconds in the timed steps: {}", ranks.join("; "))
}

/// One human-readable line.
pub fn line(c: &BenchCase) -> String {
    format!(
        "{:<14} {}D {:>8} particles {:>2} threads{} {:>4} steps {:>8.2} s  {:.3e} particle-steps/s  {:.3e} interactions/s/core  {:.1} neighbours  peak {:.0} MB  {:.0} B/particle (estimate {:.0})",
        c.name,
        c.dimension,
        c.particles,
        c.threads,
        if c.ranks > 1 {
            format!(" × {} ranks ({:.1} % exchanging)", c.ranks, 100.0 * c.exchange_share)
        } else {
            String::new()
        },
        c.steps,
        c.wall_seconds,
        c.particle_steps_per_second,
        c.interactions_per_second_per_core,
        c.mean_neighbors,
        c.peak_rss_bytes as f64 / 1e6,
        c.bytes_per_particle,
        c.estimated_bytes_per_particle
    ) + &phases_line(c)
        + &c
        .halos
        .iter()
        .map(|h| {
            format!(
                "\n  halo on {:>4} ranks ({}): {:.0} particles a rank, halo {:.1} % of them (largest {:.1} %), from {:.1} ranks (at most {})",
                h.ranks,
                match (h.actual, h.curve) {
                    (true, _) => "this run's",
                    (false, Curve::Cells) => "cell order",
                    (false, Curve::Morton) => "Morton curve",
                },
                h.particles_per_rank,
                100.0 * h.halo_share_mean,
                100.0 * h.halo_share_max,
                h.neighbour_ranks_mean,
                h.neighbour_ranks_max
            )
        })
        .collect::<String>()
}
