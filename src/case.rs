//! The validated case: what a deck means, in SI units, with no TOML left in it.
//!
//! `deck` turns a TOML file into a [`Case`]; `setup` turns a [`Case`] into particles. Every value
//! here has already been checked (positive densities, known materials, vectors of the deck's
//! dimension…), so the code downstream never needs to re-validate user input. Each user-named item
//! keeps the [`Location`] of its definition so that later checks (two bodies overlapping, say) can
//! still point at the deck's line.

pub use crate::contact::ContactLaw;

/// A place in a deck file, for error messages (1-based line and column).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Location {
    pub line: usize,
    pub column: usize,
}

/// Which smoothing kernel (see `kernel`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum KernelKind {
    #[default]
    CubicSpline,
    WendlandC2,
}

/// Which SPH formulation the conservation equations use (see `physics::correction`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Formulation {
    /// Conventional SPH: ∇_i W_ij as it is.
    #[default]
    Conventional,
    /// CN-SPH: first-order corrected gradients B_i ∇_i W_ij (Randles–Libersky).
    Corrected,
}

impl Formulation {
    /// The Courant number where the deck sets none: 0.3 in conventional SPH, half that in
    /// CN-SPH. The correction multiplies a surface particle's gradients by B, whose largest
    /// eigenvalue is 1/λ_min ≈ 2 at a face and up to 4 at a corner, and the leapfrog step must
    /// follow the stiffer surface: at C = 0.3 CN-SPH's rubber rings drift 0.85–3.5 % in energy
    /// (conventional 0.05 %) and the 7 km/s demo blows up at 0.1 µs (a plate particle of the
    /// torn rim at 82 km/s); at 0.15 the rings drift 0.12 % and the demo runs to its end
    /// (energy 2.0 %, no mixing). A per-particle step scaled by B's gain, with the same number
    /// of steps, drifted 0.35 %: the varying step costs more than it saves.
    pub fn default_cfl(self) -> f64 {
        match self {
            Formulation::Conventional => 0.3,
            Formulation::Corrected => 0.15,
        }
    }
}

/// Everything a run needs.
#[derive(Debug, Clone)]
pub struct Case {
    /// Case name (the deck's `[simulation] name`, or the deck file's stem).
    pub name: String,
    /// The deck file, as given (for messages).
    pub file: String,
    /// 2 (plane strain) or 3.
    pub dimension: usize,
    pub simulation: Simulation,
    pub materials: Vec<MaterialSpec>,
    pub bodies: Vec<BodySpec>,
    /// Interactions the deck set explicitly; a pair of distinct bodies not listed is in `contact`
    /// with default settings.
    pub interactions: Vec<InteractionSpec>,
    pub symmetry: Vec<SymmetryPlane>,
    pub output: OutputSpec,
}

/// `[simulation]`: time, kernel, numerical dissipation, gravity.
#[derive(Debug, Clone)]
pub struct Simulation {
    /// Simulated end time (s).
    pub end_time: f64,
    /// Courant number C_cfl of the time step as the deck gives it (see [`Simulation::cfl`]).
    pub cfl: Option<f64>,
    /// Optional hard cap on steps.
    pub max_steps: Option<u64>,
    pub kernel: KernelKind,
    pub formulation: Formulation,
    /// h0 = smoothing_ratio × spacing (default 1.2).
    pub smoothing_ratio: f64,
    /// Monaghan–Gingold α (default 1) and β (default 2).
    pub viscosity_alpha: f64,
    pub viscosity_beta: f64,
    /// The viscosity's limiter κ (default [`crate::physics::viscosity::LIMITER`]; 0: off).
    pub viscosity_limiter: f64,
    /// Gravity (m/s²), z = 0 in 2D.
    pub gravity: [f64; 3],
    /// h stays within [h_min_ratio, h_max_ratio] × h0 (defaults 0.5 and 2).
    pub h_min_ratio: f64,
    pub h_max_ratio: f64,
    /// The most h grows with the material's largest stretch λ_max, s_max of
    /// h = h0 (ρ0/ρ)^(1/D) min(max(λ_max, 1), s_max) (default 1.25; 1 switches it off; see
    /// `integrate::smoothing_length`).
    pub smoothing_stretch: f64,
    /// δ of the density diffusion in the continuity equation (0: none; see `physics`).
    pub density_diffusion: f64,
    /// Whether the kernel follows the material's stretch as an ellipsoid
    /// (`smoothing_shape = "tensor"`, see `physics::asph`) rather than a sphere.
    pub tensor_smoothing: bool,
    /// Impact speed for default contact stiffness; None: the largest relative speed of the bodies.
    pub impact_speed: Option<f64>,
}

impl Simulation {
    /// The Courant number: the deck's, or the formulation's default
    /// ([`Formulation::default_cfl`]).
    pub fn cfl(&self) -> f64 {
        self.cfl.unwrap_or(self.formulation.default_cfl())
    }
}

/// A material: reference density, equation of state, strength, and options.
#[derive(Debug, Clone, PartialEq)]
pub struct MaterialSpec {
    pub name: String,
    pub location: Location,
    /// ρ0 (kg/m³).
    pub density: f64,
    pub eos: EosSpec,
    pub strength: StrengthSpec,
    /// Pressure cut-off p_min (Pa, ≤ 0): pressure is never below it (spall).
    pub pressure_cutoff: Option<f64>,
    /// Artificial stress ε (Monaghan 2000), None: off.
    pub artificial_stress: Option<f64>,
    /// Damage models (none: the material never fails).
    pub damage: DamageSpec,
}

/// A material's damage models (see `material::damage`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DamageSpec {
    pub spall: Option<crate::material::Spall>,
    pub johnson_cook: Option<crate::material::JohnsonCookFailure>,
    /// Tuler–Butcher's rate-dependent spall (a deck names it instead of `spall`).
    pub tuler_butcher: Option<crate::material::TulerButcher>,
}

impl DamageSpec {
    pub fn is_none(&self) -> bool {
        self.spall.is_none() && self.johnson_cook.is_none() && self.tuler_butcher.is_none()
    }
}

#[derive(Debug, Clone, PartialEq)]
pub enum EosSpec {
    /// p = K (ρ/ρ0 − 1).
    Linear { bulk_modulus: f64 },
    /// Mie–Grüneisen referenced to the Hugoniot (LS-DYNA EOS_GRUNEISEN).
    MieGruneisen {
        c0: f64,
        s1: f64,
        s2: f64,
        s3: f64,
        gamma0: f64,
        a: f64,
    },
    /// Tillotson (hypervelocity, vaporisation).
    Tillotson(crate::material::Tillotson),
}

#[derive(Debug, Clone, PartialEq)]
pub enum StrengthSpec {
    /// No deviatoric stress (a fluid).
    Hydrodynamic,
    /// Elastic, never yields.
    Elastic { shear_modulus: f64 },
    /// von Mises with linear isotropic hardening: Y = Y0 + hardening_modulus · εp.
    VonMises {
        shear_modulus: f64,
        yield_stress: f64,
        hardening_modulus: f64,
    },
    /// Johnson–Cook: strain hardening, strain rate, thermal softening.
    JohnsonCook(crate::material::JohnsonCook),
    /// Steinberg–Guinan: pressure hardening, thermal softening, melting.
    SteinbergGuinan(crate::material::SteinbergGuinan),
}

/// A body: one shape filled with particles on a lattice, one material.
#[derive(Debug, Clone)]
pub struct BodySpec {
    pub name: String,
    pub location: Location,
    /// Index into `Case::materials`.
    pub material: usize,
    /// Lattice spacing Δp (m).
    pub spacing: f64,
    /// Initial velocity (m/s), z = 0 in 2D.
    pub velocity: [f64; 3],
    pub shape: Shape,
    pub motion: Motion,
    /// `Some(b)` for a prescribed set (`[[prescribed]]`): the particles of body b's lattice that
    /// lie in this body's `shape` (the set's region), taken out of body b, welded to it and
    /// moving at this body's velocity ([`Motion::Prescribed`]). Such bodies follow the deck's
    /// bodies, with b's material and spacing, and meet every other body as b does. None for a
    /// body of the deck.
    pub part_of: Option<usize>,
}

/// How a body moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Motion {
    /// Free: moves under its forces.
    #[default]
    Free,
    /// Moves at its initial velocity whatever the forces (a piston, a fixed support when zero).
    Prescribed,
}

/// Shapes. Particles sit at `min + (i + ½) Δp` of the shape's bounding box, inside the shape.
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// 3D box (or 2D rectangle: z ignored).
    Box { min: [f64; 3], max: [f64; 3] },
    /// 3D sphere (or 2D disc).
    Sphere { center: [f64; 3], radius: f64 },
    /// 3D cylinder: base centre, unit axis, radius, length.
    Cylinder {
        base: [f64; 3],
        axis: [f64; 3],
        radius: f64,
        length: f64,
    },
    /// Annulus in 2D (ring), or hollow sphere in 3D.
    Ring {
        center: [f64; 3],
        inner_radius: f64,
        outer_radius: f64,
    },
    /// 3D closed triangulated surface (an STL file, placed).
    Mesh(std::sync::Arc<crate::setup::mesh::Mesh>),
}

/// How two bodies meet.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum InteractionKind {
    /// The contact force of eq. (5), in the colour form or as printed (`Paper`, with its K and
    /// n; None: the defaults).
    Contact {
        law: ContactLaw,
        stiffness: Option<f64>,
        exponent: Option<f64>,
    },
    /// Conventional SPH: the bodies meet through the conservation equations.
    Welded,
}

#[derive(Debug, Clone)]
pub struct InteractionSpec {
    pub location: Location,
    /// Indices into `Case::bodies`, distinct.
    pub bodies: [usize; 2],
    pub kind: InteractionKind,
}

/// A symmetry plane x_axis = position (mirrored ghost particles), or a frictionless rigid
/// wall there (`wall`: a symmetry plane that only pushes, see `boundary`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SymmetryPlane {
    pub axis: usize,
    pub position: f64,
    pub wall: bool,
}

/// `[output]`.
#[derive(Debug, Clone)]
pub struct OutputSpec {
    /// Snapshot every this much simulated time (None: only first and last).
    pub snapshot_interval: Option<f64>,
    /// A history row every this many steps (default 10).
    pub history_every: u64,
    pub pictures: Vec<PictureSpec>,
}

/// Field a picture colours particles by.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ColorBy {
    #[default]
    Body,
    Pressure,
    PlasticStrain,
    Damage,
    Velocity,
    Density,
    VonMises,
}

/// A cross-section picture: particles in a slab |x_axis − position| < thickness/2, at given times.
#[derive(Debug, Clone, PartialEq)]
pub struct PictureSpec {
    pub times: Vec<f64>,
    /// Normal axis of the section plane (0, 1, 2); in 2D pictures show the whole plane.
    pub normal_axis: usize,
    pub position: f64,
    /// Slab thickness (m); None: one spacing of the finest body.
    pub thickness: Option<f64>,
    pub color_by: ColorBy,
}

impl Case {
    /// Whether a body's material has a damage model, so that particles may fail.
    pub fn may_fail(&self) -> bool {
        self.bodies
            .iter()
            .any(|b| !self.materials[b.material].damage.is_none())
    }

    /// The physical set-up as (key, value) lines: everything that shapes the particles and the
    /// equations — dimension, kernel, numerics, materials, bodies, interactions, symmetry — and
    /// nothing a run may change on resuming (end time, step cap, outputs). A checkpoint keeps
    /// it, so that resuming with a changed deck names what changed. Values print floats in
    /// their shortest exact form, so any change shows.
    pub fn physics_fingerprint(&self) -> Vec<(String, String)> {
        let s = &self.simulation;
        let mut out = vec![
            (
                "simulation.dimension".to_string(),
                self.dimension.to_string(),
            ),
            ("simulation.kernel".into(), format!("{:?}", s.kernel)),
            (
                "simulation.formulation".into(),
                format!("{:?}", s.formulation),
            ),
            ("simulation.cfl".into(), format!("{:?}", s.cfl())),
            (
                "simulation.smoothing_ratio".into(),
                format!("{:?}", s.smoothing_ratio),
            ),
            (
                "simulation.viscosity".into(),
                format!(
                    "alpha {:?}, beta {:?}, limiter {:?}",
                    s.viscosity_alpha, s.viscosity_beta, s.viscosity_limiter
                ),
            ),
            (
                "simulation.density_diffusion".into(),
                format!("{:?}", s.density_diffusion),
            ),
            ("simulation.gravity".into(), format!("{:?}", s.gravity)),
            (
                "simulation.smoothing_bounds".into(),
                format!("{:?}", [s.h_min_ratio, s.h_max_ratio]),
            ),
            (
                "simulation.smoothing_stretch".into(),
                format!("{:?}", s.smoothing_stretch),
            ),
            (
                "simulation.impact_speed".into(),
                format!("{:?}", s.impact_speed),
            ),
        ];
        // Only where it is not the default, so that the checkpoints of earlier versions,
        // which have no such line, resume.
        if s.tensor_smoothing {
            out.push(("simulation.smoothing_shape".into(), "tensor".into()));
        }
        for m in &self.materials {
            out.push((
                format!("materials.{}", m.name),
                format!(
                    "density {:?}, eos {:?}, strength {:?}, pressure_cutoff {:?}, artificial_stress {:?}",
                    m.density, m.eos, m.strength, m.pressure_cutoff, m.artificial_stress
                ),
            ));
        }
        for b in &self.bodies {
            out.push((
                format!("body '{}'", b.name),
                format!(
                    "material {}, spacing {:?}, velocity {:?}, motion {:?}, shape {:?}",
                    self.materials[b.material].name, b.spacing, b.velocity, b.motion, b.shape
                ),
            ));
        }
        for i in &self.interactions {
            let [a, b] = i.bodies.map(|k| self.bodies[k].name.as_str());
            out.push((format!("interaction {a}–{b}"), format!("{:?}", i.kind)));
        }
        let planes = |wall: bool| -> Vec<String> {
            self.symmetry
                .iter()
                .filter(|p| p.wall == wall)
                .map(|p| format!("{} = {:?}", ["x", "y", "z"][p.axis], p.position))
                .collect()
        };
        out.push(("symmetry".into(), format!("{:?}", planes(false))));
        let walls = planes(true);
        if !walls.is_empty() {
            out.push(("walls".into(), format!("{walls:?}")));
        }
        out
    }
}
