//! The hot passes' AVX2 builds are vectorised: their lanes run in 256-bit registers.
//!
//! Whether LLVM vectorises the lanes of the rate pass and the correction pass is its own
//! decision, and small changes elsewhere have flipped it (the crate's partition into codegen
//! units, one function inlined into the correction pass), each time making the pass about 2×
//! slower with every result unchanged, which no other test sees. This counts the packed-double
//! instructions on 256-bit registers in the release binary's `particle_rates_avx2` and
//! `correction_avx2` (all monomorphisations): vectorised, the rate pass has about 3950 and the
//! correction pass about 1000; left scalar, about 750 and 250.

use std::process::Command;

/// Packed-double instructions on ymm registers in every function named `name`.
fn wide_instructions(disassembly: &str, name: &str) -> (usize, usize) {
    let header = format!("<{name}>:");
    let (mut functions, mut count, mut inside) = (0, 0, false);
    for line in disassembly.lines() {
        if line.ends_with(&header) {
            functions += 1;
            inside = true;
        } else if line.trim().is_empty() {
            inside = false;
        } else if inside {
            let ins = line.split('\t').nth(1).unwrap_or("");
            let op = ins.split_whitespace().next().unwrap_or("");
            if op.ends_with("pd") && ins.contains("ymm") {
                count += 1;
            }
        }
    }
    (functions, count)
}

#[test]
#[cfg(target_arch = "x86_64")]
#[cfg_attr(
    debug_assertions,
    ignore = "counts the optimised build's instructions: run with --release"
)]
fn the_hot_passes_are_vectorised() {
    let out = Command::new("objdump")
        .args(["-d", "-C", "--no-show-raw-insn"])
        .arg(env!("CARGO_BIN_EXE_strike"))
        .output()
        .expect("objdump (binutils) runs");
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    let (functions, rates) = wide_instructions(&text, "strike::physics::particle_rates_avx2");
    println!("rate pass: {functions} builds, {rates} 256-bit packed-double instructions");
    assert!(functions >= 8, "{functions} rate passes found");
    assert!(
        rates >= 3000,
        "the rate pass's AVX2 builds hold {rates} 256-bit packed-double instructions (about 3950 when vectorised): LLVM left the lanes scalar"
    );
    let (functions, corrections) =
        wide_instructions(&text, "strike::physics::correction::correction_avx2");
    println!(
        "correction pass: {functions} builds, {corrections} 256-bit packed-double instructions"
    );
    assert!(functions >= 2, "{functions} correction passes found");
    assert!(
        corrections >= 700,
        "the correction pass's AVX2 builds hold {corrections} 256-bit packed-double instructions (about 1000 when vectorised): LLVM left the lanes scalar"
    );
}
