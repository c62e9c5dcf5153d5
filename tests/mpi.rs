//! MPI runs are bit-identical to the serial run on any number of ranks, and a checkpoint
//! restarts on another number of ranks bit for bit: the `mpi` build under `mpirun -n 1, 2, 3`
//! (oversubscribed on a 2-core machine) against the default build run serially, on a contact
//! case and on the CN-SPH sphere–plate (contact, symmetry ghosts, the correction and colour
//! passes, full and partial searches, a reordering and the ranks' rebalancing).
//!
//! The test builds the `mpi` binary itself (tests/support/provision_mpi.sh, which installs
//! OpenMPI where it is missing), in its own target directory, seeded with the dependencies
//! the test build has compiled already.

mod support;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// The `mpi` build of strike, built once (under a file lock across test processes).
fn mpi_strike() -> PathBuf {
    static BIN: OnceLock<PathBuf> = OnceLock::new();
    BIN.get_or_init(|| {
        let tmp = Path::new(env!("CARGO_TARGET_TMPDIR"));
        std::fs::create_dir_all(tmp).unwrap();
        let lock = std::fs::File::create(tmp.join("mpi-build.lock")).unwrap();
        lock.lock().unwrap();
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/support/provision_mpi.sh");
        // The build running the tests: its release directory seeds the mpi build's.
        let release = tmp.parent().map(|t| t.join("release")).unwrap_or_default();
        let out = Command::new("bash")
            .arg(&script)
            .arg(tmp.join("mpi-target"))
            .arg(release)
            .output()
            .unwrap_or_else(|e| panic!("cannot run {}: {e}", script.display()));
        assert!(
            out.status.success(),
            "could not build strike with the mpi feature (needs OpenMPI and libclang, which the script installs with apt-get where it can):\n{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        PathBuf::from(String::from_utf8(out.stdout).unwrap().trim())
    })
    .clone()
}

fn dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("mpi")
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// An example deck with its bodies' spacing set to `spacing` (coarser: quick), in `dir`.
fn deck(example: &str, spacing: f64, dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("examples/{example}.toml")),
    )
    .unwrap();
    let text: String = text
        .lines()
        .map(|l| {
            if l.trim_start().starts_with("spacing =") {
                format!("spacing = {spacing:e}")
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    let path = dir.join(format!("{example}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// `strike run` of `deck` into `out` for `steps` steps: serially with the default build
/// (ranks = 0), or under `mpirun -n ranks` with the mpi build; `resume` from a checkpoint.
fn run(deck: &Path, out: &Path, steps: u64, ranks: usize, resume: Option<&Path>) -> String {
    let strike = env!("CARGO_BIN_EXE_strike");
    let mut cmd = if ranks == 0 {
        Command::new(strike)
    } else {
        let mut c = Command::new("mpirun");
        c.args(["--oversubscribe", "-n", &ranks.to_string()])
            .arg(mpi_strike())
            .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
            .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1");
        c
    };
    cmd.arg("run").arg(deck).arg("--out").arg(out).args([
        "--threads",
        "1",
        "--max-steps",
        &steps.to_string(),
        "--overwrite",
    ]);
    if let Some(r) = resume {
        cmd.arg("--resume").arg(r);
    }
    let o = cmd.output().unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(o.status.success(), "{ranks} ranks: {text}");
    text
}

/// Every snapshot, the history and (`pvd`) the .pvd of run `a` are byte for byte those of
/// run `b` (the summary and checkpoint also hold the wall time). Returns how many files were
/// compared.
fn same_outputs(a: &Path, b: &Path, pvd: bool) -> usize {
    same_files(a, b, |name| {
        name.ends_with(".vtp") || (pvd && name.ends_with(".pvd")) || name == "history.csv"
    })
}

/// The serial run `serial` against a run on several ranks, `ranks`, which writes each snapshot
/// as a .pvtp of pieces: the history byte for byte, and every snapshot's points and point
/// data bit for bit as VTK's readers (ParaView's) read them, the .pvtp's pieces joined.
fn same_as_parallel(serial: &Path, ranks: &Path, example: &str) -> usize {
    let n = same_files(serial, ranks, |name| name == "history.csv");
    assert_eq!(n, 1);
    let pvd = |d: &Path| d.join(format!("{example}.pvd"));
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/vtk_check.py");
    let out = Command::new(support::vtk_python())
        .arg(script)
        .arg(pvd(serial))
        .arg("--same")
        .arg(pvd(ranks))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && stdout.starts_with("ok "),
        "{} against {}: {stdout}{}",
        serial.display(),
        ranks.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let snapshots: usize = stdout
        .split_whitespace()
        .nth(2)
        .and_then(|k| k.parse().ok())
        .unwrap();
    let pieces = std::fs::read_dir(ranks)
        .unwrap()
        .filter(|e| {
            let name = e.as_ref().unwrap().file_name().into_string().unwrap();
            name.ends_with(".pvtp")
        })
        .count();
    assert_eq!(pieces, snapshots, "every snapshot is a .pvtp");
    n + snapshots
}

/// The files of `a` that `pick` names are byte for byte those of `b`; how many.
fn same_files(a: &Path, b: &Path, pick: impl Fn(&str) -> bool) -> usize {
    let mut compared = 0;
    for entry in std::fs::read_dir(a).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        if !pick(&name) {
            continue;
        }
        let (x, y) = (
            std::fs::read(a.join(&name)).unwrap(),
            std::fs::read(b.join(&name)),
        );
        let y = y.unwrap_or_else(|e| panic!("{}: {e}", b.join(&name).display()));
        assert!(
            x == y,
            "{name} differs between {} and {}",
            a.display(),
            b.display()
        );
        compared += 1;
    }
    compared
}

/// VTK's own reader (ParaView's) opens every snapshot of the series `pvd`.
fn vtk_reads(pvd: &Path) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/vtk_check.py");
    let out = Command::new(support::vtk_python())
        .arg(script)
        .arg(pvd)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && stdout.starts_with("ok "),
        "VTK's reader on {}: {stdout}{}",
        pvd.display(),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The serial run against 1, 2 and 3 ranks.
fn ranks_match_serial(example: &str, spacing: f64, steps: u64) {
    let d = dir(example);
    let deck = deck(example, spacing, &d);
    deck_matches_serial(&deck, example, &d, steps);
}

/// The serial run of `deck` (whose case is `name`) against 1, 2 and 3 ranks, in `d`.
fn deck_matches_serial(deck: &Path, name: &str, d: &Path, steps: u64) {
    run(deck, &d.join("serial"), steps, 0, None);
    for ranks in 1..=3 {
        let out = d.join(format!("ranks{ranks}"));
        let log = run(deck, &out, steps, ranks, None);
        let n = if ranks > 1 {
            assert!(log.contains(&format!("{ranks} MPI ranks")), "{log}");
            vtk_reads(&out.join(format!("{name}.pvd")));
            same_as_parallel(&d.join("serial"), &out, name)
        } else {
            same_outputs(&d.join("serial"), &out, true)
        };
        assert!(n >= 3, "only {n} files compared");
    }
}

#[test]
fn a_contact_case_on_1_2_3_ranks_is_the_serial_run_bit_for_bit() {
    ranks_match_serial("hertz_spheres", 1.0e-3, 120);
}

/// Failure across the ranks' boundaries: pairs with a failed member cut, pairs of intact
/// particles severed by a failed one between them (`physics::CrackLists`, found once a pair
/// from whichever side has a list on the rank), the same bit for bit on 1, 2 and 3 ranks as
/// serially. The case is `strike bench`'s Johnson–Cook steel cubes (16 000 particles, an
/// 11 GPa shock), over 2000 particles failed by step 250.
#[test]
fn failure_on_1_2_3_ranks_is_the_serial_run_bit_for_bit() {
    let d = dir("cubes_3d_jc");
    let deck = d.join("cubes_3d_jc.toml");
    std::fs::write(&deck, strike::bench::cubes_3d_jc()).unwrap();
    deck_matches_serial(&deck, "cubes_3d_jc", &d, 250);
    // The run does fail: the history's last row counts the failed particles.
    let history = strike::output::history::History::read(&d.join("serial/history.csv")).unwrap();
    let failed = *history.column("failed_particles").unwrap().last().unwrap();
    assert!(failed > 1000.0, "{failed} failed particles");
}

#[test]
fn sphere_plate_cn_on_1_2_3_ranks_and_a_restart_across_ranks_are_bit_identical() {
    // 60 steps: full and partial searches, a reordering at step 50 and the ranks' rebalancing.
    ranks_match_serial("sphere_plate_cn", 5.0e-5, 60);
    // 3 ranks to step 30, then on 2 ranks from its checkpoint to step 60.
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("mpi")
        .join("sphere_plate_cn");
    let deck = d.join("sphere_plate_cn.toml");
    let out = d.join("restart");
    run(&deck, &out, 30, 3, None);
    run(&deck, &out, 60, 2, Some(&out.join("checkpoint.bin")));
    // Its .pvd also lists the snapshot the first part wrote where it stopped: the serial
    // run's snapshots are compared with the pieces' of the same steps.
    let n = same_files(&d.join("serial"), &out, |name| name == "history.csv");
    assert_eq!(n, 1);
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/vtk_check.py");
    let mut compared = 0;
    for entry in std::fs::read_dir(d.join("serial")).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        let Some(step) = name
            .strip_prefix("sphere_plate_cn_")
            .and_then(|r| r.strip_suffix(".vtp"))
        else {
            continue;
        };
        // A one-snapshot series of each, compared by VTK's readers.
        let series = |dir: &Path, file: &str, tag: &str| {
            let path = d.join(format!("{tag}_{step}.pvd"));
            let xml = format!(
                "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n    <DataSet timestep=\"0\" file=\"{}\"/>\n  </Collection>\n</VTKFile>\n",
                dir.join(file).display()
            );
            std::fs::write(&path, xml).unwrap();
            path
        };
        let a = series(&d.join("serial"), &name, "serial");
        let b = series(&out, &format!("sphere_plate_cn_{step}.pvtp"), "restart");
        let o = Command::new(support::vtk_python())
            .arg(&script)
            .arg(&a)
            .arg("--same")
            .arg(&b)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "step {step}: {}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        );
        compared += 1;
    }
    assert!(compared >= 2, "only {compared} snapshots compared");
}

/// The other commands refuse several ranks with a clear error (they would write the same
/// files from every rank).
#[test]
fn other_commands_refuse_several_ranks() {
    let d = dir("refuse");
    let deck = deck("hertz_spheres", 1.0e-3, &d);
    let o = Command::new("mpirun")
        .args(["--oversubscribe", "-n", "2"])
        .arg(mpi_strike())
        .arg("check")
        .arg(&deck)
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        text.contains("only `strike run` and `strike bench` run on several MPI ranks"),
        "{text}"
    );
}

/// `mpirun -n 2 strike bench` reports where each rank's time went over the timed steps: the
/// search, the passes and the exchanges (waits included), disjoint spans of those steps, so
/// that they add up to no more than the wall time, and both ranks exchange.
#[test]
fn bench_on_2_ranks_reports_each_ranks_phases() {
    let d = dir("bench_phases");
    let json = d.join("bench.json");
    let o = Command::new("mpirun")
        .args(["--oversubscribe", "-n", "2"])
        .arg(mpi_strike())
        .args(["bench", "--quick", "--case", "cubes_3d", "--json"])
        .arg(&json)
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .env("RAYON_NUM_THREADS", "1")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    for c in v["cases"].as_array().unwrap() {
        assert_eq!(c["ranks"], 2, "{c}");
        let wall = c["wall_seconds"].as_f64().unwrap();
        let phases = c["phases"].as_array().unwrap();
        assert_eq!(phases.len(), 2, "{c}");
        for r in phases {
            let part = |k: &str| r[k].as_f64().unwrap();
            assert!(part("search") > 0.0 && part("passes") > 0.0, "{c}");
            assert!(part("exchanges") > 0.0, "{c}");
            // Each rank times its own loop; they end within a step's last exchange.
            let sum = part("search") + part("passes") + part("exchanges");
            assert!(sum <= 1.05 * wall + 0.01, "{sum} s of {wall}: {c}");
        }
    }
}
