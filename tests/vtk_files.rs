//! Output files: .vtp/.pvd checked with VTK's own reader (through `tests/vtk_check.py`, in the
//! Python environment the tests provision themselves, see `tests/support`) and read back byte by byte; PNG pictures checked for
//! size and content.

mod support;

use std::path::{Path, PathBuf};
use std::process::Command;

use strike::case::{ColorBy, PictureSpec};
use strike::output::picture::{self, SectionFrame};
use strike::output::vtk::{self, PvdWriter};
use strike::particles::{Particles, Tensor, Vector};
use strike::tensor::Sym;

const FIELDS: &str = "body,id,velocity,pressure,density,internal_energy,deviatoric_stress,\
                      von_mises,plastic_strain,damage,smoothing_length,contact_force,mass";

fn out_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create test output folder");
    dir
}

fn python() -> PathBuf {
    support::vtk_python()
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
        p.s[k] = Sym::from_full(&(Tensor::<2>::new(1.0e6, 2.0e5, 2.0e5, -3.0e6) * k as f64));
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
        p.s[k] = Sym::from_full(
            &(Tensor::<3>::new(1.0, 2.0, 3.0, 2.0, -4.0, 5.0, 3.0, 5.0, 3.0) * 1.0e6),
        );
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
    let expected = strike::tensor::von_mises(&p.s[0].full());
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

// ---------------------------------------------------------------------------------------------
// Pictures.

/// Width and height from a PNG's IHDR chunk.
fn png_size(path: &Path) -> (u32, u32) {
    let b = std::fs::read(path).unwrap();
    assert_eq!(
        &b[..8],
        b"\x89PNG\r\n\x1a\n",
        "{} is not a PNG",
        path.display()
    );
    assert_eq!(&b[12..16], b"IHDR");
    let w = u32::from_be_bytes(b[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(b[20..24].try_into().unwrap());
    (w, h)
}

/// Size from the header, then VTK's PNG reader: the same size and at least `min_colours`
/// distinct colours.
fn check_png(path: &Path, size: (u32, u32), min_colours: usize) {
    assert_eq!(png_size(path), size, "{}", path.display());
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/vtk_check.py");
    let out = Command::new(python())
        .arg(&script)
        .arg("--png")
        .arg(path)
        .args(["--size", &format!("{}x{}", size.0, size.1)])
        .args(["--min-colours", &min_colours.to_string()])
        .output()
        .expect("run vtk_check.py");
    assert!(
        out.status.success(),
        "{}: {}{}",
        path.display(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A plane-strain projectile (disc, body 1) on a plate (body 0), ~10k particles at 0.2 mm,
/// at time `t` with a made-up crater, speed and pressure.
fn impact_2d(t: f64) -> Particles<2> {
    let dx = 0.2e-3;
    let mut p = Particles::<2>::default();
    let depth = 2.0e-3 * (t / 10e-6);
    for i in 0..200 {
        for j in 0..40 {
            let x = -20e-3 + (i as f64 + 0.5) * dx;
            let y0 = -(j as f64 + 0.5) * dx;
            let bowl = depth * (-(x / 4e-3).powi(2)).exp() * (1.0 + y0 / 10e-3);
            p.push(
                Vector::<2>::new(x, y0 - bowl),
                Vector::<2>::zeros(),
                1e-4,
                7850.0,
                1.2 * dx,
                0,
            );
        }
    }
    let r = 5e-3;
    let yc = r + 1e-3 - 800.0 * t;
    let n = (r / dx).ceil() as i32;
    for i in -n..=n {
        for j in -n..=n {
            let (x, y) = (i as f64 * dx, j as f64 * dx);
            if x * x + y * y <= r * r {
                let squash = 1.0 - 0.15 * (t / 10e-6) * (1.0 - (y + r) / (2.0 * r));
                let v = Vector::<2>::new(0.0, -800.0);
                p.push(
                    Vector::<2>::new(x / squash, yc + y * squash),
                    v,
                    1e-4,
                    2700.0,
                    1.2 * dx,
                    1,
                );
            }
        }
    }
    let contact = Vector::<2>::new(0.0, -depth);
    for k in 0..p.n_real {
        let d = (p.x[k] - contact).norm();
        p.p[k] = 4.0e9 * (t / 10e-6) * (-(d / 3e-3).powi(2)).exp() - 2.0e8 * (t / 10e-6);
        p.v[k] *= 1.0 - d / 0.04;
    }
    p
}

fn spec(color_by: ColorBy, normal_axis: usize, position: f64) -> PictureSpec {
    PictureSpec {
        times: vec![0.0, 5e-6, 10e-6],
        normal_axis,
        position,
        thickness: None,
        color_by,
    }
}

#[test]
fn section_pictures_2d() {
    let dir = out_dir("pictures_2d");
    let names = vec!["target plate".to_string(), "projectile".to_string()];
    for (color_by, file) in [
        (ColorBy::Body, "bodies.png"),
        (ColorBy::Pressure, "pressure.png"),
        (ColorBy::Velocity, "speed.png"),
    ] {
        let frames: Vec<SectionFrame> = [0.0, 5e-6, 10e-6]
            .iter()
            .map(|&t| picture::extract_section(&impact_2d(t), t, &spec(color_by, 2, 0.0), 0.2e-3))
            .collect();
        assert!(frames[0].points.len() > 9000);
        let path = dir.join(file);
        picture::draw_sections(&path, &frames, color_by, &names, ["x", "y"]).unwrap();
        let size = picture::section_image_size(&frames);
        check_png(&path, size, if color_by == ColorBy::Body { 4 } else { 30 });
    }
}

#[test]
fn section_picture_3d_and_size() {
    let dir = out_dir("pictures_3d");
    // A 20 × 20 × 20 block of 0.5 mm spacing, pressure rising with z.
    let mut p = Particles::<3>::default();
    for k in 0..8000 {
        let (i, j, l) = (k % 20, (k / 20) % 20, k / 400);
        let x = Vector::<3>::new(i as f64, j as f64, l as f64) * 0.5e-3;
        p.push(
            x,
            Vector::<3>::zeros(),
            1e-6,
            7850.0,
            0.6e-3,
            (l / 10) as u32,
        );
        p.p[k] = 1.0e6 * l as f64;
    }
    let s = spec(ColorBy::Pressure, 1, 5.0e-3);
    let frame = picture::extract_section(&p, 2e-6, &s, 0.5e-3);
    assert_eq!(frame.points.len(), 400, "one layer of the block");
    assert!(frame
        .points
        .iter()
        .all(|q| q[0] <= 9.5e-3 && q[1] <= 9.5e-3));
    let frames = vec![frame];
    let path = dir.join("pressure.png");
    picture::draw_sections(&path, &frames, ColorBy::Pressure, &[], ["x", "z"]).unwrap();
    // Square section: the largest square plot area (440 px) + 66 px labels + 2 × 12 px margins,
    // + 230 px legend column; height 36 caption + 440 + 52 labels + 2 × 12.
    assert_eq!(
        picture::section_image_size(&frames),
        (440 + 66 + 24 + 230, 36 + 440 + 52 + 24)
    );
    check_png(&path, (760, 552), 20);

    let path = dir.join("bodies.png");
    picture::draw_sections(&path, &frames, ColorBy::Body, &["lower".into()], ["x", "z"]).unwrap();
    check_png(&path, (760, 552), 3);
}

#[test]
fn history_picture() {
    let dir = out_dir("history");
    let n = 400;
    let time: Vec<f64> = (0..n).map(|k| k as f64 * 5e-8).collect();
    let ke: Vec<f64> = time.iter().map(|t| 1000.0 * (-t / 8e-6).exp()).collect();
    let ie: Vec<f64> = ke.iter().map(|k| 0.8 * (1000.0 - k)).collect();
    let ce: Vec<f64> = time
        .iter()
        .map(|t| 150.0 * (t / 4e-6) * (-t / 4e-6).exp())
        .collect();
    let total: Vec<f64> = (0..n).map(|k| ke[k] + ie[k] + ce[k]).collect();
    let mut force: Vec<f64> = time
        .iter()
        .map(|t| 2.5e5 * (t / 3e-6).powi(2) * (-t / 3e-6).exp())
        .collect();
    force[200] = f64::NAN; // breaks the line, not the picture
    let panels = vec![
        (
            "energy (J)",
            vec![
                ("kinetic", ke),
                ("internal", ie),
                ("contact", ce),
                ("total", total),
            ],
        ),
        ("contact force (N)", vec![("|F| on projectile", force)]),
    ];
    let path = dir.join("history.png");
    picture::plot_history(&path, &time, &panels).unwrap();
    assert_eq!(picture::history_image_size(2), (960, 640));
    check_png(&path, (960, 640), 6);
}

#[test]
fn picture_errors() {
    let dir = out_dir("pictures_err");
    let err = picture::draw_sections(&dir.join("a.png"), &[], ColorBy::Body, &[], ["x", "y"]);
    assert!(err.is_err());
    let frame = SectionFrame {
        time: 0.0,
        points: vec![[0.0, 0.0]],
        values: vec![],
        bodies: vec![0],
    };
    assert!(
        picture::draw_sections(&dir.join("b.png"), &[frame], ColorBy::Body, &[], ["x", "y"])
            .is_err()
    );
    let bad = dir.join("no/such/dir/c.png");
    let err = picture::plot_history(&bad, &[0.0, 1.0], &[("y", vec![("a", vec![1.0, 2.0])])]);
    assert!(matches!(err, Err(strike::Error::Io { .. })), "{err:?}");
}
