use super::*;
use crate::case::{EosSpec, StrengthSpec};
use approx::assert_relative_eq;

const DECK_3D: &str = r#"
[simulation]
dimension = 3
end_time = 2.0e-7
impact_speed = 7000.0

[materials.al]
library = "al_2024_t4"
pressure_cutoff = -1.0e9

[materials.rubber]
density = 1010.0
eos = { type = "linear" }
strength = { type = "elastic", youngs_modulus = 3.0e6, poissons_ratio = 0.45 }
artificial_stress = 0.3

[[body]]
name = "sphere"
material = "al"
spacing = 2.0e-5
velocity = [0.0, 0.0, -7000.0]
shape = { type = "sphere", center = [0, 0, 3.2e-4], radius = 3e-4 }

[[body]]
name = "plate"
material = "steel"
spacing = 2.0e-5
motion = "prescribed"
shape = { type = "box", min = [-1.5e-3, -1.5e-3, -2e-4], max = [1.5e-3, 1.5e-3, 0.0] }

[[body]]
name = "rod"
material = "rubber"
spacing = 1e-4
shape = { type = "cylinder", base = [0, 0, 1e-3], axis = [0, 0, 2], radius = 5e-4, length = 2e-3 }

[[body]]
name = "shell"
material = "Steel"
spacing = 1e-4
shape = { type = "ring", center = [0, 0, 5e-3], inner_radius = 1e-3, outer_radius = 2e-3 }

[[interaction]]
bodies = ["sphere", "plate"]
type = "contact"
law = "paper"
stiffness = 1.0e11
exponent = 4.0

[[interaction]]
bodies = ["rod", "plate"]
type = "welded"

[[symmetry]]
axis = "x"

[[symmetry]]
axis = "y"
position = 0.0

[output]
snapshot_interval = 1.0e-8

[[output.picture]]
times = [0.0, 1e-7, 2e-7]
color_by = "pressure"
"#;

#[test]
fn full_3d_deck() {
    let case = parse(DECK_3D, "examples/sphere_plate.toml").unwrap();
    assert_eq!(case.name, "sphere_plate");
    assert_eq!(case.file, "examples/sphere_plate.toml");
    assert_eq!(case.dimension, 3);

    let s = &case.simulation;
    assert_eq!(s.end_time, 2.0e-7);
    assert_eq!(s.cfl(), 0.3);
    assert_eq!(s.max_steps, None);
    assert_eq!(s.kernel, KernelKind::CubicSpline);
    assert_eq!(s.smoothing_ratio, 1.2);
    assert_eq!((s.viscosity_alpha, s.viscosity_beta), (1.0, 2.0));
    assert_eq!(s.gravity, [0.0; 3]);
    assert_eq!((s.h_min_ratio, s.h_max_ratio), (0.5, 2.0));
    assert_eq!(s.smoothing_stretch, 1.25);
    assert_eq!(s.impact_speed, Some(7000.0));

    // Deck materials in order, then the library ones bodies name directly (once).
    let names: Vec<&str> = case.materials.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["al", "rubber", "steel"]);
    let al = &case.materials[0];
    assert_eq!(
        al.location,
        Location {
            line: 7,
            column: 12
        }
    );
    assert_eq!(al.density, 2785.0);
    assert_eq!(
        al.eos,
        EosSpec::MieGruneisen {
            c0: 5328.0,
            s1: 1.338,
            s2: 0.0,
            s3: 0.0,
            gamma0: 2.0,
            a: 0.0
        }
    );
    assert_eq!(
        al.strength,
        StrengthSpec::VonMises {
            shear_modulus: 28.6e9,
            yield_stress: 0.26e9,
            hardening_modulus: 0.0
        }
    );
    assert_eq!(al.pressure_cutoff, Some(-1.0e9));
    assert_eq!(al.artificial_stress, None);

    let rubber = &case.materials[1];
    assert_eq!(rubber.density, 1010.0);
    match (&rubber.eos, &rubber.strength) {
        (EosSpec::Linear { bulk_modulus }, StrengthSpec::Elastic { shear_modulus }) => {
            assert_relative_eq!(*bulk_modulus, 3.0e6 / (3.0 * 0.1), max_relative = 1e-12);
            assert_relative_eq!(*shear_modulus, 3.0e6 / 2.9, max_relative = 1e-12);
        }
        other => panic!("rubber: {other:?}"),
    }
    assert_eq!(rubber.artificial_stress, Some(0.3));

    let steel = &case.materials[2];
    assert_eq!(steel.density, 7900.0);
    assert_eq!(
        steel.location,
        Location {
            line: 26,
            column: 12
        }
    );
    assert_eq!(
        steel.strength,
        StrengthSpec::VonMises {
            shear_modulus: 85.3e9,
            yield_stress: 0.979e9,
            hardening_modulus: 0.0
        }
    );

    assert_eq!(case.bodies.len(), 4);
    let sphere = &case.bodies[0];
    assert_eq!(sphere.name, "sphere");
    assert_eq!(
        sphere.location,
        Location {
            line: 18,
            column: 8
        }
    );
    assert_eq!(sphere.material, 0);
    assert_eq!(sphere.spacing, 2.0e-5);
    assert_eq!(sphere.velocity, [0.0, 0.0, -7000.0]);
    assert_eq!(sphere.motion, Motion::Free);
    assert_eq!(
        sphere.shape,
        Shape::Sphere {
            center: [0.0, 0.0, 3.2e-4],
            radius: 3e-4
        }
    );
    let plate = &case.bodies[1];
    assert_eq!(plate.material, 2);
    assert_eq!(plate.motion, Motion::Prescribed);
    assert_eq!(plate.velocity, [0.0; 3]);
    assert_eq!(
        plate.shape,
        Shape::Box {
            min: [-1.5e-3, -1.5e-3, -2e-4],
            max: [1.5e-3, 1.5e-3, 0.0]
        }
    );
    assert_eq!(
        case.bodies[2].shape,
        Shape::Cylinder {
            base: [0.0, 0.0, 1e-3],
            axis: [0.0, 0.0, 1.0],
            radius: 5e-4,
            length: 2e-3
        }
    );
    assert_eq!(case.bodies[2].material, 1);
    // "Steel" is the library's steel, added only once.
    assert_eq!(case.bodies[3].material, 2);
    assert_eq!(
        case.bodies[3].shape,
        Shape::Ring {
            center: [0.0, 0.0, 5e-3],
            inner_radius: 1e-3,
            outer_radius: 2e-3
        }
    );

    assert_eq!(case.interactions.len(), 2);
    assert_eq!(case.interactions[0].bodies, [0, 1]);
    assert_eq!(
        case.interactions[0].location,
        Location {
            line: 43,
            column: 1
        }
    );
    assert_eq!(
        case.interactions[0].kind,
        InteractionKind::Contact {
            law: crate::case::ContactLaw::Paper,
            stiffness: Some(1.0e11),
            exponent: Some(4.0)
        }
    );
    assert_eq!(case.interactions[1].bodies, [2, 1]);
    assert_eq!(case.interactions[1].kind, InteractionKind::Welded);

    assert_eq!(
        case.symmetry,
        [
            SymmetryPlane {
                axis: 0,
                position: 0.0,
                wall: false
            },
            SymmetryPlane {
                axis: 1,
                position: 0.0,
                wall: false
            }
        ]
    );
    assert_eq!(case.output.snapshot_interval, Some(1.0e-8));
    assert_eq!(case.output.history_every, 10);
    assert_eq!(
        case.output.pictures,
        [PictureSpec {
            times: vec![0.0, 1e-7, 2e-7],
            normal_axis: 1,
            position: 0.0,
            thickness: None,
            color_by: ColorBy::Pressure
        }]
    );
}

const DECK_2D: &str = r#"
# Two rubber rings (Gray, Monaghan & Swift 2001), plane strain.
[simulation]
name = "rings"
dimension = 2
end_time = 1e-3
cfl = 0.25
max_steps = 5000
kernel = "wendland_c2"
smoothing_ratio = 1.3
viscosity = { alpha = 0.5, beta = 0.0 }
gravity = [0.0, -9.8]
smoothing_bounds = [0.25, 4.0]
smoothing_stretch = 1.0

[materials.rubber]
density = 1010.0
eos = { type = "linear", bulk_modulus = 7.33e8 }
strength = { type = "elastic", shear_modulus = 1.61e8 }
artificial_stress = 0.3

[materials.plastic]
density = 1200.0
eos = { type = "mie_gruneisen", c0 = 2000.0, s1 = 1.5, gamma0 = 1.0, s2 = 0.1 }
strength = { type = "von_mises", youngs_modulus = 3.0e9, poissons_ratio = 0.25, yield_stress = 5e7, hardening_modulus = 1e8 }

[materials.water]
density = 1000.0
eos = { type = "linear", bulk_modulus = 2.2e9 }
strength = { type = "hydrodynamic" }

[materials.soft_al]
library = "al_6061_t6"
density = 2700.0
strength = { yield_stress = 0.1e9 }
eos = { gamma0 = 1.5 }

[[body]]
name = "left"
material = "rubber"
spacing = 1e-3
velocity = [50.0, 0.0]
shape = { type = "ring", center = [-0.05, 0.0], inner_radius = 0.03, outer_radius = 0.04 }

[[body]]
name = "right"
material = "plastic"
spacing = 1e-3
velocity = [-50.0, 0]
shape = { type = "disc", center = [0.05, 0.0], radius = 0.04 }

[[body]]
name = "floor"
material = "al_1100_o"
spacing = 2e-3
motion = "prescribed"
shape = { type = "rectangle", min = [-0.1, -0.1], max = [0.1, -0.06] }

[[body]]
name = "block"
material = "soft_al"
spacing = 2e-3
shape = { type = "box", min = [0.2, 0.0], max = [0.3, 0.1] }

[[symmetry]]
axis = "y"
position = -0.2

[output]
history_every = 5

[[output.picture]]
times = [0.0, 1e-3]
normal = "z"
position = 1e-3
thickness = 2e-3
color_by = "von_mises"
"#;

#[test]
fn full_2d_deck() {
    let case = parse(DECK_2D, "rings.toml").unwrap();
    assert_eq!(case.name, "rings");
    assert_eq!(case.dimension, 2);
    let s = &case.simulation;
    assert_eq!(s.end_time, 1e-3);
    assert_eq!(s.cfl(), 0.25);
    assert_eq!(s.max_steps, Some(5000));
    assert_eq!(s.kernel, KernelKind::WendlandC2);
    assert_eq!(s.smoothing_ratio, 1.3);
    assert_eq!((s.viscosity_alpha, s.viscosity_beta), (0.5, 0.0));
    assert_eq!(s.gravity, [0.0, -9.8, 0.0]);
    assert_eq!((s.h_min_ratio, s.h_max_ratio), (0.25, 4.0));
    assert_eq!(s.smoothing_stretch, 1.0);
    assert_eq!(s.impact_speed, None);

    let names: Vec<&str> = case.materials.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(
        names,
        ["rubber", "plastic", "water", "soft_al", "al_1100_o"]
    );
    assert_eq!(
        case.materials[0].eos,
        EosSpec::Linear {
            bulk_modulus: 7.33e8
        }
    );
    assert_eq!(
        case.materials[0].strength,
        StrengthSpec::Elastic {
            shear_modulus: 1.61e8
        }
    );
    assert_eq!(
        case.materials[1].eos,
        EosSpec::MieGruneisen {
            c0: 2000.0,
            s1: 1.5,
            s2: 0.1,
            s3: 0.0,
            gamma0: 1.0,
            a: 0.0
        }
    );
    assert_eq!(
        case.materials[1].strength,
        StrengthSpec::VonMises {
            shear_modulus: 3.0e9 / 2.5,
            yield_stress: 5e7,
            hardening_modulus: 1e8
        }
    );
    assert_eq!(case.materials[2].strength, StrengthSpec::Hydrodynamic);
    // Library material with overrides: density, yield stress and γ0 replaced, the rest kept.
    let soft = &case.materials[3];
    assert_eq!(soft.density, 2700.0);
    assert_eq!(
        soft.eos,
        EosSpec::MieGruneisen {
            c0: 5240.0,
            s1: 1.40,
            s2: 0.0,
            s3: 0.0,
            gamma0: 1.5,
            a: 0.0
        }
    );
    assert_eq!(
        soft.strength,
        StrengthSpec::VonMises {
            shear_modulus: 27.6e9,
            yield_stress: 0.1e9,
            hardening_modulus: 0.0
        }
    );
    let al1100 = &case.materials[4];
    assert_eq!(al1100.density, 2707.0);
    assert_eq!(al1100.strength, StrengthSpec::Hydrodynamic);

    let b = &case.bodies;
    assert_eq!(b[0].velocity, [50.0, 0.0, 0.0]);
    assert_eq!(
        b[0].shape,
        Shape::Ring {
            center: [-0.05, 0.0, 0.0],
            inner_radius: 0.03,
            outer_radius: 0.04
        }
    );
    assert_eq!(b[1].velocity, [-50.0, 0.0, 0.0]);
    assert_eq!(
        b[1].shape,
        Shape::Sphere {
            center: [0.05, 0.0, 0.0],
            radius: 0.04
        }
    );
    assert_eq!(b[2].material, 4);
    assert_eq!(b[2].motion, Motion::Prescribed);
    assert_eq!(
        b[2].shape,
        Shape::Box {
            min: [-0.1, -0.1, 0.0],
            max: [0.1, -0.06, 0.0]
        }
    );
    assert_eq!(b[3].material, 3);
    assert!(case.interactions.is_empty());
    assert_eq!(
        case.symmetry,
        [SymmetryPlane {
            axis: 1,
            position: -0.2,
            wall: false
        }]
    );
    assert_eq!(case.output.snapshot_interval, None);
    assert_eq!(case.output.history_every, 5);
    assert_eq!(
        case.output.pictures,
        [PictureSpec {
            times: vec![0.0, 1e-3],
            normal_axis: 2,
            position: 1e-3,
            thickness: Some(2e-3),
            color_by: ColorBy::VonMises
        }]
    );
}

#[test]
fn particle_estimates() {
    let cube = Shape::Box {
        min: [0.0; 3],
        max: [1.0, 2.0, 3.0],
    };
    assert_relative_eq!(
        estimate_particles(&cube, 0.1, 3, &[]),
        6000.0,
        max_relative = 1e-12
    );
    assert_relative_eq!(
        estimate_particles(&cube, 0.1, 2, &[]),
        200.0,
        max_relative = 1e-12
    );
    let disc = Shape::Sphere {
        center: [0.0; 3],
        radius: 1.0,
    };
    assert_relative_eq!(
        estimate_particles(&disc, 0.1, 2, &[]),
        std::f64::consts::PI * 100.0,
        max_relative = 1e-12
    );
    let ring = Shape::Ring {
        center: [0.0; 3],
        inner_radius: 0.03,
        outer_radius: 0.04,
    };
    assert_relative_eq!(
        estimate_particles(&ring, 1e-3, 2, &[]),
        std::f64::consts::PI * 700.0,
        max_relative = 1e-9
    );
}

#[test]
fn memory_check_names_the_largest_body_and_a_spacing_that_fits() {
    let deck = DECK_3D.replace(
        "spacing = 1e-4\nshape = { type = \"cylinder\"",
        "spacing = 1e-6\nshape = { type = \"cylinder\"",
    );
    let raw: raw::Deck = toml::from_str(&deck).unwrap();
    let ctx = Ctx {
        text: &deck,
        file: "x.toml",
    };
    // 1 GiB: the rod at 1e-6 would need 3.9e8 particles (a quarter of its 1.57e9, on the
    // model's side of the deck's two symmetry planes).
    let err = ctx.build(&raw, Some(1024.0f64.powi(3))).unwrap_err();
    let Error::Deck {
        key,
        message,
        help,
        location,
    } = err
    else {
        panic!("not a deck error")
    };
    assert_eq!(key, "body[2].spacing");
    assert_eq!(location.line, 34);
    assert!(message.contains("particles"), "{message}");
    assert!(message.contains("only 1.0 GiB is available"), "{message}");
    let help = help.unwrap();
    assert!(help.contains("a spacing of at least"), "{help}");
    // The suggested spacing really fits.
    let s: f64 = help
        .split_whitespace()
        .nth(5)
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("{help}"));
    let case = parse(DECK_3D, "x.toml").unwrap();
    // The quarter model's bodies, on the model's side of its two symmetry planes.
    let planes = crate::setup::symmetry_planes(&case);
    let others: f64 = case
        .bodies
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != 2)
        .map(|(_, b)| estimate_particles(&b.shape, b.spacing, 3, &planes))
        .sum();
    let rod = estimate_particles(&case.bodies[2].shape, s, 3, &planes);
    let fails = case.may_fail();
    let ratio = case.simulation.smoothing_ratio;
    let mut bodies = case.bodies.clone();
    bodies[2].spacing = s;
    let ghosts = estimate_ghosts(&bodies, 3, &planes, ratio);
    let need = crate::particles::estimated_bytes(others + rod, ghosts, 3, false, fails);
    assert!(need <= 1024.0f64.powi(3), "{s}");
    // Unknown memory: no memory check, but the u32 particle numbering still applies.
    assert!(ctx.build(&raw, None).is_ok());
}

#[test]
fn toml_errors_name_the_key() {
    let err = parse(
        "[simulation]\ndimension = 3\nend_time = 1.0\n[[body]]\nname = \"a\"\nshape = { type = \"box\", min = [0, 0, 0], max = [1, 1, \"1\"] }\n",
        "a.toml",
    )
    .unwrap_err();
    let Error::Deck {
        key,
        location,
        message,
        ..
    } = err
    else {
        panic!()
    };
    assert_eq!(key, "body[0].shape.max[2]");
    assert_eq!(location.line, 6);
    assert!(message.contains("expected a number"), "{message}");
}

/// Tables without a header of their own: dotted keys, implicit parents, sub-table headers.
const DECK_IMPLICIT: &str = r#"
simulation.dimension = 2
simulation.end_time = 1e-5

[simulation.viscosity]
alpha = 0.7

[[body]]
name = "a"
material = "steel"
spacing = 1e-3
shape.type = "rectangle"
shape.min = [0.0, 0.0]
shape.max = [0.1, 0.1]

[[body]]
name = "b"
material = "steel"
spacing = 1e-3
[body.shape]
type = "disc"
center = [0.3, 0.0]
radius = 0.05

[[output.picture]]
times = [0.0]
"#;

#[test]
fn tables_without_headers() {
    let case = parse(DECK_IMPLICIT, "implicit.toml").unwrap();
    assert_eq!(case.dimension, 2);
    assert_eq!(case.simulation.viscosity_alpha, 0.7);
    assert_eq!(case.simulation.viscosity_beta, 2.0);
    assert_eq!(
        case.bodies[0].shape,
        Shape::Box {
            min: [0.0; 3],
            max: [0.1, 0.1, 0.0]
        }
    );
    assert_eq!(
        case.bodies[1].shape,
        Shape::Sphere {
            center: [0.3, 0.0, 0.0],
            radius: 0.05
        }
    );
    assert_eq!(case.materials.len(), 1);
    assert_eq!(case.output.pictures[0].times, [0.0]);

    // Inline array of tables.
    let inline = "[simulation]\ndimension = 2\nend_time = 1.0\n\
                  body = [{ name = \"a\", material = \"steel\", spacing = 0.1, shape = { type = \"box\", min = [0, 0], max = [1, 1] } }]\n";
    // (`body` after [simulation] belongs to it: an unknown key there.)
    let Err(Error::Deck { key, location, .. }) = parse(inline, "x.toml") else {
        panic!()
    };
    assert_eq!((key.as_str(), location.line), ("simulation.body", 4));
    let inline = format!("body = [{{ name = \"a\", material = \"steel\", spacing = 0.1, shape = {{ type = \"box\", min = [0, 0], max = [1, 1] }} }}]\n{}", &inline[..inline.find("body").unwrap()]);
    let case = parse(&inline, "x.toml").unwrap();
    assert_eq!(
        case.bodies[0].location,
        Location {
            line: 1,
            column: 18
        }
    );

    // Errors in implicit tables still name the key and line.
    let bad = DECK_IMPLICIT.replace("shape.max", "shape.maxx");
    let Err(Error::Deck { key, location, .. }) = parse(&bad, "x.toml") else {
        panic!()
    };
    assert_eq!((key.as_str(), location.line), ("body[0].shape.maxx", 14));
    let bad = DECK_IMPLICIT.replace("times = [0.0]", "times = [0.0]\ncolour = \"body\"");
    let Err(Error::Deck { key, location, .. }) = parse(&bad, "x.toml") else {
        panic!()
    };
    assert_eq!(
        (key.as_str(), location.line),
        ("output.picture[0].colour", 27)
    );
    let bad = DECK_IMPLICIT.replace("simulation.dimension = 2", "simulation.dimensio = 2");
    let Err(Error::Deck { key, location, .. }) = parse(&bad, "x.toml") else {
        panic!()
    };
    assert_eq!((key.as_str(), location.line), ("simulation.dimensio", 2));
}

/// The particle count estimated from the deck alone (`check` beyond a million particles, and
/// the memory check) counts only the model's side of the symmetry planes, as the set-up fills
/// it: the paper's quarter-model demo, and a box cut off its centre (a quarter of it beyond
/// the plane). Counting whole shapes put the demo at four times its particles.
#[test]
fn estimated_particles_are_the_model_side_of_the_symmetry_planes() {
    let count = |text: &str| {
        let case = parse(text, "x.toml").unwrap();
        let estimated: f64 = estimate_case_particles(&case).iter().sum();
        let (p, _) = crate::setup::build::<3>(&case).unwrap();
        (estimated, p.len() as f64)
    };
    let (estimated, made) = count(include_str!("../../examples/sphere_plate.toml"));
    assert_eq!(made, 47_812.0);
    assert!(
        (estimated / made - 1.0).abs() < 0.02,
        "{estimated} for {made}"
    );
    // Its ghosts (the two planes' layers within reach, and the few ghosts of ghosts where the
    // planes meet, which the estimate leaves out).
    let case = parse(include_str!("../../examples/sphere_plate.toml"), "x.toml").unwrap();
    let planes = crate::setup::symmetry_planes(&case);
    let ratio = case.simulation.smoothing_ratio;
    let ghosts = estimate_ghosts(&case.bodies, 3, &planes, ratio);
    let mut sim = crate::simulation::Simulation::<3>::new(&case).unwrap();
    sim.step(f64::INFINITY).unwrap();
    let made = (sim.particles.len() - sim.particles.n_real) as f64;
    assert_eq!(made, 6948.0);
    assert!(ghosts < made && ghosts > 0.9 * made, "{ghosts} for {made}");
    let cut = "[simulation]\ndimension = 3\nend_time = 1e-6\n[materials.al]\nlibrary = \"al_6061_t6\"\n[[body]]\nname = \"b\"\nmaterial = \"al\"\nspacing = 1e-4\nshape = { type = \"box\", min = [-1e-3, 0.0, 0.0], max = [3e-3, 1e-3, 1e-3] }\n[[symmetry]]\naxis = \"x\"\n";
    let (estimated, made) = count(cut);
    assert_eq!(made, 3000.0);
    assert!(
        (estimated / made - 1.0).abs() < 0.02,
        "{estimated} for {made}"
    );
}
