//! Symmetry planes by mirrored ghost particles.
//!
//! For a plane x_k = c, every particle (real, or a ghost of an earlier plane) within the
//! largest support 2 h_max of the plane gets a ghost at its mirror image: x_k → 2c − x_k,
//! v_k → −v_k, and the components with exactly one index k of the stress, the strain rate
//! and the stretch b change sign (S_kl, l ≠ k); everything else (mass, density, energy,
//! pressure, h, body) is copied. Mirroring the ghosts of earlier planes too fills the corners
//! of a quarter model. Ghosts keep their body, so contact works across a symmetry plane.
//!
//! **Walls.** A frictionless rigid wall is a symmetry plane that only pushes. Its ghost of a
//! particle of body b < N (N real bodies) belongs to body N + b, b's mirror image, which
//! meets b (and the bodies welded to b) by [`crate::physics::PairRule::Wall`]: a pair of a
//! particle and an image passes through the conservation equations, as a symmetry plane's
//! ghost does, while it is pressed together (closing, or compressive along the line between
//! them) and not at all while it pulls apart, from when the material between the particle
//! and the image's source reaches the plane ([`wall_share`]). Pressed, a frictionless rigid
//! wall and a plane of symmetry are the same boundary (zero normal velocity, zero shear): past
//! the onset the equations are the symmetry plane's. Where the plane would pull, the wall lets
//! go and the face is free; CN-SPH's correction B then leaves the image out too
//! (`physics::corrections`), so a lifted face is corrected as the free surface it is. Other
//! bodies meet b's image as they meet b (through the contact).
//!
//! **A body that moves into a symmetry plane meets it as a wall.** A symmetry plane is a cut
//! through material that continues on its other side, whose velocity normal to the plane is
//! zero there. A body whose velocity has a component normal to the plane (into it or away from
//! it) is not such a cut: its mirror image is a second body coming at it, a twin impact, and
//! twins part where their interface would pull. So such a body's ghosts in a `[[symmetry]]`
//! plane are its wall images ([`Walled`], set from the deck's initial velocities), and bodies
//! at rest in the plane's normal direction keep the plane's ghosts (a body moving across the
//! plane it is cut by is a deck error). Until 2026-12-04 every symmetry plane held every body:
//! an elastic bar on one never rebounded, and under the Taylor rod of
//! `examples/taylor_copper.toml` it held the face's inner half at up to +6.7 GPa of σ_zz
//! (1.3 µs, when the radial release meets on the axis) and in tension for 57 of the 80 µs,
//! the face 3.6–3.9 % narrower than on the wall, where VALIDATION.md asks the rod on a plane,
//! on a wall and against its twin to agree within 2 %.

use crate::particles::Particles;
use rayon::prelude::*;
use std::ops::Range;

/// A symmetry plane x_axis = position; the model lives on the side `side` (+1: x_axis ≥ c,
/// −1: x_axis ≤ c). `wall`: which bodies meet the plane as a rigid wall (their ghosts of
/// body b < N belong to body N + b), None where none does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    pub axis: usize,
    pub position: f64,
    pub side: f64,
    pub wall: Option<Walled>,
}

/// The bodies that meet a plane as a wall, in a model of `bodies` real bodies: every one for a
/// `[[wall]]`; for a `[[symmetry]]` plane those that move into it or away from it (see the
/// module doc), bit b of `mask` for body b (bodies from 64 on only when every body is walled).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Walled {
    pub bodies: u32,
    pub mask: u64,
}

impl Walled {
    /// Every body of a model of `bodies`.
    pub fn all(bodies: u32) -> Walled {
        Walled {
            bodies,
            mask: u64::MAX,
        }
    }

    /// Whether body `b`'s ghosts are its wall images.
    pub fn walls(&self, b: u32) -> bool {
        b < self.bodies
            && match b {
                0..=63 => self.mask >> b & 1 == 1,
                _ => self.mask == u64::MAX,
            }
    }
}

impl Plane {
    /// Signed distance of a coordinate into the model side.
    pub fn depth(&self, coordinate: f64) -> f64 {
        self.side * (coordinate - self.position)
    }
}

/// How far past touching, in spacings, a wall's image pair takes to come in whole
/// ([`wall_share`]).
pub const WALL_ONSET: f64 = 0.02;

/// The difference in height over a wall, in spacings, up to which the two particles of a
/// wall's image pair lie side by side in one layer, and from which one lies above the other
/// ([`wall_share`]); smoothly between.
pub const WALL_LAYER: (f64, f64) = (0.25, 0.75);

/// The share of the pair of particle i (at `xi`, spacing `dpi`) and a wall's image j (at `xj`,
/// its source's spacing `dpj`, of image body `image`) that the pass counts: 0 until the
/// material between i and j's source reaches the wall, 1 once it is pressed [`WALL_ONSET`]
/// spacings past touching, smoothly (t²(3 − 2t)) between; over every walled plane the pair
/// straddles, the least. The same share for the mirrored pair (j's source, image of i).
///
/// A particle stands for a cell reaching Δp/2 beyond its centre, so it touches the wall when
/// its centre is Δp/2 from the plane, and no sooner. Where the pair's two particles lie one
/// above the other (their heights over the wall differ by [`WALL_LAYER`].1 Δp or more), the
/// segment between i and j crosses the plane under the lower one, and the pair counts from
/// when the lower one touches. Where they lie side by side in the face's layer (heights within
/// [`WALL_LAYER`].0 Δp), the segment crosses the plane between the two, where the face reaches
/// the wall only once both cells do: the pair counts from when the higher one touches. Between
/// the two, the height the pair counts from goes smoothly from the higher one's to the lower
/// one's. A flat face lies in one layer, so a face pressed on the wall is met as a symmetry
/// plane meets it.
///
/// Met whole whenever the pair lay within the support, a curved body was met over every
/// particle within 2h of the plane: one of Hertz's spheres (`tests/symmetry_and_threads.rs`)
/// met it as a flat punch from the first step (14.9 kN at 0.92 µs against Hertz's 3.2),
/// peaking 15.9 / 13.6 % high at R/Δp = 16 / 20. Met from when the lower particle of the pair
/// touched (2026-12-04), a face particle beside the patch met the images of its touching
/// neighbours as if in contact itself, and the wall was a stiffer contact than the twin
/// through the contact by a gap that did not close with refinement: at 10 µs into the
/// loading, 1.121 / 1.099 × Hertz's force at R/Δp = 20 / 30 against the twin's 1.100 / 1.074
/// (conventional SPH), peaks +8.7 / +7.0 % against +7.3 / +4.8 %. Counted as above, the wall
/// reads 1.062 × Hertz's force at 10 µs at R/Δp = 30 and peaks +8.0 / +5.3 / +4.1 % at R/Δp =
/// 16 / 20 / 30, at or below the twin's (measured 2026-12-04, later). Heights are in each
/// particle's own spacing, which is one spacing where a body meets its own image.
///
/// The onset is smoothed because a pair switched on whole within one step is an impulse: a
/// sharp switch at Δp/2 read +21 / +18 % of Hertz's peak. The sphere does not see its width
/// (0.005 to 0.1 Δp). A face at rest on the wall does: it settles into the onset before the
/// wall holds it in full, a compliance of WALL_ONSET Δp. Under a bar pushed on by a body force
/// the wall departs from the bonded plane, over 40 µs, by 15 % of the bar's largest mean
/// velocity with an onset of 0.02 Δp, 37 % with 0.05 and 69 % with 0.1 (L/Δp = 100), and by
/// half as much at half the spacing; hence the narrow onset (measured 2026-12-04).
pub fn wall_share<const D: usize>(
    walls: &[Plane],
    image: u32,
    (xi, dpi): (&[f64; D], f64),
    (xj, dpj): (&[f64; D], f64),
) -> f64 {
    let smooth = |t: f64| {
        let t = t.clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    };
    let mut share = 1.0_f64;
    for plane in walls {
        let Some(walled) = plane.wall else { continue };
        if !image
            .checked_sub(walled.bodies)
            .is_some_and(|b| walled.walls(b))
        {
            continue;
        }
        let (di, dj) = (plane.depth(xi[plane.axis]), plane.depth(xj[plane.axis]));
        if di < 0.0 || dj >= 0.0 {
            continue;
        }
        // Heights over the wall in spacings: i's, and j's source's.
        let (ti, tj) = (di / dpi, -dj / dpj);
        let (lower, rise) = (ti.min(tj), (ti - tj).abs());
        let (beside, above) = WALL_LAYER;
        let touch = lower + rise * smooth((above - rise) / (above - beside));
        share = share.min(smooth((0.5 - touch) / WALL_ONSET));
    }
    share
}

/// Which particle each ghost mirrors (ghost k is particle n_real + k); the ghosts of plane p
/// are `first[p]..first[p + 1]` (counted from n_real).
#[derive(Debug, Clone, Default)]
pub struct Ghosts {
    sources: Vec<usize>,
    first: Vec<usize>,
    /// For each plane, whether each particle there when it was mirrored (the real ones and
    /// the ghosts of earlier planes) got a ghost in it.
    mirrored: Vec<Vec<bool>>,
}

impl Ghosts {
    /// Drop the old ghosts and make new ones for every particle within `reach` of a plane.
    pub fn rebuild<const D: usize>(&mut self, p: &mut Particles<D>, planes: &[Plane], reach: f64) {
        p.truncate_to_real();
        self.sources.clear();
        self.first.clear();
        self.mirrored.resize_with(planes.len(), Vec::new);
        for (pi, plane) in planes.iter().enumerate() {
            let n = p.len();
            self.first.push(self.sources.len());
            self.mirrored[pi].clear();
            self.mirrored[pi].extend((0..n).map(|i| plane.depth(p.x[i][plane.axis]) < reach));
            let count = self.mirrored[pi].iter().filter(|&&m| m).count();
            p.reserve_exact(count);
            for i in 0..n {
                if self.mirrored[pi][i] {
                    p.push_copy(i);
                    self.sources.push(i);
                }
            }
            mirror(p, n..p.len(), plane);
        }
        self.first.push(self.sources.len());
    }

    /// Whether the ghosts still cover every particle within `reach` of a plane (each particle
    /// without a ghost in a plane is still farther from it), of those `mine` (an MPI rank's own
    /// particles and the ghosts that mirror them, by index: see [`Ghosts::real_source`]).
    /// Their positions must be up to date ([`Ghosts::update`]).
    pub fn cover<const D: usize>(
        &self,
        p: &Particles<D>,
        planes: &[Plane],
        reach: f64,
        mine: impl Fn(usize) -> bool + Sync,
    ) -> bool {
        planes.iter().zip(&self.mirrored).all(|(plane, mirrored)| {
            mirrored
                .par_iter()
                .enumerate()
                .all(|(i, &m)| m || !mine(i) || plane.depth(p.x[i][plane.axis]) >= reach)
        })
    }

    /// The ghosts whose real source lies in `owned` (an MPI rank's own range), ascending.
    pub fn mirroring(&self, owned: &Range<usize>, n_real: usize) -> Vec<u32> {
        (0..self.sources.len())
            .filter(|&k| owned.contains(&self.real_source(n_real + k, n_real)))
            .map(|k| (n_real + k) as u32)
            .collect()
    }

    /// Extend per-particle `values` of the real particles to the ghosts, in ghost order: each
    /// ghost gets its source's value passed through `mirror(value, axis)` for its plane's
    /// axis (a vector changes the sign of that component; a scalar stays).
    pub fn extend_to_ghosts_with<T: Copy>(
        &self,
        values: &mut Vec<T>,
        planes: &[Plane],
        mut mirror: impl FnMut(T, usize) -> T,
    ) {
        for (plane, w) in planes.iter().zip(self.first.windows(2)) {
            for &s in &self.sources[w[0]..w[1]] {
                let v = values[s];
                values.push(mirror(v, plane.axis));
            }
        }
    }

    /// The real particle that particle `index` is, or (a ghost) mirrors, through the ghosts
    /// of earlier planes where a ghost mirrors one of those.
    pub fn real_source(&self, mut index: usize, n_real: usize) -> usize {
        while index >= n_real {
            index = self.sources[index - n_real];
        }
        index
    }

    /// Refresh the ghosts from the current state of their sources (same ghosts, same order).
    pub fn update<const D: usize>(&self, p: &mut Particles<D>, planes: &[Plane]) {
        let n = p.n_real;
        // Plane by plane: a plane's ghosts mirror particles made before them. (No ghosts
        // before the first rebuild.)
        for (plane, w) in planes.iter().zip(self.first.windows(2)) {
            let ghosts = w[0]..w[1];
            p.copy_many(n + ghosts.start, &self.sources[ghosts.clone()]);
            mirror(p, n + ghosts.start..n + ghosts.end, plane);
        }
    }

    /// [`Ghosts::update`] of the positions and smoothing lengths only: what the neighbour
    /// search reads. Under MPI the rest of the ghosts' state waits for the halo, whose
    /// sources another rank advanced (`Simulation::receive_halo` updates them whole).
    pub fn update_positions<const D: usize>(&self, p: &mut Particles<D>, planes: &[Plane]) {
        let n = p.n_real;
        for (plane, w) in planes.iter().zip(self.first.windows(2)) {
            let ghosts = w[0]..w[1];
            p.copy_positions(n + ghosts.start, &self.sources[ghosts.clone()]);
            mirror_positions(&mut p.x[n + ghosts.start..n + ghosts.end], plane);
        }
    }
}

/// Put back real particles that crossed a plane: each is replaced by its mirror image (the
/// transformation its ghost gets). Nothing crosses a symmetry plane in the symmetric problem;
/// a particle that drifts across would otherwise be pushed further out by its own ghost and
/// meet ghosts of particles beyond the ghost layer's reach, which breaks the pairwise balance
/// of forces along the plane (seen as a drift of the momentum parallel to it in the 7 km/s
/// quarter model). |v| and the components along the plane are kept, so energy and the
/// conserved momentum are too. Only the particles of `range` (an MPI rank's own) are looked at.
pub fn reflect_crossed<const D: usize>(
    p: &mut Particles<D>,
    planes: &[Plane],
    range: Range<usize>,
) {
    for plane in planes {
        let crossed = |i: usize| plane.depth(p.x[i][plane.axis]) < 0.0;
        // Rare: look in parallel, put back one by one.
        if !range.clone().into_par_iter().any(crossed) {
            continue;
        }
        for i in range.clone() {
            if plane.depth(p.x[i][plane.axis]) < 0.0 {
                // Its own image: the body stays.
                let own = Plane {
                    wall: None,
                    ..*plane
                };
                mirror(p, i..i + 1, &own);
            }
        }
    }
}

/// Rebuild the ghosts from scratch (the reach: the largest support 2 h_max).
pub fn rebuild_ghosts<const D: usize>(p: &mut Particles<D>, planes: &[Plane]) {
    let reach = 2.0 * p.h.iter().copied().fold(0.0_f64, f64::max);
    Ghosts::default().rebuild(p, planes, reach);
}

/// Mirror particles `range` in the plane (in parallel); a wall's ghosts of real bodies become
/// their mirror bodies.
fn mirror<const D: usize>(p: &mut Particles<D>, range: Range<usize>, plane: &Plane) {
    const MIN: usize = 256;
    let k = plane.axis;
    let r = range;
    if let Some(walled) = plane.wall {
        for b in &mut p.body[r.clone()] {
            if walled.walls(*b) {
                *b += walled.bodies;
            }
        }
    }
    // Each field of the range, in parallel.
    fn each<T: Send>(field: &mut [T], f: impl Fn(&mut T) + Sync + Send) {
        field.par_iter_mut().with_min_len(MIN).for_each(f);
    }
    mirror_positions(&mut p.x[r.clone()], plane);
    for field in [&mut p.v, &mut p.vh, &mut p.a, &mut p.contact_force] {
        each(&mut field[r.clone()], |v| v[k] = -v[k]);
    }
    for field in [&mut p.u, &mut p.dv] {
        each(&mut field[r.clone()], |v| v[k] = -v[k]);
    }
    each(&mut p.s[r.clone()], |s| s.mirror(k));
    each(&mut p.strain_rate[r.clone()], |s| s.mirror(k));
    // b's principal stretches are the source's, its axes mirrored (the tensor kernel's
    // ellipsoid, `physics::asph`; h reads only the largest stretch).
    each(&mut p.stretch[r], |s| s.mirror(k));
}

/// Mirror positions `x` in the plane (in parallel).
fn mirror_positions<const D: usize>(x: &mut [crate::particles::Vector<D>], plane: &Plane) {
    let (k, c) = (plane.axis, plane.position);
    x.par_iter_mut()
        .with_min_len(256)
        .for_each(|x| x[k] = 2.0 * c - x[k]);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::particles::{Tensor, Vector};
    use crate::tensor::Sym;

    /// A wall's image pair comes in from touching: none of it while the nearer particle is
    /// Δp/2 or more off the plane, all of it WALL_ONSET Δp closer, smoothly between; the same
    /// share for the mirrored pair (j, image of i); whole for a body the plane does not wall,
    /// and for a pair that does not straddle a walled plane.
    #[test]
    fn a_walls_image_pair_comes_in_from_touching() {
        // The plane z = 0, model above; body 0 of 2 walled, body 1 bonded.
        let walls = [Plane {
            axis: 2,
            position: 0.0,
            side: 1.0,
            wall: Some(Walled {
                bodies: 2,
                mask: 0b01,
            }),
        }];
        let dp = 2e-3;
        // i at height a Δp beside the image of j at height b Δp (body 0's image: 2).
        let share = |a: f64, b: f64, image: u32| {
            wall_share(
                &walls,
                image,
                (&[0.0, 0.0, a * dp], dp),
                (&[1.5 * dp, 0.0, -b * dp], dp),
            )
        };
        assert_eq!(share(0.5, 1.5, 2), 0.0, "touching");
        assert_eq!(share(0.6, 0.8, 2), 0.0, "not yet touching");
        assert_eq!(share(0.5 - WALL_ONSET, 1.5, 2), 1.0, "past the onset");
        assert_eq!(share(0.2, 0.2, 2), 1.0, "pressed");
        let half = share(0.5 - 0.5 * WALL_ONSET, 1.5, 2);
        assert!((half - 0.5).abs() < 1e-12, "half way: {half}");
        let quarter = share(0.5 - 0.25 * WALL_ONSET, 1.5, 2);
        assert!(
            (quarter - 0.15625).abs() < 1e-12,
            "a quarter of the way: {quarter}"
        );
        // The mirrored pair, and the lower particle's touch whichever side it is on.
        assert_eq!(share(1.5, 0.5 - 0.25 * WALL_ONSET, 2), quarter);
        // Side by side in the face's layer, the pair waits for the higher one: a face
        // particle beside the patch does not meet its touching neighbour's image.
        assert_eq!(share(0.47, 0.67, 2), 0.0, "beside, one touching");
        assert_eq!(share(0.67, 0.47, 2), 0.0, "the mirrored pair");
        assert_eq!(share(0.3, 0.45, 2), 1.0, "beside, both pressed");
        // One above the other, the lower one's touch: the face's second layer meets the
        // images of the face's pressed particles.
        assert_eq!(share(0.47, 0.47 + WALL_LAYER.1 + 0.05, 2), 1.0, "above");
        // Half-way between, the pair counts from half the rise above the lower one, smoothly
        // (here a quarter spacing higher).
        let mid = |lower: f64| share(lower, lower + 0.5 * (WALL_LAYER.0 + WALL_LAYER.1), 2);
        assert_eq!(
            mid(0.26),
            0.0,
            "its lower one touching, not the height counted"
        );
        assert_eq!(
            mid(0.22),
            1.0,
            "pressed past the onset at the height counted"
        );
        // Body 1 meets the plane bonded: its images (3) are not a wall's.
        assert_eq!(share(0.5, 1.5, 3), 1.0);
        // j on the model's side: the pair does not straddle the plane.
        assert_eq!(share(0.9, -0.9, 2), 1.0);
    }

    #[test]
    fn quarter_model_corner_gets_three_ghosts() {
        let mut p = Particles::<3>::default();
        p.push(
            Vector::<3>::new(0.1, 0.2, 5.0),
            Vector::<3>::new(1.0, 2.0, 3.0),
            1.0,
            1.0,
            0.5,
            0,
        );
        p.s[0] = Sym::from_full(&Tensor::<3>::new(
            1.0, 2.0, 3.0, 2.0, 4.0, 5.0, 3.0, 5.0, -5.0,
        ));
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
        rebuild_ghosts(&mut p, &planes);
        assert_eq!(p.len(), 4);
        assert_eq!(p.n_real, 1);
        // The diagonal ghost: both x and y mirrored; S_xy keeps its sign, S_xz and S_yz flip.
        assert_eq!(p.x[3], Vector::<3>::new(-0.1, -0.2, 5.0));
        assert_eq!(p.v[3], Vector::<3>::new(-1.0, -2.0, 3.0));
        assert_eq!(
            p.s[3],
            Sym::from_full(&Tensor::<3>::new(
                1.0, 2.0, -3.0, 2.0, 4.0, -5.0, -3.0, -5.0, -5.0
            ))
        );
        // Rebuilding replaces the ghosts, it does not add to them.
        rebuild_ghosts(&mut p, &planes);
        assert_eq!(p.len(), 4);
        // Updating carries the sources' new state to the same ghosts.
        let mut ghosts = Ghosts::default();
        ghosts.rebuild(&mut p, &planes, 1.0);
        p.x[0][2] = 6.0;
        p.rho[0] = 2.0;
        ghosts.update(&mut p, &planes);
        assert_eq!(p.len(), 4);
        assert_eq!(p.x[3], Vector::<3>::new(-0.1, -0.2, 6.0));
        assert_eq!(p.rho[3], 2.0);
        // Positions only (under MPI, before the halo): the ghosts' places and smoothing
        // lengths move with their sources, through both planes; the rest waits.
        p.x[0] = Vector::<3>::new(0.3, 0.4, 7.0);
        p.h[0] = 0.7;
        p.rho[0] = 3.0;
        ghosts.update_positions(&mut p, &planes);
        assert_eq!(p.x[1], Vector::<3>::new(-0.3, 0.4, 7.0));
        assert_eq!(p.x[2], Vector::<3>::new(0.3, -0.4, 7.0));
        assert_eq!(p.x[3], Vector::<3>::new(-0.3, -0.4, 7.0));
        assert!(p.h[1..].iter().all(|&h| h == 0.7));
        assert!(p.rho[1..].iter().all(|&r| r == 2.0));
    }

    #[test]
    fn a_crossed_particle_is_put_back_as_its_mirror_image() {
        let mut p = Particles::<2>::default();
        p.push(
            Vector::<2>::new(-0.1, 1.0),
            Vector::<2>::new(-2.0, 3.0),
            1.0,
            1.0,
            0.5,
            0,
        );
        p.push(
            Vector::<2>::new(0.3, 1.0),
            Vector::<2>::new(-2.0, 3.0),
            1.0,
            1.0,
            0.5,
            0,
        );
        p.s[0] = Sym::from_full(&Tensor::<2>::new(1.0, 2.0, 2.0, -1.0));
        let planes = [Plane {
            axis: 0,
            position: 0.0,
            side: 1.0,
            wall: None,
        }];
        reflect_crossed(&mut p, &planes, 0..2);
        assert_eq!(p.x[0], Vector::<2>::new(0.1, 1.0));
        assert_eq!(p.vh[0], Vector::<2>::new(2.0, 3.0));
        assert_eq!(p.s[0].full(), Tensor::<2>::new(1.0, -2.0, -2.0, -1.0));
        // The particle on the model's side is left alone.
        assert_eq!(p.x[1], Vector::<2>::new(0.3, 1.0));
    }
}
