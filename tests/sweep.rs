//! `strike sweep` as a user meets it: a sweep's table and plot, a ballistic limit's bracket
//! (examples/plate_2d.toml: a steel rod through a clamped aluminium plate, plane strain), its
//! independence of how many runs go at once, and the mistakes a user makes.

use std::path::{Path, PathBuf};
use std::process::Command;

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

fn out_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("sweep")
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn table(path: &Path) -> Vec<std::collections::HashMap<String, String>> {
    let mut r = csv::Reader::from_path(path).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    r.records()
        .map(|rec| {
            header
                .iter()
                .cloned()
                .zip(rec.unwrap().iter().map(String::from))
                .collect()
        })
        .collect()
}

fn is_png(path: &Path) -> bool {
    std::fs::read(path).is_ok_and(|b| b.starts_with(b"\x89PNG\r\n\x1a\n"))
}

/// Two speeds and two plate densities: four runs, every combination, in a table with the keys'
/// values and the outcomes, and a plot. The rod is held at 150 m/s and goes through at 400 m/s
/// with most of its speed (the plate takes a few per cent of its energy).
#[test]
fn a_sweep_tabulates_every_combination() {
    let out = out_dir("speeds");
    let o = strike(&[
        "sweep",
        "examples/plate_2d.toml",
        "--set",
        "body.rod.velocity=150,400",
        "--set",
        "materials.al.density=2703,2800",
        "--jobs",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = table(&out.join("sweep.csv"));
    assert_eq!(rows.len(), 4);
    for r in &rows {
        let v: f64 = r["body.rod.velocity"].parse().unwrap();
        assert_eq!(r["status"], "completed");
        assert_eq!(r["perforated"], (v > 300.0).to_string(), "{r:?}");
        if v > 300.0 {
            let vr: f64 = r["residual_velocity_m_s"].parse().unwrap();
            assert!(vr > 0.8 * v && vr < v, "{r:?}");
            assert_eq!(r["residual_mass_fraction"].parse::<f64>().unwrap(), 1.0);
        }
        assert!(r["energy_error"].parse::<f64>().unwrap() < 0.01, "{r:?}");
    }
    assert_eq!(rows[0]["body.rod.velocity"], "150");
    assert_eq!(rows[1]["materials.al.density"], "2800");
    assert!(is_png(&out.join("sweep.png")));
    // The same directory again is refused without --overwrite.
    let again = strike(&[
        "sweep",
        "examples/plate_2d.toml",
        "--set",
        "body.rod.velocity=150",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!again.status.success());
    assert!(String::from_utf8_lossy(&again.stderr).contains("--overwrite"));
}

/// The ballistic limit: the bracket is at most the tolerance wide, its lower run held and its
/// upper run perforated, every slower run held and every faster one went through; the runs at
/// the bracket's ends give the same bits whether the runs go one or two at a time.
#[test]
fn the_ballistic_limit_is_bracketed_alike_one_or_two_at_a_time() {
    let mut brackets = Vec::new();
    let mut ends = Vec::new();
    for jobs in ["1", "2"] {
        let out = out_dir(&format!("limit_{jobs}"));
        let o = strike(&[
            "sweep",
            "examples/plate_2d.toml",
            "--ballistic-limit",
            "rod",
            "--speeds",
            "100:1000",
            "--tolerance",
            "20",
            "--jobs",
            jobs,
            "--out",
            out.to_str().unwrap(),
        ]);
        let stdout = String::from_utf8_lossy(&o.stdout).to_string();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        println!("{jobs} at a time: {}", stdout.lines().next().unwrap_or(""));
        let json: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(out.join("ballistic_limit.json")).unwrap(),
        )
        .unwrap();
        let (below, above) = (
            json["below"].as_f64().unwrap(),
            json["above"].as_f64().unwrap(),
        );
        assert!(above > below && above - below <= 20.0, "{below} {above}");
        let rows = table(&out.join("ballistic_limit.csv"));
        for r in &rows {
            let v: f64 = r["impact_speed_m_s"].parse().unwrap();
            // (serde_json reads floats to within an ulp.)
            assert_eq!(
                r["perforated"],
                (v >= above * (1.0 - 1e-12)).to_string(),
                "{r:?}"
            );
        }
        assert!(is_png(&out.join("ballistic_limit.png")));
        brackets.push((below, above));
        ends.push(
            rows.iter()
                .filter(|r| r["impact_speed_m_s"] == "100" || r["impact_speed_m_s"] == "1000")
                .map(|r| r["residual_velocity_m_s"].clone())
                .collect::<Vec<_>>(),
        );
    }
    // Bisection and trisection close on the same limit.
    let (a, b) = (brackets[0], brackets[1]);
    assert!(a.0 < b.1 && b.0 < a.1, "{brackets:?}");
    assert_eq!(ends[0], ends[1]);
}

#[test]
fn mistakes_are_named() {
    let cases: [(&[&str], &str); 6] = [
        (
            &["--set", "body.bullet.velocity=100"],
            "no `body` is named `bullet`",
        ),
        (&["--set", "body.rod.velocity=fast"], "not a finite number"),
        (&["--set", "simulation.cfl=5"], "simulation.cfl"),
        (&["--ballistic-limit", "rod"], "--speeds"),
        (
            &["--ballistic-limit", "rod", "--speeds", "900:1000"],
            "already perforates",
        ),
        (&[], "nothing to sweep"),
    ];
    for (args, expect) in cases {
        let out = out_dir("mistake");
        let mut all = vec![
            "sweep",
            "examples/plate_2d.toml",
            "--out",
            out.to_str().unwrap(),
        ];
        all.extend_from_slice(args);
        let o = strike(&all);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?}");
        assert!(err.contains(expect), "{args:?}: {err}");
    }
}
