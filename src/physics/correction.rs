//! The kernel corrections of corrected normalised SPH (CN-SPH; Vignjevic, De Vuyst & Campbell
//! 2006 §2; DESIGN.md §6), in their own pass before the rates, over each particle's own body
//! and the bodies welded to it (the paper's W = 0 across bodies in contact holds here too),
//! except B at a face in contact (see [`Counts::Facing`]):
//!
//! - **Shepard normalisation.** S_i = Σ_j V_j W_ij (i itself included): the paper's shape
//!   function N_ij = V_j W_ij / S_i sums to one, so a constant field is interpolated exactly,
//!   also at a free surface where S_i falls to about ½ (a face) or less (an edge, a corner).
//!   No step needs it ([`shepard`]): strike never interpolates a field with the kernel (the
//!   density comes from the continuity equation), only its gradients.
//! - **First-order corrected gradient** (Randles & Libersky 1996; Bonet & Lok 1999):
//!   A_i = Σ_j V_j ∇_i W_ij ⊗ x_ji, B_i = A_i⁻¹ and ∇̃_i W_ij = B_i ∇_i W_ij. Then
//!   Σ_j V_j (f_j − f_i) ∇̃_i W_ij = B_i A_i ∇f = ∇f for any linear field f, at a surface too.
//!   In the interior of a regular lattice A_i = I.
//!
//! A_i is near-singular where a particle's neighbours lie on a line or a plane (a filament, a
//! lone particle): there the uncorrected gradient is kept (B_i = I) and the particle counted.
//! The test is the smallest eigenvalue λ_min of A_i (symmetric: ∇W is radial), which is also the
//! surface indicator of DESIGN.md §6. Measured with the cubic spline at h = 1.2 Δp: 0.99 /
//! 0.98 inside (2D / 3D), 0.50 / 0.49 at a face, 0.29 / 0.23 at a corner, down to 0.19 at a
//! corner of a lattice perturbed by ±0.2 Δp; 0 for a lone particle or a line of particles.
//! Below [`LAMBDA_MIN`] the correction is not applied: DESIGN.md's 0.2 for "isolated" would
//! drop the corners, whose A_i inverts well.

use super::asph::{self, Metric};
use crate::kernel::Kernel;
use crate::neighbors::NeighborList;
use crate::particles::{Particles, Tensor};
use rayon::prelude::*;
use std::ops::Range;

/// Below this smallest eigenvalue of A_i the correction is not applied (see the module
/// doc).
pub const LAMBDA_MIN: f64 = 0.05;

/// At or above this λ_min a particle is inside its body, below it on its surface: measured on
/// a face of a lattice perturbed by up to ±0.2 Δp, the surface layer reads 0.42–0.55 and the
/// layer beneath it 0.80–0.97 (cubic spline, h = 1.2 Δp, 3D).
pub const LAMBDA_SURFACE: f64 = 0.7;

/// A particle's corrections.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Correction<const D: usize> {
    /// B_i: multiplies ∇_i W_ij (the identity where the correction is not applied).
    pub b: Tensor<D>,
    /// The surface indicator: the smallest eigenvalue of A_i, or a lower bound of it on the
    /// same side of [`LAMBDA_MIN`] and [`LAMBDA_SURFACE`] (see [`surface_indicator`]).
    pub lambda_min: f64,
    /// Whether A_i was too near singular and the uncorrected gradient is kept.
    pub fallback: bool,
    /// Which entries of the particle's neighbour list lie in its support, for the rate pass,
    /// which then need not test them again (see [`Support`]); `None` where the particle has
    /// neighbours of other bodies or more than [`SUPPORT_ENTRIES`] entries.
    pub support: Option<Support>,
}

/// Entry k of a particle's neighbour list lies in the support (0 < r_ij < h_i + h_j) where bit
/// k % 64 of word k / 64 is set: the test this pass makes at every entry anyway, kept so that
/// the rate pass of the same step reads only the entries set, in list order, instead of the
/// whole list with its skin (in CN-SPH's cubes that filter was 30 % of the rate pass). The
/// test is the rate pass's own, on the same positions, so the rates are bit-identical.
pub type Support = [u64; 2];

/// The longest list a [`Support`] covers (3D lists hold about 70 entries at h = 1.2 Δp with
/// the skin; longer ones are filtered by the rate pass itself).
pub const SUPPORT_ENTRIES: usize = 128;

/// A placeholder, for the particles another rank evaluates (see `ranks`).
impl<const D: usize> Default for Correction<D> {
    fn default() -> Self {
        Correction {
            b: Tensor::identity(),
            lambda_min: 1.0,
            fallback: false,
            support: None,
        }
    }
}

/// Neighbours are summed this many at a time, one lane each, with no branch, so that the sums
/// vectorise; the lanes are added up in lane order, the same on every machine.
const LANES: usize = 4;

/// What the pass's filter reads of a neighbour, in one aligned record (32 bytes in 3D) that
/// never straddles two cache lines: with the volume and the body in it, 48 bytes, it did.
#[derive(Clone, Copy)]
#[repr(C, align(32))]
struct Point<const D: usize> {
    x: [f64; D],
    h: f64,
}

/// Every particle's [`Point`] and volume (ghosts included, and the padding record last), and
/// its body.
#[derive(Clone, Copy)]
struct Points<'a, const D: usize> {
    at: &'a [Point<D>],
    vol: &'a [f64],
}

/// Which of a particle's neighbours its corrections count.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Counts {
    /// A neighbour of i's own body, of a body welded to it, or a wall's image pressed against
    /// it: in A_i, hence in B_i and in the surface indicator λ_min.
    Body,
    /// A neighbour of a body in contact with i's: in the moments that B_i inverts, not in
    /// λ_min (so the face stays a surface, and the contact normal its own plane's).
    ///
    /// This departs from DESIGN.md §6 (B over the own body only), for a measured reason. The
    /// colour contact's traction σ_u(ε) is built, and validated (planar shocks, Hertz, bars),
    /// against conventional SPH's face, whose own pressure sum pulls it outwards about as hard
    /// as the contact pushes back. A B over the own body alone redistributes that pull: in two
    /// fluid blocks compressed together (`validate::blocks::face_layers`) at 5 % strain the
    /// facing layer's net force is +0.38 of a layer's traction, towards the other body, and the
    /// layer beneath it −0.40 (conventional SPH: −0.13 and +0.03); at 35 %, −0.53 and −0.24
    /// (−0.98 and −0.10). The face comes apart from the layers behind it: at the 7 km/s demo's
    /// lip (Δp = 10 µm) plate particles of the face read 1.7–1.9 ρ0 from the continuity
    /// equation with their nearest neighbours 1.2–1.37 Δp away, at 4–6 times the shock's
    /// internal energy, and 18 of them crossed into the sphere. With the facing body's
    /// particles in B's moments the face's B is a full support's (as a welded face's is), its
    /// layers feel conventional SPH's forces within 0.015 of the traction (`strike validate
    /// --case contact_direction`), and the demo at 10 µm has no mixing (peak pressure 214 →
    /// 135 GPa). Free surfaces keep the exact first-order correction.
    ///
    /// `physics::corrections` counts a facing body so only where the pair meets through the
    /// colour law, whose traction is the material's own σ_u(ε). Eq. (5) as printed is a
    /// penalty of fixed stiffness, which the paper pairs with B over the own body: with the
    /// facing body in B its 7 km/s planar lattices mixed (0.72 Δp, 4 particles, closest 0.33
    /// Δp at Δp = 0.1 mm, against none and 0.80 Δp), so it keeps the paper's CN-SPH.
    Facing,
    /// A wall's image coming into touch: as [`Counts::Body`], this share of it (the share the
    /// rate pass counts, `boundary::wall_share`), so that B stays exact for a linear field.
    Share(f64),
    /// Not counted.
    Not,
}

/// The `counts` of a model with no welds, walls or contacts: i and j of the same body.
pub fn same_body<const D: usize>(p: &Particles<D>) -> impl Fn(usize, usize) -> Counts + Sync + '_ {
    move |i, j| {
        if p.body[i] == p.body[j] {
            Counts::Body
        } else {
            Counts::Not
        }
    }
}

/// The corrections of the real particles in `owned` (`out[i]`; `out` holds one for every real
/// particle), from the neighbours j as `counts(i, j)` counts them: its own body's and those it
/// meets through the conservation equations (welded bodies, a wall's images while pressed) in
/// everything, a facing body's in B only. Returns how many of them fell back to the
/// uncorrected gradient.
///
/// ∇_i W_ij is radial, so A_i = −Σ_j V_j (1/r dW/dr) x_ij ⊗ x_ij is symmetric: six sums in 3D.
///
/// With the tensor smoothing length (`metric`: every particle's, ghosts included; empty for
/// the round kernel) ∇_i W_ij is the ellipsoid's, A_ij x_ij times a scalar with A_ij the
/// pair's mean metric ([`asph`]), and A_i is not symmetric: see [`ellipsoid_correction`].
pub fn corrections<const D: usize, K: Kernel>(
    kernel: K,
    p: &Particles<D>,
    nl: &NeighborList,
    counts: impl Fn(usize, usize) -> Counts + Sync,
    owned: &Range<usize>,
    out: &mut Vec<Correction<D>>,
    metric: &[Metric],
) -> usize {
    corrections_on(
        kernel,
        p,
        nl,
        counts,
        owned,
        out,
        (crate::physics::wide_lanes(), metric),
    )
}

/// [`corrections`], on AVX2 (`wide`, where the CPU has it) or portable: the same numbers.
pub(crate) fn corrections_on<const D: usize, K: Kernel>(
    kernel: K,
    p: &Particles<D>,
    nl: &NeighborList,
    counts: impl Fn(usize, usize) -> Counts + Sync,
    owned: &Range<usize>,
    out: &mut Vec<Correction<D>>,
    (wide, metric): (bool, &[Metric]),
) -> usize {
    assert!(
        !wide || crate::physics::wide_lanes(),
        "AVX2 pass asked for on a CPU without AVX2"
    );
    let mut at: Vec<Point<D>> = Vec::with_capacity(p.len() + 1);
    at.par_extend((0..p.len()).into_par_iter().map(|j| Point {
        x: std::array::from_fn(|a| p.x[j][a]),
        h: p.h[j],
    }));
    let mut vol: Vec<f64> = Vec::with_capacity(p.len() + 1);
    vol.par_extend((0..p.len()).into_par_iter().map(|j| p.volume(j)));
    // Fills the last chunk: far beyond every support, so that its terms are exactly zero.
    at.push(Point {
        x: [1e100; D],
        h: 0.0,
    });
    vol.push(0.0);
    let points = Points { at: &at, vol: &vol };
    crate::ranks::fill(out, p.n_real, owned, |i| {
        // Particles with no neighbour of another body (see `NeighborList::classify`) need no
        // check of the pair's bodies.
        let mixed = nl.mixed.get(i).copied().unwrap_or(true);
        nl.with_list(i, |list| {
            if !metric.is_empty() {
                return ellipsoid_correction(kernel, i, list, (points, metric), mixed, &counts);
            }
            #[cfg(target_arch = "x86_64")]
            if wide {
                // SAFETY: the CPU has AVX2 (asserted above).
                return unsafe { correction_avx2(kernel, i, list, points, mixed, &counts) };
            }
            correction(kernel, i, list, points, mixed, &counts)
        })
    });
    out[owned.clone()].par_iter().filter(|c| c.fallback).count()
}

/// [`correction`] compiled for AVX2 (bit-identical: see `physics::wide_lanes`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn correction_avx2<const D: usize, K: Kernel>(
    kernel: K,
    i: usize,
    list: &[u32],
    points: Points<D>,
    mixed: bool,
    counts: &impl Fn(usize, usize) -> Counts,
) -> Correction<D> {
    correction(kernel, i, list, points, mixed, counts)
}

/// Particle i's correction from its neighbour list (`mixed`: it has neighbours of other
/// bodies, counted as `counts(i, j)` says).
#[inline(always)]
fn correction<const D: usize, K: Kernel>(
    kernel: K,
    i: usize,
    list: &[u32],
    points: Points<D>,
    mixed: bool,
    counts: &impl Fn(usize, usize) -> Counts,
) -> Correction<D> {
    let (body, facing, support) = if mixed {
        let [body, facing] = moments::<D, K, true>(kernel, i, list, points, counts).0;
        (body, Some(facing), None)
    } else {
        let ([sums, _], mask) = moments::<D, K, false>(kernel, i, list, points, counts);
        (sums, None, (list.len() <= SUPPORT_ENTRIES).then_some(mask))
    };
    let a = tensor_of::<D>(&body);
    let lambda_min = surface_indicator(&a);
    // B inverts the body's moments and the facing bodies' together (none: the same A).
    let (a, lambda_b) = match facing.map(|f| tensor_of::<D>(&f)) {
        Some(f) if f != Tensor::<D>::zeros() => {
            let full = a + f;
            (full, surface_indicator(&full))
        }
        _ => (a, lambda_min),
    };
    let inverse = invert(&a, lambda_b);
    Correction {
        b: inverse.unwrap_or_else(Tensor::<D>::identity),
        lambda_min,
        fallback: inverse.is_none(),
        support,
    }
}

/// Particle i's correction with the tensor smoothing length: A_i = Σ_j V_j ∇_i W_ij ⊗ x_ji
/// with the ellipsoid's ∇_i W_ij = g_ij A_ij x_ij ([`asph::pair_gradient`]), the moments
/// counted as [`moments`] counts them, and B_i = A_i⁻¹, so that the corrected gradient is
/// exact for a linear field as with the round kernel (the rate pass's L_i = −(Σ_j V_j v_ij ⊗
/// ∇_i W_ij) B_iᵀ reads L for v = L x). A_ij differs from pair to pair, so A_i is not
/// symmetric: nine sums, a general inverse, and for the surface indicator the smallest real
/// part of its eigenvalues ([`min_real_eigenvalue`]). On a lattice deformed by F, with every
/// metric from b = F Fᵀ, A_i = F⁻ᵀ A_i⁰ Fᵀ: similar to the undeformed lattice's moment, so its
/// eigenvalues, and the indicator, are the undeformed lattice's (`physics::tests`). Scalar,
/// one neighbour at a time: the ellipsoid's pair gradient already costs the rate pass its
/// lanes. The entries in the ellipsoid's support are marked for the rate pass, which queues
/// them as its own filter would (the round support, then [`asph::within`]).
fn ellipsoid_correction<const D: usize, K: Kernel>(
    kernel: K,
    i: usize,
    list: &[u32],
    (points, metric): (Points<D>, &[Metric]),
    mixed: bool,
    counts: &impl Fn(usize, usize) -> Counts,
) -> Correction<D> {
    let pi = &points.at[i];
    let mut body = Tensor::<D>::zeros();
    let mut facing = Tensor::<D>::zeros();
    let mut mask: Support = [0; 2];
    for (k, &j) in list.iter().enumerate() {
        let (xij, r2, hj) = separations::<D, 1>(pi, &[j], points);
        let xij: [f64; D] = std::array::from_fn(|a| xij[a][0]);
        let support = pi.h + hj[0];
        let (ai, aj) = (&metric[i].a, &metric[j as usize].a);
        // The rate pass's filter, to the bit (the round support, then the ellipsoid's).
        let inside = r2[0] < support * support && r2[0] > 0.0 && asph::within(ai, aj, &xij);
        if !inside {
            continue;
        }
        if let Some(word) = mask.get_mut(k / 64) {
            *word |= 1 << (k % 64);
        }
        let (share, sum) = match if mixed {
            counts(i, j as usize)
        } else {
            Counts::Body
        } {
            Counts::Body => (1.0, &mut body),
            Counts::Share(share) => (share, &mut body),
            Counts::Facing => (1.0, &mut facing),
            Counts::Not => continue,
        };
        let (grad, _, _) = asph::pair_gradient(kernel, ai, aj, &xij);
        let v = share * points.vol[j as usize];
        for a in 0..D {
            for b in 0..D {
                // x_ji = −x_ij.
                sum[(a, b)] -= v * grad[a] * xij[b];
            }
        }
    }
    let lambda_min = min_real_eigenvalue(&body);
    let (a, lambda_b) = if facing != Tensor::<D>::zeros() {
        let full = body + facing;
        (full, min_real_eigenvalue(&full))
    } else {
        (body, lambda_min)
    };
    let inverse = (lambda_b >= LAMBDA_MIN)
        .then(|| a.try_inverse())
        .flatten()
        .filter(|b| b.iter().all(|x| x.is_finite()));
    Correction {
        b: inverse.unwrap_or_else(Tensor::<D>::identity),
        lambda_min,
        fallback: inverse.is_none(),
        support: (!mixed && list.len() <= SUPPORT_ENTRIES).then_some(mask),
    }
}

/// The smallest real part of the eigenvalues of a real D × D matrix, D ≤ 3, in closed form:
/// the quadratic's roots in 2D; in 3D the characteristic cubic λ³ − I₁λ² + I₂λ − I₃ = 0,
/// depressed to y³ + py + q = 0 (λ = y + I₁/3), by the trigonometric solution where its three
/// roots are real and by Cardano's where one is, the complex pair's real part −y₁/2
/// (Abramowitz & Stegun 3.8.2). For a symmetric matrix it is [`min_eigenvalue`].
pub fn min_real_eigenvalue<const D: usize>(m: &Tensor<D>) -> f64 {
    match D {
        1 => m[(0, 0)],
        2 => {
            let half = 0.5 * m.trace();
            let disc = half * half - (m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)]);
            if disc >= 0.0 {
                half - disc.sqrt()
            } else {
                half
            }
        }
        _ => {
            let i1 = m.trace();
            let minor = |a: usize, b: usize| m[(a, a)] * m[(b, b)] - m[(a, b)] * m[(b, a)];
            let i2 = minor(0, 1) + minor(0, 2) + minor(1, 2);
            let i3 = m[(0, 0)] * (m[(1, 1)] * m[(2, 2)] - m[(1, 2)] * m[(2, 1)])
                - m[(0, 1)] * (m[(1, 0)] * m[(2, 2)] - m[(1, 2)] * m[(2, 0)])
                + m[(0, 2)] * (m[(1, 0)] * m[(2, 1)] - m[(1, 1)] * m[(2, 0)]);
            let shift = i1 / 3.0;
            let p = i2 - i1 * i1 / 3.0;
            let q = -2.0 * i1 * i1 * i1 / 27.0 + i1 * i2 / 3.0 - i3;
            let disc = 0.25 * q * q + p * p * p / 27.0;
            if p < 0.0 && disc <= 0.0 {
                let r = 2.0 * (-p / 3.0).sqrt();
                let cos = (3.0 * q / (p * r)).clamp(-1.0, 1.0);
                let phi = cos.acos() / 3.0;
                shift + r * (phi + 2.0 * std::f64::consts::PI / 3.0).cos()
            } else {
                let root = disc.max(0.0).sqrt();
                let y1 = (-0.5 * q + root).cbrt() + (-0.5 * q - root).cbrt();
                shift + y1.min(-0.5 * y1)
            }
        }
    }
}

/// B = A⁻¹ where A inverts robustly (its smallest eigenvalue `lambda_min` at least
/// [`LAMBDA_MIN`], every entry of the inverse finite); `None` where the uncorrected gradient is
/// to be kept. A is symmetric, and so is its inverse: adj(A)/det A from its distinct cofactors
/// (six in 3D; nalgebra's general inverse cost 1.4 % of a CN-SPH step).
pub fn invert<const D: usize>(a: &Tensor<D>, lambda_min: f64) -> Option<Tensor<D>> {
    if lambda_min < LAMBDA_MIN {
        return None;
    }
    let mut b = Tensor::<D>::zeros();
    match D {
        1 => b[(0, 0)] = 1.0 / a[(0, 0)],
        2 => {
            let inv_det = 1.0 / (a[(0, 0)] * a[(1, 1)] - a[(0, 1)] * a[(0, 1)]);
            b[(0, 0)] = a[(1, 1)] * inv_det;
            b[(1, 1)] = a[(0, 0)] * inv_det;
            b[(0, 1)] = -a[(0, 1)] * inv_det;
            b[(1, 0)] = b[(0, 1)];
        }
        _ => {
            let (a00, a11, a22) = (a[(0, 0)], a[(1, 1)], a[(2, 2)]);
            let (a01, a02, a12) = (a[(0, 1)], a[(0, 2)], a[(1, 2)]);
            let c00 = a11 * a22 - a12 * a12;
            let c01 = a02 * a12 - a01 * a22;
            let c02 = a01 * a12 - a02 * a11;
            let inv_det = 1.0 / (a00 * c00 + a01 * c01 + a02 * c02);
            let cof = [
                ((0, 0), c00),
                ((1, 1), a00 * a22 - a02 * a02),
                ((2, 2), a00 * a11 - a01 * a01),
                ((0, 1), c01),
                ((0, 2), c02),
                ((1, 2), a01 * a02 - a00 * a12),
            ];
            for ((r, c), v) in cof {
                b[(r, c)] = v * inv_det;
                b[(c, r)] = b[(r, c)];
            }
        }
    }
    b.iter().all(|x| x.is_finite()).then_some(b)
}

/// A_i from [`moments`]' lanes, added up in lane order.
fn tensor_of<const D: usize>(sums: &[[f64; LANES]; 6]) -> Tensor<D> {
    let mut a = Tensor::<D>::zeros();
    for (k, &(r, c)) in SYM.iter().enumerate() {
        if r < D && c < D {
            let v: f64 = sums[k].iter().sum();
            a[(r, c)] = v;
            a[(c, r)] = v;
        }
    }
    a
}

/// −Σ_j V_j (1/r dW/dr) x_ij ⊗ x_ij over i's list, its symmetric components per lane: over
/// every neighbour (`CHECK` false; the sums in the first of the two), or (`CHECK`) over the
/// neighbours j that `counts(i, j)` counts as [`Counts::Body`] in the first and as
/// [`Counts::Facing`] in the second, from one walk of the list. The neighbours in i's support
/// are queued first (the list also holds the skin's; filtered four entries at a time), each to
/// its sum's queue, then summed [`LANES`] at a time, the last chunk filled up with the padding
/// record, as in the rate pass (sending the whole list through the lanes instead made the
/// CN-SPH cubes of `strike bench` 25 % slower; queueing each neighbour's x_ij and r² from the
/// filter, to spare the sums their gathers, 4 % slower than gathering again; a walk of the
/// list for each sum, at the particles beside another body, about 5 % slower than one). Also
/// returns which of the first [`SUPPORT_ENTRIES`] entries lie in the support (see
/// [`Support`]).
#[inline(always)]
#[allow(clippy::needless_range_loop)] // lane loops read as the lanes' own
fn moments<const D: usize, K: Kernel, const CHECK: bool>(
    kernel: K,
    i: usize,
    list: &[u32],
    points: Points<D>,
    counts: &impl Fn(usize, usize) -> Counts,
) -> ([[[f64; LANES]; 6]; 2], Support) {
    let padding = (points.at.len() - 1) as u32;
    let pi = &points.at[i];
    let mut sums = [[[0.0; LANES]; 6]; 2];
    let mut mask: Support = [0; 2];
    // Room for one more quad of entries past a full batch, in each queue.
    let mut queues = [[padding; BATCH + LANES]; 2];
    let mut queued = [0; 2];
    // Entry j, in the support or not, to the queue of the sum that counts it (if any). The
    // queueing and the flush as closures, which the compiler keeps out of line: as methods
    // inlined into the walk the cubes ran 4 % slower, with the flush alone out of line 7 %.
    let queue = |queues: &mut [[u32; BATCH + LANES]; 2],
                 queued: &mut [usize; 2],
                 sums: &mut [[[f64; LANES]; 6]; 2],
                 j: u32,
                 inside: bool| {
        if CHECK {
            let c = if inside {
                counts(i, j as usize)
            } else {
                Counts::Not
            };
            if let Counts::Share(share) = c {
                // Rare (a face coming into touch with a wall): at once, in the first lane.
                let (xij, r2, hj) = separations::<D, 1>(pi, &[j], points);
                let r = r2[0].sqrt();
                let gf = kernel.grad_factor::<D>(r, 0.5 * (pi.h + hj[0]));
                let w = -share * points.vol[j as usize] * gf;
                for (k, &(a, b)) in SYM.iter().enumerate() {
                    if a < D && b < D {
                        sums[0][k][0] += w * xij[a][0] * xij[b][0];
                    }
                }
            }
            queues[0][queued[0]] = j;
            queued[0] += (c == Counts::Body) as usize;
            queues[1][queued[1]] = j;
            queued[1] += (c == Counts::Facing) as usize;
        } else {
            queues[0][queued[0]] = j;
            queued[0] += inside as usize;
        }
    };
    let flush = |queues: &mut [[u32; BATCH + LANES]; 2],
                 queued: &mut [usize; 2],
                 sums: &mut [[[f64; LANES]; 6]; 2]| {
        for k in 0..if CHECK { 2 } else { 1 } {
            flush_batch::<D, K>(
                kernel,
                pi,
                &mut queues[k],
                &mut queued[k],
                points,
                &mut sums[k],
            );
        }
    };
    // 64 entries at a time, each one's bit of the support kept in a register (the words past
    // the second, of lists longer than a `Support` covers, are dropped); within them, four
    // entries at a time.
    for (w, part) in list.chunks(64).enumerate() {
        let mut bits = 0u64;
        let mut quads = part.chunks_exact(LANES);
        let mut k = 0;
        for quad in &mut quads {
            let inside = in_support::<D, LANES>(pi, quad, points);
            for l in 0..LANES {
                bits |= (inside[l] as u64) << (k + l);
                queue(&mut queues, &mut queued, &mut sums, quad[l], inside[l]);
            }
            k += LANES;
            flush(&mut queues, &mut queued, &mut sums);
        }
        for &j in quads.remainder() {
            let inside = in_support::<D, 1>(pi, &[j], points)[0];
            bits |= (inside as u64) << k;
            queue(&mut queues, &mut queued, &mut sums, j, inside);
            k += 1;
            flush(&mut queues, &mut queued, &mut sums);
        }
        if let Some(m) = mask.get_mut(w) {
            *m = bits;
        }
    }
    for k in 0..if CHECK { 2 } else { 1 } {
        let used = queued[k].div_ceil(LANES) * LANES;
        queues[k][queued[k]..used].fill(padding);
        sum_queue::<D, K>(kernel, pi, &queues[k][..used], points, &mut sums[k]);
    }
    (sums, mask)
}

/// Whether each of the entries `js` lies in i's support, 0 < r_ij < h_i + h_j, with r² and
/// the support computed as the rate pass computes them (`physics::particle_rates`), to the
/// bit: the rate pass trusts this pass's [`Support`]. A coincident neighbour (r = 0) has no
/// direction and adds nothing. With no branch, so that it vectorises (tested one by one with a
/// branch, the skin's entries, among the support's in no order a branch could predict, cost a
/// third of the pass).
#[inline(always)]
fn in_support<const D: usize, const N: usize>(
    pi: &Point<D>,
    js: &[u32],
    points: Points<D>,
) -> [bool; N] {
    let (_, r2, hj) = separations::<D, N>(pi, js, points);
    std::array::from_fn(|l| {
        let support = pi.h + hj[l];
        (r2[l] < support * support) & (r2[l] > 0.0)
    })
}

/// x_ij, r² and h_j of the entries `js`, one lane each: gathered first, then each loop over
/// the lanes innermost, so that the arithmetic vectorises.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // index loops over lanes and axes read as the equations
#[allow(clippy::type_complexity)] // three lane arrays
fn separations<const D: usize, const N: usize>(
    pi: &Point<D>,
    js: &[u32],
    points: Points<D>,
) -> ([[f64; N]; D], [f64; N], [f64; N]) {
    let mut xj = [[0.0; N]; D];
    let mut hj = [0.0; N];
    for l in 0..N {
        let p = &points.at[js[l] as usize];
        for a in 0..D {
            xj[a][l] = p.x[a];
        }
        hj[l] = p.h;
    }
    let mut xij = [[0.0; N]; D];
    let mut r2 = [0.0; N];
    for a in 0..D {
        for l in 0..N {
            xij[a][l] = pi.x[a] - xj[a][l];
            r2[l] += xij[a][l] * xij[a][l];
        }
    }
    (xij, r2, hj)
}

/// Sums a full batch of the queue, and moves what was queued past it to the front: the
/// neighbours still meet the lanes [`LANES`] at a time in list order, so the sums do not
/// depend on where the batches fall.
#[inline(always)]
fn flush_batch<const D: usize, K: Kernel>(
    kernel: K,
    pi: &Point<D>,
    queue: &mut [u32; BATCH + LANES],
    queued: &mut usize,
    points: Points<D>,
    sums: &mut [[f64; LANES]; 6],
) {
    if *queued >= BATCH {
        sum_queue::<D, K>(kernel, pi, &queue[..BATCH], points, sums);
        queue.copy_within(BATCH.., 0);
        *queued -= BATCH;
    }
}

/// The queued neighbours' terms, two chunks of [`LANES`] at a time: their arithmetic
/// (a square root and a division each, in one chain) is independent, and computed together
/// the two chains overlap; they are still added chunk after chunk, so the sums are the same
/// to the bit as one chunk at a time.
#[inline(always)]
fn sum_queue<const D: usize, K: Kernel>(
    kernel: K,
    pi: &Point<D>,
    queue: &[u32],
    points: Points<D>,
    sums: &mut [[f64; LANES]; 6],
) {
    let mut pairs = queue.chunks_exact(2 * LANES);
    for chunk in &mut pairs {
        lanes::<D, K, { 2 * LANES }>(kernel, pi, chunk, points, sums);
    }
    for chunk in pairs.remainder().chunks_exact(LANES) {
        lanes::<D, K, LANES>(kernel, pi, chunk, points, sums);
    }
}

/// N of [`moments`]' queued neighbours (one or two chunks of [`LANES`]): straight-line
/// arithmetic over the lanes, no branch, so that it vectorises (the padding record lies far
/// beyond every support and adds exactly zero).
#[inline(always)]
#[allow(clippy::needless_range_loop)] // index loops over lanes and axes read as the equations
fn lanes<const D: usize, K: Kernel, const N: usize>(
    kernel: K,
    pi: &Point<D>,
    js: &[u32],
    points: Points<D>,
    sums: &mut [[f64; LANES]; 6],
) {
    let (xij, r2, hj) = separations::<D, N>(pi, js, points);
    let vj: [f64; N] = std::array::from_fn(|l| points.vol[js[l] as usize]);
    let r: [f64; N] = std::array::from_fn(|l| r2[l].sqrt());
    let h: [f64; N] = std::array::from_fn(|l| 0.5 * (pi.h + hj[l]));
    let gf = kernel.grad_factors::<D, N>(&r, &h);
    let w: [f64; N] = std::array::from_fn(|l| -vj[l] * gf[l]);
    // Chunk after chunk, each lane into its own sum.
    for c in 0..N / LANES {
        for (k, &(a, b)) in SYM.iter().enumerate() {
            if a < D && b < D {
                for l in 0..LANES {
                    let m = c * LANES + l;
                    sums[k][l] += w[m] * xij[a][m] * xij[b][m];
                }
            }
        }
    }
}

/// In-support neighbours are queued this many (a multiple of [`LANES`]) before their sums.
const BATCH: usize = 64;

/// The symmetric components summed: the diagonal, then xy, xz, yz.
const SYM: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];

/// The Shepard sum S_i = Σ_j V_j W_ij (i itself included) over the neighbours j that
/// `counts(i, j)` counts as i's body ([`Counts::Body`]): the denominator of the paper's shape
/// function N_ij = V_j W_ij / S_i, which interpolates a constant exactly, at a surface too
/// (see the module doc).
pub fn shepard<const D: usize, K: Kernel>(
    kernel: K,
    p: &Particles<D>,
    nl: &NeighborList,
    counts: impl Fn(usize, usize) -> Counts + Sync,
) -> Vec<f64> {
    (0..p.n_real)
        .into_par_iter()
        .map(|i| {
            let mut s = p.volume(i) * kernel.w::<D>(0.0, p.h[i]);
            for j in nl.list(i) {
                let j = j as usize;
                if counts(i, j) != Counts::Body {
                    continue;
                }
                let r = (p.x[i] - p.x[j]).norm();
                let hij = 0.5 * (p.h[i] + p.h[j]);
                if r > 0.0 && r < 2.0 * hij {
                    s += p.volume(j) * kernel.w::<D>(r, hij);
                }
            }
            s
        })
        .collect()
}

/// λ_min of A_i as [`Correction::lambda_min`] has it: a lower bound of it on the same side
/// of both [`LAMBDA_MIN`] and [`LAMBDA_SURFACE`], the only values it is ever compared with.
/// Gershgorin's lower bound stands in for it where the bound already clears
/// [`LAMBDA_SURFACE`] (the interior, most particles), or clears [`LAMBDA_MIN`] and [`exceeds`]
/// shows λ_min does not clear [`LAMBDA_SURFACE`] (a surface that inverts); otherwise a
/// threshold that [`exceeds`] shows λ_min to clear does (the layer beneath a surface; a corner
/// whose bound is loose). The exact value's trigonometric solution ([`min_eigenvalue`]) cost
/// 7 % of a CN-SPH step when every particle took it, and 2.4 % when the surface particles
/// still did. Kept out of line: inlined, it cost the correction pass its vectorised lanes.
#[inline(never)]
pub fn surface_indicator<const D: usize>(a: &Tensor<D>) -> f64 {
    let bound = gershgorin_lower_bound(a);
    if bound >= LAMBDA_SURFACE {
        bound
    } else if exceeds(a, LAMBDA_SURFACE) {
        LAMBDA_SURFACE
    } else if bound >= LAMBDA_MIN {
        bound
    } else if exceeds(a, LAMBDA_MIN) {
        LAMBDA_MIN
    } else {
        bound
    }
}

/// Whether every eigenvalue of the symmetric matrix m exceeds t: m − t I is positive definite
/// when every pivot of its LDLᵀ factorisation is positive (Golub & Van Loan, §4.2). It settles
/// the layer beneath a surface (λ_min 0.8–0.97, where Gershgorin's bound is too loose) with
/// a few products instead of the trigonometric eigenvalue.
#[allow(clippy::needless_range_loop)] // the factorisation reads as its equations
pub fn exceeds<const D: usize>(m: &Tensor<D>, t: f64) -> bool {
    let mut l = [[0.0; D]; D];
    let mut d = [0.0; D];
    for j in 0..D {
        let mut pivot = m[(j, j)] - t;
        for k in 0..j {
            pivot -= l[j][k] * l[j][k] * d[k];
        }
        if pivot.is_nan() || pivot <= 0.0 {
            return false;
        }
        d[j] = pivot;
        for i in j + 1..D {
            let mut v = m[(i, j)];
            for k in 0..j {
                v -= l[i][k] * l[j][k] * d[k];
            }
            l[i][j] = v / pivot;
        }
    }
    true
}

/// Gershgorin's lower bound of a symmetric matrix's eigenvalues, min_k (m_kk − Σ_{l≠k} |m_kl|)
/// (Golub & Van Loan, Matrix Computations, thm. 7.2.1): every eigenvalue lies in a disc about a
/// diagonal entry of radius its row's off-diagonal sum.
#[inline(always)]
pub fn gershgorin_lower_bound<const D: usize>(m: &Tensor<D>) -> f64 {
    (0..D)
        .map(|k| {
            m[(k, k)]
                - (0..D)
                    .filter(|&l| l != k)
                    .map(|l| m[(k, l)].abs())
                    .sum::<f64>()
        })
        .fold(f64::INFINITY, f64::min)
}

/// The smallest eigenvalue of a symmetric D × D matrix, D ≤ 3, in closed form (the
/// trigonometric solution of the characteristic cubic in 3D; Smith 1961).
pub fn min_eigenvalue<const D: usize>(m: &Tensor<D>) -> f64 {
    match D {
        1 => m[(0, 0)],
        2 => {
            let (a, b, d) = (m[(0, 0)], m[(0, 1)], m[(1, 1)]);
            0.5 * (a + d) - (0.25 * (a - d) * (a - d) + b * b).sqrt()
        }
        _ => {
            let q = m.trace() / 3.0;
            let off = m[(0, 1)].powi(2) + m[(0, 2)].powi(2) + m[(1, 2)].powi(2);
            let p2 = (0..3).map(|k| (m[(k, k)] - q).powi(2)).sum::<f64>() + 2.0 * off;
            if p2 <= 1e-30 * q * q {
                return q;
            }
            let pp = (p2 / 6.0).sqrt();
            let bm = (m - Tensor::<D>::identity() * q) / pp;
            let det = bm[(0, 0)] * (bm[(1, 1)] * bm[(2, 2)] - bm[(1, 2)] * bm[(2, 1)])
                - bm[(0, 1)] * (bm[(1, 0)] * bm[(2, 2)] - bm[(1, 2)] * bm[(2, 0)])
                + bm[(0, 2)] * (bm[(1, 0)] * bm[(2, 1)] - bm[(1, 1)] * bm[(2, 0)]);
            let r: f64 = (0.5 * det).clamp(-1.0, 1.0);
            let phi = r.acos() / 3.0;
            q + 2.0 * pp * (phi + 2.0 * std::f64::consts::PI / 3.0).cos()
        }
    }
}

/// The scatter matrix C = s − m ⊗ m / w of a weighted set of points (moments as in
/// [`plane_normal`]), its smallest eigenvalue λ and the mean of its other eigenvalues.
fn scatter<const D: usize>(w: f64, m: &[f64; D], s: &Tensor<D>) -> (Tensor<D>, f64, f64) {
    let c = Tensor::<D>::from_fn(|a, b| s[(a, b)] - m[a] * m[b] / w);
    let lambda = min_eigenvalue(&c);
    let others = (c.trace() - lambda) / (D - 1).max(1) as f64;
    (c, lambda, others)
}

/// The roughness (a scatter's smallest eigenvalue over the mean of its others) beyond which
/// [`plane_normal`] gives the plane up: the points are an edge or a corner, not a face.
pub const PLANE_ROUGHNESS: f64 = 0.2;

/// The unit normal of the plane that best fits a weighted set of points (least squares), from
/// their moments about any origin: w = Σ w_k, m = Σ w_k d_k, s = Σ w_k d_k ⊗ d_k. It is the
/// eigenvector of the smallest eigenvalue of the scatter matrix C = s − m ⊗ m / w; None where
/// the points do not lie near a plane (fewer than D of them, or that eigenvalue above
/// [`PLANE_ROUGHNESS`] times the mean of the others: an edge or a corner of a body) or near a
/// line. Its sign is arbitrary. With it comes the points' roughness: the scatter's smallest
/// eigenvalue over the mean of the others, 0 on a plane, the normal given up beyond
/// [`PLANE_ROUGHNESS`], at most 1 and 1 where it is undefined (fewer than D points); the
/// square of the normal's uncertainty in angle grows with it.
pub fn plane_normal<const D: usize>(
    count: usize,
    w: f64,
    m: &[f64; D],
    s: &Tensor<D>,
) -> (Option<[f64; D]>, f64) {
    if count < D || w <= 0.0 {
        return (None, 1.0);
    }
    let (c, lambda, others) = scatter(w, m, s);
    if others.is_nan() || others <= 0.0 {
        return (None, 1.0);
    }
    let roughness = (lambda.max(0.0) / others).min(1.0);
    if lambda > PLANE_ROUGHNESS * others {
        return (None, roughness);
    }
    // The null direction of C − λI: in 2D perpendicular to its larger row, in 3D the largest
    // cross product of two of its rows.
    let k = c - Tensor::<D>::identity() * lambda;
    let mut best = [0.0; D];
    let mut best2 = 0.0;
    let mut consider = |v: [f64; D]| {
        let n2: f64 = v.iter().map(|x| x * x).sum();
        if n2 > best2 {
            best = v;
            best2 = n2;
        }
    };
    match D {
        1 => consider(std::array::from_fn(|_| 1.0)),
        2 => {
            for a in 0..2 {
                consider(std::array::from_fn(|b| {
                    if b == 0 {
                        -k[(a, 1)]
                    } else {
                        k[(a, 0)]
                    }
                }));
            }
        }
        _ => {
            for (a, b) in [(0, 1), (0, 2), (1, 2)] {
                let (u, v) = (k.row(a), k.row(b));
                consider(std::array::from_fn(|e| {
                    let (f, g) = ((e + 1) % 3, (e + 2) % 3);
                    u[f] * v[g] - u[g] * v[f]
                }));
            }
        }
    }
    // |null vector| is the product of C's other D − 1 eigenvalues less λ: small against the
    // mean's power where the points lie on a line (3D), and the normal then is undefined.
    let n = best2.sqrt();
    if n.is_nan() || n <= 0.04 * others.powi(D as i32 - 1) {
        return (None, roughness);
    }
    (Some(std::array::from_fn(|a| best[a] / n)), roughness)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::CubicSpline;
    use crate::particles::Vector;
    use crate::validate::blocks::block;

    /// The closed-form smallest eigenvalue against known spectra.
    #[test]
    fn smallest_eigenvalue() {
        let m2 = Tensor::<2>::new(2.0, 1.0, 1.0, 2.0);
        assert!((min_eigenvalue(&m2) - 1.0).abs() < 1e-14);
        // Q diag(0.3, 1, 2) Qᵀ with Q a rotation.
        let (c, s) = (0.6_f64, 0.8_f64);
        let q = Tensor::<3>::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
        let m3 = q * Tensor::<3>::from_diagonal(&Vector::<3>::new(0.3, 1.0, 2.0)) * q.transpose();
        assert!(
            (min_eigenvalue(&m3) - 0.3).abs() < 1e-12,
            "{}",
            min_eigenvalue(&m3)
        );
        assert!((min_eigenvalue(&(Tensor::<3>::identity() * 0.7)) - 0.7).abs() < 1e-15);
    }

    /// A plane's points are smooth (roughness 0) and give its normal; an edge's (two
    /// perpendicular faces) are rough and give none; too few points are rough.
    #[test]
    fn roughness_and_plane_normal() {
        let moments = |pts: &[[f64; 3]]| {
            let (mut m, mut s) = ([0.0; 3], Tensor::<3>::zeros());
            for p in pts {
                for a in 0..3 {
                    m[a] += p[a];
                    for b in 0..3 {
                        s[(a, b)] += p[a] * p[b];
                    }
                }
            }
            (pts.len(), pts.len() as f64, m, s)
        };
        let mut face = Vec::new();
        let mut edge = Vec::new();
        for k in -2..=2 {
            for l in -2..=2 {
                face.push([k as f64, l as f64, 0.3]);
                if l <= 0 {
                    edge.push([k as f64, l as f64, 0.0]);
                    edge.push([k as f64, 0.0, -l as f64]);
                }
            }
        }
        let (n, w, m, s) = moments(&face);
        let (normal, r) = plane_normal::<3>(n, w, &m, &s);
        assert!(r < 1e-12);
        let normal = normal.unwrap();
        assert!((normal[2].abs() - 1.0).abs() < 1e-12, "{normal:?}");
        let (n, w, m, s) = moments(&edge);
        let (normal, r) = plane_normal::<3>(n, w, &m, &s);
        assert!(r > 0.2 && r <= 1.0, "{r}");
        assert!(normal.is_none());
        let (n, w, m, s) = moments(&face[..2]);
        assert_eq!(plane_normal::<3>(n, w, &m, &s), (None, 1.0));
    }

    /// Gershgorin's bound lies below the smallest eigenvalue (equal for a diagonal matrix),
    /// the pivots' test says whether it exceeds a value, and the indicator is a lower bound on
    /// the same side of both thresholds.
    #[test]
    fn gershgorin_bound_and_indicator() {
        let mut rnd = crate::validate::blocks::uniform(5);
        let (mut settled, mut surface, mut near_min) = (0, 0, [0, 0]);
        for n in 0..1000 {
            let e = Tensor::<3>::from_fn(|_, _| 0.4 * rnd());
            let m = Tensor::<3>::identity() + (e + e.transpose()) * 0.5;
            let (bound, exact) = (gershgorin_lower_bound(&m), min_eigenvalue(&m));
            assert!(bound <= exact + 1e-12, "{bound} > {exact}");
            for t in [0.0, 0.3, LAMBDA_SURFACE, 0.9] {
                if (exact - t).abs() > 1e-12 {
                    assert_eq!(exceeds(&m, t), exact > t, "{exact} against {t}");
                }
            }
            let l = surface_indicator(&m);
            assert!(l <= exact + 1e-12);
            assert_eq!(l < LAMBDA_SURFACE, exact < LAMBDA_SURFACE);
            assert_eq!(l < LAMBDA_MIN, exact < LAMBDA_MIN);
            // Scaled to λ_min 0.8 or 1.25 times LAMBDA_MIN.
            let scale = LAMBDA_MIN / exact * if n % 2 == 0 { 0.8 } else { 1.25 };
            let (small, small_exact) = (m * scale, exact * scale);
            if (small_exact - LAMBDA_MIN).abs() > 1e-12 {
                let l = surface_indicator(&small);
                assert!(l <= small_exact + 1e-12);
                assert_eq!(l < LAMBDA_MIN, small_exact < LAMBDA_MIN, "{small_exact}");
                assert!(l < LAMBDA_SURFACE);
                near_min[(small_exact < LAMBDA_MIN) as usize] += 1;
            }
            if exact < LAMBDA_SURFACE {
                surface += 1;
            } else if bound < LAMBDA_SURFACE {
                settled += 1;
            }
        }
        // Both branches are taken.
        assert!(
            settled > 100 && surface > 20 && near_min == [500, 500],
            "{settled} settled, {surface} surface, {near_min:?} about LAMBDA_MIN"
        );
        assert!(!exceeds(&Tensor::<3>::identity(), 1.0));
        assert!(exceeds(&Tensor::<2>::identity(), 0.999));
        let d = Tensor::<3>::from_diagonal(&Vector::<3>::new(0.9, 0.8, 1.2));
        assert_eq!(gershgorin_lower_bound(&d), 0.8);
    }

    /// Lists longer than a batch and than a [`Support`] covers (h = 2.5 Δp: about 500
    /// neighbours in the support, and the skin's among them, so that a batch fills in the middle
    /// of a quad):
    /// B_i A_i = I with A_i summed here one neighbour at a time, inside and at a corner of a
    /// perturbed block, the same on both builds, and no support marked.
    #[test]
    fn long_lists_sum_every_neighbour() {
        let mut p = block::<3>(12, 0.2);
        p.h.iter_mut().for_each(|h| *h = 2.5);
        let mut nl = NeighborList::default();
        // With a skin, so that the list's quads hold entries outside the support too.
        nl.build(&p.x, &p.h, p.n_real, 1.0);
        let all = 0..p.n_real;
        let (mut wide, mut portable) = (Vec::new(), Vec::new());
        corrections(CubicSpline, &p, &nl, same_body(&p), &all, &mut wide, &[]);
        corrections_on(
            CubicSpline,
            &p,
            &nl,
            same_body(&p),
            &all,
            &mut portable,
            (false, &[]),
        );
        assert_eq!(wide, portable);
        for i in [6 + 6 * 12 + 6 * 144, 0] {
            let mut a = Tensor::<3>::zeros();
            let mut inside = 0;
            for j in nl.list(i) {
                let j = j as usize;
                let xij = p.x[i] - p.x[j];
                let (r, h) = (xij.norm(), 0.5 * (p.h[i] + p.h[j]));
                if r > 0.0 && r < 2.0 * h {
                    a -= xij * xij.transpose() * (p.volume(j) * CubicSpline.dw::<3>(r, h) / r);
                    inside += 1;
                }
            }
            assert!(inside > BATCH, "particle {i}: {inside} neighbours");
            let err = (wide[i].b * a - Tensor::<3>::identity()).norm();
            assert!(err < 1e-12, "particle {i}: |B A − I| = {err}");
            assert!(!wide[i].fallback && wide[i].support.is_none());
        }
    }

    /// The smallest real part of a general matrix's eigenvalues: a symmetric matrix's smallest
    /// eigenvalue; unchanged by a similarity S M S⁻¹ (three real roots); with a complex pair
    /// (a rotation's), the pair's real part where it is the smaller; in 2D likewise.
    #[test]
    fn smallest_real_eigenvalue_of_a_general_matrix() {
        let m = Tensor::<3>::new(2.0, 0.3, -0.4, 0.3, 1.1, 0.2, -0.4, 0.2, 0.7);
        let s = Tensor::<3>::new(1.5, 0.3, 0.0, 0.1, 0.7, 0.2, 0.0, -0.4, 1.2);
        let lambda = min_eigenvalue(&m);
        assert!((min_real_eigenvalue(&m) - lambda).abs() < 1e-14);
        let similar = s * m * s.try_inverse().unwrap();
        assert!((min_real_eigenvalue(&similar) - lambda).abs() < 1e-12);
        // Real eigenvalue 2 and the pair 0.5 ± 0.8i, in a skewed basis.
        let rotation = Tensor::<3>::new(0.5, -0.8, 0.0, 0.8, 0.5, 0.0, 0.0, 0.0, 2.0);
        let skewed = s * rotation * s.try_inverse().unwrap();
        assert!((min_real_eigenvalue(&skewed) - 0.5).abs() < 1e-12);
        let flipped = Tensor::<3>::new(2.5, -0.8, 0.0, 0.8, 2.5, 0.0, 0.0, 0.0, -1.0);
        assert!(
            (min_real_eigenvalue(&(s * flipped * s.try_inverse().unwrap())) + 1.0).abs() < 1e-12
        );
        let m2 = Tensor::<2>::new(1.0, 0.4, 0.4, 0.3);
        assert!((min_real_eigenvalue(&m2) - min_eigenvalue(&m2)).abs() < 1e-15);
        assert_eq!(
            min_real_eigenvalue(&Tensor::<2>::new(0.5, -0.8, 0.8, 0.5)),
            0.5
        );
    }

    /// The surface indicator and the fallback: about 1 inside, lower at a face and a corner,
    /// and a lone particle or a line of particles (in 2D) keeps the uncorrected gradient.
    #[test]
    fn indicator_and_fallback() {
        let p = block::<2>(9, 0.0);
        let mut nl = NeighborList::default();
        nl.build(&p.x, &p.h, p.n_real, 0.0);
        let mut c = Vec::new();
        corrections(
            CubicSpline,
            &p,
            &nl,
            same_body(&p),
            &(0..p.n_real),
            &mut c,
            &[],
        );
        let (inside, face, corner) = (c[4 + 4 * 9], c[4], c[0]);
        assert!(
            (inside.lambda_min - 1.0).abs() < 0.05,
            "{}",
            inside.lambda_min
        );
        assert!((0.2..0.8).contains(&face.lambda_min), "{}", face.lambda_min);
        assert!(
            (0.2..0.8).contains(&corner.lambda_min),
            "{}",
            corner.lambda_min
        );
        let mut line = Particles::<2>::default();
        for k in 0..5 {
            line.push(
                Vector::<2>::new(k as f64, 0.0),
                Vector::<2>::zeros(),
                1.0,
                1.0,
                1.2,
                0,
            );
        }
        line.push(
            Vector::<2>::new(20.0, 20.0),
            Vector::<2>::zeros(),
            1.0,
            1.0,
            1.2,
            0,
        );
        let mut nl = NeighborList::default();
        nl.build(&line.x, &line.h, line.n_real, 0.0);
        let fallbacks = corrections(
            CubicSpline,
            &line,
            &nl,
            same_body(&line),
            &(0..line.n_real),
            &mut c,
            &[],
        );
        assert_eq!(fallbacks, 6);
        assert!(c.iter().all(|c| c.b == Tensor::<2>::identity()));
    }
}
