//! STL bodies: generated surfaces of known volume filled with lattice particles (count × Δp³
//! within 1 % of the enclosed volume), ASCII and binary alike, placed by scale, rotation and
//! translation; small gaps tolerated; open surfaces, missing files and damaged files refused
//! with the deck's key.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use strike::case::Shape;

type Tri = [[f64; 3]; 3];

fn dir() -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join("stl_bodies");
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write(name: &str, tris: &[Tri], ascii: bool) -> PathBuf {
    let path = dir().join(name);
    if ascii {
        let mut s = String::from("solid test\n");
        for t in tris {
            s.push_str("  facet normal 0 0 0\n    outer loop\n");
            for v in t {
                s.push_str(&format!("      vertex {:e} {:e} {:e}\n", v[0], v[1], v[2]));
            }
            s.push_str("    endloop\n  endfacet\n");
        }
        s.push_str("endsolid test\n");
        std::fs::write(&path, s).unwrap();
    } else {
        let triangles: Vec<stl_io::Triangle> = tris
            .iter()
            .map(|t| stl_io::Triangle {
                normal: stl_io::Normal::new([0.0; 3]),
                vertices: t.map(|v| stl_io::Vertex::new(v.map(|c| c as f32))),
            })
            .collect();
        let mut f = std::fs::File::create(&path).unwrap();
        stl_io::write_stl(&mut f, triangles.iter()).unwrap();
    }
    path
}

/// A UV sphere (radius r, centre c), outward, its poles shared exactly.
fn sphere(c: [f64; 3], r: f64, rings: usize) -> Vec<Tri> {
    let seg = 2 * rings;
    let at = |i: usize, j: usize| -> [f64; 3] {
        if i == 0 || i == rings {
            return [c[0], c[1], c[2] + if i == 0 { r } else { -r }];
        }
        let (th, ph) = (
            PI * i as f64 / rings as f64,
            2.0 * PI * (j % seg) as f64 / seg as f64,
        );
        [
            c[0] + r * th.sin() * ph.cos(),
            c[1] + r * th.sin() * ph.sin(),
            c[2] + r * th.cos(),
        ]
    };
    let mut out = Vec::new();
    for i in 0..rings {
        for j in 0..seg {
            let (a, b, cc, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            if i > 0 {
                out.push([a, b, d]);
            }
            if i + 1 < rings {
                out.push([b, cc, d]);
            }
        }
    }
    out
}

/// A torus about the z axis (tube radius a, centre-line radius big), outward.
fn torus(big: f64, a: f64, n: usize, m: usize) -> Vec<Tri> {
    let at = |i: usize, j: usize| -> [f64; 3] {
        let (u, v) = (
            2.0 * PI * (i % n) as f64 / n as f64,
            2.0 * PI * (j % m) as f64 / m as f64,
        );
        let r = big + a * v.cos();
        [r * u.cos(), r * u.sin(), a * v.sin()]
    };
    let mut out = Vec::new();
    for i in 0..n {
        for j in 0..m {
            let (p, q, s, t) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            out.push([p, q, s]);
            out.push([p, s, t]);
        }
    }
    out
}

/// A unit cube [0, 1]³, outward.
fn cube() -> Vec<Tri> {
    let v = |i: usize| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64];
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut out = Vec::new();
    for q in quads {
        out.push([v(q[0]), v(q[1]), v(q[2])]);
        out.push([v(q[0]), v(q[2]), v(q[3])]);
    }
    out
}

/// Signed enclosed volume of a triangle set.
fn volume(tris: &[Tri]) -> f64 {
    tris.iter()
        .map(|[a, b, c]| {
            (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0
        })
        .sum()
}

fn deck(file: &Path, spacing: f64, extra: &str) -> String {
    format!(
        r#"[simulation]
dimension = 3
end_time = 1.0e-6

[[body]]
name = "part"
material = "al_6061_t6"
spacing = {spacing:e}
shape = {{ type = "stl", file = "{}"{extra} }}
"#,
        file.file_name().unwrap().to_str().unwrap()
    )
}

/// Parses a deck written beside the STL file (so the relative path resolves) and fills it.
#[allow(clippy::result_large_err)]
fn fill(file: &Path, spacing: f64, extra: &str) -> Result<usize, strike::Error> {
    let deck_path = file.with_extension("toml");
    std::fs::write(&deck_path, deck(file, spacing, extra)).unwrap();
    let case = strike::deck::load(&deck_path)?;
    let (p, _) = strike::setup::build::<3>(&case)?;
    Ok(p.n_real)
}

fn check_volume(label: &str, n: usize, spacing: f64, v: f64) {
    let filled = n as f64 * spacing.powi(3);
    let err = filled / v - 1.0;
    println!(
        "{label}: {n} particles, count·Δp³/V − 1 = {:+.3} %",
        100.0 * err
    );
    assert!(err.abs() < 0.01, "{label}: {:+.3} %", 100.0 * err);
}

#[test]
fn generated_surfaces_fill_their_volume() {
    // Sphere, 20 mm diameter at Δp = 0.5 mm (R/Δp = 20), ASCII and binary alike.
    let s = sphere([0.0, 0.0, 0.0], 1.0, 40);
    let v = volume(&s) * 1e-6;
    let ascii = write("sphere_ascii.stl", &s, true);
    let binary = write("sphere_binary.stl", &s, false);
    let extra = ", scale = 1.0e-2";
    let n_ascii = fill(&ascii, 5e-4, extra).unwrap();
    let n_binary = fill(&binary, 5e-4, extra).unwrap();
    assert_eq!(n_ascii, n_binary);
    check_volume("sphere", n_ascii, 5e-4, v);

    // A torus (not convex, genus 1): R = 12, a = 5 (mm), Δp = 0.4 mm.
    let t = torus(12.0, 5.0, 96, 48);
    let v = volume(&t) * 1e-9;
    let f = write("torus.stl", &t, false);
    check_volume(
        "torus",
        fill(&f, 4e-4, ", scale = 1.0e-3").unwrap(),
        4e-4,
        v,
    );

    // A cube of 10 mm turned by 30°, 20° and 10° and moved: the lattice is not aligned.
    let f = write("cube.stl", &cube(), false);
    let placed = ", scale = 1.0e-2, rotate = [30.0, 20.0, 10.0], translate = [0.1, -0.2, 0.3]";
    check_volume(
        "turned cube",
        fill(&f, 2.5e-4, placed).unwrap(),
        2.5e-4,
        1e-6,
    );

    // An inside-out export (every triangle reversed) fills the same.
    let reversed: Vec<Tri> = s.iter().map(|t| [t[0], t[2], t[1]]).collect();
    let f = write("inside_out.stl", &reversed, false);
    assert_eq!(fill(&f, 5e-4, extra).unwrap(), n_binary);
}

#[test]
fn placement_moves_the_particles() {
    let f = write("placed_cube.stl", &cube(), false);
    let deck_path = f.with_extension("toml");
    let extra = ", scale = 1.0e-3, rotate = [0.0, 0.0, 90.0], translate = [0.01, 0.0, 0.0]";
    std::fs::write(&deck_path, deck(&f, 1e-4, extra)).unwrap();
    let case = strike::deck::load(&deck_path).unwrap();
    let Shape::Mesh(m) = &case.bodies[0].shape else {
        panic!("not a mesh")
    };
    // [0, 1 mm]³ turned by 90° about z spans x ∈ [−1, 0] mm, then moved by 10 mm.
    let want_min = [0.009, 0.0, 0.0];
    let want_max = [0.010, 0.001, 0.001];
    for k in 0..3 {
        assert!((m.min[k] - want_min[k]).abs() < 1e-9, "{:?}", m.min);
        assert!((m.max[k] - want_max[k]).abs() < 1e-9, "{:?}", m.max);
    }
    let (p, _) = strike::setup::build::<3>(&case).unwrap();
    assert_eq!(p.n_real, 1000);
}

#[test]
fn small_gaps_are_filled_and_holes_refused() {
    let s = sphere([0.0, 0.0, 0.0], 1.0, 40);
    let v = volume(&s) * 1e-6;
    // One missing facet (a gap of a real export, about Δp/4 across) and a crack: still filled.
    let mut gap = s.clone();
    gap.remove(gap.len() / 3);
    let f = write("gap.stl", &gap, false);
    check_volume(
        "sphere with a gap",
        fill(&f, 5e-4, ", scale = 1.0e-2").unwrap(),
        5e-4,
        v,
    );

    // A bowl (the sphere without its top third): refused, naming the key.
    let bowl: Vec<Tri> = s
        .iter()
        .copied()
        .filter(|t| t.iter().any(|v| v[2] < 0.3))
        .collect();
    let f = write("bowl.stl", &bowl, false);
    let err = fill(&f, 5e-4, ", scale = 1.0e-2").unwrap_err();
    let text = format!("{err:?}");
    println!("{text}");
    assert!(text.contains("not closed"), "{text}");
    assert!(text.contains("body[0].shape.file"), "{text}");
}

#[test]
fn missing_damaged_and_misplaced_files_are_deck_errors() {
    let dir = dir();
    let deck_path = dir.join("missing.toml");
    std::fs::write(&deck_path, deck(&dir.join("nowhere.stl"), 1e-3, "")).unwrap();
    let text = format!("{:?}", strike::deck::load(&deck_path).unwrap_err());
    assert!(
        text.contains("body[0].shape.file") && text.contains("nowhere.stl"),
        "{text}"
    );
    assert!(text.contains("line: 9"), "{text}");

    // A binary file cut in the middle of a triangle.
    let f = write("cut.stl", &cube(), false);
    let bytes = std::fs::read(&f).unwrap();
    std::fs::write(&f, &bytes[..bytes.len() - 20]).unwrap();
    let text = format!("{:?}", fill(&f, 1e-3, "").unwrap_err());
    assert!(text.contains("body[0].shape.file"), "{text}");

    // Not an STL at all, and an empty file.
    let f = dir.join("text.stl");
    std::fs::write(&f, "this is not a surface\n").unwrap();
    assert!(fill(&f, 1e-3, "").is_err());
    let f = dir.join("empty.stl");
    std::fs::write(&f, "").unwrap();
    assert!(fill(&f, 1e-3, "").is_err());

    // A negative scale and a 2D deck.
    let f = write("scaled.stl", &cube(), false);
    let text = format!("{:?}", fill(&f, 1e-3, ", scale = -1.0").unwrap_err());
    assert!(text.contains("body[0].shape.scale"), "{text}");
    let deck_path = dir.join("flat.toml");
    let d = deck(&f, 1e-3, "").replace("dimension = 3", "dimension = 2");
    std::fs::write(&deck_path, d).unwrap();
    let text = format!("{:?}", strike::deck::load(&deck_path).unwrap_err());
    assert!(text.contains("3D shape"), "{text}");
}

/// The example's ogive projectile (examples/ogive_projectile.stl) holds the volume of the
/// tangent ogive it was written from, π ∫ r(z)² dz (the quarter model's count × 4): within 1 %
/// filled at Δp = 0.1 mm, and closer than at 0.2 mm (the lattice's staircase at the nose
/// shrinks with the spacing).
#[test]
fn the_example_ogive_holds_its_analytic_volume() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/ogive_plate.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    // Calibre 5 mm, CRH 3, 20 mm long (see examples/ogive_projectile.py), in m.
    let (r0, rho, length): (f64, f64, f64) = (2.5e-3, 15.0e-3, 20.0e-3);
    let nose = (rho * rho - (rho - r0) * (rho - r0)).sqrt();
    let radius = |z: f64| {
        if z >= nose {
            r0
        } else {
            ((rho * rho - (nose - z) * (nose - z)).sqrt() + r0 - rho).max(0.0)
        }
    };
    let steps = 20_000;
    let dz = length / steps as f64;
    let v: f64 = (0..steps)
        .map(|k| PI * radius((k as f64 + 0.5) * dz).powi(2) * dz)
        .sum();
    let mut errors = Vec::new();
    for dp in [2.0e-4, 1.0e-4] {
        let mut case = strike::deck::parse(&text, path.to_str().unwrap()).unwrap();
        for b in &mut case.bodies {
            b.spacing = dp;
        }
        let (p, _) = strike::setup::build::<3>(&case).unwrap();
        let n = (0..p.n_real).filter(|&i| p.body[i] == 0).count();
        let err = (4 * n) as f64 * dp.powi(3) / v - 1.0;
        println!(
            "ogive projectile, Δp = {dp:e} m: {n} particles, count·Δp³/V − 1 = {:+.3} %",
            100.0 * err
        );
        errors.push(err);
    }
    assert!(errors[1].abs() < 0.01, "{errors:?}");
    assert!(errors[1].abs() < errors[0].abs(), "{errors:?}");
}

/// A changed surface file changes the case's physical fingerprint (a checkpoint taken with the
/// old file refuses to resume with the new one).
#[test]
fn a_changed_file_changes_the_fingerprint() {
    let f = write("changing.stl", &cube(), false);
    let deck_path = f.with_extension("toml");
    std::fs::write(&deck_path, deck(&f, 1e-3, ", scale = 1.0e-2")).unwrap();
    let before = strike::deck::load(&deck_path)
        .unwrap()
        .physics_fingerprint();
    let bigger: Vec<Tri> = cube()
        .iter()
        .map(|t| t.map(|v| v.map(|c| 1.1 * c)))
        .collect();
    write("changing.stl", &bigger, false);
    let after = strike::deck::load(&deck_path)
        .unwrap()
        .physics_fingerprint();
    assert_ne!(before, after);
}
