//! Structure-of-arrays particle store, generic over the dimension `D` (2: plane strain, 3).
//!
//! Real particles come first (`0..n_real`); symmetry-plane ghosts, rebuilt every step by
//! `boundary`, follow them. Physics loops run over real particles and read ghosts as neighbours.

use crate::tensor::Sym;
use nalgebra::{SMatrix, SVector};
use rayon::prelude::*;

/// A point or vector in D dimensions.
pub type Vector<const D: usize> = SVector<f64, D>;
/// A D×D tensor (stress, velocity gradient).
pub type Tensor<const D: usize> = SMatrix<f64, D, D>;

/// Calls `$m!(field, …)` with every per-particle field of [`Particles`]: the one list that the
/// whole-particle operations (copy, truncate, reorder) go through, so a new field cannot be
/// forgotten in one of them.
macro_rules! for_each_field {
    ($m:ident) => {
        $m!(
            x,
            v,
            vh,
            a,
            u,
            m,
            rho,
            e,
            eh,
            p,
            c,
            s,
            h,
            h0,
            eps_p,
            plastic_work,
            stretch,
            damage,
            body,
            id,
            contact_force,
            strain_rate,
            dv
        )
    };
}

/// Per-particle state. Indices are particle numbers; `id` follows a particle through reordering.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Particles<const D: usize> {
    /// Position x (m).
    pub x: Vec<Vector<D>>,
    /// Velocity v (m/s) at the whole step t_n (predicted from the leapfrog velocity; what the
    /// rates and the output use).
    pub v: Vec<Vector<D>>,
    /// Leapfrog velocity at the half step t_{n−½} (m/s).
    pub vh: Vec<Vector<D>>,
    /// Acceleration of the last step (m/s²), for the velocity predictor.
    pub a: Vec<Vector<D>>,
    /// Energy-correction displacement u = (v̄ − v_pred) Δt of the last step (m), v̄ the mean of
    /// the half-step velocities: see `integrate` (lagged energy correction). In single
    /// precision, as the rate pass reads it (`physics::Gather`).
    pub u: Vec<SVector<f32, D>>,
    /// Mass m (kg).
    pub m: Vec<f64>,
    /// Density ρ (kg/m³).
    pub rho: Vec<f64>,
    /// Specific internal energy e (J/kg) at the whole step t_n (predicted; what the EOS and the
    /// output use).
    pub e: Vec<f64>,
    /// Leapfrog specific internal energy at the half step t_{n−½} (J/kg).
    pub eh: Vec<f64>,
    /// Pressure p (Pa), from the EOS.
    pub p: Vec<f64>,
    /// Sound speed c = √((K_s + 4G/3)/ρ) (m/s).
    pub c: Vec<f64>,
    /// Deviatoric stress S (Pa). In 2D plane strain the stored 2×2 block is the in-plane part and
    /// S_zz = −(S_xx + S_yy) (see [`crate::tensor::out_of_plane`]). Symmetric: one triangle
    /// is kept ([`Sym`]).
    pub s: Vec<Sym<f64, D>>,
    /// Smoothing length h (m) and its initial value h0.
    pub h: Vec<f64>,
    pub h0: Vec<f64>,
    /// Equivalent plastic strain εp.
    pub eps_p: Vec<f64>,
    /// Plastic work per unit mass w_p = Σ σ_eq Δεp / ρ (J/kg): the heat source of the models
    /// with adiabatic heating (Johnson–Cook).
    pub plastic_work: Vec<f64>,
    /// The left Cauchy–Green tensor b = F Fᵀ of the particle's deformation since the start
    /// (the identity at first): its largest eigenvalue is the square of the largest stretch,
    /// which h follows (`integrate::smoothing_length`). Symmetric: one triangle is kept.
    pub stretch: Vec<Sym<f64, D>>,
    /// Damage D ∈ [0, 1] (see `material::damage`); 1: failed.
    pub damage: Vec<f64>,
    /// Body index (into the case's bodies).
    pub body: Vec<u32>,
    /// Original particle number (stable through reordering; ghosts carry their source's).
    pub id: Vec<u32>,
    /// Contact force on the particle (N), from the last force evaluation.
    pub contact_force: Vec<Vector<D>>,
    /// The strain rate D = sym L of the last step (1/s), in single precision: what the
    /// artificial viscosity's limiter reads of the flow (`physics::viscosity::limited`); zero
    /// once the particle has flowed plastically (εp > 0), whose pairs keep the plain viscosity.
    pub strain_rate: Vec<Sym<f32, D>>,
    /// What the continuity equation and the velocity gradient add to [`Particles::v`] (m/s),
    /// in single precision: v + dv is the velocity at the middle of the coming step, v^{n+½},
    /// extrapolated from the last two accelerations (see `integrate`, "Staggered material
    /// update").
    pub dv: Vec<SVector<f32, D>>,
    /// Number of real particles; `len() - n_real` are ghosts.
    pub n_real: usize,
}

/// The real particles of a store (no ghosts), serialised exactly as a [`Particles`] holding only
/// them would be: a checkpoint is written from the running state without copying it.
pub struct RealParticles<'a, const D: usize>(pub &'a Particles<D>);

impl<const D: usize> serde::Serialize for RealParticles<'_, D> {
    fn serialize<S: serde::Serializer>(&self, ser: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let (p, n) = (self.0, self.0.n_real);
        // The fields of `Particles` in their order, then n_real.
        let mut st = ser.serialize_struct("Particles", 24)?;
        macro_rules! fields {
            ($($f:ident),*) => { $(st.serialize_field(stringify!($f), &p.$f[..n])?;)* };
        }
        for_each_field!(fields);
        st.serialize_field("n_real", &n)?;
        st.end()
    }
}

impl<const D: usize> Particles<D> {
    /// All particles, ghosts included.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Volume V = m/ρ.
    pub fn volume(&self, i: usize) -> f64 {
        self.m[i] / self.rho[i]
    }

    /// Cauchy stress σ = −p I + S.
    pub fn stress(&self, i: usize) -> Tensor<D> {
        self.s[i].full() - Tensor::<D>::identity() * self.p[i]
    }

    /// Append one particle (all derived fields zero; `h0 = h`).
    #[allow(clippy::too_many_arguments)]
    pub fn push(&mut self, x: Vector<D>, v: Vector<D>, m: f64, rho: f64, h: f64, body: u32) {
        let id = self.x.len() as u32;
        self.x.push(x);
        self.v.push(v);
        self.vh.push(v);
        self.a.push(Vector::<D>::zeros());
        self.u.push(SVector::<f32, D>::zeros());
        self.m.push(m);
        self.rho.push(rho);
        self.e.push(0.0);
        self.eh.push(0.0);
        self.p.push(0.0);
        self.c.push(0.0);
        self.s.push(Sym::zeros());
        self.stretch.push(Sym::from_full(&Tensor::<D>::identity()));
        self.h.push(h);
        self.h0.push(h);
        self.eps_p.push(0.0);
        self.plastic_work.push(0.0);
        self.damage.push(0.0);
        self.body.push(body);
        self.id.push(id);
        self.contact_force.push(Vector::<D>::zeros());
        self.strain_rate.push(Sym::zeros());
        self.dv.push(SVector::<f32, D>::zeros());
        self.n_real = self.x.len();
    }

    /// Room for `additional` more particles in every field, exactly (pushing past an exact fit
    /// would double the capacity of every array).
    pub fn reserve_exact(&mut self, additional: usize) {
        macro_rules! reserve {
            ($($f:ident),*) => { $(self.$f.reserve_exact(additional);)* };
        }
        for_each_field!(reserve);
    }

    /// Drop ghosts, keeping the real particles.
    pub fn truncate_to_real(&mut self) {
        let n = self.n_real;
        macro_rules! truncate {
            ($($f:ident),*) => { $(self.$f.truncate(n);)* };
        }
        for_each_field!(truncate);
    }

    /// Append a copy of particle `i` (used for ghosts); returns its index.
    pub fn push_copy(&mut self, i: usize) -> usize {
        macro_rules! push {
            ($($f:ident),*) => { $(self.$f.push(self.$f[i]);)* };
        }
        for_each_field!(push);
        self.x.len() - 1
    }

    /// Copy particle `sources[k]` onto particle `first + k` for every k, in parallel; every
    /// source must lie below `first`.
    pub fn copy_many(&mut self, first: usize, sources: &[usize]) {
        macro_rules! copy_many {
            ($($f:ident),*) => { $(copy_onto(&mut self.$f, first, sources);)* };
        }
        for_each_field!(copy_many);
    }

    /// [`Particles::copy_many`] of the positions and smoothing lengths only.
    pub fn copy_positions(&mut self, first: usize, sources: &[usize]) {
        copy_onto(&mut self.x, first, sources);
        copy_onto(&mut self.h, first, sources);
    }

    /// Reorder real particles by `order` (new position k holds old particle `order[k]`).
    pub fn permute(&mut self, order: &[usize]) {
        fn apply<T: Copy>(v: &mut Vec<T>, order: &[usize]) {
            // The capacity stays, room for the ghosts included.
            let old = std::mem::replace(v, Vec::with_capacity(v.capacity()));
            v.extend(order.iter().map(|&k| old[k]));
        }
        self.truncate_to_real();
        macro_rules! permute {
            ($($f:ident),*) => { $(apply(&mut self.$f, order);)* };
        }
        for_each_field!(permute);
    }

    /// Append the states of particles `idx` to `out`, field by field: the message of a halo
    /// exchange (`ranks::Plan`), read back by [`Particles::unpack`] on the other rank.
    pub fn pack(&self, idx: &[u32], out: &mut Vec<u8>) {
        out.reserve(idx.len() * state_bytes::<D>());
        macro_rules! pack {
            ($($f:ident),*) => { $(for &i in idx { out.extend_from_slice(bytes_of(&self.$f[i as usize])); })* };
        }
        for_each_field!(pack);
    }

    /// Set the states of particles `idx` from a message of [`Particles::pack`] for them.
    pub fn unpack(&mut self, idx: &[u32], mut from: &[u8]) {
        macro_rules! unpack {
            ($($f:ident),*) => { $(for &i in idx { from = read_into(&mut self.$f[i as usize], from); })* };
        }
        for_each_field!(unpack);
        debug_assert!(from.is_empty(), "{} bytes left over", from.len());
    }

    /// [`Particles::pack`] of the positions and smoothing lengths only: what another rank's
    /// neighbour refresh reads of the particles near its own (`Simulation`'s position plan).
    pub fn pack_positions(&self, idx: &[u32], out: &mut Vec<u8>) {
        out.reserve(idx.len() * (std::mem::size_of::<Vector<D>>() + std::mem::size_of::<f64>()));
        for &i in idx {
            out.extend_from_slice(bytes_of(&self.x[i as usize]));
        }
        for &i in idx {
            out.extend_from_slice(bytes_of(&self.h[i as usize]));
        }
    }

    /// Set the positions and smoothing lengths of particles `idx` from a message of
    /// [`Particles::pack_positions`] for them.
    pub fn unpack_positions(&mut self, idx: &[u32], mut from: &[u8]) {
        for &i in idx {
            from = read_into(&mut self.x[i as usize], from);
        }
        for &i in idx {
            from = read_into(&mut self.h[i as usize], from);
        }
        debug_assert!(from.is_empty(), "{} bytes left over", from.len());
    }

    /// After each rank has advanced its own range `parts[rank]` of the real particles, give
    /// every rank all of them (each field all-gathered; nothing to do on one rank).
    pub fn share_real(&mut self, ranks: crate::ranks::Ranks, parts: &[std::ops::Range<usize>]) {
        let n = self.n_real;
        macro_rules! share {
            ($($f:ident),*) => { $(ranks.share(&mut self.$f[..n], parts);)* };
        }
        for_each_field!(share);
    }

    /// [`Particles::share_real`] of the positions and smoothing lengths only.
    pub fn share_positions(
        &mut self,
        ranks: crate::ranks::Ranks,
        parts: &[std::ops::Range<usize>],
    ) {
        let n = self.n_real;
        ranks.share(&mut self.x[..n], parts);
        ranks.share(&mut self.h[..n], parts);
    }

    /// Position as a 3-vector (z = 0 in 2D), for output.
    pub fn position3(&self, i: usize) -> [f64; 3] {
        to3(&self.x[i])
    }

    /// Velocity as a 3-vector (z = 0 in 2D), for output.
    pub fn velocity3(&self, i: usize) -> [f64; 3] {
        to3(&self.v[i])
    }
}

/// The bytes of a field's value. Every field of [`Particles`] is plain data without padding
/// (numbers, and vectors and [`crate::tensor::Sym`]s of one number type), so each of its bytes
/// is initialised.
fn bytes_of<T: Copy>(v: &T) -> &[u8] {
    // SAFETY: `v` is a valid T of `size_of::<T>()` initialised bytes (no padding, above).
    unsafe { std::slice::from_raw_parts((v as *const T).cast::<u8>(), std::mem::size_of::<T>()) }
}

/// Set `v` from the first `size_of::<T>()` bytes of `from` (written by [`bytes_of`] for a T
/// of this same program); returns the rest.
fn read_into<'a, T: Copy>(v: &mut T, from: &'a [u8]) -> &'a [u8] {
    let (b, rest) = from.split_at(std::mem::size_of::<T>());
    // SAFETY: `b` holds exactly the bytes of a valid T (above); read unaligned, as a byte
    // buffer need not be aligned for T.
    *v = unsafe { std::ptr::read_unaligned(b.as_ptr().cast::<T>()) };
    rest
}

/// A D-vector as 3 components, zero-padded.
pub fn to3<const D: usize>(a: &Vector<D>) -> [f64; 3] {
    let mut out = [0.0; 3];
    for k in 0..D.min(3) {
        out[k] = a[k];
    }
    out
}

/// The first D components of a 3-array.
pub fn from3<const D: usize>(a: [f64; 3]) -> Vector<D> {
    Vector::<D>::from_fn(|k, _| a[k])
}

/// Estimated memory of a run of `n` particles in bytes, used by `strike check`, the deck's
/// memory check and `strike bench`: what `strike bench` measures (peak resident memory over
/// the steps, set-up included) plus about 5 %, and `FIXED_BYTES`. A figure a particle for
/// what grows with the particles, and the rate pass's neighbour records apart
/// ([`crate::physics::record_bytes`]), which do not: a ring of a window's records (26 bytes
/// a particle at a million in 3D, a floor of a few MB for small cases) or, once a particle of
/// a material with a damage model (`fails`) has failed, every particle's record (200 bytes a
/// particle in 3D). In 3D (2026-11-30, a cube of 10⁶ particles): 773 B a particle, of which
/// the state is about 360 B, the packed neighbour lists with their skin about 165
/// (`neighbors`), the rate pass's results 152 and its window of records about 25, and the
/// search's buffers about 60; the peak of 3 steps of `strike run` is 783 MB. Contact adds the
/// colour states' slots (4 B; the states themselves only for the particles near another body)
/// and the search radii max(h, h0) (8 B): two cubes in contact, 1.02·10⁶ particles, 790 B.
/// CN-SPH adds B, (σ/ρ²)B and the correction pass's records: 1110 B. In 2D at 5·10⁵
/// particles: 537 B, and 744 B in CN-SPH (3 steps of `strike run`).
///
/// `ghosts`: the symmetry planes' ghosts (`deck::estimate_ghosts`), each a particle's state,
/// its neighbour record and, in CN-SPH, B and (σ/ρ²)B (the sphere–plate demo has 6 948 for its
/// 47 812 particles, about 80 bytes a particle).
pub fn estimated_bytes(n: f64, ghosts: f64, dimension: usize, corrected: bool, fails: bool) -> f64 {
    // The figures of 2026-11-30 (with 5 %) less the records at those sizes: 26 B a particle
    // at 10⁶ in 3D, 23 at 5·10⁵ in 2D.
    let per = match (dimension, corrected) {
        (2, false) => 542.0,
        (2, true) => 752.0,
        (_, false) => 784.0,
        (_, true) => 1134.0,
    };
    let records = crate::physics::record_bytes(n.min(u32::MAX as f64) as usize, dimension, fails);
    let state = match dimension {
        2 => state_bytes::<2>(),
        _ => state_bytes::<3>(),
    };
    let tensors = if corrected {
        2 * dimension * dimension * 8
    } else {
        0
    };
    let ghost = state + crate::physics::record_size(dimension) + tensors;
    n * per + records + ghosts * ghost as f64 + FIXED_BYTES
}

/// What a run holds whatever its size, beyond the per-particle figures and the records: the
/// allocator's arenas and the thread pool's first allocations. `strike bench`'s cases of
/// 16 000–20 000 particles, each first in a fresh process, grew 1.1–1.8 MB more than the
/// rest of the model (2026-12-02).
const FIXED_BYTES: f64 = 1.5e6;

/// Bytes of one particle's state: every field of [`Particles`].
pub fn state_bytes<const D: usize>() -> usize {
    fn element<T>(_: &[T]) -> usize {
        std::mem::size_of::<T>()
    }
    let p = Particles::<D>::default();
    let mut total = 0;
    macro_rules! add {
        ($($f:ident),*) => { $(total += element(&p.$f);)* };
    }
    for_each_field!(add);
    total
}

/// `v[first + k] = v[sources[k]]` for every k, in parallel (every source below `first`).
fn copy_onto<T: Copy + Send + Sync>(v: &mut [T], first: usize, sources: &[usize]) {
    let (from, to) = v.split_at_mut(first);
    to[..sources.len()]
        .par_iter_mut()
        .zip(sources)
        .with_min_len(256)
        .for_each(|(d, &s)| *d = from[s]);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A store of `n` particles whose every field of every particle holds its own bytes (all
    /// of them finite numbers), different from a freshly pushed particle's.
    fn patterned(n: usize) -> Particles<3> {
        let mut p = Particles::<3>::default();
        for _ in 0..n {
            p.push(Vector::<3>::zeros(), Vector::<3>::zeros(), 1.0, 1.0, 1.0, 0);
        }
        let mut fill = 0x10_u8;
        macro_rules! pattern {
            ($($f:ident),*) => { $(for i in 0..n {
                let bytes = vec![fill; std::mem::size_of_val(&p.$f[i])];
                read_into(&mut p.$f[i], &bytes);
                fill = 0x10 + (fill - 0x0f) % 0x2f;
            })* };
        }
        for_each_field!(pattern);
        p
    }

    /// A halo message carries every field: particles 3 and 1 of one store, packed and unpacked
    /// onto particles 0 and 2 of another, are theirs exactly, and the others are untouched.
    #[test]
    fn pack_and_unpack_carry_every_field() {
        let from = patterned(4);
        let mut to = Particles::<3>::default();
        for _ in 0..4 {
            to.push(Vector::<3>::zeros(), Vector::<3>::zeros(), 1.0, 1.0, 1.0, 0);
        }
        let mut expect = to.clone();
        macro_rules! differ_and_expect {
            ($($f:ident),*) => { $(
                assert_ne!(from.$f[3], to.$f[0], stringify!($f));
                expect.$f[0] = from.$f[3];
                expect.$f[2] = from.$f[1];
            )* };
        }
        for_each_field!(differ_and_expect);
        let mut message = Vec::new();
        from.pack(&[3, 1], &mut message);
        to.unpack(&[0, 2], &message);
        assert_eq!(to, expect);
    }
}
