//! Checkpoints resume bit for bit: a run stopped at a snapshot and resumed from its checkpoint
//! ends exactly where the uninterrupted run ends.

use std::path::{Path, PathBuf};
use strike::case::Case;
use strike::deck;
use strike::output::checkpoint::Checkpoint;
use strike::run::{run, RunOptions};

fn case() -> Case {
    // The coarse quarter sphere-plate: contact, symmetry ghosts, searches and reordering.
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
    }
}

#[test]
fn resumed_run_is_bit_identical() {
    let case = case();
    let total = 130;
    // A: uninterrupted.
    let a = opts("a", total, None);
    let sa = run(&case, &a).unwrap();
    // A snapshot step of A in the middle of the run (snapshot files are named by step).
    let pvd = std::fs::read_to_string(a.out_dir.join("sphere_plate.pvd")).unwrap();
    let steps: Vec<u64> = pvd
        .split("sphere_plate_")
        .skip(1)
        .filter_map(|s| s.get(..6)?.parse().ok())
        .collect();
    let mid = *steps
        .iter()
        .find(|&&s| s > 30 && s < total - 30)
        .expect("a snapshot mid-run");
    // B: the same run stopped there; C: resumed from B's checkpoint.
    let b = opts("b", mid, None);
    run(&case, &b).unwrap();
    let mut c = opts("b", total, Some(b.out_dir.join("checkpoint.bin")));
    c.out_dir = b.out_dir.clone();
    let sc = run(&case, &c).unwrap();

    let ca = Checkpoint::<3>::read(&a.out_dir.join("checkpoint.bin"), &case.name).unwrap();
    let cc = Checkpoint::<3>::read(&c.out_dir.join("checkpoint.bin"), &case.name).unwrap();
    println!(
        "resumed at step {mid} of {total}; {} particles",
        ca.particles.n_real
    );
    assert_eq!(ca.sim, cc.sim, "scalar state differs");
    assert!(ca.particles == cc.particles, "particles differ");
    assert_eq!(ca.run.tally, cc.run.tally, "tallies differ");
    assert_eq!(ca.run.snapshots, cc.run.snapshots, "snapshot lists differ");
    assert_eq!(sa.steps, sc.steps);
    assert_eq!(sa.energy_error, sc.energy_error);
    assert_eq!(sa.momentum_error, sc.momentum_error);
    assert_eq!(sa.min_interbody_distance, sc.min_interbody_distance);
    // The history of C continues B's into exactly A's.
    let history = |dir: &Path| std::fs::read_to_string(dir.join("history.csv")).unwrap();
    assert_eq!(history(&a.out_dir), history(&c.out_dir));
    // A checkpoint of another case is refused.
    let mut other = case.clone();
    other.name = "another".into();
    assert!(Checkpoint::<3>::read(&a.out_dir.join("checkpoint.bin"), &other.name).is_err());
}
