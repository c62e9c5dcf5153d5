//! Checkpoints resume bit for bit: from a checkpoint taken at any step — a multiple of the
//! reorder interval, a step with a full neighbour search, one with a partial rebuild, or none of
//! these — a resumed run ends exactly where the uninterrupted run ends.

use std::path::{Path, PathBuf};
use strike::case::Case;
use strike::deck;
use strike::output::checkpoint::Checkpoint;
use strike::particles::Particles;
use strike::run::{run, RunOptions};
use strike::simulation::{SimState, Simulation, REORDER_EVERY};

fn case() -> Case {
    // The coarse quarter sphere-plate: contact, symmetry ghosts, full and partial searches,
    // reordering.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/sphere_plate.toml");
    let mut case = deck::load(&path).unwrap();
    for b in &mut case.bodies {
        b.spacing = 50e-6;
    }
    case.output.snapshot_interval = Some(2.0e-8);
    case.output.pictures.clear();
    case
}

fn opts(dir: &str, max_steps: u64, resume: Option<PathBuf>) -> RunOptions {
    let out_dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("checkpoint")
        .join(dir);
    if resume.is_none() {
        let _ = std::fs::remove_dir_all(&out_dir);
    }
    RunOptions {
        out_dir,
        progress: false,
        max_steps: Some(max_steps),
        write_fields: true,
        resume,
        ..Default::default()
    }
}

/// The engine alone: checkpoints taken during one run at steps of every kind, each resumed in a
/// fresh simulation and run on to the same end, give the uninterrupted run's particles and state
/// bit for bit.
#[test]
fn engine_resumes_bit_for_bit_from_any_step() {
    let case = case();
    let total = 2 * REORDER_EVERY + 25;
    let mut sim = Simulation::<3>::new(&case).unwrap();
    let mut saved: Vec<(u64, &str, Particles<3>, SimState, _)> = Vec::new();
    let (mut full, mut partial) = (None, None);
    while sim.state.step < total {
        let before = sim.stats;
        let step = sim.state.step;
        let (p, s, st) = sim.checkpoint_state();
        sim.step(f64::INFINITY).unwrap();
        // Which kind of step this was is known once it ran; keep its checkpoint if wanted.
        let kind = if step > 0 && step.is_multiple_of(REORDER_EVERY) {
            Some("a reorder step")
        } else if step > 0 && sim.stats.searches > before.searches && full.is_none() {
            full = Some(step);
            Some("a full search")
        } else if sim.stats.partial_searches > before.partial_searches
            && partial.is_none()
            && step > 10
        {
            partial = Some(step);
            Some("a partial rebuild")
        } else if step == 37 || step == 83 {
            Some("a plain step")
        } else {
            None
        };
        if let Some(kind) = kind {
            saved.push((step, kind, p, s, st));
        }
    }
    assert!(full.is_some() && partial.is_some(), "{full:?} {partial:?}");
    let kinds: Vec<&str> = saved.iter().map(|s| s.1).collect();
    println!(
        "resuming at steps {:?}",
        saved.iter().map(|s| (s.0, s.1)).collect::<Vec<_>>()
    );
    for k in [
        "a reorder step",
        "a full search",
        "a partial rebuild",
        "a plain step",
    ] {
        assert!(kinds.contains(&k), "no checkpoint at {k}");
    }
    for (step, kind, p, s, st) in saved {
        let mut resumed = Simulation::<3>::new(&case).unwrap();
        resumed.restore(p, s, st);
        while resumed.state.step < total {
            resumed.step(f64::INFINITY).unwrap();
        }
        let (pa, sa, _) = sim.checkpoint_state();
        let (pb, sb, _) = resumed.checkpoint_state();
        assert_eq!(
            sa, sb,
            "state differs after resuming at step {step} ({kind})"
        );
        assert!(
            pa == pb,
            "particles differ after resuming at step {step} ({kind})"
        );
    }
}

/// Whole runs: stopped by `--max-steps` at a multiple of the reorder interval and between two
/// snapshots, each resumed from its checkpoint, continue into exactly the uninterrupted run's
/// particles, tallies and history.
#[test]
fn resumed_run_is_bit_identical() {
    let case = case();
    let total = 3 * REORDER_EVERY + 10;
    // A: uninterrupted.
    let a = opts("a", total, None);
    let sa = run(&case, &a).unwrap();
    let ca = Checkpoint::<3>::read(&a.out_dir.join("checkpoint.bin"), &case).unwrap();
    // Snapshot steps of A (files are named by step): the stops below are not among them.
    let pvd = std::fs::read_to_string(a.out_dir.join("sphere_plate.pvd")).unwrap();
    let snapshots: Vec<u64> = pvd
        .split("sphere_plate_")
        .skip(1)
        .filter_map(|s| s.get(..6)?.parse().ok())
        .collect();
    // Two stops at multiples of the reorder interval and one between, none at a snapshot.
    let free = |s: &u64| !snapshots.contains(s);
    let mut stops: Vec<u64> = (1..)
        .map(|k| k * REORDER_EVERY)
        .take_while(|&s| s < total)
        .filter(free)
        .take(2)
        .collect();
    stops.extend((77..total).filter(|s| s % REORDER_EVERY != 0).find(free));
    assert_eq!(stops.len(), 3, "no stop left between the snapshots");
    for stop in stops {
        let dir = format!("stop{stop}");
        // B: the same run stopped there; then resumed from B's checkpoint.
        let b = opts(&dir, stop, None);
        let sb = run(&case, &b).unwrap();
        assert_eq!(sb.steps, stop);
        let c = opts(&dir, total, Some(b.out_dir.join("checkpoint.bin")));
        let sc = run(&case, &c).unwrap();
        let cc = Checkpoint::<3>::read(&c.out_dir.join("checkpoint.bin"), &case).unwrap();
        assert_eq!(ca.sim, cc.sim, "stop {stop}: scalar state differs");
        assert!(
            ca.particles == cc.particles,
            "stop {stop}: particles differ"
        );
        assert_eq!(ca.run.tally, cc.run.tally, "stop {stop}: tallies differ");
        assert_eq!(sa.steps, sc.steps);
        assert_eq!(sa.energy_error, sc.energy_error);
        assert_eq!(sa.momentum_error, sc.momentum_error);
        assert_eq!(sa.min_interbody_distance, sc.min_interbody_distance);
        // The history of the resumed run continues B's into exactly A's.
        let history = |dir: &Path| std::fs::read_to_string(dir.join("history.csv")).unwrap();
        assert_eq!(history(&a.out_dir), history(&c.out_dir), "stop {stop}");
    }
}
