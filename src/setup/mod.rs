//! Setup: a validated [`Case`] → particles on lattices and the [`Model`] the equations use.

pub mod mesh;
pub mod shapes;

use crate::boundary::{Plane, Walled};
use crate::case::{
    BodySpec, Case, ContactLaw, EosSpec, InteractionKind, KernelKind, Motion, SymmetryPlane,
};
use crate::contact::colour::ColourLaw;
use crate::contact::{self, ContactParams};
use crate::error::{DeckLocation, Error, Result};
use crate::kernel::{CubicSpline, WendlandC2};
use crate::material::Material;
use crate::neighbors::NeighborList;
use crate::particles::{from3, Particles, Vector};
use crate::physics::{Model, PairRule, PairTable};

/// Refuses a surface with a hole: more than 1 % of the body's particles where the winding
/// number is between ½ and ¾ (a closed surface has 1 at every particle; see [`mesh`]). Small
/// gaps of a real export pass, with a note in the log.
fn check_closed<const D: usize>(
    case: &Case,
    b: usize,
    mesh: &mesh::Mesh,
    points: &[Vector<D>],
) -> Result<()> {
    if mesh.open_edges == 0 {
        return Ok(());
    }
    let p3: Vec<[f64; 3]> = points.iter().map(crate::particles::to3).collect();
    let unsure = mesh.ambiguous(&p3);
    let share = unsure as f64 / points.len().max(1) as f64;
    if share > 0.01 {
        return Err(deck_error(
            case,
            case.bodies[b].location,
            &format!("body[{b}].shape.file"),
            format!(
                "the surface in {} is not closed: {} edges belong to one triangle only, and {:.1} % of the body's particles lie where it is open (winding number between ½ and ¾)",
                mesh.file,
                mesh.open_edges,
                100.0 * share
            ),
            "export the solid as a closed (watertight) surface, or close its holes in a mesh tool",
        ));
    }
    tracing::warn!(
        "body '{}': the surface in {} has {} open edges (small gaps); filled by its winding number ({unsure} particles near a gap)",
        case.bodies[b].name,
        mesh.file,
        mesh.open_edges
    );
    Ok(())
}

/// Default contact exponent n (Monaghan's artificial-stress exponent).
pub const DEFAULT_EXPONENT: f64 = 4.0;

/// Particles and model for a case. Errors (bodies overlapping, a body left without particles)
/// name the deck's line.
pub fn build<const D: usize>(case: &Case) -> Result<(Particles<D>, Model<D>)> {
    let planes = symmetry_planes(case);
    check_walls(case, &planes)?;
    let materials: Vec<Material> = case.materials.iter().map(Material::from_spec).collect();
    let mut p = Particles::<D>::default();
    for (b, body) in case.bodies.iter().enumerate() {
        let mat = &materials[body.material];
        let dp = body.spacing;
        let h0 = case.simulation.smoothing_ratio * dp;
        let mass = mat.rho0 * dp.powi(D as i32);
        let v = from3::<D>(body.velocity);
        let before = p.len();
        let points = body_lattice::<D>(case, b, &planes);
        if let (crate::case::Shape::Mesh(mesh), None) = (&body.shape, body.part_of) {
            check_closed(case, b, mesh, &points)?;
        }
        p.reserve_exact(points.len());
        for x in points {
            p.push(x, v, mass, mat.rho0, h0, b as u32);
            let i = p.len() - 1;
            p.p[i] = mat.pressure(mat.rho0, 0.0);
            p.c[i] = mat.sound_speed(mat.rho0, 0.0);
        }
        if let (true, Some(of)) = (p.len() == before, body.part_of) {
            // Sets follow the deck's bodies, in the deck's order.
            let first = case.bodies.iter().position(|b| b.part_of.is_some());
            let k = b - first.unwrap_or(b);
            let parent = &case.bodies[of];
            return Err(deck_error(
                case,
                body.location,
                &format!("prescribed[{k}].region"),
                format!("the prescribed set '{}' holds no particle: its region holds none of the particles of body '{}' (on the model's side of the symmetry planes), or an earlier set took them", body.name, parent.name),
                "make the region cover the particles to hold, which sit at min + (i + ½) × spacing of the body's shape's bounding box",
            ));
        }
        if p.len() == before && case.bodies.iter().any(|s| s.part_of == Some(b)) {
            return Err(deck_error(
                case,
                body.location,
                &format!("body[{b}].shape"),
                format!("body '{}' has no particle left: its prescribed sets' regions hold every one of them", body.name),
                "make the body larger than its sets' regions, or make it prescribed itself (`motion = \"prescribed\"`)",
            ));
        }
        if p.len() == before {
            return Err(deck_error(
                case,
                body.location,
                &format!("body[{b}].shape"),
                format!("body '{}' has no particle: its shape holds no lattice point at spacing {dp:e} m (on the model's side of the symmetry planes)", body.name),
                "make the shape larger than the spacing, or the spacing smaller",
            ));
        }
    }
    check_overlap(case, &p)?;

    // With a wall, body N + b is b's mirror image (see `boundary`), of b's material (images
    // are ghosts: never integrated).
    let n = case.bodies.len();
    let images = if planes.iter().any(|p| p.wall.is_some()) {
        2
    } else {
        1
    };
    let body_material = (0..images * n)
        .map(|b| case.bodies[b % n].material)
        .collect();
    let body_prescribed = (0..images * n)
        .map(|b| &case.bodies[b % n])
        .map(|b| (b.motion == Motion::Prescribed).then(|| from3::<D>(b.velocity)))
        .collect();
    let pairs = PairTable::new(images * n, |a, b| match (a < n, b < n) {
        (true, true) => pair_rule::<D>(case, &materials, a, b),
        (true, false) => wall_rule::<D>(case, &materials, a, b - n),
        _ => PairRule::Conserve,
    });
    let s = &case.simulation;
    let model = Model {
        materials,
        body_material,
        body_prescribed,
        pairs,
        alpha: s.viscosity_alpha,
        beta: s.viscosity_beta,
        limiter: s.viscosity_limiter,
        gravity: from3::<D>(s.gravity),
        cfl: s.cfl(),
        smoothing_ratio: s.smoothing_ratio,
        h_min_ratio: s.h_min_ratio,
        h_max_ratio: s.h_max_ratio,
        smoothing_stretch: s.smoothing_stretch,
        density_diffusion: s.density_diffusion,
        tensor_smoothing: s.tensor_smoothing,
        colour: None,
        formulation: s.formulation,
        walls: planes
            .iter()
            .filter(|p| p.wall.is_some())
            .copied()
            .collect(),
    };
    let mut model = model;
    if model
        .pairs
        .any(|r| matches!(r, PairRule::Contact(c) if c.law == ContactLaw::Colour))
    {
        let ratio = s.smoothing_ratio;
        model.colour = Some(match s.kernel {
            KernelKind::CubicSpline => ColourLaw::new::<D, _>(CubicSpline, ratio, &model.materials),
            KernelKind::WendlandC2 => ColourLaw::new::<D, _>(WendlandC2, ratio, &model.materials),
        });
    }
    Ok((p, model))
}

/// The lattice points of body `b`: its shape's lattice, less the points its prescribed sets
/// take; for a prescribed set, the points of its body's lattice in its region that no earlier
/// set of that body took (so that a set's particles are exactly where the body's would be).
fn body_lattice<const D: usize>(case: &Case, b: usize, planes: &[Plane]) -> Vec<Vector<D>> {
    let body = &case.bodies[b];
    let whole = body.part_of.unwrap_or(b);
    let owner = &case.bodies[whole];
    let sets: Vec<(usize, &BodySpec)> = case
        .bodies
        .iter()
        .enumerate()
        .filter(|(_, s)| s.part_of == Some(whole))
        .collect();
    let mut points = shapes::lattice::<D>(&owner.shape, owner.spacing, planes);
    if sets.is_empty() {
        return points;
    }
    // The set that takes a point: the first whose region holds it.
    let taker = |x: &Vector<D>| {
        sets.iter()
            .find(|(_, s)| shapes::contains(&s.shape, x))
            .map(|&(k, _)| k)
    };
    points.retain(|x| match body.part_of {
        Some(_) => taker(x) == Some(b),
        None => taker(x).is_none(),
    });
    points
}

/// The deck's symmetry planes with their model side: the side of the centre of all bodies'
/// bounding boxes (the positive side when that centre lies on the plane, as for a sphere cut
/// in quarters).
pub fn symmetry_planes(case: &Case) -> Vec<Plane> {
    planes_of(&case.bodies, &case.symmetry)
}

/// [`symmetry_planes`] of these bodies and planes (wall images numbered after the bodies).
pub fn planes_of(bodies: &[BodySpec], symmetry: &[SymmetryPlane]) -> Vec<Plane> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    // A prescribed set's region lies about particles of its body's.
    for b in bodies.iter().filter(|b| b.part_of.is_none()) {
        let (l, h) = shapes::bounding_box(&b.shape);
        for k in 0..3 {
            lo[k] = lo[k].min(l[k]);
            hi[k] = hi[k].max(h[k]);
        }
    }
    symmetry
        .iter()
        .map(|s| {
            let centre = 0.5 * (lo[s.axis] + hi[s.axis]);
            let side = if centre >= s.position - 1e-12 * (hi[s.axis] - lo[s.axis]).abs() {
                1.0
            } else {
                -1.0
            };
            let n = bodies.len() as u32;
            let wall = if s.wall {
                Some(Walled::all(n))
            } else {
                // The bodies that move across the plane's normal meet it as a wall.
                let mask = (0..bodies.len().min(64))
                    .filter(|&b| crosses(&bodies[b], s.axis))
                    .fold(0u64, |m, b| m | 1 << b);
                (mask != 0).then_some(Walled { bodies: n, mask })
            };
            Plane {
                axis: s.axis,
                position: s.position,
                side,
                wall,
            }
        })
        .collect()
}

/// Whether `body` moves across a plane normal to `axis`: its initial velocity has a component
/// along it (beyond round-off of its speed). Such a body meets a symmetry plane as a wall (see
/// `boundary`).
fn crosses(body: &BodySpec, axis: usize) -> bool {
    let speed = body.velocity.iter().map(|v| v * v).sum::<f64>().sqrt();
    body.velocity[axis].abs() > 1e-12 * speed
}

/// Every body lies on its walls' side: a symmetry plane may cut a body at rest across it (the
/// model keeps one side), a wall may not (the part beyond it would silently be lost), nor may
/// a symmetry plane cut a body that moves across it (no symmetry of the problem: its mirror
/// half would move the other way through the same material).
fn check_walls(case: &Case, planes: &[Plane]) -> Result<()> {
    for (plane, spec) in planes.iter().zip(&case.symmetry) {
        for (b, body) in case.bodies.iter().enumerate() {
            let walled = plane.wall.is_some_and(|w| w.walls(b as u32));
            if !walled {
                if b >= 64 && crosses(body, plane.axis) {
                    return Err(deck_error(
                        case,
                        body.location,
                        &format!("body[{b}].velocity"),
                        format!(
                            "body '{}' moves across the symmetry plane {} = {}, and a symmetry plane meets at most the first 64 bodies as a wall",
                            body.name, ["x", "y", "z"][plane.axis], plane.position
                        ),
                        "list the bodies that move across the plane first, or use a [[wall]]",
                    ));
                }
                continue;
            }
            let (lo, hi) = shapes::bounding_box(&body.shape);
            let k = plane.axis;
            let beyond = -plane.depth(lo[k]).min(plane.depth(hi[k]));
            if beyond <= 1e-6 * body.spacing {
                continue;
            }
            let axis = ["x", "y", "z"][k];
            return Err(if spec.wall {
                deck_error(
                    case,
                    body.location,
                    &format!("body[{b}].shape"),
                    format!(
                        "body '{}' reaches {beyond:e} m past the wall {axis} = {} (the bodies lie on the side of their centre)",
                        body.name, plane.position
                    ),
                    "move the body to the wall's side, or the wall; a symmetry plane, not a wall, may cut a body",
                )
            } else {
                deck_error(
                    case,
                    body.location,
                    &format!("body[{b}].velocity"),
                    format!(
                        "body '{}' is cut by the symmetry plane {axis} = {} and moves across it ({} m/s along {axis}): the plane is no symmetry of the problem",
                        body.name, plane.position, body.velocity[k]
                    ),
                    "a body cut by a symmetry plane moves along it; a body that meets its mirror image lies on one side of the plane",
                )
            });
        }
    }
    Ok(())
}

/// The rule between body a and the wall's image of body b: [`PairRule::Wall`] for a's own
/// image and the images of bodies welded to a, and otherwise the rule of a and b (their
/// contact meets the wall's side as it meets b).
fn wall_rule<const D: usize>(case: &Case, materials: &[Material], a: usize, b: usize) -> PairRule {
    if a == b {
        return PairRule::Wall;
    }
    match pair_rule::<D>(case, materials, a, b) {
        PairRule::Conserve => PairRule::Wall,
        rule => rule,
    }
}

/// The rule between bodies a and b: the deck's, or contact with default settings.
fn pair_rule<const D: usize>(case: &Case, materials: &[Material], a: usize, b: usize) -> PairRule {
    let spec = case
        .interactions
        .iter()
        .find(|s| s.bodies == [a, b] || s.bodies == [b, a]);
    let (law, stiffness, exponent) = match spec.map(|s| s.kind) {
        Some(InteractionKind::Welded) => return PairRule::Conserve,
        Some(InteractionKind::Contact {
            law,
            stiffness,
            exponent,
        }) => (law, stiffness, exponent),
        None => (ContactLaw::Colour, None, None),
    };
    let spacing = 0.5 * (case.bodies[a].spacing + case.bodies[b].spacing);
    if law == ContactLaw::Colour {
        return PairRule::Contact(ContactParams {
            law,
            stiffness: 0.0,
            exponent: 0.0,
            spacing,
        });
    }
    let n = exponent.unwrap_or(DEFAULT_EXPONENT);
    let k = stiffness.unwrap_or_else(|| {
        let p = expected_contact_pressure(case, materials, a, b);
        let ratio = case.simulation.smoothing_ratio;
        match case.simulation.kernel {
            KernelKind::CubicSpline => contact::default_stiffness::<D, _>(CubicSpline, ratio, p, n),
            KernelKind::WendlandC2 => contact::default_stiffness::<D, _>(WendlandC2, ratio, p, n),
        }
    });
    PairRule::Contact(ContactParams {
        law,
        stiffness: k,
        exponent: n,
        spacing,
    })
}

/// The interface pressure a contact between bodies a and b must carry: the Hugoniot impact
/// pressure at their relative speed (or the deck's `impact_speed`), the weight of the heavier
/// body on its footprint under gravity, and at least 10⁻⁴ of the smaller bulk modulus.
pub fn expected_contact_pressure(case: &Case, materials: &[Material], a: usize, b: usize) -> f64 {
    let (ba, bb) = (&case.bodies[a], &case.bodies[b]);
    let (ma, mb) = (&materials[ba.material], &materials[bb.material]);
    let v = case.simulation.impact_speed.unwrap_or_else(|| {
        (0..3)
            .map(|k| (ba.velocity[k] - bb.velocity[k]).powi(2))
            .sum::<f64>()
            .sqrt()
    });
    let hugoniot = |body: &BodySpec, m: &Material| {
        let s1 = match case.materials[body.material].eos {
            EosSpec::MieGruneisen { s1, .. } => s1,
            EosSpec::Linear { .. } => 0.0,
            // p ≈ Aμ + Bμ² against a linear Hugoniot's K μ (1 + (2 S1 − 1) μ) to second order.
            EosSpec::Tillotson(t) => 0.5 * (1.0 + t.big_b / t.big_a),
        };
        (m.rho0, m.sound_speed0(), s1)
    };
    let impact = contact::impact_pressure(v, hugoniot(ba, ma), hugoniot(bb, mb));
    let g = case.simulation.gravity;
    let g_norm = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
    let weight = |body: &BodySpec, m: &Material| {
        if g_norm == 0.0 {
            return 0.0;
        }
        let (lo, hi) = shapes::bounding_box(&body.shape);
        let extent: f64 = (0..3).map(|k| (hi[k] - lo[k]) * g[k].abs() / g_norm).sum();
        m.rho0 * g_norm * extent
    };
    let floor = 1e-4 * ma.bulk_modulus0().min(mb.bulk_modulus0());
    impact.max(weight(ba, ma)).max(weight(bb, mb)).max(floor)
}

/// No particle of one body may start closer than 0.5 Δp_avg to a particle of another.
fn check_overlap<const D: usize>(case: &Case, p: &Particles<D>) -> Result<()> {
    if case.bodies.len() < 2 {
        return Ok(());
    }
    // With h = Δp/4 the search support h_i + h_j is exactly 0.5 Δp_avg.
    let h: Vec<f64> = p
        .body
        .iter()
        .map(|&b| 0.25 * case.bodies[b as usize].spacing)
        .collect();
    let mut nl = NeighborList::default();
    nl.build(&p.x, &h, p.len(), 0.0);
    for i in 0..p.len() {
        for j in nl.list(i) {
            let j = j as usize;
            let (bi, bj) = (p.body[i] as usize, p.body[j] as usize);
            if bi < bj {
                let (a, b) = (&case.bodies[bi], &case.bodies[bj]);
                let d = (p.x[i] - p.x[j]).norm();
                return Err(deck_error(
                    case,
                    b.location,
                    &format!("body[{bj}].shape"),
                    format!(
                        "bodies '{}' and '{}' overlap: particles at {} and {} are {d:.3e} m apart, less than half their spacing",
                        a.name,
                        b.name,
                        fmt_point(&p.x[i]),
                        fmt_point(&p.x[j]),
                    ),
                    "move one body so that their facing particle layers are at least one spacing apart",
                ));
            }
        }
    }
    Ok(())
}

fn fmt_point<const D: usize>(x: &Vector<D>) -> String {
    let parts: Vec<String> = x.iter().map(|c| format!("{c:.4e}")).collect();
    format!("({})", parts.join(", "))
}

fn deck_error(
    case: &Case,
    loc: crate::case::Location,
    key: &str,
    message: String,
    help: &str,
) -> Error {
    Error::Deck {
        location: DeckLocation {
            file: case.file.clone(),
            line: loc.line,
            column: loc.column,
            offset: 0,
            length: 0,
        },
        key: key.to_string(),
        message,
        help: Some(help.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// With a wall, each body meets its own image and the images of the bodies welded to it
    /// pressed-only ([`PairRule::Wall`]), and the images of the bodies it is in contact with
    /// through that contact; the images have their bodies' materials.
    #[test]
    fn bodies_meet_a_walls_images_as_they_meet_the_bodies() {
        let deck = r#"
[simulation]
dimension = 2
end_time = 1.0e-6
[materials.al]
library = "al_6061_t6"
[materials.cu]
library = "ofhc_copper"
[[body]]
name = "a"
material = "al"
spacing = 1.0e-3
shape = { type = "rectangle", min = [0.0, 0.0], max = [0.01, 0.01] }
[[body]]
name = "b"
material = "cu"
spacing = 1.0e-3
shape = { type = "rectangle", min = [0.01, 0.0], max = [0.02, 0.01] }
[[body]]
name = "c"
material = "al"
spacing = 1.0e-3
shape = { type = "rectangle", min = [-0.01, 0.0], max = [0.0, 0.01] }
[[interaction]]
bodies = ["a", "c"]
type = "welded"
[[wall]]
axis = "y"
"#;
        let case = crate::deck::parse(deck, "walls.toml").unwrap();
        let (_, model) = build::<2>(&case).unwrap();
        let rule = |a: u32, b: u32| *model.pairs.rule(a, b);
        assert_eq!(model.pairs.bodies(), 6);
        assert_eq!(rule(0, 3), PairRule::Wall);
        assert_eq!(rule(0, 5), PairRule::Wall);
        assert_eq!(rule(5, 0), PairRule::Wall);
        assert!(matches!(rule(0, 4), PairRule::Contact(_)));
        assert_eq!(rule(0, 4), rule(0, 1));
        assert_eq!(model.body_material[4], model.body_material[1]);
        // Without a wall, no images.
        let case = crate::deck::parse(&deck.replace("[[wall]]", "[[symmetry]]"), "s.toml").unwrap();
        assert_eq!(build::<2>(&case).unwrap().1.pairs.bodies(), 3);
        // A wall through a body is a deck error that names the body; a symmetry plane there
        // cuts it.
        let through = deck.replace("axis = \"y\"", "axis = \"y\"\nposition = 0.004");
        let case = crate::deck::parse(&through, "w.toml").unwrap();
        let Err(Error::Deck { key, message, .. }) = build::<2>(&case) else {
            panic!("a wall through the bodies was accepted");
        };
        assert_eq!(key, "body[0].shape", "{message}");
        assert!(
            message.contains("'a'") && message.contains("wall y = 0.004"),
            "{message}"
        );
        let cut = through.replace("[[wall]]", "[[symmetry]]");
        assert!(build::<2>(&crate::deck::parse(&cut, "c.toml").unwrap()).is_ok());
    }

    /// A body that moves across a symmetry plane meets it as a wall (its ghosts there are its
    /// wall images), one at rest across it keeps the plane's ghosts, and a body cut by the plane
    /// that moves across it is a deck error that names it.
    #[test]
    fn bodies_moving_into_a_symmetry_plane_meet_it_as_a_wall() {
        let deck = r#"
[simulation]
dimension = 2
end_time = 1.0e-6
[materials.al]
library = "al_6061_t6"
[[body]]
name = "a"
material = "al"
spacing = 1.0e-3
velocity = [50.0, -100.0]
shape = { type = "rectangle", min = [0.0, 0.0], max = [0.01, 0.01] }
[[body]]
name = "b"
material = "al"
spacing = 1.0e-3
velocity = [50.0, 0.0]
shape = { type = "rectangle", min = [0.02, -0.01], max = [0.03, 0.01] }
[[symmetry]]
axis = "y"
"#;
        let case = crate::deck::parse(deck, "s.toml").unwrap();
        let planes = symmetry_planes(&case);
        let walled = planes[0].wall.expect("body a moves into the plane");
        assert!(walled.walls(0) && !walled.walls(1));
        let (mut p, model) = build::<2>(&case).unwrap();
        crate::boundary::rebuild_ghosts(&mut p, &planes);
        assert_eq!(model.pairs.bodies(), 4);
        assert_eq!(*model.pairs.rule(0, 2), PairRule::Wall);
        // a's ghosts are its images (body 2), b's (cut by the plane, at rest across it) its own.
        let ghosts = |b: u32| (p.n_real..p.len()).filter(|&i| p.body[i] == b).count();
        assert!(ghosts(2) > 0 && ghosts(1) > 0 && ghosts(0) == 0 && ghosts(3) == 0);
        // Moving along the plane: no wall, no images.
        let along = deck.replace("[50.0, -100.0]", "[50.0, 0.0]");
        let case = crate::deck::parse(&along, "s.toml").unwrap();
        assert_eq!(symmetry_planes(&case)[0].wall, None);
        assert_eq!(build::<2>(&case).unwrap().1.pairs.bodies(), 2);
        // b, cut by the plane, moving across it.
        let across = deck.replace("velocity = [50.0, 0.0]", "velocity = [50.0, 1.0]");
        let case = crate::deck::parse(&across, "s.toml").unwrap();
        let Err(Error::Deck { key, message, .. }) = build::<2>(&case) else {
            panic!("a body moving across the plane that cuts it was accepted");
        };
        assert_eq!(key, "body[1].velocity", "{message}");
        assert!(
            message.contains("'b'") && message.contains("no symmetry"),
            "{message}"
        );
    }
}
