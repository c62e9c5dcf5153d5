//! The command line as a user meets it: every example checks and runs, each kind of output file
//! opens in VTK's own reader (tests/vtk_check.py, with the Python environment the tests provision themselves), and
//! mistakes give located errors and a non-zero exit.

mod support;

use std::path::{Path, PathBuf};
use std::process::Command;
use strike::output::checkpoint::Checkpoint;
use strike::output::history::History;
use strike::output::summary::Summary;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn strike(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_strike"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("strike runs")
}

fn python() -> PathBuf {
    support::vtk_python()
}

fn examples() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(root().join("examples"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    v.sort();
    assert!(!v.is_empty());
    v
}

fn out_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("cli")
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Every example deck passes `strike check` and runs a few steps to completion.
#[test]
fn every_example_checks_and_runs() {
    for deck in examples() {
        let name = deck.file_stem().unwrap().to_string_lossy().to_string();
        let check = strike(&["check", deck.to_str().unwrap()]);
        let text = String::from_utf8_lossy(&check.stdout);
        assert!(
            check.status.success(),
            "{name}: check failed: {}",
            String::from_utf8_lossy(&check.stderr)
        );
        assert!(
            text.contains("particles:") && text.contains("first time step"),
            "{name}: {text}"
        );
        let out = out_dir(&name);
        let run = strike(&[
            "run",
            deck.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--max-steps",
            "3",
        ]);
        assert!(
            run.status.success(),
            "{name}: run failed: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        let s = Summary::read(&out.join("summary.json")).unwrap();
        assert_eq!(s.status, "max_steps", "{name}");
        assert_eq!(s.steps, 3, "{name}");
        assert!(
            s.particles > 0 && s.particle_steps_per_second > 0.0,
            "{name}"
        );
    }
}

/// A run's snapshots (.vtp and the .pvd series) open in VTK's reader with every field; the
/// history and summary carry the documented columns and keys.
#[test]
fn run_outputs_open_in_vtk() {
    let out = out_dir("outputs");
    let run = strike(&[
        "run",
        "examples/hugoniot_elastic_limit.toml",
        "--out",
        out.to_str().unwrap(),
        "--max-steps",
        "40",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let s = Summary::read(&out.join("summary.json")).unwrap();
    // The run's peak resident memory, in bytes (not kB: a few MB at least, well below a TB).
    if cfg!(target_os = "linux") {
        let peak = s.peak_memory_bytes.expect("Linux reports the peak memory");
        assert!(peak > 4 << 20 && peak < 1 << 40, "peak memory {peak} B");
    }
    let fields = "body,velocity,pressure,density,internal_energy,deviatoric_stress,von_mises,plastic_strain,damage,smoothing_length,contact_force";
    let pvd = out.join("hugoniot_elastic_limit.pvd");
    let check = Command::new(python())
        .arg(root().join("tests/vtk_check.py"))
        .arg(&pvd)
        .args(["--points", &s.particles.to_string(), "--fields", fields])
        .output()
        .unwrap();
    assert!(
        check.status.success(),
        "{}{}",
        String::from_utf8_lossy(&check.stdout),
        String::from_utf8_lossy(&check.stderr)
    );
    let h = History::read(&out.join("history.csv")).unwrap();
    for c in [
        "time",
        "dt",
        "kinetic_energy",
        "internal_energy",
        "total_energy",
        "momentum_x",
        "momentum_y",
        "momentum_z",
        "contact_energy",
        "min_interbody_distance",
    ] {
        assert!(h.columns.iter().any(|x| x == c), "history lacks {c}");
    }
    assert!(h.rows.len() >= 2);
    // momentum_z is 0 in 2D.
    assert!(h.column("momentum_z").unwrap().iter().all(|&m| m == 0.0));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    for k in [
        "particles",
        "steps",
        "wall_seconds",
        "particle_steps_per_second",
        "end_time",
        "energy_error",
        "status",
        "momentum_error",
        "min_interbody_distance",
    ] {
        assert!(json.get(k).is_some(), "summary lacks {k}");
    }
    assert_eq!(s.steps, 40);
}

/// A bad deck: non-zero exit, and the message names the file, line and key, with no panic.
#[test]
fn bad_deck_gives_a_located_error() {
    let dir = out_dir("bad_deck");
    std::fs::create_dir_all(&dir).unwrap();
    let deck = dir.join("bad.toml");
    let text = std::fs::read_to_string(root().join("examples/elastic_wave.toml"))
        .unwrap()
        .replace("density = 2700.0", "density = -2700.0");
    std::fs::write(&deck, &text).unwrap();
    let line = text
        .lines()
        .position(|l| l.contains("density = -2700.0"))
        .unwrap()
        + 1;
    for cmd in ["check", "run"] {
        let out = strike(&[cmd, deck.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success());
        assert!(err.contains(&format!("bad.toml:{line}:")), "{err}");
        assert!(err.contains("density"), "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    let missing = strike(&["run", "no/such/deck.toml"]);
    assert!(!missing.status.success());
    assert!(String::from_utf8_lossy(&missing.stderr).contains("no/such/deck.toml"));
}

/// A run that goes unstable exits non-zero, says which particle, body, place and cause, and
/// leaves its last good snapshot and a summary whose status gives the reason.
#[test]
fn unstable_run_stops_with_a_reason() {
    let dir = out_dir("unstable");
    std::fs::create_dir_all(&dir).unwrap();
    let deck = dir.join("unstable.toml");
    // A 20 km/s impact with no artificial viscosity: plain SPH cannot hold the shock and the
    // particles scatter (the speed check trips; at 5 km/s, since the material advances with
    // the step's middle velocity, the shock holds without viscosity).
    let text = r#"
[simulation]
dimension = 2
end_time = 2.0e-6
viscosity = { alpha = 0.0, beta = 0.0 }
[materials.al]
library = "al_1100_o"
damage = { type = "none" }
[[body]]
name = "flyer"
material = "al"
spacing = 0.2e-3
velocity = [20000.0, 0.0]
shape = { type = "rectangle", min = [-2.0e-3, 0.0], max = [0.0, 0.8e-3] }
[[body]]
name = "target"
material = "al"
spacing = 0.2e-3
shape = { type = "rectangle", min = [0.0, 0.0], max = [4.0e-3, 0.8e-3] }
[[interaction]]
bodies = ["flyer", "target"]
type = "welded"
"#;
    std::fs::write(&deck, text).unwrap();
    let out = dir.join("run");
    let run = strike(&[
        "run",
        deck.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success(), "{err}");
    assert!(
        err.contains("particle ") && err.contains("run stopped"),
        "{err}"
    );
    let s = Summary::read(&out.join("summary.json")).unwrap();
    assert_eq!(s.status, "unstable");
    for part in ["particle ", "of body '", ") m: ", "exceeds"] {
        assert!(s.reason.contains(part), "{}", s.reason);
    }
    // The last good state is on disk, after the first snapshot.
    let snapshots = std::fs::read_dir(&out)
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .path()
                .extension()
                .is_some_and(|x| x == "vtp")
        })
        .count();
    assert!(snapshots >= 2, "{snapshots} snapshots");
    // …and a checkpoint of it, which resumes (and fails again the same way).
    assert!(out.join("checkpoint.bin").exists());
    let again = strike(&[
        "run",
        deck.to_str().unwrap(),
        "--resume",
        out.join("checkpoint.bin").to_str().unwrap(),
    ]);
    assert!(!again.status.success());
    let s2 = Summary::read(&out.join("summary.json")).unwrap();
    assert_eq!((s2.status, s2.reason), (s.status, s.reason));
}

/// `strike bench` with `args`, its report read back (`name`: the output directory).
fn bench_json(name: &str, args: &[&str]) -> serde_json::Value {
    let dir = out_dir(name);
    std::fs::create_dir_all(&dir).unwrap();
    let json = dir.join("bench.json");
    let mut all = vec!["bench", "--json", json.to_str().unwrap()];
    all.extend_from_slice(args);
    let out = strike(&all);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap()
}

/// `strike bench --quick` measures every built-in case on 1 thread and all cores and writes
/// bench.json with the documented keys; the neighbour counts are those of the lattices
/// (h = 1.2 Δp: about 50 in 3D, 20 in 2D, fewer at free surfaces).
#[test]
fn bench_writes_its_report() {
    let v = bench_json("bench", &["--quick"]);
    let cases = v["cases"].as_array().unwrap();
    let keys = [
        "name",
        "dimension",
        "particles",
        "threads",
        "steps",
        "wall_seconds",
        "particle_steps_per_second",
        "interactions_per_second_per_core",
        "mean_neighbors",
        "peak_rss_bytes",
        "bytes_per_particle",
        "estimated_bytes_per_particle",
    ];
    for c in cases {
        for k in keys {
            assert!(c.get(k).is_some(), "{k} missing in {c}");
        }
        let nb = c["mean_neighbors"].as_f64().unwrap();
        let range = if c["dimension"] == 3 {
            30.0..60.0
        } else {
            12.0..22.0
        };
        assert!(range.contains(&nb), "{}: {nb} neighbours", c["name"]);
        // Where the time went: one entry a rank, the search and the passes parts of the
        // timed steps (disjoint spans of them, so together within the wall time), and on one
        // process next to nothing in the exchanges (calls that return at once).
        let phases = c["phases"].as_array().unwrap();
        assert_eq!(phases.len(), 1, "{c}");
        let part = |k: &str| phases[0][k].as_f64().unwrap();
        let wall = c["wall_seconds"].as_f64().unwrap();
        assert!(part("search") > 0.0 && part("passes") > 0.0, "{c}");
        assert!(part("search") + part("passes") <= wall, "{c}");
        assert!(part("exchanges") < 0.01 * wall, "{c}");
    }
    // Every case on 1 thread and on all cores (the large case and the scaling runs have their
    // own thread counts).
    for name in strike::bench::GROUPS
        .into_iter()
        .filter(|g| !matches!(*g, "large" | "scaling"))
    {
        let threads: Vec<u64> = cases
            .iter()
            .filter(|c| c["name"] == name)
            .map(|c| c["threads"].as_u64().unwrap())
            .collect();
        assert!(threads.contains(&1), "{name} on 1 thread");
        assert_eq!(
            threads.len(),
            if num_cpus() > 1 { 2 } else { 1 },
            "{name}: {threads:?}"
        );
        // The halos once a case (on all cores): 2, 3, 4 and 8 ranks along each curve; on 2
        // ranks each needs some of the other's particles and nobody else's.
        let halos: Vec<&serde_json::Value> = cases
            .iter()
            .filter(|c| c["name"] == name)
            .flat_map(|c| c["halos"].as_array().unwrap())
            .collect();
        assert_eq!(halos.len(), 8, "{name}: {halos:?}");
        for h in halos.iter().filter(|h| h["ranks"] == 2) {
            assert_eq!(h["neighbour_ranks_max"], 1, "{name}: {h}");
            let share = h["halo_share_mean"].as_f64().unwrap();
            assert!(share > 0.0 && share < 0.5, "{name}: {h}");
        }
    }
}

/// The memory that `strike check` and the deck's memory check estimate per particle is within
/// 10 % of what `strike bench` measures on a cube of a million particles (measured first, in a
/// fresh process, so that the growth of the peak resident memory is the case's own).
#[test]
fn check_estimates_the_memory_bench_measures() {
    let v = bench_json("bench_memory", &["--case", "scaling"]);
    let cube = &v["cases"][0];
    assert_eq!(cube["particles"], 1_000_000);
    let measured = cube["bytes_per_particle"].as_f64().unwrap();
    let estimate = cube["estimated_bytes_per_particle"].as_f64().unwrap();
    assert!(
        (estimate - measured).abs() <= 0.1 * measured,
        "check estimates {estimate} B a particle, bench measured {measured}"
    );
}

/// The same for the shocked steel cubes (16 000 particles, von Mises), whose lists grow as
/// they are compressed, on 1 thread first in a fresh process. With glibc's default mmap
/// threshold the holes their growing blocks left in its heap read 17 % over the estimate
/// (see `machine::map_large_allocations`).
#[test]
fn check_estimates_the_memory_of_the_shocked_cubes() {
    let v = bench_json("bench_memory_shocked", &["--case", "cubes_3d_vm"]);
    let cubes = &v["cases"][0];
    assert_eq!(
        (&cubes["particles"], &cubes["threads"]),
        (&16_000.into(), &1.into())
    );
    let measured = cubes["bytes_per_particle"].as_f64().unwrap();
    let estimate = cubes["estimated_bytes_per_particle"].as_f64().unwrap();
    assert!(
        (estimate - measured).abs() <= 0.1 * measured,
        "check estimates {estimate} B a particle, bench measured {measured}"
    );
}

fn num_cpus() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Every example stopped by `--max-steps` at a reorder step (50) and resumed from its checkpoint
/// ends at step 60 exactly as the run that went straight there.
#[test]
fn every_example_resumes_bit_for_bit() {
    for deck in examples() {
        let name = deck.file_stem().unwrap().to_string_lossy().to_string();
        let case = strike::deck::load(&deck).unwrap();
        let straight = out_dir(&format!("resume_{name}_a"));
        let stopped = out_dir(&format!("resume_{name}_b"));
        let d = deck.to_str().unwrap();
        for (out, steps) in [(&straight, "60"), (&stopped, "50")] {
            let r = strike(&[
                "run",
                d,
                "--out",
                out.to_str().unwrap(),
                "--max-steps",
                steps,
            ]);
            assert!(
                r.status.success(),
                "{name}: {}",
                String::from_utf8_lossy(&r.stderr)
            );
        }
        let cp = stopped.join("checkpoint.bin");
        let r = strike(&[
            "run",
            d,
            "--resume",
            cp.to_str().unwrap(),
            "--max-steps",
            "60",
        ]);
        assert!(
            r.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&r.stderr)
        );
        let read = |dir: &Path| -> (Vec<u8>, Vec<u8>) {
            let text = std::fs::read(dir.join("history.csv")).unwrap();
            let state = match case.dimension {
                2 => {
                    let c = Checkpoint::<2>::read(&dir.join("checkpoint.bin"), &case).unwrap();
                    postcard::to_stdvec(&(c.particles, c.sim, c.run.tally)).unwrap()
                }
                _ => {
                    let c = Checkpoint::<3>::read(&dir.join("checkpoint.bin"), &case).unwrap();
                    postcard::to_stdvec(&(c.particles, c.sim, c.run.tally)).unwrap()
                }
            };
            (state, text)
        };
        let (a, b) = (read(&straight), read(&stopped));
        assert!(
            a.0 == b.0,
            "{name}: state differs after resuming at step 50"
        );
        assert!(
            a.1 == b.1,
            "{name}: history differs after resuming at step 50"
        );
    }
}
