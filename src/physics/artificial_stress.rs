//! Artificial stress against the tensile instability (Monaghan 2000; Gray, Monaghan & Swift
//! 2001). In the principal frame of σ_i, each tensile principal stress σ_a > 0 gets
//! R_a = −ε σ_a/ρ_i² (compressive ones get 0); R_i is rotated back to the x frame. In the
//! momentum equation the pair term gains A_ij = (R_i + R_j) f_ij^n with f_ij = W_ij/W(Δp),
//! n = 4, which pushes apart particles that tension would clump.

use crate::particles::Tensor;
use crate::tensor::symmetric_eigen;

/// Exponent n of f_ij^n (Monaghan 2000 uses 4).
pub const EXPONENT: i32 = 4;

/// R_i for a particle with stress σ (tension positive) and density ρ.
pub fn tensor<const D: usize>(sigma: &Tensor<D>, rho: f64, epsilon: f64) -> Tensor<D> {
    let (lambda, q) = symmetric_eigen(sigma);
    let mut r = Tensor::<D>::zeros();
    let mut any = false;
    for (a, &l) in lambda.iter().enumerate() {
        if l > 0.0 {
            r[(a, a)] = -epsilon * l / (rho * rho);
            any = true;
        }
    }
    if !any {
        return Tensor::<D>::zeros();
    }
    q * r * q.transpose()
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn only_tensile_directions_are_corrected() {
        // σ = diag(+2, −3) rotated by 30°: R = rotation of diag(−ε·2/ρ², 0).
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let q = Tensor::<2>::new(c, -s, s, c);
        let sigma = q * Tensor::<2>::new(2.0, 0.0, 0.0, -3.0) * q.transpose();
        let r = tensor(&sigma, 2.0, 0.3);
        let expect = q * Tensor::<2>::new(-0.3 * 2.0 / 4.0, 0.0, 0.0, 0.0) * q.transpose();
        assert_relative_eq!(r, expect, epsilon = 1e-12);
        // Pure compression: no correction.
        let compressive = q * Tensor::<2>::new(-1.0, 0.0, 0.0, -2.0) * q.transpose();
        assert_eq!(tensor(&compressive, 2.0, 0.3), Tensor::<2>::zeros());
    }
}
