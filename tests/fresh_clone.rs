//! A new user's two commands work on a fresh clone: the README's test command is exactly what
//! CI runs, needs no set-up step before it, and provisions VTK's Python reader by itself.

mod support;

use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn read(name: &str) -> String {
    std::fs::read_to_string(root().join(name)).unwrap()
}

/// The README's test command, as CI runs it, with nothing before it that a new user would not
/// run: `.ci/run` calls exactly that command and prepares nothing (the tests provision what
/// they need, see `tests/support`).
#[test]
fn readme_test_command_is_what_ci_runs_with_no_set_up_step() {
    let readme = read("README.md");
    let command = readme
        .lines()
        .map(str::trim)
        .find(|l| l.starts_with("cargo test"))
        .expect("the README names its test command")
        .split('#')
        .next()
        .unwrap()
        .trim()
        .to_string();
    let ci = read(".ci/run");
    let lines: Vec<&str> = ci
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .collect();
    assert!(
        lines.contains(&command.as_str()),
        ".ci/run does not run the README's `{command}`"
    );
    for l in &lines {
        assert!(
            !l.contains("setup") && !l.contains("pip ") && !l.contains("venv"),
            ".ci/run prepares something before the tests: {l}"
        );
    }
    // No test reads a hand-made environment.
    for entry in std::fs::read_dir(root().join("tests")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "rs") {
            let text = std::fs::read_to_string(&path).unwrap();
            assert!(
                !text.contains(&format!("{}venv/", '.')),
                "{} uses a hand-made .venv",
                path.display()
            );
        }
    }
}

/// From nothing (no environment at all) the tests' provisioning makes a Python that imports
/// VTK, as on a fresh clone.
#[test]
fn vtk_reader_is_provisioned_from_nothing() {
    let venv = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fresh-clone-venv");
    let _ = std::fs::remove_dir_all(&venv);
    let python = support::provision(&venv).unwrap_or_else(|e| panic!("{e}"));
    let out = std::process::Command::new(&python)
        .args(["-c", "import vtk; print(vtk.vtkVersion.GetVTKVersion())"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    println!(
        "provisioned VTK {}",
        String::from_utf8_lossy(&out.stdout).trim()
    );
    let _ = std::fs::remove_dir_all(&venv);
}
