//! `strike validate` as a user meets it: the report's files, the exit status when a check
//! fails, the README's table written between its markers, and unknown cases named.

use std::path::{Path, PathBuf};
use std::process::Command;

fn strike(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_strike"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("strike runs")
}

fn out_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("validate")
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The elastic wave passes: a Markdown report with its table and plots, an HTML page with
/// the plots inside it, and the table written into a README between its markers (the text
/// around them untouched). At a thousandth of its tolerances the same case fails, and the
/// exit status says so.
#[test]
fn a_report_a_readme_table_and_a_failing_exit() {
    let out = out_dir("wave");
    let readme = out.join("README.md");
    std::fs::write(
        &readme,
        "intro\n<!-- strike validate: begin -->\nold\n<!-- strike validate: end -->\nrest\n",
    )
    .unwrap();
    let o = strike(&[
        "validate",
        "--case",
        "elastic_wave",
        "--out",
        out.to_str().unwrap(),
        "--readme",
        readme.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        md.contains("| elastic_wave | front speed |") && md.contains("| pass |"),
        "{md}"
    );
    assert!(md.contains("elastic_wave_profile_conventional.png"));
    assert!(out.join("elastic_wave_profile_cn.png").exists());
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(html.contains("data:image/png;base64,iVBOR"));
    let text = std::fs::read_to_string(&readme).unwrap();
    assert!(
        text.starts_with("intro\n<!-- strike validate: begin -->\nWritten by `strike validate`")
    );
    assert!(text.ends_with("<!-- strike validate: end -->\nrest\n"));
    assert!(!text.contains("old") && text.contains("| elastic_wave | σ_xx behind the front |"));

    let o = strike(&[
        "validate",
        "--case",
        "elastic_wave",
        "--out",
        out.to_str().unwrap(),
        "--tolerance-factor",
        "0.001",
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("1 of 1 cases failed: elastic_wave"));
    assert!(std::fs::read_to_string(out.join("report.md"))
        .unwrap()
        .contains("**FAIL**"));
}

#[test]
fn unknown_cases_and_readmes_without_markers_are_named() {
    let out = out_dir("mistakes");
    let o = strike(&[
        "validate",
        "--case",
        "hertz_sphere",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr).replace(['│', '\n'], " ");
    assert!(
        err.contains("no verification case `hertz_sphere`")
            && err.contains("elastic_wave")
            && err.contains("hertz"),
        "{err}"
    );
    let readme = out.join("README.md");
    std::fs::write(&readme, "no markers\n").unwrap();
    let o = strike(&[
        "validate",
        "--case",
        "hel",
        "--out",
        out.to_str().unwrap(),
        "--readme",
        readme.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("block to write the table into"));
    // The help names every case.
    let help = String::from_utf8_lossy(&strike(&["validate", "--help"]).stdout).to_string();
    for c in strike::validate::cases() {
        assert!(help.contains(c.name), "`{}` missing from the help", c.name);
    }
}
