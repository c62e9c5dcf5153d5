//! What a hostile tester tries: signals, kill -9, a full disk, damaged or mismatched
//! checkpoints, re-runs into an old output directory, absurd output settings, huge decks, logs
//! that are not terminals. Each test drives the `strike` binary as a user would.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};
use strike::output::summary::Summary;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn strike(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_strike"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("strike runs")
}

/// A fresh directory for one test.
fn dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("reliability")
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The bars example with `edits` (from → to) applied, written to `dir/name.toml`.
fn bars_deck(dir: &Path, name: &str, edits: &[(&str, &str)]) -> PathBuf {
    let mut text = std::fs::read_to_string(root().join("examples/bars_contact.toml")).unwrap();
    for (from, to) in edits {
        assert!(text.contains(from), "{from}");
        text = text.replacen(from, to, 1);
    }
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `strike run DECK --resume OUT/checkpoint.bin --max-steps CAP`.
fn resume(deck: &Path, out: &Path, cap: &str) -> Output {
    strike(&[
        "run",
        s(deck),
        "--resume",
        s(&out.join("checkpoint.bin")),
        "--max-steps",
        cap,
    ])
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Files in `dir` whose names start with a dot (the atomic writer's temporary names).
fn hidden_files(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect()
}

fn files_ending(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.to_string_lossy().ends_with(ext)
                && !p.file_name().unwrap().to_string_lossy().starts_with('.')
        })
        .collect();
    v.sort();
    v
}

/// Wait for `child` to exit (at most `limit`), killing it and failing if it does not.
fn wait(child: &mut Child, limit: Duration) -> std::process::ExitStatus {
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return status;
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            panic!("strike did not exit within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Start a long run of the bars in the background and wait until it has written `rows` history
/// rows.
fn start_long_run(deck: &Path, out: &Path, rows: usize) -> Child {
    let mut child = Command::new(env!("CARGO_BIN_EXE_strike"))
        .args(["run", s(deck), "--out", s(out), "--threads", "1"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        let text = std::fs::read_to_string(out.join("history.csv")).unwrap_or_default();
        if text.lines().count() > rows {
            return child;
        }
        if let Some(status) = child.try_wait().unwrap() {
            let mut err = String::new();
            use std::io::Read;
            let _ = child.stderr.take().unwrap().read_to_string(&mut err);
            panic!("the run ended early: {status}: {err}");
        }
        assert!(start.elapsed() < Duration::from_secs(120), "no progress");
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// SIGINT and SIGTERM end a run after its current step: exit status 130, a checkpoint of that
/// step, `summary.json` with status `interrupted`; the checkpoint then resumes to the end.
#[test]
fn signals_stop_with_a_checkpoint_that_resumes() {
    let d = dir("signals");
    // Long enough that the signal surely arrives mid-run.
    let deck = bars_deck(&d, "bars", &[("end_time = 30.0e-6", "end_time = 3.0e-3")]);
    for signal in ["INT", "TERM"] {
        let out = d.join(signal);
        let mut child = start_long_run(&deck, &out, 5);
        let kill = Command::new("kill")
            .args([&format!("-{signal}"), &child.id().to_string()])
            .status()
            .unwrap();
        assert!(kill.success());
        let status = wait(&mut child, Duration::from_secs(60));
        assert_eq!(status.code(), Some(130), "SIG{signal}");
        let summary = Summary::read(&out.join("summary.json")).unwrap();
        assert_eq!(summary.status, "interrupted", "SIG{signal}");
        assert!(summary.steps > 0 && summary.end_time < 3.0e-3);
        assert!(hidden_files(&out).is_empty(), "{:?}", hidden_files(&out));
        // The checkpoint is of the last step and goes on from it (briefly: a step cap).
        let cap = (summary.steps + 20).to_string();
        let resumed = resume(&deck, &out, &cap);
        assert!(resumed.status.success(), "{}", stderr(&resumed));
        let again = Summary::read(&out.join("summary.json")).unwrap();
        assert_eq!(again.status, "max_steps");
        assert_eq!(again.steps, summary.steps + 20);
    }
}

/// `kill -9` in the middle of a run that writes a snapshot at every step leaves only complete
/// files: every snapshot ends with its closing tag, the series lists only existing snapshots,
/// and the checkpoint reads (checksum) and resumes.
#[test]
fn kill_9_leaves_only_complete_files() {
    let d = dir("kill9");
    let deck = bars_deck(
        &d,
        "bars",
        &[
            ("end_time = 30.0e-6", "end_time = 3.0e-3"),
            ("snapshot_interval = 5.0e-6", "snapshot_interval = 1.0e-7"),
            ("spacing = 0.5e-3", "spacing = 0.25e-3"),
            ("spacing = 0.5e-3", "spacing = 0.25e-3"),
        ],
    );
    let out = d.join("out");
    let mut child = start_long_run(&deck, &out, 3);
    std::thread::sleep(Duration::from_millis(300));
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    let snapshots = files_ending(&out, ".vtp");
    assert!(snapshots.len() >= 3, "{} snapshots", snapshots.len());
    for f in &snapshots {
        let bytes = std::fs::read(f).unwrap();
        assert!(
            bytes.ends_with(b"</VTKFile>\n"),
            "{} is incomplete",
            f.display()
        );
    }
    let pvd = std::fs::read_to_string(out.join("bars_contact.pvd")).unwrap();
    assert!(pvd.ends_with("</VTKFile>\n"));
    for listed in pvd.split("file=\"").skip(1) {
        let name = listed.split('"').next().unwrap();
        assert!(out.join(name).exists(), "{name} listed but missing");
    }
    // The checkpoint reads (magic, checksum, set-up) and resumes for a few steps.
    let case = strike::deck::load(&deck).unwrap();
    let c = strike::output::checkpoint::Checkpoint::<2>::read(&out.join("checkpoint.bin"), &case)
        .unwrap();
    let cap = (c.sim.step + 5).to_string();
    let resumed = resume(&deck, &out, &cap);
    assert!(resumed.status.success(), "{}", stderr(&resumed));
}

/// A disk that fills (here: a file-size limit, which fails writes the same way) stops the run
/// with status `failed` naming the file, leaves no temporary file, and still writes
/// `summary.json`.
#[test]
fn full_disk_fails_cleanly_with_a_summary() {
    let d = dir("full_disk");
    let deck = bars_deck(&d, "bars", &[]);
    let out = d.join("out");
    std::fs::create_dir_all(&out).unwrap();
    // 150 kB per file: the history and summary fit, a snapshot (190 kB) does not.
    let run = Command::new("bash")
        .arg("-c")
        .arg(format!(
            "trap '' XFSZ; ulimit -f 150; exec '{}' run '{}' --out '{}'",
            env!("CARGO_BIN_EXE_strike"),
            s(&deck),
            s(&out)
        ))
        .output()
        .unwrap();
    let err = stderr(&run);
    assert!(!run.status.success(), "{err}");
    assert!(err.contains(".vtp"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let summary = Summary::read(&out.join("summary.json")).unwrap();
    assert_eq!(summary.status, "failed");
    assert!(summary.reason.contains(".vtp"), "{}", summary.reason);
    assert!(hidden_files(&out).is_empty(), "{:?}", hidden_files(&out));
    assert!(files_ending(&out, ".vtp").is_empty());
}

/// A re-run into a directory holding an earlier run is refused; with --overwrite the earlier
/// run's files go (and only they), so no old snapshot stands beside the new ones.
#[test]
fn earlier_run_is_refused_and_overwrite_removes_only_its_files() {
    let d = dir("overwrite");
    let dense = bars_deck(
        &d,
        "dense",
        &[("snapshot_interval = 5.0e-6", "snapshot_interval = 1.0e-6")],
    );
    let out = d.join("out");
    let first = strike(&["run", s(&dense), "--out", s(&out)]);
    assert!(first.status.success(), "{}", stderr(&first));
    let old = files_ending(&out, ".vtp").len();
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let sparse = bars_deck(&d, "sparse", &[]);
    let again = strike(&["run", s(&sparse), "--out", s(&out)]);
    assert!(!again.status.success());
    let err = stderr(&again);
    assert!(
        err.contains("earlier run") && err.contains("--overwrite"),
        "{err}"
    );
    assert_eq!(
        files_ending(&out, ".vtp").len(),
        old,
        "a refused run changed nothing"
    );
    let replaced = strike(&["run", s(&sparse), "--out", s(&out), "--overwrite"]);
    assert!(replaced.status.success(), "{}", stderr(&replaced));
    let new = files_ending(&out, ".vtp").len();
    // 30 µs every 5 µs: 0, 5, …, 30 → 7 snapshots (the old run wrote 31).
    assert_eq!((old, new), (31, 7));
    assert_eq!(
        std::fs::read_to_string(out.join("notes.txt")).unwrap(),
        "mine"
    );
}

/// A damaged checkpoint (a flipped bit, a truncated file) and a checkpoint of another physical
/// set-up are refused, naming what is wrong; changed end time and outputs are accepted.
#[test]
fn damaged_or_mismatched_checkpoints_are_refused() {
    let d = dir("checkpoints");
    let deck = bars_deck(&d, "bars", &[]);
    let out = d.join("out");
    let run = strike(&["run", s(&deck), "--out", s(&out), "--max-steps", "30"]);
    assert!(run.status.success(), "{}", stderr(&run));
    let good = std::fs::read(out.join("checkpoint.bin")).unwrap();
    let resume = |file: &Path, deck: &Path| {
        strike(&[
            "run",
            s(deck),
            "--resume",
            s(file),
            "--out",
            s(&out),
            "--max-steps",
            "40",
        ])
    };
    let mut flipped = good.clone();
    let k = flipped.len() / 2;
    flipped[k] ^= 0x10;
    let bad = d.join("flipped.bin");
    std::fs::write(&bad, &flipped).unwrap();
    let r = resume(&bad, &deck);
    assert!(!r.status.success());
    assert!(stderr(&r).contains("checksum"), "{}", stderr(&r));
    std::fs::write(&bad, &good[..good.len() - 100]).unwrap();
    let r = resume(&bad, &deck);
    assert!(!r.status.success());
    assert!(stderr(&r).contains("damaged"), "{}", stderr(&r));
    let changed = bars_deck(&d, "changed", &[("density = 2700.0", "density = 2800.0")]);
    let r = resume(&out.join("checkpoint.bin"), &changed);
    assert!(!r.status.success());
    let err = stderr(&r);
    assert!(
        err.contains("materials.al_6061") && err.contains("2700") && err.contains("2800"),
        "{err}"
    );
    let moved = bars_deck(
        &d,
        "moved",
        &[("velocity = [10.0, 0.0]", "velocity = [12.0, 0.0]")],
    );
    let r = resume(&out.join("checkpoint.bin"), &moved);
    assert!(stderr(&r).contains("body 'left'"), "{}", stderr(&r));
    let later = bars_deck(
        &d,
        "later",
        &[
            ("end_time = 30.0e-6", "end_time = 40.0e-6"),
            ("snapshot_interval = 5.0e-6", "snapshot_interval = 2.0e-6"),
        ],
    );
    let r = resume(&out.join("checkpoint.bin"), &later);
    assert!(r.status.success(), "{}", stderr(&r));
}

/// Snapshots far denser than the steps: at most one per step, the physical time step is not
/// shortened (the same steps as with sparse snapshots), `--max-steps` is honoured, and `check`
/// reports the snapshot count and volume.
#[test]
fn dense_outputs_never_stall_or_shrink_the_run() {
    let d = dir("dense_outputs");
    let none = bars_deck(&d, "none", &[("snapshot_interval = 5.0e-6", "")]);
    let dense = bars_deck(
        &d,
        "dense",
        &[("snapshot_interval = 5.0e-6", "snapshot_interval = 3.0e-10")],
    );
    let check = strike(&["check", s(&dense)]);
    let text = String::from_utf8_lossy(&check.stdout);
    assert!(check.status.success(), "{}", stderr(&check));
    assert!(
        text.contains("snapshots: ") && text.contains("MB in all"),
        "{text}"
    );
    assert!(text.contains("one snapshot per step"), "{text}");
    let a = strike(&["run", s(&none), "--out", s(&d.join("a"))]);
    let b = strike(&["run", s(&dense), "--out", s(&d.join("b"))]);
    assert!(a.status.success() && b.status.success(), "{}", stderr(&b));
    let sa = Summary::read(&d.join("a/summary.json")).unwrap();
    let sb = Summary::read(&d.join("b/summary.json")).unwrap();
    assert_eq!(sa.steps, sb.steps, "dense snapshots changed the time steps");
    let snapshots = files_ending(&d.join("b"), ".vtp").len() as u64;
    assert!(
        snapshots <= sb.steps + 1,
        "{snapshots} snapshots in {} steps",
        sb.steps
    );
    assert!(
        snapshots > sb.steps / 2,
        "{snapshots} snapshots in {} steps",
        sb.steps
    );
    let c = strike(&[
        "run",
        s(&dense),
        "--out",
        s(&d.join("c")),
        "--max-steps",
        "7",
    ]);
    assert!(c.status.success());
    let sc = Summary::read(&d.join("c/summary.json")).unwrap();
    assert_eq!((sc.steps, sc.status.as_str()), (7, "max_steps"));
}

/// `check` on a ten-million-particle deck: refused with the memory it needs when the process
/// may not have it (ulimit -v), never an allocation abort; estimated without being set up when
/// it fits, with a warning for a run beyond a day.
#[test]
fn check_estimates_huge_decks_before_allocating() {
    let d = dir("huge");
    let huge = |name: &str, n_side: f64, end: &str| {
        let spacing = format!("{:e}", 0.1 / n_side);
        let text = format!(
            "[simulation]\ndimension = 3\nend_time = {end}\n[[body]]\nname = \"block\"\nmaterial = \"al_6061_t6\"\nspacing = {spacing}\nshape = {{ type = \"box\", min = [0.0, 0.0, 0.0], max = [0.1, 0.1, 0.1] }}\n"
        );
        let path = d.join(format!("{name}.toml"));
        std::fs::write(&path, text).unwrap();
        path
    };
    let ten_million = huge("ten_million", 215.5, "1.0e-6");
    let limited = Command::new("bash")
        .arg("-c")
        .arg(format!(
            "ulimit -v 4000000; exec '{}' check '{}'",
            env!("CARGO_BIN_EXE_strike"),
            s(&ten_million)
        ))
        .output()
        .unwrap();
    let err = stderr(&limited);
    assert_eq!(limited.status.code(), Some(1), "{err}");
    assert!(
        err.contains("ten_million.toml:7:") && err.contains("of memory"),
        "{err}"
    );
    assert!(err.contains("GiB"), "{err}");
    assert!(
        !err.contains("memory allocation") && !err.contains("panicked"),
        "{err}"
    );
    let three_million = huge("three_million", 144.3, "1.0e-2");
    let checked = strike(&["check", s(&three_million)]);
    let text = String::from_utf8_lossy(&checked.stdout);
    assert!(checked.status.success(), "{}", stderr(&checked));
    assert!(text.contains("estimated: the case is too large"), "{text}");
    assert!(text.contains("particles: ~3.00"), "{text}");
    assert!(text.contains("warning: the run would take about"), "{text}");
}

/// Logs and error reports written to a file or pipe carry no terminal colour codes.
#[test]
fn no_colour_codes_off_a_terminal() {
    let d = dir("colour");
    let deck = bars_deck(&d, "bars", &[]);
    let run = strike(&[
        "run",
        s(&deck),
        "--out",
        s(&d.join("out")),
        "--max-steps",
        "2",
    ]);
    let bad = bars_deck(&d, "bad", &[("density = 2700.0", "density = -2700.0")]);
    let check = strike(&["check", s(&bad)]);
    for o in [&run, &check] {
        let text = format!("{}{}", stderr(o), String::from_utf8_lossy(&o.stdout));
        assert!(!text.is_empty());
        assert!(!text.contains('\u{1b}'), "escape codes in {text:?}");
    }
    assert!(stderr(&check).contains("bad.toml:"));
}

/// `check` gives each body's mass against its shape's, and warns where a lattice too coarse
/// for a curved body misses it: the basalt disc 1 mm across at 50 µm holds its area (316
/// particles for 314.2, +0.6 %), the same disc 0.24 mm across holds 16 particles for 18.1
/// (−11.6 %, the nearest of its lattice's layouts: `setup::shapes::lattice`), and is warned of.
#[test]
fn check_warns_of_a_body_whose_lattice_misses_its_mass() {
    let d = dir("mass");
    let text = std::fs::read_to_string(root().join("examples/basalt_impact_2d.toml")).unwrap();
    let fine = strike(&["check", "examples/basalt_impact_2d.toml"]);
    let out = String::from_utf8_lossy(&fine.stdout);
    assert!(fine.status.success(), "{}", stderr(&fine));
    assert!(out.contains("(+0.6 % of its shape's)"), "{out}");
    assert!(!out.contains("of its shape's mass"), "{out}");
    let coarse = d.join("coarse.toml");
    std::fs::write(
        &coarse,
        text.replace("radius = 5.0e-4 }", "radius = 1.2e-4 }"),
    )
    .unwrap();
    let checked = strike(&["check", s(&coarse)]);
    let out = String::from_utf8_lossy(&checked.stdout);
    assert!(checked.status.success(), "{}", stderr(&checked));
    assert!(
        out.contains("warning: body 'disc' carries -11.6 % of its shape's mass"),
        "{out}"
    );
}
