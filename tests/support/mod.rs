//! What several test files share: the example decks, at one resolution or two, and the Python
//! with VTK's own reader that checks output files.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;
use strike::case::Case;

/// The deck `examples/NAME.toml`.
pub fn example(name: &str) -> Case {
    let path = format!("{}/examples/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    strike::deck::load(Path::new(&path)).unwrap_or_else(|e| panic!("{path}: {e:?}"))
}

/// The deck `examples/NAME.toml`, and the same with every spacing halved.
pub fn two_resolutions(name: &str) -> [Case; 2] {
    let coarse = example(name);
    let mut fine = coarse.clone();
    for b in &mut fine.bodies {
        b.spacing *= 0.5;
    }
    [coarse, fine]
}

/// The Python of a virtual environment holding VTK's Python package, made by
/// `tests/support/provision_vtk.sh` the first time a test asks for it (on a fresh clone, the
/// first `cargo test`), under a file lock so that concurrent test processes make it once. It
/// lives in the build's temporary directory, so `cargo clean` removes it. A failure to provision
/// fails the test that asked, with the script's output: the check is never skipped.
pub fn vtk_python() -> PathBuf {
    static PYTHON: OnceLock<PathBuf> = OnceLock::new();
    PYTHON
        .get_or_init(|| {
            let venv = Path::new(env!("CARGO_TARGET_TMPDIR")).join("vtk-venv");
            provision(&venv).unwrap_or_else(|e| panic!("{e}"))
        })
        .clone()
}

/// Make (or check) the VTK environment at `venv`; returns its Python.
pub fn provision(venv: &Path) -> Result<PathBuf, String> {
    let python = venv.join("bin/python");
    let parent = venv.parent().ok_or("no parent directory")?;
    std::fs::create_dir_all(parent).map_err(|e| format!("{}: {e}", parent.display()))?;
    let lock_path = venv.with_extension("lock");
    let lock =
        std::fs::File::create(&lock_path).map_err(|e| format!("{}: {e}", lock_path.display()))?;
    lock.lock()
        .map_err(|e| format!("lock {}: {e}", lock_path.display()))?;
    let ready = Command::new(&python)
        .args(["-c", "import vtk"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ready {
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/support/provision_vtk.sh");
        let out = Command::new("bash")
            .arg(&script)
            .arg(venv)
            .output()
            .map_err(|e| format!("cannot run {}: {e}", script.display()))?;
        if !out.status.success() {
            return Err(format!(
                "could not provision VTK's Python package in {} (needs python3 and the network to PyPI):\n{}{}",
                venv.display(),
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr)
            ));
        }
    }
    drop(lock);
    Ok(python)
}

/// Every check of a `strike validate` case within its tolerance, each printed first (run with
/// `--nocapture` for the figures); returns the checks.
pub fn validated(
    outcome: strike::Result<strike::validate::Outcome>,
) -> Vec<strike::validate::Check> {
    let outcome = outcome.unwrap_or_else(|e| panic!("the case does not run: {e}"));
    for c in &outcome.checks {
        println!(
            "{} ({}): {:.6e} {} against {:.6e}, {:?}{}",
            c.quantity,
            c.setting,
            c.measured,
            c.unit,
            c.reference,
            c.bound,
            if c.bound == strike::validate::Bound::Relative {
                format!(
                    " {:+.3} % (tolerance {} %)",
                    100.0 * c.error(),
                    100.0 * c.tolerance
                )
            } else {
                String::new()
            }
        );
    }
    for c in &outcome.checks {
        assert!(c.passes(1.0), "{c:?}");
    }
    outcome.checks
}
