//! Output files: .vtp/.pvd checked with VTK's own reader (through `tests/vtk_check.py` in the
//! `.venv` made by `.ci/setup_python.sh`) and read back byte by byte; PNG pictures checked for
//! size and content.

use std::path::{Path, PathBuf};
use std::process::Command;

use strike::output::vtk::{self, PvdWriter};
use strike::particles::{Particles, Tensor, Vector};

const FIELDS: &str = "body,id,velocity,pressure,density,internal_energy,deviatoric_stress,\
                      von_mises,plastic_strain,smoothing_length,contact_force,mass";

fn out_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create test output folder");
    dir
}

fn python() -> PathBuf {
    let py = Path::new(env!("CARGO_MANIFEST_DIR")).join(".venv/bin/python");
    assert!(
        py.exists(),
        "{} is missing: run .ci/setup_python.sh first (it creates .venv with VTK's python \
         package, which these tests use to read the files back)",
        py.display()
    );
    py
}

/// Run tests/vtk_check.py on `file`; panics with its output unless it succeeds.
fn vtk_check(file: &Path, points: usize, extra: &[&str]) -> String {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/vtk_check.py");
    let out = Command::new(python())
        .arg(&script)
        .arg(file)
        .args(["--points", &points.to_string(), "--fields", FIELDS])
        .args(extra)
        .output()
        .expect("run vtk_check.py");
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        out.status.success(),
        "vtk_check.py failed on {}:\n{stdout}\n{stderr}",
        file.display()
    );
    assert!(stdout.starts_with("ok "), "unexpected output: {stdout}");
    stdout
}

fn particles_2d() -> Particles<2> {
    let mut p = Particles::<2>::default();
    for k in 0..6 {
        let x = Vector::<2>::new(0.001 * k as f64, -0.002 * k as f64);
        let v = Vector::<2>::new(10.0 * k as f64, -3.0);
        p.push(
            x,
            v,
            1e-6 * (k + 1) as f64,
            7800.0 + k as f64,
            1.2e-3,
            (k % 2) as u32,
        );
        p.p[k] = 1.0e8 * k as f64 + 0.125;
        p.e[k] = 3.5 * k as f64;
        p.eps_p[k] = 0.01 * k as f64;
        p.s[k] = Tensor::<2>::new(1.0e6, 2.0e5, 2.0e5, -3.0e6) * k as f64;
        p.contact_force[k] = Vector::<2>::new(k as f64, -(k as f64));
    }
    p.p[3] = std::f64::consts::PI * 1.0e9;
    // Two ghosts: must not be written.
    p.push_copy(0);
    p.push_copy(1);
    p.n_real = 6;
    p
}

fn particles_3d() -> Particles<3> {
    let mut p = Particles::<3>::default();
    for k in 0..10 {
        let x = Vector::<3>::new(0.001 * k as f64, 0.0005 * k as f64, -0.001 * k as f64);
        let v = Vector::<3>::new(1.0, 2.0, 3.0 * k as f64);
        p.push(x, v, 1e-6, 2700.0, 1.0e-3, (k / 5) as u32);
        p.p[k] = -1.5e7 * k as f64;
        p.s[k] = Tensor::<3>::new(1.0, 2.0, 3.0, 2.0, -4.0, 5.0, 3.0, 5.0, 3.0) * 1.0e6;
    }
    p.p[3] = 1.0 / 3.0;
    p
}

/// The raw bytes of array `name` in a .vtp written by `vtk::write_snapshot`.
fn appended_array(bytes: &[u8], name: &str) -> Vec<u8> {
    let marker = b"<AppendedData encoding=\"raw\">";
    let start = bytes
        .windows(marker.len())
        .position(|w| w == marker)
        .expect("AppendedData element");
    let header = std::str::from_utf8(&bytes[..start]).expect("XML header is UTF-8");
    assert!(header.starts_with("<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\""));
    assert!(header.contains("byte_order=\"LittleEndian\""));
    assert!(header.contains("header_type=\"UInt64\""));
    let underscore = start
        + marker.len()
        + bytes[start + marker.len()..]
            .iter()
            .position(|&b| b == b'_')
            .expect("`_` starting the appended data");
    let data = &bytes[underscore + 1..];
    let tag = format!("Name=\"{name}\"");
    let line = header
        .lines()
        .find(|l| l.contains(&tag))
        .unwrap_or_else(|| panic!("no array {name}"));
    let offset: usize = line
        .split("offset=\"")
        .nth(1)
        .and_then(|s| s.split('"').next())
        .and_then(|s| s.parse().ok())
        .expect("offset attribute");
    let count = u64::from_le_bytes(data[offset..offset + 8].try_into().unwrap()) as usize;
    data[offset + 8..offset + 8 + count].to_vec()
}

fn f64_at(raw: &[u8], k: usize) -> f64 {
    f64::from_le_bytes(raw[8 * k..8 * k + 8].try_into().unwrap())
}

#[test]
fn vtp_2d_reads_back() {
    let dir = out_dir("vtk_2d");
    let p = particles_2d();
    let file = dir.join("snap.vtp");
    vtk::write_snapshot(&file, &p, 1.25e-6).unwrap();
    let out = vtk_check(&file, 6, &["--time", "1.25e-6"]);
    assert!(out.contains("6 points"), "{out}");

    let bytes = std::fs::read(&file).unwrap();
    let pressure = appended_array(&bytes, "pressure");
    assert_eq!(pressure.len(), 6 * 8);
    assert_eq!(f64_at(&pressure, 3), std::f64::consts::PI * 1.0e9);
    let points = appended_array(&bytes, "Points");
    assert_eq!(points.len(), 6 * 3 * 8);
    assert_eq!(f64_at(&points, 3 * 4), 0.004);
    assert_eq!(f64_at(&points, 3 * 4 + 1), -0.008);
    assert_eq!(f64_at(&points, 3 * 4 + 2), 0.0);
    // Plane strain: S_zz = −(S_xx + S_yy), zero elsewhere in the z row and column.
    let s = appended_array(&bytes, "deviatoric_stress");
    let s2: Vec<f64> = (0..9).map(|c| f64_at(&s, 9 * 2 + c)).collect();
    assert_eq!(s2, [2e6, 4e5, 0.0, 4e5, -6e6, 0.0, 0.0, 0.0, 4e6]);
    let body = appended_array(&bytes, "body");
    let body: Vec<i32> = body
        .chunks(4)
        .map(|c| i32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(body, [0, 1, 0, 1, 0, 1]);
    assert_eq!(f64_at(&appended_array(&bytes, "TIME"), 0), 1.25e-6);
}

#[test]
fn vtp_3d_and_pvd_read_back() {
    let dir = out_dir("vtk_3d");
    let mut p = particles_3d();
    let mut pvd = PvdWriter::new(&dir.join("run.pvd"));
    for step in 0..3 {
        let t = step as f64 * 5.0e-7;
        let name = format!("snap_{step:04}.vtp");
        vtk::write_snapshot(&dir.join(&name), &p, t).unwrap();
        pvd.add(t, &name).unwrap();
        // The collection is valid after every add.
        let out = vtk_check(&dir.join("run.pvd"), 10, &[]);
        assert!(out.contains(&format!("{} snapshots", step + 1)), "{out}");
        for x in &mut p.x {
            x[2] -= 1.0e-4;
        }
    }
    assert_eq!(pvd.len(), 3);
    let out = vtk_check(&dir.join("snap_0002.vtp"), 10, &["--time", "1e-6"]);
    assert!(out.contains("10 points"), "{out}");

    let bytes = std::fs::read(dir.join("snap_0002.vtp")).unwrap();
    assert_eq!(f64_at(&appended_array(&bytes, "pressure"), 3), 1.0 / 3.0);
    let v = appended_array(&bytes, "velocity");
    assert_eq!(
        [f64_at(&v, 9), f64_at(&v, 10), f64_at(&v, 11)],
        [1.0, 2.0, 9.0]
    );
    let vm = appended_array(&bytes, "von_mises");
    let expected = strike::tensor::von_mises(&p.s[0]);
    assert_eq!(f64_at(&vm, 0), expected);
    let conn = appended_array(&bytes, "connectivity");
    assert_eq!(conn.len(), 10 * 8);
}

#[test]
fn write_to_missing_folder_is_an_error() {
    let dir = out_dir("vtk_missing");
    let p = particles_2d();
    let err = vtk::write_snapshot(&dir.join("no/such/dir/a.vtp"), &p, 0.0).unwrap_err();
    assert!(matches!(err, strike::Error::Io { .. }), "{err}");
    let mut pvd = PvdWriter::new(&dir.join("no/such/dir/a.pvd"));
    assert!(pvd.add(0.0, "a.vtp").is_err());
}
