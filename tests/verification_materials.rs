//! Materials and failure (VALIDATION.md §F; issue 13), each case at two resolutions.

use strike::case::Case;
use strike::simulation::Simulation;
use strike::validate::{pull_back, spall_plane, spall_run, SpallRun, SPALL_LAGRANGIAN_1D};

mod support;
use support::{example as load, two_resolutions, validated};

/// Al 6061-T6's density and longitudinal wave speed c_L = √((K0 + 4G/3)/ρ0) in
/// `examples/spall.toml`: the acoustic relation's (see the first spall test).
const RHO0: f64 = 2703.0;
fn c_l() -> f64 {
    ((RHO0 * 5240.0f64.powi(2) + 4.0 / 3.0 * 27.6e9) / RHO0).sqrt()
}

/// `examples/spall.toml` with the spall strength `strength` (Pa) and `refine` times its
/// spacing.
fn spall_at(strength: f64, refine: f64) -> Case {
    let set = format!("spall_strength = {strength:e}");
    let deck = spall_text().replace("spall_strength = 1.0e9", &set);
    assert!(deck.contains(&set), "the deck's spall strength moved");
    spall_case(&deck, refine)
}

/// The text of `examples/spall.toml`.
fn spall_text() -> String {
    std::fs::read_to_string(format!(
        "{}/examples/spall.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

/// A variant `deck` of `examples/spall.toml` with `refine` times its spacing, in a strip of
/// the deck's ten rows at every spacing. The strip lies between two symmetry planes, so its
/// motion is uniaxial strain whatever its width: the finer runs need no more rows, and a run
/// at half the spacing costs 4 times the deck's, not 8 (the deck itself, `refine` 1, is run as
/// it is).
fn spall_case(deck: &str, refine: f64) -> Case {
    let mut case = strike::deck::parse(deck, "spall.toml").unwrap();
    for b in &mut case.bodies {
        let strike::case::Shape::Box { max, .. } = &mut b.shape else {
            panic!("the spall deck's bodies are rectangles")
        };
        assert_eq!((max[1] / b.spacing).round(), 10.0, "the strip moved");
        max[1] *= refine;
        b.spacing *= refine;
    }
    let upper = case
        .symmetry
        .iter_mut()
        .find(|s| s.axis == 1 && s.position > 0.0);
    upper.expect("the strip's upper symmetry plane").position *= refine;
    case
}

/// A flyer-plate run of `case`, printed against its set spall strength `strength` (Pa) and
/// the independent solution's spall plane `plane_ref`: the free face's peak and pull-back
/// minimum (m/s), the strength they read back, ½ ρ0 c_L Δu_fs (Pa), the spall plane (m), and
/// the run.
fn read_spall(case: &Case, strength: f64, plane_ref: f64) -> (f64, f64, f64, f64, SpallRun) {
    let run = spall_run(case).unwrap();
    let (u_max, u_min) = pull_back(&run.free_face);
    let (sigma, plane) = (0.5 * RHO0 * c_l() * (u_max - u_min), spall_plane(&run));
    println!(
        "spall at {:.1} GPa, Δp = {:.1e} m: {u_max:.1} → {u_min:.1} m/s, ½ ρ0 c0 Δu = {:.3} GPa ({:+.2} %), plane {:.4} mm ({:+.2} %), {} failed, momentum {:.1e}",
        strength * 1e-9,
        case.bodies[1].spacing,
        sigma * 1e-9,
        100.0 * (sigma / strength - 1.0),
        plane * 1e3,
        100.0 * (plane / plane_ref - 1.0),
        run.failed_x0.len(),
        run.momentum_error
    );
    (u_max, u_min, sigma, plane, run)
}

/// [`read_spall`] of [`spall_at`]`(strength, refine)`, without the run.
fn spall_reading(strength: f64, refine: f64, plane_ref: f64) -> (f64, f64, f64, f64) {
    let (u_max, u_min, sigma, plane, _) =
        read_spall(&spall_at(strength, refine), strength, plane_ref);
    (u_max, u_min, sigma, plane)
}

/// Issue 13, item 6 (spall): a flyer-plate impact spalls the target, and the free-face pull-back
/// gives back the spall strength set in the deck, σ_s = ½ ρ0 c Δu_fs, within 10 %, at two
/// resolutions (`examples/spall.toml`: a thin flyer, so that the pulse is triangular).
///
/// The same at σ_s = 0.6 GPa: the readback within 10 % and the spall plane within 2 % of the
/// independent solution's at both resolutions, its pull-back minimum converging.
///
/// The wave speed of the acoustic relation is that of the release that carries the tension:
/// here the elastic one, c_L = √((K0 + 4G/3)/ρ0) = 6409 m/s, because the tension at the spall
/// plane is the incident pulse's stress decrement, and a decrement of 1 GPa lies inside the
/// elastic release range 2 HEL ≈ 1.2 GPa of Al 6061-T6 (Kanel 2010, Int. J. Fract. 163, 173,
/// on the acoustic approximation). With the bulk speed 5240 m/s the same runs read 0.81 GPa.
///
/// SPH's own solution is held against an independent one of the same deck,
/// `examples/spall_lagrangian_1d.py` converged at 1 µm cells (`SPALL_LAGRANGIAN_1D`): the free
/// face's peak and pull-back minimum within 10 % at 20 µm and 8 % at 10 µm, and closer at the
/// finer spacing (the kernel rounds off the short peak: 354 / 370 m/s at 20 / 10 µm against
/// 386.4; 365 / 374, and 384 at 5 µm, before the material update at the step's middle of
/// 2026-11-28, whose absence sharpened the pulse), and the spall plane within 2 %. The plane
/// is where the failed particles started (their material coordinate): where they are at the
/// end is no measure of it, since the spalled layers open and fly apart (+3.5 / +5.0 % at
/// 20 / 10 µm by their current places, the independent solution's own +3.4–3.8 %). The same
/// run with damage off shows the diagnostic sees the difference: the free face then falls
/// back towards rest.
#[test]
fn flyer_plate_spall_gives_back_the_spall_strength() {
    let sigma_s = 1.0e9;
    let (u_max_ref, u_min_ref, plane_ref) = SPALL_LAGRANGIAN_1D;
    // The free face's peak and minimum, the strength they read back, the spall plane.
    let results: Vec<_> = [1.0, 0.5]
        .map(|refine| spall_case(&spall_text(), refine))
        .iter()
        .map(|case| read_spall(case, sigma_s, plane_ref))
        .collect();
    let error = |x: f64, reference: f64| (x / reference - 1.0).abs();
    for (k, (u_max, u_min, sigma, plane, run)) in results.iter().enumerate() {
        let tolerance = if k == 0 { 0.10 } else { 0.08 };
        assert!(
            error(*u_max, u_max_ref) < tolerance,
            "free face peak {u_max}"
        );
        assert!(
            error(*u_min, u_min_ref) < tolerance,
            "pull-back minimum {u_min}"
        );
        assert!(
            (sigma / sigma_s - 1.0).abs() < 0.10,
            "spall strength from the pull-back {sigma:.3e} vs {sigma_s:.3e}"
        );
        assert!(!run.failed_x0.is_empty(), "the target did not spall");
        assert!(error(*plane, plane_ref) < 0.02, "spall plane at {plane}");
        assert!(
            run.momentum_error < 1e-10,
            "momentum {}",
            run.momentum_error
        );
    }
    let (coarse, fine) = (&results[0], &results[1]);
    assert!(
        error(fine.0, u_max_ref) < error(coarse.0, u_max_ref),
        "the free face's peak does not converge"
    );
    assert!(
        error(fine.1, u_min_ref) < error(coarse.1, u_min_ref),
        "the pull-back minimum does not converge"
    );
    // A weaker spall: σ_s = 0.6 GPa. The independent solution at 1 µm cells
    // (`python3 examples/spall_lagrangian_1d.py --cells-um 1 --strengths-gpa 0.6`): pull-back
    // minimum 321.4 m/s, spall plane 2.4671 mm, and the acoustic readback itself −6.1 %.
    // Measured 2026-11-28: readback −4.6 / −2.6 %, minimum 287.9 / 302.0 m/s, plane 2.423 /
    // 2.473 mm at 20 / 10 µm (−11.5 / −14.3 % readback before the material update at the
    // step's middle). At 1.5 GPa see `spall_at_1_5_gpa_reads_back_within_10_percent_at_5_um`.
    let (weak, u_min_weak, plane_weak) = (0.6e9, 321.4, 2.4671e-3);
    let mut minima = Vec::new();
    for refine in [1.0, 0.5] {
        let (_, u_min, sigma, plane) = spall_reading(weak, refine, plane_weak);
        assert!(
            (sigma / weak - 1.0).abs() < 0.10,
            "0.6 GPa read back as {sigma:.3e}"
        );
        assert!(error(plane, plane_weak) < 0.02, "0.6 GPa: plane at {plane}");
        minima.push(u_min);
    }
    assert!(
        error(minima[1], u_min_weak) < error(minima[0], u_min_weak),
        "0.6 GPa: the pull-back minimum does not converge: {minima:?}"
    );
    // Without damage the target holds the tension and the free face falls back to rest.
    let mut intact = load("spall");
    intact.materials[0].damage = Default::default();
    let run = spall_run(&intact).unwrap();
    let (u_max, u_min) = pull_back(&run.free_face);
    println!("no damage: u_fs {u_max:.1} → {u_min:.1} m/s");
    assert!(run.failed_x0.is_empty());
    assert!(
        u_min < 0.3 * u_max,
        "no spall, yet the free face stays at {u_min}"
    );
}

/// Issue 13, item 6 (spall) at a stronger spall, σ_s = 1.5 GPa, past the elastic release
/// range: there the spall cuts the steep plastic release short, and the acoustic relation
/// needs a fine lattice. Measured 2026-12-02 at Δp = 10 / 5 µm (2D, 28 000 particles at 5 µm:
/// about a minute on 2 cores; the same figures in the ten-row strip of [`spall_case`], 7 000
/// particles, 2026-12-06):
/// - readback −13.0 / −9.3 %: within 10 % at 5 µm, and closer than at 10;
/// - free-face peak 369.5 / 381.1 m/s against the independent solution's 386.4;
/// - pull-back minimum 218.9 / 224.0 m/s against its 224.2;
/// - spall plane within 2 % of its 2.473 mm at both.
///
/// The independent solution is `python3 examples/spall_lagrangian_1d.py --cells-um 1
/// --strengths-gpa 1.5`. Its own readback is −11.5 % at 10 µm cells and −6.4 % at 1 µm:
/// that is the relation's error on this pulse, not SPH's.
///
/// At 20 µm the peak and minimum are 354.0 and 199.2 m/s. Both converge from there, but
/// their difference, which the readback takes, reads −10.6 %: the readback is not monotone
/// between 20 and 10 µm.
#[test]
fn spall_at_1_5_gpa_reads_back_within_10_percent_at_5_um() {
    let strong = 1.5e9;
    let (u_min_ref, plane_ref) = (224.2, 2.473e-3);
    let error = |x: f64, reference: f64| (x / reference - 1.0).abs();
    let mut read = Vec::new();
    for refine in [0.5, 0.25] {
        let (_, u_min, sigma, plane) = spall_reading(strong, refine, plane_ref);
        assert!(error(plane, plane_ref) < 0.02, "1.5 GPa: plane at {plane}");
        read.push((error(sigma, strong), error(u_min, u_min_ref)));
    }
    let ((sigma_10, min_10), (sigma_5, min_5)) = (read[0], read[1]);
    assert!(sigma_5 < 0.10, "1.5 GPa read back {sigma_5:.3} off at 5 µm");
    assert!(
        sigma_5 < sigma_10,
        "1.5 GPa: the readback does not converge: {read:?}"
    );
    assert!(
        min_5 < 0.02 && min_5 < min_10,
        "1.5 GPa: the pull-back minimum does not converge on the independent solution's: {read:?}"
    );
}

/// The library's nylon 6/6 spalls (issue 13, item 4; the spall strength of PA66, 0.23 GPa,
/// from Pan et al. 2025's plate impacts): `examples/spall.toml` with flyer and target of
/// `nylon_66`, a hydrodynamic material, followed to 1.45 µs. Symmetric impact at 400 m/s:
/// u_p = 200 m/s, 0.67 GPa. Without strength the release is not elastic and the pulse is
/// square; the free face sits at 2 u_p = 400 m/s, then falls by the pull-back until the
/// spall's recompression arrives.
///
/// Against the independent solution (`python3 examples/spall_lagrangian_1d.py --nylon`, the
/// same EOS and spall strength, a cell failing the instant it passes σ_s): the spall plane
/// within 2 % of its 2.4538 mm (1 µm cells), and the pull-back minimum above its 257.6 m/s by
/// less than 20 % and closer at 10 µm than at 20. The minimum converges slowly, and from
/// above, in both codes: the independent one reads 292.5 / 284.8 / 274.3 / 262.9 / 257.6 m/s
/// at 20 / 10 / 5 / 2 / 1 µm cells, SPH 297.5 / 292.8 m/s at Δp = 20 / 10 µm (+15.5 /
/// +13.7 %; 288.2 at 5 µm, 2026-12-02). The band tells the strengths apart: at Δp = 20 µm SPH
/// reads 345.7 m/s with σ_s = 0.15 GPa (+34 %) and 226.5 with 0.35 GPa (−12 %). The acoustic
/// readback ½ ρ0 c0 (v0 − u_min) is reported, not held: −31.5 % at 20 µm cells in the
/// independent code itself, −9.3 % at 1 µm; SPH −34.7 / −31.7 % at 20 / 10 µm.
#[test]
fn library_nylon_spalls_as_the_independent_solution_does() {
    let (rho0, c0, sigma_s, v0) = (1140.0, 2570.0, 0.23e9, 400.0);
    let (u_min_ref, plane_ref) = (257.6, 2.4538e-3);
    let deck = spall_text()
        .replace("library = \"al_6061_t6\"", "library = \"nylon_66\"")
        .replace("damage = { type = \"spall\", spall_strength = 1.0e9 }", "")
        .replace("end_time = 1.2e-6", "end_time = 1.45e-6");
    assert!(deck.contains("nylon_66") && !deck.contains("spall_strength"));
    let mut errors = Vec::new();
    for refine in [1.0, 0.5] {
        let case = spall_case(&deck, refine);
        let run = spall_run(&case).unwrap();
        // The lowest free-face velocity after the face first passes 350 m/s.
        let rise = run.free_face.iter().position(|&(_, u)| u > 350.0);
        let u_min = run.free_face[rise.expect("the shock never reached the free face")..]
            .iter()
            .map(|&(_, u)| u)
            .fold(f64::INFINITY, f64::min);
        let plane = spall_plane(&run);
        let sigma = 0.5 * rho0 * c0 * (v0 - u_min);
        println!(
            "nylon, Δp = {:.0e} m: pull-back minimum {u_min:.1} m/s ({:+.1} %), readback {:.3} GPa ({:+.1} %), plane {:.4} mm, {} failed",
            case.bodies[1].spacing,
            100.0 * (u_min / u_min_ref - 1.0),
            sigma * 1e-9,
            100.0 * (sigma / sigma_s - 1.0),
            plane * 1e3,
            run.failed_x0.len()
        );
        assert!(!run.failed_x0.is_empty(), "the nylon target did not spall");
        assert!(
            (plane / plane_ref - 1.0).abs() < 0.02,
            "nylon: spall plane at {plane}"
        );
        let error = u_min / u_min_ref - 1.0;
        assert!(
            (0.0..0.20).contains(&error),
            "nylon: pull-back minimum {u_min}"
        );
        assert!(
            run.momentum_error < 1e-10,
            "momentum {}",
            run.momentum_error
        );
        errors.push(error);
    }
    assert!(
        errors[1] < errors[0],
        "nylon: the pull-back minimum does not converge: {errors:?}"
    );
}

/// The flyer plate of [`flyer_plate_spall_gives_back_the_spall_strength`] with the tensor
/// smoothing length, whose cut of a failed particle's pairs is the ellipsoid's: the pull-back
/// reads back the spall strength (1 GPa) within 10 % and the spall plane lies within 2 % of
/// the independent solution's, at both resolutions, the free face's peak and pull-back minimum
/// within 10 % of it and the minimum converging. Measured 2026-12-05 at 20 / 10 µm: readback
/// −5.78 / −2.91 %, plane −0.91 / +0.33 %, pull-back minimum 245.8 / 257.5 m/s (the round
/// kernel's −5.59 / −2.42 %, −0.51 / +0.40 %, 245.0 / 256.9 m/s): in this near-uniaxial
/// strain the ellipsoid stays near round.
#[test]
fn flyer_plate_spalls_with_the_tensor_smoothing_length() {
    let sigma_s = 1.0e9;
    let (u_max_ref, u_min_ref, plane_ref) = SPALL_LAGRANGIAN_1D;
    let error = |x: f64, reference: f64| (x / reference - 1.0).abs();
    let mut minima = Vec::new();
    for mut case in [1.0, 0.5].map(|refine| spall_case(&spall_text(), refine)) {
        case.simulation.tensor_smoothing = true;
        let (u_max, u_min, sigma, plane, run) = read_spall(&case, sigma_s, plane_ref);
        assert!(
            (sigma / sigma_s - 1.0).abs() < 0.10,
            "spall strength from the pull-back {sigma:.3e}"
        );
        assert!(error(u_max, u_max_ref) < 0.10, "peak {u_max}");
        assert!(error(u_min, u_min_ref) < 0.10, "pull-back minimum {u_min}");
        assert!(error(plane, plane_ref) < 0.02, "spall plane at {plane}");
        assert!(
            run.momentum_error < 1e-10,
            "momentum {}",
            run.momentum_error
        );
        minima.push(u_min);
    }
    assert!(
        error(minima[1], u_min_ref) < error(minima[0], u_min_ref),
        "the pull-back minimum does not converge: {minima:?}"
    );
}

/// Issue 13, item 6 (Taylor bar, Johnson–Cook; `strike validate --case taylor`): 42CrMo4 at
/// 287 m/s on a frictionless rigid wall (the `[[wall]]` z = 0), quarter model, R0/Δp = 8,
/// with the deck's tensor smoothing length and artificial stress, against the finite-element
/// results: the final length within 2 % (26.763 mm, +0.84 %) and the impact-face diameter
/// within 5 % (11.256 mm, +0.63 %; 2026-12-05; R0/Δp = 16 in
/// [`taylor_bars_converge_and_their_walls_agree`]). With the round kernel it read 26.908 mm
/// and 10.747 mm here, and its face moved away from the published one with refinement.
#[test]
fn taylor_bar_final_length_matches_the_finite_element_results() {
    validated(strike::validate::taylor(false));
}

/// The Taylor rod's measure (`validate::taylor_measure`) reads a mushroomed rod of known
/// shape: a quarter lattice (Δp = 0.2 mm) 100 layers high, radius 3.2 mm, on a face layer
/// 7 mm in radius whose rim is lifted 0.7 Δp (as a rim off its wall is). Face 14 mm and length
/// 100 Δp within a spacing; and so they stay with one particle of the face 0.42 Δp below its
/// layer near the axis, as the copper twin's was at R0/Δp = 16 in CN-SPH (2026-12-03), where a
/// face measured from the lowest particle misses the rim (checked here too: the rod sees the
/// failure it guards).
#[test]
fn taylor_measure_reads_a_known_rod_and_no_single_particle_moves_it() {
    let dp = 0.2e-3;
    let centre = |k: usize| (k as f64 + 0.5) * dp;
    let mut rod = Vec::new();
    for i in 0..40 {
        for j in 0..40 {
            let r = centre(i).hypot(centre(j));
            for k in 0..100 {
                let (z, within) = match k {
                    0 if r > 5.0e-3 => (centre(0) + 0.7 * dp, r <= 7.0e-3),
                    0 => (centre(0), true),
                    _ => (centre(k), r <= 3.2e-3),
                };
                if within {
                    rod.push([z, r]);
                }
            }
        }
    }
    let rim = rod.iter().map(|p| p[1]).fold(0.0, f64::max);
    for stray in [false, true] {
        let mut rod = rod.clone();
        if stray {
            let k = rod.iter().position(|p| p[0] == centre(0)).unwrap();
            rod[k][0] -= 0.42 * dp;
            let lowest = rod[k][0];
            let from_lowest = rod
                .iter()
                .filter(|p| p[0] < lowest + dp)
                .map(|p| p[1])
                .fold(0.0, f64::max);
            assert!(from_lowest < 0.8 * rim, "the stray does not hide the rim");
        }
        let m = strike::validate::taylor_measure(&rod, dp);
        eprintln!(
            "stray {stray}: face {} mm, length {} mm",
            m.face * 1e3,
            m.length * 1e3
        );
        assert!(
            (m.face - 14.0e-3).abs() < dp,
            "stray {stray}: face {}",
            m.face
        );
        assert!(
            (m.length - 100.0 * dp).abs() < dp,
            "stray {stray}: length {}",
            m.length
        );
    }
}

/// Issue 13, item 6 (the copper Taylor test; `strike validate --case taylor_ofhc`): Johnson &
/// Cook's OFHC copper rod (25.4 × 7.62 mm) at 190 m/s on the anvil (a `[[wall]]`) with the
/// library's Johnson–Cook constants at R0/Δp = 8 and 12: the final length within 12 % of the
/// recovered rod's (L_f/L0 = 0.638) at 12 (+14.4 / +11.1 % at 8 / 12), and length and face
/// converging on the continuum of the same model on the same wall (axisymmetric finite
/// elements, `examples/taylor_fe_axisymmetric.py --material ofhc`: 17.355 and 14.744 mm),
/// within 5 % and 12 % of it at 12 (+6.8 / +3.7 % and −14.3 / −10.3 % at 8 / 12, 2026-12-06;
/// the face against the test's, −6.9 / −2.4 %, is reported: the continuum is 8.7 % wider than
/// the test). The library's failure is off, as the rods were whole. With it on, the spall
/// model breaks the rod (README, Not yet) and the test fails.
#[test]
fn ofhc_copper_taylor_rods_converge_on_their_continuum_and_match_the_tests_length() {
    validated(strike::validate::taylor_ofhc(false));
}

/// Issue 13 (Steinberg–Guinan in a run, `strike validate --case shocked_strength`): behind a
/// 14 GPa shock into Al 6061-T6 the particles flow at Steinberg–Guinan's stress of the shocked
/// state, 0.600 GPa by the Rayleigh line (twice Y0), within 10 %, and the compression is the
/// jump's within 1 %: both formulations, Δp = 0.1 and 0.05 mm (−5.8 / −5.5 % conventional).
/// The same column with von Mises at Y0 reads less than half of it: the check tells the models
/// apart.
#[test]
fn steinberg_guinan_flows_at_its_shocked_state() {
    validated(strike::validate::shocked_strength(true));
    let mut case = load("shocked_strength");
    let k = case.bodies[1].material;
    case.materials[k].strength = strike::case::StrengthSpec::VonMises {
        shear_modulus: 27.6e9,
        yield_stress: 0.29e9,
        hardening_modulus: 0.0,
    };
    let mut sim = Simulation::<2>::new(&case).unwrap();
    while sim.state.time < case.simulation.end_time * (1.0 - 1e-12) {
        sim.step(case.simulation.end_time - sim.state.time).unwrap();
    }
    let p = &sim.particles;
    let behind: Vec<f64> = (0..p.n_real)
        .filter(|&i| p.body[i] == 1 && (6e-3..14e-3).contains(&p.x[i][0]))
        .map(|i| strike::tensor::von_mises(&p.s[i].full()))
        .collect();
    let vm = behind.iter().sum::<f64>() / behind.len() as f64;
    assert!(vm < 0.5 * 0.600e9 && vm > 0.2e9, "von Mises column: {vm}");
}

/// Issue 13, items 5 and 6 (`strike validate --fine --case taylor --case taylor_walls`): the
/// steel bar against the finite-element results at R0/Δp = 8 and 16; the steel and copper bars
/// in CN-SPH on their `[[wall]]`, against their twin through the contact and on a fixed wall
/// through the contact, agreeing within 2 % in final length and face diameter at R0/Δp = 16,
/// the faces' disagreement not growing with refinement (reported at 8; on a symmetry plane,
/// which meets the rod moving into it as the wall, the same to the bit); the copper bar on its wall in conventional SPH within 4 % (length)
/// and 5 % (face) of the published results at R0/Δp = 16. By hand on 2026-12-03 with the face
/// measure's foot level, the CN faces through the contact at 16 read −0.13 % (copper twin,
/// with the contact's tie at touching broken), −0.79 % (copper fixed block) and −0.79 % (steel
/// twin, before the tie) of the wall's, the lengths within 0.4 %; the steel fixed block read
/// +1.1 % with the old measure. **It fails since the wall meets a particle from touching**
/// (`boundary::wall_share`, 2026-12-04): by hand that day, the steel twin's face −2.77 % of
/// the wall's at 16 (−3.19 % at 8), the steel fixed block's −1.16 %, the copper twin's −0.71 %
/// (README, Not yet). The steel bar's own face fails too since 2026-12-05, when its error at
/// 16 came to be held no larger than at 8: with the round kernel −3.92 / +4.83 % of the
/// published face (+12.0 % at 24 by hand); with the tensor smoothing length the deck takes
/// since that evening, −1.18 / +1.22 % of the converged face on the same wall (11.256 / 11.529
/// mm, by hand through `validate::taylor_run`). About five hours on 2 cores:
/// `cargo test --release --test verification_materials -- --ignored`.
#[test]
#[ignore = "long (the validation command, about five hours on 2 cores); fails since the wall meets a particle from touching of 2026-12-04 (by hand: the steel twin's face −2.77 % of the wall's at R0/Δp = 16), and on the steel face's error growing from R0/Δp = 8 to 16 (tensor smoothing length: −1.18 / +1.22 % of the converged face on the same wall)"]
fn taylor_bars_converge_and_their_walls_agree() {
    validated(strike::validate::taylor(true));
    validated(strike::validate::taylor_walls(true));
}

/// Issue 13, item 6, hypervelocity (`strike validate --fine --case crater`): a 1 mm Al 6061-T6
/// sphere at 6 km/s into a thick 6061-T6 block at d/Δp = 8 and 10 (about 18 minutes on 2
/// cores). The crater's depth is reported against the Cour-Palais equation's; held: it does not
/// move away from it with refinement, the floor stands on a plateau
/// (`validate::contact::floor_spread`), no mixing, momentum. It fails: since the sphere keeps its
/// mass (2026-12-04, latest) the depth reads +18.5 / +19.6 % of the fit, and the floor's spread
/// (3.5 / 1.46 Δp) and the convergence check (0.196 against 0.185) fail at both: the library's
/// failure lays a loose layer on the floor (README, Not yet).
#[test]
#[ignore = "long (the validation command); fails since 2026-12-04: the floor is read off a loose failed layer (spread 3.5 / 1.46 Δp at d/Δp = 8 / 10, the depth +18.5 / +19.6 % of the Cour-Palais depth)"]
fn hypervelocity_crater_does_not_move_away_with_refinement() {
    validated(strike::validate::contact::crater(true));
}

/// The Cour-Palais depth by hand: d = 1 mm, V = 6 km/s, 6061-T6 (HB 95, C = √(68.9 GPa /
/// 2700 kg/m³) = 5051.6 m/s): 5.24 · 0.1^(19/18) · 95^(−1/4) · (6/5.0516)^(2/3) cm.
#[test]
fn cour_palais_crater_depth_by_hand() {
    let c = (68.9e9_f64 / 2700.0).sqrt();
    let p = strike::validate::contact::cour_palais_depth(1e-3, 6000.0 / c, 1.0, 95.0);
    assert!((p / 1.656382e-3 - 1.0).abs() < 1e-6, "{p}");
    // The size scaling d^(19/18) and the density ratio's square root.
    let p2 = strike::validate::contact::cour_palais_depth(2e-3, 6000.0 / c, 4.0, 95.0);
    assert!((p2 / p - 2.0 * 2.0_f64.powf(19.0 / 18.0)).abs() < 1e-12);
}

/// The crater's measure (`validate::contact::crater_shape`) sees a bowl of known size: a
/// quarter lattice (Δp = 0.05 mm) below z = 0 with a hemisphere of radius R about the origin
/// taken out reads depth R and diameter 2R within a spacing, for two radii, with a few loose
/// particles lying in the bowl (which must not count as its floor or its wall), on a regular
/// lattice and on one stretched along z by 3 % (0.97 ρ0, as the floor of the crater case is
/// stretched by the flow) from the surface to 6 Δp below the bowl, regular below. The floor is
/// looked for within R/4 of the axis, about the ratio of the crater case's (0.4 d against a
/// crater some 3.5 d across), where the bowl's own curvature lifts it by 0.03 R. With a whole
/// lattice's count asked under the floor (`FLOOR_FILL` = 1, until 2026-12-04) the stretched
/// bowl of R = 1.2 mm reads 1.494 mm deep, 5.9 spacings too deep, where the regular lattice
/// starts (R = 0.8 mm: 0.825 mm, within the spacing by chance). Every bowl's floor stands on a
/// plateau (`floor_spread` 0).
#[test]
fn crater_measure_reads_a_known_bowl() {
    let dp = 5e-5;
    for (radius, stretch) in [(0.8e-3, 1.0), (1.2e-3, 1.0), (0.8e-3, 1.03), (1.2e-3, 1.03)] {
        let centre = |k: usize| (k as f64 + 0.5) * dp;
        // The layers down to 6 Δp below the bowl are `stretch` Δp apart, the rest Δp.
        let band = (radius / dp) as usize + 6;
        let z = |k: usize| {
            if k < band {
                -centre(k) * stretch
            } else {
                -(centre(band) * stretch + (k - band) as f64 * dp)
            }
        };
        let mut block = Vec::new();
        for i in 0..40 {
            for j in 0..40 {
                for k in 0..40 {
                    let x = [centre(i), centre(j), z(k)];
                    if x.iter().map(|c| c * c).sum::<f64>().sqrt() > radius {
                        block.push(x);
                    }
                }
            }
        }
        // Loose debris inside the bowl: a few particles on the axis, and a few at 0.7 R in
        // the surface layer, where the wall is looked for.
        for f in [0.3_f64, 0.6, 0.9] {
            block.push([0.5 * dp, 0.5 * dp, -f * radius]);
            let angle = f * std::f64::consts::FRAC_PI_2;
            block.push([
                0.7 * radius * angle.cos(),
                0.7 * radius * angle.sin(),
                -0.5 * dp,
            ]);
        }
        let (depth, diameter) =
            strike::validate::contact::crater_shape(&block, (dp, 0.0, 4.0), 0.25 * radius).unwrap();
        let spread =
            strike::validate::contact::floor_spread(&block, (dp, 4.0), 0.25 * radius).unwrap();
        eprintln!(
            "R = {radius}, stretched {stretch}: depth {depth}, diameter {diameter}, spread {spread}"
        );
        // A floor of whole layers is a plateau: every share reads the same layer.
        assert!(
            spread.abs() < 0.01 * dp,
            "R = {radius}, stretched {stretch}: spread {spread}"
        );
        // Within a spacing, to the rounding of the lattice's centres.
        assert!(
            (depth - radius).abs() < 1.01 * dp,
            "R = {radius}, stretched {stretch}: depth {depth}"
        );
        assert!(
            (diameter - 2.0 * radius).abs() < 1.01 * dp,
            "R = {radius}, stretched {stretch}: diameter {diameter}"
        );
    }
}

/// The crater's floor stands on no plateau where a loose layer lies on it, and
/// `floor_spread` sees it: the bowl of R = 0.8 mm of `crater_measure_reads_a_known_bowl` with
/// three layers inside its wall filled to 40 % (the lattice sites whose index sum is 0 or 2
/// modulo 5; rubble, or a failed layer lifting off). Half a lattice's count reads the floor at
/// the loose layer's top, nine tenths at its lowest layer, which lies on the wall: the two part
/// by more than the spacing that `strike validate --case crater` allows (2 Δp; 0 without the
/// layer, and 1.0 Δp with the layer filled to 60 %).
#[test]
fn crater_floor_spread_sees_a_loose_layer() {
    let (dp, radius) = (5e-5, 0.8e-3);
    let centre = |k: usize| (k as f64 + 0.5) * dp;
    let mut block = Vec::new();
    for i in 0..40 {
        for j in 0..40 {
            for k in 0..40 {
                let x = [centre(i), centre(j), -centre(k)];
                let r = x.iter().map(|c| c * c).sum::<f64>().sqrt();
                let loose = r > radius - 3.0 * dp && matches!((i + j + k) % 5, 0 | 2);
                if r > radius || loose {
                    block.push(x);
                }
            }
        }
    }
    let spread = strike::validate::contact::floor_spread(&block, (dp, 4.0), 0.25 * radius).unwrap();
    eprintln!("spread {} Δp", spread / dp);
    assert!(spread > 1.5 * dp, "spread {spread}");
}

/// Rubble keeps its energy and its density. A cube of failed aluminium (every particle at
/// damage 1: it pushes but cannot pull) with random velocities of ±20 m/s and no mean motion:
/// its particles knock into each other and drift apart. Energy must stay within 0.5 % and no
/// particle may be compressed by more than a 20 m/s knock does (Δρ/ρ ≈ v/c ≈ 0.4 %), at
/// most 2 %. With the separating pairs of failed particles dropped from the continuity
/// equation (strike's first rule) the density ratcheted up at every knock: 1.4 ρ0 and 65 GPa
/// in the rubble of `examples/ogive_plate.toml`, and its energy grew by 10 %.
#[test]
fn rubble_keeps_its_energy_and_density() {
    let deck = r#"
[simulation]
dimension = 3
end_time = 3.0e-5

[[body]]
name = "rubble"
material = "al_6061_t6"
spacing = 1.0e-3
shape = { type = "box", min = [0.0, 0.0, 0.0], max = [0.01, 0.01, 0.01] }
"#;
    let case = strike::deck::parse(deck, "rubble.toml").unwrap();
    let mut sim = Simulation::<3>::new(&case).unwrap();
    let rho0 = sim.particles.rho[0];
    let n = sim.particles.n_real;
    let mut seed = 12345u64;
    let mut random = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    for i in 0..n {
        sim.particles.damage[i] = 1.0;
        for k in 0..3 {
            sim.particles.v[i][k] = 20.0 * random();
        }
    }
    // No mean motion.
    let mean: Vec<f64> = (0..3)
        .map(|k| (0..n).map(|i| sim.particles.v[i][k]).sum::<f64>() / n as f64)
        .collect();
    for i in 0..n {
        for (k, m) in mean.iter().enumerate() {
            sim.particles.v[i][k] -= m;
        }
        sim.particles.vh[i] = sim.particles.v[i];
    }
    let end = case.simulation.end_time;
    let (mut e0, mut drift, mut rho_max) = (None, 0.0_f64, 0.0_f64);
    while sim.state.time < end * (1.0 - 1e-12) {
        let d = sim.step(end - sim.state.time).unwrap();
        let e0 = *e0.get_or_insert(d.total);
        drift = drift.max((d.total - e0).abs() / e0);
        rho_max = (0..n).map(|i| sim.particles.rho[i]).fold(rho_max, f64::max);
    }
    println!(
        "rubble: {} steps, energy drift {:.3e}, densest {:.4} ρ0",
        sim.state.step,
        drift,
        rho_max / rho0
    );
    assert!(drift < 5e-3, "energy drift {drift}");
    assert!(rho_max / rho0 < 1.02, "densest {}", rho_max / rho0);
}

/// Issue 13 (Johnson–Cook failure in a run; `examples/jc_failure_compression.toml`): a 2024-T3
/// block squeezed in plane strain between frictionless platens at 20 m/s, at two resolutions,
/// in both formulations and in conventional SPH with the tensor smoothing length (whose cut of
/// a failed particle's pairs is the ellipsoid's, `physics::cut_pair`). Its core (the particles
/// that start in the middle quarter) flows at the Johnson–Cook flow stress of its own plastic
/// strain, rate and adiabatic temperature, undamaged, until it fails, and it fails at the
/// failure strain of plane-strain compression's triaxiality, ε_f = D1 + D2 e^(−D3/√3) = 0.4391
/// (D4 = D5 = 0 in the deck).
///
/// The flow stress is held within 4 % while no particle of the block has failed (from the
/// first failure anywhere the block's bands unload its core: with the tensor smoothing length
/// the block's edges fail first, and by 60 failed particles the core's mean stress read 6.7 %
/// below its yield while none of the core had failed): the damage is a fracture indicator and
/// takes nothing off the strength before D = 1. With the damage scaling the yield stress by
/// (1 − D), as it did before 2026-11-26, the core's flow stress fell to 43 % of it and it
/// failed at εp = 0.34: this test then fails. The failure strain is held within 15 % at the coarser spacing and 10 %
/// at the finer, its error not growing with refinement. The core's triaxiality is not quite
/// −1/√3: the block's faces against the platens flow outwards ahead of its middle (its faces
/// 3.5 % wider than its waist at 15 µs, Δp = 0.1 mm, against 1.0 % before: the contact face's
/// own error, see README, Not yet), so σ* averages −0.51 / −0.54 in conventional SPH and
/// −0.61 / −0.57 in CN-SPH.
/// Measured on 2026-11-29: conventional SPH fails at εp = 0.388 / 0.401 (−11.7 / −8.7 % of
/// 0.439) at Δp = 0.1 / 0.05 mm, CN-SPH at 0.406 / 0.430 (−7.4 / −2.2 %). Until 2026-11-29
/// conventional SPH's contact dropped half of each pair's tangential force at every load,
/// which held the faces back like a friction of μ ≈ 0.02 (`contact_fidelity`,
/// `platens_squeeze_a_block_without_friction`), and it failed at 0.416 / 0.414 (−5.2 / −5.7 %,
/// the error growing with refinement) with σ* −0.54 / −0.55.
///
/// Not all of the core fails: once its first particles have, the flow gathers in the failed
/// bands between them and blocks of intact particles ride on them, as a compressed block
/// breaks along shear bands; the bands narrow with the spacing, so their share of the core
/// does too (100 / 43 % of the core in conventional SPH, 64 / 17 % in CN-SPH; 88 / 48 and
/// 57 / 55 % on 2026-11-27). At least two bands' worth must fail, twice as many particles as
/// the core has across. Until 2026-11-27 every core particle failed: intact particles read
/// the motion of failed neighbours that no longer pushed on them (at no pressure), and of
/// intact ones across a failed band, as their own strain, and failed in turn, so that a failed
/// zone swept through the whole block (`jc_failure_tension` shows the same in tension, and
/// what changed).
///
/// Measured on 2026-12-05 (flow stress within; core particles failed; εp at failure; the
/// core's σ*), at Δp = 0.1 / 0.05 mm: conventional SPH 0.10 / 0.07 %, 72 / 281, 0.3886 /
/// 0.3972 (−11.5 / −9.5 %), −0.514 / −0.547; CN-SPH 0.07 / 0.10 %, 88 / 184, 0.4083 / 0.4105
/// (−7.0 / −6.5 %), −0.556 / −0.553; with the tensor smoothing length 0.08 / 0.08 %, 24 /
/// 216, 0.4185 / 0.4296 (−4.7 / −2.2 %), −0.566 / −0.577: its block flows the most evenly,
/// its core's triaxiality the nearest to −1/√3.
///
/// Since 2026-12-06 the test runs the block's quarter x, y ≥ 0 on two symmetry planes
/// (`examples/jc_failure_compression_quarter.toml`), at a quarter of the cost (64 s for the six
/// runs, 4.5 minutes before); the core is the quarter's, the counts a quarter of the block's.
/// It reads the whole block's figures: (core failed of 25 / 100; εp at failure) conventional
/// SPH 18 / 72, 0.3886 / 0.3977 (−11.50 / −9.42 %); CN-SPH 22 / 49, 0.4081 / 0.4096 (−7.06 /
/// −6.71 %); tensor 6 / 52, 0.4185 / 0.4295 (−4.69 / −2.18 %); the coarse ones the block's to
/// the digit, the fine ones within 0.2 points (the whole block's bands are not quite
/// symmetric there).
#[test]
fn johnson_cook_failure_in_plane_strain_compression() {
    use strike::case::Formulation;
    // Lesuer 2000's 2024-T3, as the library has it; the test's own hand formulas.
    let (a, b, n, c, m) = (369e6, 684e6, 0.73, 0.0083, 1.7);
    let (t_room, t_melt, c_p, chi) = (293.15, 775.0, 875.0, 0.9);
    let eps_f = 0.13 + 0.13 * (1.5 / 3f64.sqrt()).exp();
    let closing = 20.0;
    // Both formulations with the round kernel, and conventional SPH with the tensor smoothing
    // length, which must cut a failed particle's pairs on its ellipsoid.
    for (formulation, tensor) in [
        (Formulation::Conventional, true),
        (Formulation::Conventional, false),
        (Formulation::Corrected, false),
    ] {
        let mut errors = Vec::new();
        for mut case in two_resolutions("jc_failure_compression_quarter") {
            case.simulation.formulation = formulation;
            case.simulation.tensor_smoothing = tensor;
            let dp = case.bodies[0].spacing;
            let mut sim = Simulation::<2>::new(&case).unwrap();
            let p = &sim.particles;
            let core: std::collections::HashSet<u32> = (0..p.n_real)
                .filter(|&i| p.body[i] == 0 && p.x[i][0].abs() < 0.5e-3 && p.x[i][1].abs() < 0.5e-3)
                .map(|i| p.id[i])
                .collect();
            let mut failed_at: std::collections::HashMap<u32, f64> = Default::default();
            let (mut worst_flow, mut samples, mut next) = (0.0f64, 0, 1.0e-6);
            let mut triaxiality = 0.0;
            let end = case.simulation.end_time;
            while sim.state.time < end * (1.0 - 1e-12) {
                sim.step(end - sim.state.time).unwrap();
                let p = &sim.particles;
                let in_core: Vec<usize> = (0..p.n_real)
                    .filter(|&i| p.body[i] == 0 && core.contains(&p.id[i]))
                    .collect();
                for &i in &in_core {
                    if p.damage[i] >= 1.0 {
                        failed_at.entry(p.id[i]).or_insert(p.eps_p[i]);
                    }
                }
                // The flow stress is the homogeneous flow's until the block first fails
                // anywhere: from then its shear bands unload the core.
                let block_failed = (0..p.n_real).any(|i| p.body[i] == 0 && p.damage[i] >= 1.0);
                if sim.state.time < next || block_failed {
                    continue;
                }
                next += 1.0e-6;
                let k = in_core.len() as f64;
                let mean =
                    |f: &dyn Fn(usize) -> f64| in_core.iter().map(|&i| f(i)).sum::<f64>() / k;
                let eps_p = mean(&|i| p.eps_p[i]);
                if eps_p < 0.05 {
                    continue;
                }
                let sigma_eq = mean(&|i| strike::tensor::von_mises(&p.s[i].full()));
                triaxiality += mean(&|i| -p.p[i] / strike::tensor::von_mises(&p.s[i].full()));
                // The platens' gap, the block's height (twice the quarter's, whose lowest
                // particles lie Δp/2 above the plane y = 0): the nominal equivalent strain
                // rate of plane strain, 2/√3 v/H.
                let (_, hi) = extent_y(p, 0);
                let rate = 2.0 / 3f64.sqrt() * closing / (2.0 * hi + dp);
                let t_star = (chi * mean(&|i| p.plastic_work[i]) / c_p) / (t_melt - t_room);
                let y = (a + b * eps_p.powf(n)) * (1.0 + c * rate.ln()) * (1.0 - t_star.powf(m));
                worst_flow = worst_flow.max((sigma_eq / y - 1.0).abs());
                samples += 1;
            }
            let strains: Vec<f64> = failed_at.values().copied().collect();
            let at_failure = strains.iter().sum::<f64>() / strains.len().max(1) as f64;
            let triaxiality = triaxiality / samples.max(1) as f64;
            println!(
                "JC compression, {formulation:?}, tensor {tensor}, Δp = {dp:.1e} m: flow stress within {:.2} % of Johnson–Cook over {samples} samples; {} of {} core particles failed, at εp = {at_failure:.4} (ε_f {eps_f:.4}, {:+.2} %); the core's mean σ* {triaxiality:.3}, where ε_f = {:.4}",
                100.0 * worst_flow,
                strains.len(),
                core.len(),
                100.0 * (at_failure / eps_f - 1.0),
                0.13 + 0.13 * (-1.5 * triaxiality).exp()
            );
            assert!(samples >= 10, "too few samples before failure: {samples}");
            assert!(
                worst_flow < 0.04,
                "flow stress off Johnson–Cook by {worst_flow}"
            );
            // Two bands' worth of the whole core, twice as many particles as it has across
            // (twice the quarter's): a quarter of that in the quarter.
            let across = 2.0 * (core.len() as f64).sqrt();
            assert!(
                strains.len() as f64 >= 2.0 * across / 4.0,
                "{} of {} core particles failed ({across} across)",
                strains.len(),
                core.len()
            );
            let error = (at_failure / eps_f - 1.0).abs();
            // 15 % at the coarser spacing (`two_resolutions` gives it first), 10 % at the finer.
            let tolerance = [0.15, 0.10][errors.len()];
            assert!(
                error < tolerance,
                "{formulation:?}, tensor {tensor}, Δp = {dp}: failed at εp = {at_failure} against ε_f = {eps_f}"
            );
            errors.push(error);
        }
        assert!(
            errors[1] <= errors[0],
            "{formulation:?}, tensor {tensor}: the failure strain's error grows with refinement: {errors:?}"
        );
    }
}

/// Issue 13 (Johnson–Cook failure in tension; `examples/jc_failure_tension.toml`): a 2024-T3
/// strip, 3 × 1 mm in plane strain, pulled by welded grips at ±10 m/s, at two resolutions
/// (CN-SPH at the coarser). It breaks, and its cracks stay cracks:
/// - its intact particles no longer join the two grips (pieces: linked within 1.5 Δp);
/// - the failed particles lie on lines, not over areas: in the strip as it was built, a failed
///   particle has on average fewer than 5.25 failed particles among its 8 nearest: a band at
///   most two particles wide (one wide reads 2; two wide 4 on the diagonal, 5 along the
///   lattice; three wide 5.3 and 6; a failed zone 8);
/// - at most 15 % of the strip has failed;
/// - the two end pieces go with their grips, their mean velocity within 20 % of ∓10 m/s.
///
/// How it breaks depends on the spacing, as a localisation does: across two straight cracks at
/// Δp = 0.1 mm, by crossing shear bands two particles wide at 0.05 mm. Measured on 2026-11-28,
/// with the material update at the step's middle (failed of the strip; failed of 8 nearest;
/// the end pieces' speeds): conventional SPH 16 of 300, 1.75, ∓10.03 m/s at 0.1 mm and 112 of
/// 1200, 4.95, −9.00 / +9.59 m/s at 0.05 mm; CN-SPH 28 of 300, 1.86, ∓10.04 m/s and, by hand,
/// 81 of 1200, 4.25, −8.74 / +9.76 m/s. The count at 0.05 mm is a property of where the bands
/// cross and branch more than of their width: the same deck read 3.71 (98 failed) with the
/// whole-step update of 2026-11-27, and 3.1 to 5.5 with variants of the update (its
/// extrapolation off for failed or for plastic particles, the viscosity's limiter off), every
/// one of them the same two-wide bands; CN-SPH read 6.18 (99 failed), a band 3 to 4 wide,
/// before. CN-SPH runs here at 0.1 mm only, for CI's time. Before 2026-11-27 the cracks' intact
/// neighbours read their opening as their own expansion (continuity) and strain (velocity
/// gradient), went into 2–4 GPa of tension and failed in turn: 288 of the strip's 300
/// particles failed at Δp = 0.1 mm (7.1 failed of 8 nearest), and the rubble flew apart
/// (`physics::severed` and the pass's `cut!` say what changed).
///
/// Not held here: the tensor smoothing length (by hand, 2026-12-05). At Δp = 0.1 mm it breaks
/// the strip as the round kernel does (36 of 300 failed, 4.78 of 8 nearest, ∓10.06 m/s), but
/// at 0.05 mm it necks at two places near the grips in crossing shear bands, and where they
/// cross 48 particles fail within 0.4 µs: 260 of 1200 failed, 6.53 of 8 nearest, a failed
/// zone (the same with a stretch bound of 2; with the artificial stress 0.3, 5.36 at 0.1 mm).
#[test]
fn johnson_cook_failure_in_tension_leaves_a_crack() {
    use strike::case::Formulation;
    let [coarse, fine] = two_resolutions("jc_failure_tension");
    // CN-SPH at the coarse spacing only, for CI's time (its fine run, which holds only the
    // failed share, is in the doc above and the README).
    let runs = [
        (Formulation::Conventional, coarse.clone()),
        (Formulation::Conventional, fine),
        (Formulation::Corrected, coarse),
    ];
    for (formulation, mut case) in runs {
        case.simulation.formulation = formulation;
        let dp = case.bodies[0].spacing;
        let v = case.bodies[2].velocity[0];
        let mut sim = Simulation::<2>::new(&case).unwrap();
        let built: std::collections::HashMap<u32, strike::particles::Vector<2>> =
            (0..sim.particles.n_real)
                .map(|i| (sim.particles.id[i], sim.particles.x[i]))
                .collect();
        let end = case.simulation.end_time;
        let mut first = None;
        while sim.state.time < end * (1.0 - 1e-12) {
            sim.step(end - sim.state.time).unwrap();
            if first.is_none() && sim.particles.damage.iter().any(|&d| d >= 1.0) {
                first = Some(sim.state.time);
            }
        }
        let p = &sim.particles;
        let strip: Vec<usize> = (0..p.n_real).filter(|&i| p.body[i] == 0).collect();
        let failed = strip.iter().filter(|&&i| p.damage[i] >= 1.0).count();
        let intact: Vec<usize> = strip
            .iter()
            .copied()
            .filter(|&i| p.damage[i] < 1.0)
            .collect();
        let pieces = pieces(p, &intact, 1.5 * dp);
        let (left, right) = (
            end_piece(p, &intact, &pieces, f64::min),
            end_piece(p, &intact, &pieces, f64::max),
        );
        let speed = |piece: usize| {
            let members: Vec<usize> = (0..intact.len()).filter(|&k| pieces[k] == piece).collect();
            members.iter().map(|&k| p.v[intact[k]][0]).sum::<f64>() / members.len() as f64
        };
        let (v_left, v_right) = (speed(left), speed(right));
        // Failed particles among each failed particle's 8 nearest, where they were built.
        let at: Vec<_> = strip
            .iter()
            .filter(|&&i| p.damage[i] >= 1.0)
            .map(|&i| built[&p.id[i]])
            .collect();
        let near = at
            .iter()
            .map(|a| at.iter().filter(|b| (*a - **b).norm() < 1.5 * dp).count() - 1)
            .sum::<usize>() as f64
            / failed.max(1) as f64;
        println!(
                "JC tension, {formulation:?}, Δp = {dp:.1e} m: first failure at {:.2} µs; {failed} of {} failed, {near:.2} failed of their 8 nearest; the end pieces at {v_left:+.2} / {v_right:+.2} m/s (grips ∓{v} m/s)",
                first.unwrap_or(f64::NAN) * 1e6,
                strip.len()
            );
        assert!(first.is_some(), "the strip did not break");
        assert_ne!(
            left, right,
            "the grips are still joined through intact particles"
        );
        assert!(near < 5.25, "a failed zone: {near} failed of 8 nearest");
        assert!(
            100 * failed <= 15 * strip.len(),
            "{failed} of {} failed",
            strip.len()
        );
        assert!(
            (v_left / -v - 1.0).abs() < 0.2,
            "left piece at {v_left} m/s"
        );
        assert!(
            (v_right / v - 1.0).abs() < 0.2,
            "right piece at {v_right} m/s"
        );
    }
}

/// Which piece each of the particles `members` belongs to (pieces join particles closer than
/// `link`), numbered by their first member.
fn pieces(p: &strike::particles::Particles<2>, members: &[usize], link: f64) -> Vec<usize> {
    let mut root: Vec<usize> = (0..members.len()).collect();
    fn find(root: &mut [usize], mut k: usize) -> usize {
        while root[k] != k {
            root[k] = root[root[k]];
            k = root[k];
        }
        k
    }
    for a in 0..members.len() {
        for b in a + 1..members.len() {
            if (p.x[members[a]] - p.x[members[b]]).norm() < link {
                let (ra, rb) = (find(&mut root, a), find(&mut root, b));
                root[ra.max(rb)] = ra.min(rb);
            }
        }
    }
    (0..members.len()).map(|k| find(&mut root, k)).collect()
}

/// The piece of the particle of `members` furthest to one side (`pick`: `f64::min`, left).
fn end_piece(
    p: &strike::particles::Particles<2>,
    members: &[usize],
    pieces: &[usize],
    pick: fn(f64, f64) -> f64,
) -> usize {
    let x = members
        .iter()
        .map(|&i| p.x[i][0])
        .fold(p.x[members[0]][0], pick);
    let k = (0..members.len())
        .find(|&k| p.x[members[k]][0] == x)
        .unwrap();
    pieces[k]
}

/// The lowest and highest y of body `b`'s particles.
fn extent_y(p: &strike::particles::Particles<2>, b: u32) -> (f64, f64) {
    (0..p.n_real)
        .filter(|&i| p.body[i] == b)
        .map(|i| p.x[i][1])
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| {
            (lo.min(y), hi.max(y))
        })
}

/// A 3D `case` run to its end time.
fn run_to_end(case: &Case) -> Simulation<3> {
    let mut sim = Simulation::<3>::new(case).unwrap();
    let end = case.simulation.end_time;
    while sim.state.time < end * (1.0 - 1e-12) {
        sim.step(end - sim.state.time).unwrap();
    }
    sim
}

/// The density diffusion keeps a plastic flow's density noise from failing it
/// (`examples/taylor_ofhc_anvil.toml`: Johnson & Cook's OFHC rod at 190 m/s onto a steel
/// anvil, the library's spall at 1.3 GPa on, R0/Δp = 8, its first 8 µs). Without the
/// diffusion the foot's density is noisy, neighbours 1–3 GPa apart where the smooth pressure is
/// near zero, and the tensile tail of that noise fails particles of the rod (58 by 8 µs in
/// conventional SPH, 17 in CN-SPH, measured 2026-12-03), which the recovered rods show no sign
/// of; with δ = 0.1 none fails in either formulation. The runs without the diffusion stop at
/// their fifth failed particle, all that is held of them.
#[test]
fn density_diffusion_keeps_the_copper_rods_foot_whole() {
    use strike::case::Formulation;
    for formulation in [Formulation::Conventional, Formulation::Corrected] {
        for delta in [0.0, 0.1] {
            let mut case = load("taylor_ofhc_anvil");
            case.simulation.end_time = 8.0e-6;
            case.simulation.formulation = formulation;
            case.simulation.density_diffusion = delta;
            // Without the diffusion the run stops once 5 particles of the rod have failed.
            let mut sim = Simulation::<3>::new(&case).unwrap();
            let end = case.simulation.end_time;
            let failed = |sim: &Simulation<3>| {
                let p = &sim.particles;
                (0..p.n_real)
                    .filter(|&i| p.body[i] == 0 && p.damage[i] >= 1.0)
                    .count()
            };
            while sim.state.time < end * (1.0 - 1e-12) && (delta > 0.0 || failed(&sim) < 5) {
                sim.step(end - sim.state.time).unwrap();
            }
            let failed = failed(&sim);
            println!(
                "{formulation:?}, δ = {delta}: {failed} of the rod's particles failed by {:.2} µs",
                sim.state.time * 1e6
            );
            if delta == 0.0 {
                assert!(
                    failed >= 5,
                    "{formulation:?}: the noise no longer fails the rod"
                );
            } else {
                assert_eq!(failed, 0, "{formulation:?}: the rod failed");
            }
        }
    }
}

/// A slab of uniaxial strain expanding uniformly ([`expanding_slab`]).
struct SlabRun<'a> {
    /// The material's lines after its density (2700 kg/m³): EOS, strength, damage.
    material: &'a str,
    /// Half the slab's length (m): its free faces' release reaches the middle after about
    /// (half_length − 0.2 mm)/c_L.
    half_length: f64,
    /// ε̇ (1/s).
    rate: f64,
    dp: f64,
    formulation: strike::case::Formulation,
    /// The run's end (s), past the analytic failure.
    end: f64,
}

/// Runs a 2D slab 0.2 mm across between symmetry planes (uniaxial strain) given the velocity
/// field v_x = ε̇ x, so that its middle (|x| < 0.2 mm) expands uniformly, until a particle of
/// the middle fails. Returns how far the middle's mean damage strayed from `d_at(t)` before
/// that, when the first failed, and the longest step.
fn expanding_slab(slab: &SlabRun<'_>, d_at: &dyn Fn(f64) -> f64) -> (f64, f64, f64) {
    let deck = format!(
        r#"
[simulation]
dimension = 2
end_time = {end:e}

[materials.m]
density = 2700.0
{material}

[[body]]
name = "slab"
material = "m"
spacing = {dp:e}
shape = {{ type = "rectangle", min = [-{l:e}, 0.0], max = [{l:e}, 0.2e-3] }}

[[symmetry]]
axis = "y"
position = 0.0

[[symmetry]]
axis = "y"
position = 0.2e-3
"#,
        end = slab.end,
        material = slab.material,
        dp = slab.dp,
        l = slab.half_length,
    );
    let mut case = strike::deck::parse(&deck, "slab.toml").unwrap();
    case.simulation.formulation = slab.formulation;
    let mut sim = Simulation::<2>::new(&case).unwrap();
    let n = sim.particles.n_real;
    for i in 0..n {
        let x = sim.particles.x[i][0];
        sim.particles.v[i][0] = slab.rate * x;
        sim.particles.vh[i] = sim.particles.v[i];
    }
    let middle: Vec<usize> = (0..n)
        .filter(|&i| sim.particles.x[i][0].abs() < 0.2e-3)
        .collect();
    let end = case.simulation.end_time;
    let (mut worst, mut failed_at, mut dt_max) = (0.0_f64, None, 0.0_f64);
    while failed_at.is_none() && sim.state.time < end {
        let t0 = sim.state.time;
        sim.step(end - t0).unwrap();
        let t = sim.state.time;
        dt_max = dt_max.max(t - t0);
        let p = &sim.particles;
        if middle.iter().any(|&i| p.damage[i] >= 1.0) {
            failed_at = Some(t);
        } else {
            let d = middle.iter().map(|&i| p.damage[i]).sum::<f64>() / middle.len() as f64;
            worst = worst.max((d - d_at(t)).abs());
        }
    }
    (worst, failed_at.expect("the middle never failed"), dt_max)
}

/// Tuler–Butcher's spall strength rises with the loading rate, in a run. A 3 mm slab between
/// symmetry planes (uniaxial strain) is given the velocity field v_x = ε̇ x: its middle expands
/// uniformly, so there ρ = ρ0/(1 + ε̇ t) and, with a linear EOS and no strength, the tension
/// σ1 = K (1 − 1/(1 + ε̇ t)) until the free faces' release arrives (after 0.28 µs, later than
/// any failure here). The damage of the middle's particles must follow
/// D(t) = (1/K_f) ∫ (σ1 − σ0)^λ dt (quadrature of that σ1) and reach 1 when it does, at
/// ε̇ = 5e4 and 4e5 1/s (σ0 = 0.4 GPa, λ = 2, K_f = 5e9 Pa² s: failure at 0.779 and
/// 1.156 GPa, the excess over σ0 doubling for eight times the rate, as
/// σ0 + ((λ + 1) σ̇ K_f)^(1/(λ+1)) has it), at Δp = 20 and 10 µm, in both formulations.
/// CN-SPH's corrected gradient takes the linear field's divergence exactly: its damage follows
/// the analytic history to first order in the step (measured 2026-12-04: off by at most
/// 0.0062 / 0.0031 at 5e4 1/s, 0.024 / 0.012 at 4e5, failing within 0.16 ns). Conventional
/// SPH's kernel sums read the divergence 0.9 % low on this lattice at every spacing (the
/// kernel's own lattice error, h = 1.2 Δp), so its tension lags by 0.9 % and its damage by up
/// to 0.042, and the middle fails 0.7–2.1 ns late (1 % of the time, 1–4 steps).
#[test]
fn tuler_butcher_spall_strength_rises_with_the_rate() {
    use strike::case::Formulation;
    let k = 74.0e9;
    let (s0, lambda, k_f) = (0.4e9, 2.0, 5.0e9);
    for formulation in [Formulation::Conventional, Formulation::Corrected] {
        let mut failure = Vec::new();
        for rate in [5.0e4, 4.0e5] {
            // The analytic history: D(t) by the trapezoidal rule on a fine grid.
            let sigma = |t: f64| k * (1.0 - 1.0 / (1.0 + rate * t));
            let f = |t: f64| (sigma(t) - s0).max(0.0).powf(lambda) / k_f;
            let dt_fine = 1e-12;
            let (mut t, mut d, mut history) = (0.0, 0.0, vec![(0.0, 0.0)]);
            while d < 1.0 {
                d += 0.5 * (f(t) + f(t + dt_fine)) * dt_fine;
                t += dt_fine;
                history.push((t, d));
            }
            let t_fail = t;
            let d_at = |time: f64| {
                let i = history
                    .partition_point(|&(s, _)| s < time)
                    .min(history.len() - 1);
                history[i].1
            };
            let mut errors = Vec::new();
            for dp in [20.0e-6, 10.0e-6] {
                let material = format!(
                    r#"eos = {{ type = "linear", bulk_modulus = {k:e} }}
strength = {{ type = "hydrodynamic" }}
damage = {{ type = "tuler_butcher", threshold = {s0:e}, exponent = {lambda}, impulse = {k_f:e} }}"#
                );
                let slab = SlabRun {
                    material: &material,
                    half_length: 1.5e-3,
                    rate,
                    dp,
                    formulation,
                    end: 1.3 * t_fail,
                };
                let (worst, failed_at, dt_max) = expanding_slab(&slab, &d_at);
                println!(
                    "{formulation:?}, ε̇ = {rate:e}/s, Δp = {:.0} µm: D off the analytic by at most {worst:.4}; the middle fails at {:.2} ns against {:.2} ns (σ1 {:.4} against {:.4} GPa; steps of {:.2} ns)",
                    dp * 1e6,
                    failed_at * 1e9,
                    t_fail * 1e9,
                    sigma(failed_at) / 1e9,
                    sigma(t_fail) / 1e9,
                    dt_max * 1e9
                );
                // Conventional SPH's tension lags by 0.9 %: its failure by as much of the time.
                let (bound, late) = match formulation {
                    Formulation::Corrected => (0.03, 0.0),
                    _ => (0.05, 0.015),
                };
                assert!(
                    worst < bound,
                    "{formulation:?}: the damage left the analytic history by {worst}"
                );
                assert!(
                    failed_at >= t_fail - dt_max && failed_at <= t_fail * (1.0 + late) + dt_max,
                    "{formulation:?}: failed at {failed_at:e} s, not at {t_fail:e} s"
                );
                errors.push(worst);
                failure.push(sigma(failed_at));
            }
            if formulation == Formulation::Corrected {
                assert!(
                    errors[1] < 0.6 * errors[0],
                    "CN-SPH's damage error does not converge: {errors:?}"
                );
            }
        }
        // Eight times the rate: the excess over σ0 carried at failure doubles.
        for fine in 0..2 {
            let ratio = (failure[2 + fine] - s0) / (failure[fine] - s0);
            println!("{formulation:?}: the excess grew by {ratio:.4}");
            assert!((ratio - 2.0).abs() < 0.1, "the excess grew by {ratio}");
        }
    }
}

/// Johnson–Cook failure with Tuler–Butcher's spall in one material (`damage = { type =
/// "johnson_cook", …, tuler_butcher_threshold = … }`): one fracture indicator grown by both,
/// D = Σ Δεp/ε_f + (1/K_f) ∫ (σ1 − σ0)^λ dt, the particle failing at D = 1 (Miner's linear
/// rule). The slab of [`tuler_butcher_spall_strength_rises_with_the_rate`], 6 mm long, with
/// von Mises strength (G = 26 GPa, Y = 0.3 GPa): its middle's uniaxial strain e = ln(1 + ε̇ t)
/// is elastic until 2G e = Y (s_xx = 4G e/3), then flows at s_xx = 2Y/3 with
/// ε̇p = (2/3) ε̇/(1 + ε̇ t), so that σ1 = K (1 − 1/(1 + ε̇ t)) + s_xx and, flowing, the
/// triaxiality is σ* = −p/Y. With D1 = 0.004, D2 = 0.1, D3 = −1.5 (no rate or temperature
/// term), σ0 = 0.4 GPa, λ = 2 and K_f = 2e10 Pa² s, the middle's damage must follow that sum
/// and fail when it reaches 1, at ε̇ = 5e4 and 4e5 1/s and Δp = 20 and 10 µm, in both
/// formulations: at 0.2015 and 0.0338 µs, where Tuler–Butcher alone would fail it at 0.2200 /
/// 0.0482 µs and Johnson–Cook alone at 0.3083 / 0.0385 µs (each at least 7 % later, which the
/// test asks, so that it sees either part missing). Measured 2026-12-04 (D's largest departure
/// from the sum at Δp = 20 / 10 µm; the failure's delay): CN-SPH 0.0031 / 0.0016 at 5e4 1/s
/// and 0.0125 / 0.0062 at 4e5, failing within 0.2 % of the time; conventional SPH 0.022 /
/// 0.025 and 0.003 / 0.010, failing 0.7 % and 0.9 % late.
#[test]
fn johnson_cook_failure_and_tuler_butcher_add_up() {
    use strike::case::Formulation;
    let (k, g, y) = (74.0e9, 26.0e9, 0.3e9);
    let (s0, lambda, k_f) = (0.4e9, 2.0, 2.0e10);
    let (d1, d2, d3) = (0.004, 0.1, -1.5);
    let material = format!(
        r#"eos = {{ type = "linear", bulk_modulus = {k:e} }}
strength = {{ type = "von_mises", shear_modulus = {g:e}, yield_stress = {y:e} }}
damage = {{ type = "johnson_cook", d1 = {d1}, d2 = {d2}, d3 = {d3}, tuler_butcher_threshold = {s0:e}, tuler_butcher_exponent = {lambda}, tuler_butcher_impulse = {k_f:e} }}"#
    );
    // The middle's D(t) with either model or both (explicit quadrature, steps of 1 ps).
    let history = |rate: f64, tb: bool, jc: bool| {
        let (dt, e_y) = (1e-12, y / (2.0 * g));
        let (mut t, mut d, mut e, mut h) = (0.0, 0.0, 0.0_f64, vec![(0.0, 0.0)]);
        while d < 1.0 {
            let e_new = (rate * (t + dt)).ln_1p();
            let flowing = e_new > e_y;
            let s_xx = if flowing {
                2.0 * y / 3.0
            } else {
                4.0 * g * e_new / 3.0
            };
            let p = k * (1.0 / (1.0 + rate * (t + dt)) - 1.0);
            let sigma_1 = s_xx - p;
            if tb && sigma_1 > s0 {
                d += (sigma_1 - s0).powf(lambda) * dt / k_f;
            }
            if jc && flowing {
                let eps_f = (d1 + d2 * (d3 * (-p / y)).exp()).max(1e-3);
                d += 2.0 / 3.0 * (e_new - e.max(e_y)) / eps_f;
            }
            (e, t) = (e_new, t + dt);
            h.push((t, d));
        }
        h
    };
    let mut errors = Vec::new();
    for rate in [5.0e4, 4.0e5] {
        let both = history(rate, true, true);
        let t_fail = both[both.len() - 1].0;
        let alone =
            [history(rate, true, false), history(rate, false, true)].map(|h| h[h.len() - 1].0);
        println!(
            "ε̇ = {rate:e}/s: both fail the middle at {:.4} µs, Tuler–Butcher alone at {:.4}, Johnson–Cook alone at {:.4}",
            t_fail * 1e6,
            alone[0] * 1e6,
            alone[1] * 1e6
        );
        assert!(
            t_fail < 0.93 * alone[0].min(alone[1]),
            "one model fails the middle nearly alone: the test would not see the other"
        );
        let d_at = |time: f64| {
            let i = both.partition_point(|&(s, _)| s < time).min(both.len() - 1);
            both[i].1
        };
        for formulation in [Formulation::Conventional, Formulation::Corrected] {
            for dp in [20.0e-6, 10.0e-6] {
                let slab = SlabRun {
                    material: &material,
                    half_length: 3.0e-3,
                    rate,
                    dp,
                    formulation,
                    end: 1.3 * t_fail,
                };
                let (worst, failed_at, dt_max) = expanding_slab(&slab, &d_at);
                println!(
                    "{formulation:?}, ε̇ = {rate:e}/s, Δp = {:.0} µm: D off the sum by at most {worst:.4}; the middle fails at {:.4} µs against {:.4} µs (steps of {:.2} ns)",
                    dp * 1e6,
                    failed_at * 1e6,
                    t_fail * 1e6,
                    dt_max * 1e9
                );
                // Conventional SPH's tension and strain lag by 0.9 % (the slab's divergence,
                // see the test above): its damage strays more and fails later.
                let (bound, lag) = match formulation {
                    Formulation::Corrected => (0.02, 0.0),
                    _ => (0.04, 0.015),
                };
                assert!(worst < bound, "{formulation:?}: D left the sum by {worst}");
                assert!(
                    failed_at >= t_fail - dt_max && failed_at <= (1.0 + lag) * t_fail + dt_max,
                    "{formulation:?}: failed at {failed_at:e} s, not at {t_fail:e} s"
                );
                errors.push(worst);
            }
            if formulation == Formulation::Corrected {
                let n = errors.len();
                assert!(
                    errors[n - 1] < 0.6 * errors[n - 2],
                    "CN-SPH's damage error does not converge: {errors:?}"
                );
            }
        }
    }
}

/// Tuler–Butcher's spall in a wave problem: `examples/spall_tuler_butcher.toml`, the flyer
/// plate of `examples/spall.toml` with
/// `damage = { type = "tuler_butcher", threshold = 0.7e9, exponent = 2, impulse = 1e9 }`, and
/// the same with a flyer twice as thick (1 mm: a longer pulse, whose tension rises more
/// slowly), against the independent 1D Lagrangian solution of each
/// (`examples/spall_lagrangian_1d.py --tuler-butcher 0.7,2,1e9 [--flyer-mm 1.0]`, 1 µm cells:
/// pull-back minimum 265.7 / 288.4 m/s, spall plane 2.5143 / 1.9863 mm): at Δp = 20 / 10 µm
/// the minimum within 10 / 6 % and the plane within 6 / 4 %, each closer at the finer spacing.
/// Measured 2026-12-04: thin 244.1 / 255.0 m/s (−8.1 / −4.0 %), plane 2.430 / 2.470 mm (−3.4 /
/// −1.8 %); thick 293.4 / 288.8 m/s (+1.7 / +0.1 %), plane 2.089 / 2.055 mm (+5.2 / +3.5 %).
/// Failure at the threshold alone (0.7 GPa) reads 316.6 m/s for the thin flyer in the 1D code
/// (5 µm cells), +19 %: the test sees a criterion without its integral.
#[test]
fn tuler_butcher_flyer_plate_spalls_as_the_independent_solution_does() {
    let deck = std::fs::read_to_string(format!(
        "{}/examples/spall_tuler_butcher.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let thick = deck.replace("min = [-0.5e-3, 0.0]", "min = [-1.0e-3, 0.0]");
    assert!(
        deck.contains("tuler_butcher") && thick != deck,
        "the deck moved"
    );
    for (deck, u_min_ref, plane_ref) in
        [(deck.clone(), 265.7, 2.5143e-3), (thick, 288.4, 1.9863e-3)]
    {
        let mut errors = Vec::new();
        for (refine, u_tol, plane_tol) in [(1.0, 0.10, 0.06), (0.5, 0.06, 0.04)] {
            let (_, u_min, _, plane, run) =
                read_spall(&spall_case(&deck, refine), 0.7e9, plane_ref);
            assert!(!run.failed_x0.is_empty(), "nothing failed");
            let (eu, ep) = (u_min / u_min_ref - 1.0, plane / plane_ref - 1.0);
            assert!(
                eu.abs() < u_tol,
                "pull-back minimum {u_min} against {u_min_ref}"
            );
            assert!(
                ep.abs() < plane_tol,
                "spall plane {plane} against {plane_ref}"
            );
            errors.push((eu.abs(), ep.abs()));
        }
        assert!(
            errors[1].0 < errors[0].0 && errors[1].1 < errors[0].1,
            "not closer at the finer spacing: {errors:?}"
        );
    }
}

/// `examples/upsetting.toml` run to its end (`formulation` in place of the deck's): the
/// rod's core plastic strain (particles within half the largest radius of the axis, between
/// a quarter and three quarters of the height) and the continuum's, ln(H0/H) less the elastic
/// σ/E of the platen's mean stress, H the platen's height at the end.
fn upset(formulation: strike::case::Formulation) -> (f64, f64) {
    let mut case = load("upsetting");
    case.simulation.formulation = formulation;
    let strike::case::Shape::Cylinder {
        radius: r0,
        length: h0,
        ..
    } = case.bodies[0].shape
    else {
        panic!("the upsetting deck's rod is not a cylinder");
    };
    // The platen's speed, and 42CrMo4's Young's modulus (the library's, for the elastic σ/E).
    let (speed, young) = (-case.bodies[1].velocity[2], 206.9e9);
    let sim = run_to_end(&case);
    let p = &sim.particles;
    let h = h0 - speed * sim.state.time;
    let rod: Vec<usize> = (0..p.n_real).filter(|&i| p.body[i] == 0).collect();
    let radius = |i: usize| p.x[i][0].hypot(p.x[i][1]);
    let r_max = rod.iter().map(|&i| radius(i)).fold(0.0, f64::max);
    let core: Vec<f64> = rod
        .iter()
        .filter(|&&i| radius(i) < 0.5 * r_max && (0.25 * h..0.75 * h).contains(&p.x[i][2]))
        .map(|&i| p.eps_p[i])
        .collect();
    assert!(core.len() >= 20, "{} core particles", core.len());
    let eps = core.iter().sum::<f64>() / core.len() as f64;
    // The platen's push on the quarter rod over the rod's continuum cross-section.
    let force: f64 = 4.0 * rod.iter().map(|&i| p.contact_force[i][2]).sum::<f64>();
    let area = std::f64::consts::PI * r0 * r0 * h0 / h;
    let reference = (h0 / h).ln() - (force / area).abs() / young;
    println!(
        "upsetting, {formulation:?}: core εp {eps:.4} against {reference:.4} ({:+.2} %), platen stress {:.3} GPa",
        100.0 * (eps / reference - 1.0),
        force / area * 1e-9
    );
    (eps, reference)
}

/// A cylinder upset between frictionless platens flows evenly: its core's plastic strain is
/// the geometry's, ln(H0/H) less σ/E (0.974 at the end). CN-SPH holds it within 2 %: measured
/// +0.9 % at R0/Δp = 8 (the deck) and −0.6 % at 16 (by hand, 14 minutes on 2 cores; not run
/// here). Conventional SPH registers less than the particles move (read as its kernel sums'
/// moment Σ V_j x_ji ⊗ ∇W drifting from the identity as the lattice flattens to 0.37 of its
/// height and widens 1.65-fold, which CN-SPH's B removes; not measured): −6.2 / −3.9 % at
/// R0/Δp = 8 / 16 (16 by hand), converging; held here within 8 %, so that a change that
/// loses more of the flow is seen.
#[test]
fn upsetting_registers_the_plastic_strain_of_the_geometry() {
    use strike::case::Formulation;
    let (eps, reference) = upset(Formulation::Corrected);
    assert!(
        (eps / reference - 1.0).abs() < 0.02,
        "CN-SPH: {eps} against {reference}"
    );
    let (eps, reference) = upset(Formulation::Conventional);
    assert!(
        (eps / reference - 1.0).abs() < 0.08,
        "conventional: {eps} against {reference}"
    );
}

/// The plane-strain slab of `examples/taylor_slab_2d.toml` in `formulation` at `speed` and R0/Δp =
/// `ratio`, as the deck sets it up or (`round`) with the defaults it changes (the round kernel,
/// h's stretch up to 1.25, no artificial stress): its rim, the lowest layer's farthest particle
/// plus Δp/2, from the plane (m).
fn slab_rim(formulation: strike::case::Formulation, speed: f64, ratio: f64, round: bool) -> f64 {
    let mut case = load("taylor_slab_2d");
    case.simulation.formulation = formulation;
    // The half thickness R0, from the deck's rectangle.
    let strike::case::Shape::Box { min, max } = case.bodies[0].shape else {
        panic!("the slab deck's body is not a rectangle");
    };
    let dp = (max[0] - min[0]) / ratio;
    case.bodies[0].spacing = dp;
    case.bodies[0].velocity = [0.0, -speed, 0.0];
    if round {
        case.simulation.tensor_smoothing = false;
        case.simulation.smoothing_stretch = 1.25;
        case.materials[0].artificial_stress = None;
    }
    let mut sim = Simulation::<2>::new(&case).unwrap();
    let lowest: std::collections::HashSet<u32> = (0..sim.particles.n_real)
        .filter(|&i| sim.particles.x[i][1] < dp)
        .map(|i| sim.particles.id[i])
        .collect();
    let end = case.simulation.end_time;
    while sim.state.time < end * (1.0 - 1e-12) {
        sim.step(end - sim.state.time).unwrap();
    }
    let p = &sim.particles;
    let rim = (0..p.n_real)
        .filter(|&i| lowest.contains(&p.id[i]))
        .map(|i| p.x[i][0])
        .fold(0.0, f64::max)
        + 0.5 * dp;
    println!(
        "slab at {speed} m/s, R0/Δp = {ratio}, {formulation:?}, {}: rim {:.4} mm",
        if round { "round kernel" } else { "the deck's" },
        rim * 1e3
    );
    rim
}

/// The Taylor face in plane strain converges on the finite elements' with the tensor
/// smoothing length (`physics::asph`) and the artificial stress, the slab deck's set-up.
/// References: `python3 examples/taylor_fe_axisymmetric.py --plane-strain --chi 0 --v0 V`,
/// half-faces 4.520 / 4.518 mm at 150 m/s and 8.230 / 8.252 mm at 287 m/s (8 / 16 elements
/// across). Measured 2026-12-05 at R0/Δp = 8 / 16 / 32 (32 by hand): 4.407 / 4.503 / 4.554 mm
/// (−2.5 / −0.3 / +0.8 %) at 150 m/s and 7.749 / 8.247 / 8.253 mm (−5.8 / −0.1 / +0.0 %) at
/// 287 m/s. With the round kernel the rim moves away: 4.334 / 4.606 / 4.935 / 5.623 mm at 150
/// m/s and R0/Δp = 8 / 16 / 32 / 64, 8.761 / 9.171 mm (+6.2 / +11.1 %) at 287 m/s and 16 / 32;
/// the test runs the round kernel at 287 m/s and R0/Δp = 16 to show that it would fail it.
#[test]
fn taylor_slab_face_converges_with_the_tensor_smoothing_length() {
    slab_faces_converge(strike::case::Formulation::Conventional);
    let round = slab_rim(strike::case::Formulation::Conventional, 287.0, 16.0, true);
    assert!(
        round / 8.252e-3 - 1.0 > 0.04,
        "round kernel at 287 m/s: {round}"
    );
}

/// The slab's rim at both speeds in `formulation` (the deck's tensor smoothing length and
/// artificial stress): within 8 % of the finite elements' at R0/Δp = 8, 2 % at 16, and nearer
/// at 16.
fn slab_faces_converge(formulation: strike::case::Formulation) {
    for (speed, fe) in [(150.0, 4.518e-3), (287.0, 8.252e-3)] {
        let coarse = slab_rim(formulation, speed, 8.0, false);
        let fine = slab_rim(formulation, speed, 16.0, false);
        let (e8, e16) = ((coarse / fe - 1.0).abs(), (fine / fe - 1.0).abs());
        assert!(
            e8 < 0.08,
            "{formulation:?}, {speed} m/s, R0/Δp = 8: rim {coarse} against {fe}"
        );
        assert!(
            e16 < 0.02,
            "{formulation:?}, {speed} m/s, R0/Δp = 16: rim {fine} against {fe}"
        );
        assert!(
            e16 < e8,
            "{formulation:?}, {speed} m/s: the rim moves away, {coarse} then {fine} against {fe}"
        );
    }
}

/// The slab's face in CN-SPH with the tensor smoothing length (`physics::correction`'s B
/// inverting the ellipsoid's moments, since 2026-12-06), held as the conventional run is
/// held. Measured 2026-12-06 (before the passes left out the pairs beyond the ellipsoid, which
/// changes the sums' order): 4.404 / 4.499 mm at 150 m/s (−2.5 / −0.4 %; conventional 4.407 /
/// 4.503) and 7.791 / 8.310 mm at 287 m/s (−5.3 / +0.7 %; 7.749 / 8.247) at R0/Δp = 8 / 16,
/// peak plastic strain 0.546 / 0.655 at 150 m/s (finite elements 0.738 at 16). Long for CI (the
/// four runs took 16 minutes on 2 cores shared with other work): the validation command's.
#[test]
#[ignore = "long (the validation command): CN-SPH's four slabs, about 16 minutes on 2 cores"]
fn taylor_slab_face_converges_in_cn_sph_with_the_tensor_smoothing_length() {
    slab_faces_converge(strike::case::Formulation::Corrected);
}
