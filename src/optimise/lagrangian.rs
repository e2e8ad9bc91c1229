//! The curvature of the convexified sub-step: per frame, the Hessian of the Lagrangian of the
//! fixed-N problem, projected onto the positive semidefinite matrices.
//!
//! The sub-problem maximises progress subject to the frames `x_k = f(x_{k-1}, u_k)` and the walls. The
//! walls are half-planes, linear in the positions, and progress is linear in the last position, so all
//! the curvature sits in the frames: with `z_k` the multipliers of frame `k`'s dynamics rows (Clarabel's
//! duals, in its convention `P x + q + A' z = 0`), the Lagrangian's Hessian in frame `k`'s inputs is
//!
//! ```text
//! W_k = - sum_i z_k,i  d2 f_k,i / d(V, psi, sigma, c)^2
//! ```
//!
//! A linear model with a trust region (what the sub-step is without `W`) is exact only to first order,
//! and along a 400-frame line the second-order error of moving every frame's heading a little is as
//! large as the predicted gain: the trust region stays tiny and the iterations many. With `W` the model
//! is right to second order where `W` is convex. Where it is not, the negative eigenvalues are set to
//! zero (the model stays linear in those directions and the trust region bounds them), so the
//! sub-problem stays a convex QP for Clarabel.

use super::model::FrameHessian;
use faer::{Mat, Side};

/// A frame's block of the Lagrangian's Hessian, inputs `(V, psi, sigma, c)` of [`FrameHessian`].
pub type CurvatureBlock = [[f64; 4]; 4];

/// `W_k = - sum_i z_i H_i` for the frame's Hessians `hessian` and its dynamics duals `z`
/// (order `px, py, V, psi`).
pub fn lagrangian_block(hessian: &FrameHessian, z: &[f64; 4]) -> CurvatureBlock {
    let mut w = [[0.0; 4]; 4];
    for (h, &zi) in hessian.h.iter().zip(z) {
        for (wr, hr) in w.iter_mut().zip(h) {
            for (wij, hij) in wr.iter_mut().zip(hr) {
                *wij -= zi * hij;
            }
        }
    }
    w
}

/// The nearest positive semidefinite matrix to the symmetric `w` (in the Frobenius norm): its
/// eigendecomposition with the negative eigenvalues set to zero. A non-finite block, or one whose
/// decomposition fails, gives zero curvature (the linear model).
pub fn convexify(w: &CurvatureBlock) -> CurvatureBlock {
    if w.iter().flatten().any(|v| !v.is_finite()) {
        return [[0.0; 4]; 4];
    }
    let m = Mat::<f64>::from_fn(4, 4, |i, j| 0.5 * (w[i][j] + w[j][i]));
    let Ok(eig) = m.self_adjoint_eigen(Side::Lower) else {
        return [[0.0; 4]; 4];
    };
    let (u, s) = (eig.U(), eig.S().column_vector());
    let mut out = [[0.0; 4]; 4];
    for k in 0..4 {
        let lambda = s[k];
        if lambda <= 0.0 {
            continue;
        }
        for (i, row) in out.iter_mut().enumerate() {
            for (j, o) in row.iter_mut().enumerate() {
                *o += lambda * u[(i, k)] * u[(j, k)];
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(w: &CurvatureBlock, x: &[f64; 4]) -> f64 {
        (0..4)
            .map(|i| (0..4).map(|j| x[i] * w[i][j] * x[j]).sum::<f64>())
            .sum()
    }

    #[test]
    fn a_positive_definite_block_is_kept() {
        let w = [
            [4.0, 1.0, 0.0, 0.0],
            [1.0, 3.0, 0.5, 0.0],
            [0.0, 0.5, 2.0, 0.1],
            [0.0, 0.0, 0.1, 1.0],
        ];
        let c = convexify(&w);
        for i in 0..4 {
            for j in 0..4 {
                assert!((c[i][j] - w[i][j]).abs() < 1e-12, "{i},{j}");
            }
        }
    }

    #[test]
    fn negative_curvature_is_removed_and_positive_kept() {
        // Eigenvalues 2 (along (1,1,0,0)/sqrt 2) and -2 (along (1,-1,0,0)/sqrt 2), 0 elsewhere.
        let w = [
            [0.0, 2.0, 0.0, 0.0],
            [2.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 0.0],
        ];
        let c = convexify(&w);
        assert!(quad(&c, &[1.0, -1.0, 0.0, 0.0]).abs() < 1e-12);
        assert!((quad(&c, &[1.0, 1.0, 0.0, 0.0]) - 4.0).abs() < 1e-12);
        // Positive semidefinite on a spread of directions.
        for k in 0..50 {
            let t = f64::from(k) * 0.37;
            let x = [t.sin(), t.cos(), (2.0 * t).sin(), (3.0 * t).cos()];
            assert!(quad(&c, &x) >= -1e-12);
        }
    }

    #[test]
    fn non_finite_blocks_give_no_curvature() {
        let mut w = [[1.0; 4]; 4];
        w[2][3] = f64::NAN;
        assert_eq!(convexify(&w), [[0.0; 4]; 4]);
    }

    #[test]
    fn the_block_weighs_each_output_by_minus_its_dual() {
        let mut h = FrameHessian {
            h: [[[0.0; 4]; 4]; 4],
        };
        h.h[0][0][0] = 1.0;
        h.h[3][1][2] = 2.0;
        h.h[3][2][1] = 2.0;
        let w = lagrangian_block(&h, &[3.0, 0.0, 0.0, -0.5]);
        assert_eq!(w[0][0], -3.0);
        assert_eq!(w[1][2], 1.0);
        assert_eq!(w[2][1], 1.0);
    }
}
