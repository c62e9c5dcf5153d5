//! Shapes filled with particles on a simple cubic (square in 2D) lattice.
//!
//! Lattice points sit at o + (i + ½) Δp per axis. The origin o is the shape's bounding-box
//! minimum, except along an axis with a symmetry plane, where o is shifted (by less than Δp) to
//! lie on the plane (the first plane on that axis), so that the first layer sits Δp/2 from it
//! and its ghosts Δp away: the mirrored lattice continues the real one.
//!
//! **Curved surfaces.** On a lattice a curved surface is a staircase: the top layer of a
//! sphere is a flat disc of radius ≈ √(R Δp) (4.5 Δp at R = 20 Δp), as wide as the contact
//! patch of a Hertz impact, and a contact sees a flat punch. The outermost layer of spheres,
//! discs, rings and cylinders is therefore moved along the surface normal to the depth Δp/2
//! that a particle on a flat face has ([`conform`]): the bodies' surfaces are then smooth at
//! the scale of the lattice, with every particle kept and the lattice untouched inside.

use crate::boundary::Plane;
use crate::case::Shape;
use crate::particles::{from3, Vector};
use rayon::prelude::*;

/// Bounding box (min, max) of a shape in 3 components (z of 2D shapes is ignored by callers).
pub fn bounding_box(shape: &Shape) -> ([f64; 3], [f64; 3]) {
    match *shape {
        Shape::Mesh(ref m) => (m.min, m.max),
        Shape::Box { min, max } => (min, max),
        Shape::Sphere { center, radius }
        | Shape::Ring {
            center,
            outer_radius: radius,
            ..
        } => (center.map(|c| c - radius), center.map(|c| c + radius)),
        Shape::Cylinder {
            base,
            axis,
            radius,
            length,
        } => {
            let mut lo = [0.0; 3];
            let mut hi = [0.0; 3];
            for k in 0..3 {
                let top = base[k] + axis[k] * length;
                // Extent of the disc of radius r normal to the axis along k: r √(1 − a_k²).
                let e = radius * (1.0 - axis[k] * axis[k]).max(0.0).sqrt();
                lo[k] = base[k].min(top) - e;
                hi[k] = base[k].max(top) + e;
            }
            (lo, hi)
        }
    }
}

/// Is point x (first D components meaningful) inside the shape?
pub fn contains<const D: usize>(shape: &Shape, x: &Vector<D>) -> bool {
    let c3 = |a: [f64; 3]| Vector::<D>::from_fn(|k, _| a[k]);
    match *shape {
        Shape::Mesh(ref m) => m.contains(crate::particles::to3(x)),
        Shape::Box { min, max } => (0..D).all(|k| x[k] >= min[k] && x[k] <= max[k]),
        Shape::Sphere { center, radius } => (x - c3(center)).norm() <= radius,
        Shape::Ring {
            center,
            inner_radius,
            outer_radius,
        } => {
            let r = (x - c3(center)).norm();
            r >= inner_radius && r <= outer_radius
        }
        Shape::Cylinder {
            base,
            axis,
            radius,
            length,
        } => {
            let d = x - c3(base);
            let a = c3(axis);
            let t = d.dot(&a);
            t >= 0.0 && t <= length && (d - a * t).norm() <= radius
        }
    }
}

/// The share of the shape's volume (area in 2D) on the model's side of the symmetry planes:
/// 1 where no plane cuts its bounding box, 0 where one leaves it wholly out, and otherwise
/// the share of the inside points of a regular sample of the box (SAMPLES per axis, the points
/// at the cells' centres) that lie on that side. A quarter model's sphere reads 1/4 exactly
/// (the sample is symmetric about a plane through its centre); any cut, within about a
/// sample's width over the body's. What a body's particle count is estimated from before it
/// is set up (`deck::estimate_particles`): until 2026-12-02 the whole shape was counted, so
/// `check` put the sphere–plate demo at 10 µm at 1.53·10⁶ particles for its 381 716.
pub fn model_share<const D: usize>(shape: &Shape, planes: &[Plane]) -> f64 {
    const SAMPLES: usize = 48;
    let (lo, hi) = bounding_box(shape);
    let mut cutting = Vec::new();
    for p in planes {
        let (a, b) = (p.depth(lo[p.axis]), p.depth(hi[p.axis]));
        if a < 0.0 && b < 0.0 {
            return 0.0;
        }
        if a < 0.0 || b < 0.0 {
            cutting.push(p);
        }
    }
    if cutting.is_empty() {
        return 1.0;
    }
    let width: [f64; 3] = std::array::from_fn(|k| (hi[k] - lo[k]) / SAMPLES as f64);
    let per_axis = |k: usize| if k < D { SAMPLES } else { 1 };
    let (inside, kept) = (0..per_axis(0))
        .into_par_iter()
        .map(|a| {
            let (mut inside, mut kept) = (0u64, 0u64);
            for b in 0..per_axis(1) {
                for c in 0..per_axis(2) {
                    let idx = [a, b, c];
                    let x = Vector::<D>::from_fn(|k, _| lo[k] + (idx[k] as f64 + 0.5) * width[k]);
                    if contains(shape, &x) {
                        inside += 1;
                        kept += u64::from(cutting.iter().all(|p| p.depth(x[p.axis]) >= 0.0));
                    }
                }
            }
            (inside, kept)
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    if inside == 0 {
        // A shape thinner than the sample: the share of its box along the cut axes.
        return cutting
            .iter()
            .map(|p| {
                let (a, b) = (p.depth(lo[p.axis]), p.depth(hi[p.axis]));
                a.max(b) / (a - b).abs()
            })
            .product();
    }
    kept as f64 / inside as f64
}

/// The particles of the shape (at spacing `dp`, on the model's side of the planes) that each
/// symmetry plane mirrors as ghosts, those within `reach` of it, summed over the planes: per
/// plane, the whole lattice layers within reach of it (the lattice is laid from the plane, its
/// first layer Δp/2 off) times the shape's section in the middle of them, read from a
/// regular sample of the section's box (SAMPLES^(D−1) points, as [`model_share`] reads a
/// volume). The ghosts of ghosts along the line where two planes meet are left out (about 5 %
/// of the sphere–plate demo's 6 948 ghosts). What `check` adds to the memory for them.
pub fn ghost_estimate<const D: usize>(shape: &Shape, dp: f64, planes: &[Plane], reach: f64) -> f64 {
    const SAMPLES: usize = 96;
    let (lo, hi) = bounding_box(shape);
    let mut ghosts = 0.0;
    for p in planes {
        let (a, b) = (p.depth(lo[p.axis]), p.depth(hi[p.axis]));
        let (near, far) = (a.min(b).max(0.0), a.max(b));
        // Lattice layers at depths (k + ½) Δp within reach and within the shape's box.
        let layers = ((reach.min(far) / dp - 0.5).ceil() - (near / dp - 0.5).ceil()).max(0.0);
        if layers == 0.0 {
            continue;
        }
        let middle = near + 0.5 * layers * dp;
        let across: Vec<usize> = (0..D).filter(|&k| k != p.axis).collect();
        let width: [f64; 3] = std::array::from_fn(|k| (hi[k] - lo[k]) / SAMPLES as f64);
        let per_axis = |j: usize| if j < across.len() { SAMPLES } else { 1 };
        let mut inside = 0u64;
        for s in 0..per_axis(0) {
            for t in 0..per_axis(1) {
                let mut x = Vector::<D>::zeros();
                x[p.axis] = p.position + p.side * middle;
                for (j, &k) in across.iter().enumerate() {
                    let i = [s, t][j];
                    x[k] = lo[k] + (i as f64 + 0.5) * width[k];
                }
                let kept = planes.iter().all(|q| q.depth(x[q.axis]) >= 0.0);
                inside += u64::from(kept && contains(shape, &x));
            }
        }
        let area: f64 = across.iter().map(|&k| width[k]).product::<f64>() * inside as f64;
        ghosts += area * layers * dp / dp.powi(D as i32);
    }
    ghosts
}

/// The shape's volume (area in 2D), the whole shape's, whatever the symmetry planes keep of it.
pub fn measure(shape: &Shape, dimension: usize) -> f64 {
    use std::f64::consts::PI;
    let two_d = dimension == 2;
    match shape {
        Shape::Box { min, max } => (0..dimension.min(3))
            .map(|k| (max[k] - min[k]).max(0.0))
            .product(),
        Shape::Sphere { radius, .. } if two_d => PI * radius * radius,
        Shape::Sphere { radius, .. } => 4.0 / 3.0 * PI * radius.powi(3),
        Shape::Cylinder { radius, length, .. } if two_d => 2.0 * radius * length,
        Shape::Cylinder { radius, length, .. } => PI * radius * radius * length,
        Shape::Ring {
            inner_radius: ri,
            outer_radius: ro,
            ..
        } if two_d => PI * (ro * ro - ri * ri),
        Shape::Ring {
            inner_radius: ri,
            outer_radius: ro,
            ..
        } => 4.0 / 3.0 * PI * (ro.powi(3) - ri.powi(3)),
        Shape::Mesh(m) => m.volume,
    }
}

/// How far a sphere's or a ring's particle count (its mass) may miss its volume over Δp^D
/// before [`lattice`] lays the lattice half a spacing over (see there).
pub const LATTICE_MASS_TOLERANCE: f64 = 0.02;

/// Lattice points of the shape at spacing dp, on the model's side of the symmetry planes.
///
/// **A sphere's or a ring's mass.** Each particle carries ρ0 Δp^D, so a body's mass is its
/// count of lattice points, which for a curved body depends on where the lattice falls on it:
/// a sphere 6 Δp across (the coarse crater, `examples/crater.toml`) holds 136 points with the
/// lattice laid from its bounding box (Δp/2 off its centre on every axis), 20 % more than its
/// volume's 113, and [`conform`] packs them into the sphere. Where the count of a sphere or a
/// ring misses its volume by more than [`LATTICE_MASS_TOLERANCE`], the lattice is laid half a
/// spacing over along the axes that no symmetry plane fixes, each such axis or not, and the
/// layout whose count comes nearest is kept (ties keep the plain one): 112 points for that
/// sphere in the full model (28 in its quarter, 34 before). Both layouts are symmetric about
/// the centre of a shape an even or odd number of spacings across, so twins stay mirror
/// images. Bodies within the tolerance (R ≥ 6 Δp in the examples) keep the plain lattice, and
/// with it a quarter model's particles are exactly the full model's quarter; a coarse body's
/// quarter and full models may be laid differently, each with its mass. Boxes and cylinders
/// keep the plain lattice, whose flat faces it fits (their layers Δp/2 inside), as do meshes.
pub fn lattice<const D: usize>(shape: &Shape, dp: f64, planes: &[Plane]) -> Vec<Vector<D>> {
    let plain = lattice_points::<D>(shape, dp, planes, [false; 3]);
    if !matches!(shape, Shape::Sphere { .. } | Shape::Ring { .. }) {
        return plain
            .into_par_iter()
            .map(|x| conform(shape, x, dp))
            .collect();
    }
    let want = measure(shape, D) * model_share::<D>(shape, planes) / dp.powi(D as i32);
    let miss = |n: usize| (n as f64 - want).abs();
    let chosen = if miss(plain.len()) > LATTICE_MASS_TOLERANCE * want {
        let free: Vec<usize> = (0..D)
            .filter(|&k| !planes.iter().any(|p| p.axis == k))
            .collect();
        let mut best = (miss(plain.len()), plain);
        for mask in 1..1usize << free.len() {
            let mut shift = [false; 3];
            for (j, &k) in free.iter().enumerate() {
                shift[k] = mask >> j & 1 == 1;
            }
            let points = lattice_points::<D>(shape, dp, planes, shift);
            if miss(points.len()) < best.0 {
                best = (miss(points.len()), points);
            }
        }
        best.1
    } else {
        plain
    };
    chosen
        .into_par_iter()
        .map(|x| conform(shape, x, dp))
        .collect()
}

/// The lattice points inside the shape, on the model's side of the planes, in lattice order
/// (x slowest), before [`conform`]. Along an axis with `shift` the lattice is laid half a
/// spacing over, its points at the bounding box's minimum + i Δp instead of + (i + ½) Δp.
fn lattice_points<const D: usize>(
    shape: &Shape,
    dp: f64,
    planes: &[Plane],
    shift: [bool; 3],
) -> Vec<Vector<D>> {
    let (lo, hi) = bounding_box(shape);
    let mut origin = [0.0; 3];
    let mut count = [1usize; 3];
    for k in 0..D {
        origin[k] = if shift[k] { lo[k] - 0.5 * dp } else { lo[k] };
        if let Some(pl) = planes.iter().find(|p| p.axis == k) {
            origin[k] = pl.position - ((pl.position - lo[k]) / dp).ceil() * dp;
        }
        // A relative tolerance keeps a box of exactly n spacings at n layers; laid over, the
        // lattice reaches the box's maximum too (its last point on it when the box is a whole
        // number of spacings across), and the shape's inside test keeps what is in it.
        let over = if shift[k] { 0.5 } else { 0.0 };
        count[k] = ((hi[k] - origin[k]) / dp + over + 1e-9).floor().max(0.0) as usize;
    }
    let (nx, ny, nz) = (count[0], count[1], if D == 3 { count[2] } else { 1 });
    // In parallel over x-slices: a surface mesh's inside test costs a tree walk per point.
    (0..nx)
        .into_par_iter()
        .flat_map_iter(|a| {
            let mut slice = Vec::new();
            for b in 0..ny {
                for c in 0..nz {
                    let idx = [a, b, c];
                    let x = Vector::<D>::from_fn(|k, _| origin[k] + (idx[k] as f64 + 0.5) * dp);
                    let on_model_side = planes.iter().all(|p| p.depth(x[p.axis]) >= 0.0);
                    if on_model_side && contains(shape, &x) {
                        slice.push(x);
                    }
                }
            }
            slice
        })
        .collect()
}

/// A lattice point of a curved shape within Δp of its surface, moved along the surface normal
/// to the depth Δp/2 (see the module doc); other points, and every point of a box, unchanged.
/// A shape cut by a symmetry plane is symmetric about it, so the particles of a quarter model
/// and their ghosts are exactly those of the full model.
pub fn conform<const D: usize>(shape: &Shape, x: Vector<D>, dp: f64) -> Vector<D> {
    let c3 = |a: [f64; 3]| Vector::<D>::from_fn(|k, _| a[k]);
    // The nearest surface: its depth below it and its outward normal.
    let (depth, normal) = match *shape {
        Shape::Box { .. } => return x,
        Shape::Mesh(ref m) => {
            let p = crate::particles::to3(&x);
            let Some(q) = m.nearest(p, dp) else {
                return x;
            };
            let out = from3::<D>(q) - x;
            let d = out.norm();
            if d == 0.0 {
                return x;
            }
            (d, out / d)
        }
        Shape::Sphere { center, radius } => {
            let d = x - c3(center);
            let r = d.norm();
            if r == 0.0 {
                return x;
            }
            (radius - r, d / r)
        }
        Shape::Ring {
            center,
            inner_radius,
            outer_radius,
        } => {
            let d = x - c3(center);
            let r = d.norm();
            if r == 0.0 {
                return x;
            }
            if outer_radius - r <= r - inner_radius || inner_radius == 0.0 {
                (outer_radius - r, d / r)
            } else {
                (r - inner_radius, -d / r)
            }
        }
        Shape::Cylinder {
            base,
            axis,
            radius,
            length,
        } => {
            let a = c3(axis);
            let d = x - c3(base);
            let t = d.dot(&a);
            let radial = d - a * t;
            let rr = radial.norm();
            let side = radius - rr;
            let (low, high) = (t, length - t);
            if side <= low.min(high) && rr > 0.0 {
                (side, radial / rr)
            } else if low <= high {
                (low, -a)
            } else {
                (high, a)
            }
        }
    };
    if depth >= dp {
        return x;
    }
    x + normal * (depth - 0.5 * dp)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_holds_exact_layers_and_sphere_volume() {
        let b = Shape::Box {
            min: [0.0, 0.0, 0.0],
            max: [1.0, 0.5, 0.2],
        };
        assert_eq!(lattice::<3>(&b, 0.1, &[]).len(), 10 * 5 * 2);
        let s = Shape::Sphere {
            center: [0.0; 3],
            radius: 1.0,
        };
        let n = lattice::<3>(&s, 0.05, &[]).len() as f64;
        let v = n * 0.05f64.powi(3);
        assert!(
            (v / (4.0 / 3.0 * std::f64::consts::PI) - 1.0).abs() < 0.01,
            "{v}"
        );
        // A quarter sphere keeps a quarter of the particles, the first layer at Δp/2.
        let planes = [
            Plane {
                axis: 0,
                position: 0.0,
                side: 1.0,
                wall: None,
            },
            Plane {
                axis: 1,
                position: 0.0,
                side: 1.0,
                wall: None,
            },
        ];
        let q = lattice::<3>(&s, 0.05, &planes);
        assert_eq!(q.len() as f64, n / 4.0);
        // Inside, the first layer sits Δp/2 from the planes (the surface shell is conformed).
        let xmin = q
            .iter()
            .filter(|x| x.norm() < 0.9)
            .map(|x| x[0])
            .fold(f64::INFINITY, f64::min);
        assert!((xmin - 0.025).abs() < 1e-12);
    }

    /// A sphere 6 Δp across holds 136 lattice points laid from its bounding box, 20 % more
    /// than its volume's 113; laid half a spacing over it holds 112 (−1 %), whole and in a
    /// quarter model, and stays symmetric about its centre. A disc 6 Δp across: 32 points
    /// for its area's 28.3 (+13 %), laid over along both axes 29 (+2.6 %; along one, 26). A
    /// sphere 40 Δp across is within the tolerance and keeps the plain lattice.
    #[test]
    fn coarse_spheres_and_discs_keep_their_mass() {
        use std::f64::consts::PI;
        let (dp, r) = (1.0, 3.0);
        let s = Shape::Sphere {
            center: [0.0; 3],
            radius: r,
        };
        let v = 4.0 / 3.0 * PI * r.powi(3);
        let plain = lattice_points::<3>(&s, dp, &[], [false; 3]).len();
        assert_eq!(plain, 136);
        let whole = lattice::<3>(&s, dp, &[]);
        assert_eq!(whole.len(), 112, "{}", whole.len() as f64 / v);
        for x in &whole {
            assert!(whole.iter().any(|y| (x + y).norm() < 1e-12), "{x}");
        }
        let plane = |axis| Plane {
            axis,
            position: 0.0,
            side: 1.0,
            wall: None,
        };
        let quarter = lattice::<3>(&s, dp, &[plane(0), plane(1)]);
        assert_eq!(quarter.len(), 28);
        assert!(quarter.iter().all(|x| x[0] > 0.0 && x[1] > 0.0));
        let disc = Shape::Sphere {
            center: [0.0; 3],
            radius: 3.0,
        };
        assert_eq!(lattice_points::<2>(&disc, dp, &[], [false; 3]).len(), 32);
        assert_eq!(lattice::<2>(&disc, dp, &[]).len(), 29);
        let fine = Shape::Sphere {
            center: [0.0; 3],
            radius: 20.0,
        };
        let plain = lattice_points::<3>(&fine, dp, &[], [false; 3]);
        let kept = lattice::<3>(&fine, dp, &[]);
        assert_eq!(plain.len(), kept.len());
    }

    #[test]
    fn disc_area_2d() {
        let s = Shape::Sphere {
            center: [0.3, 0.1, 0.0],
            radius: 1.0,
        };
        let n = lattice::<2>(&s, 0.02, &[]).len() as f64;
        assert!((n * 0.0004 / std::f64::consts::PI - 1.0).abs() < 0.01);
    }
}
