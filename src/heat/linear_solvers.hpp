#pragma once
// Allocation-free Krylov solvers for the per-particle heat systems: Jacobi-preconditioned CG
// (Hestenes & Stiefel 1952) and BiCGSTAB (van der Vorst 1992, SIAM J. Sci. Stat. Comput. 13,
// Alg. "Bi-CGSTAB" with right preconditioning, as in Eigen's BiCGSTAB). Eigen's own solvers
// allocate their work vectors at every call; these reuse a workspace, so a thermal step never
// touches the heap. Convergence test: ||b - A x||_2 <= tolerance * ||b||_2.

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace kiln::heat {

/// Row-major sparse matrix (CSR) of a heat system (W/K).
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

/// Outcome of one linear solve.
struct SolveStats {
    int iterations = 0;     ///< Krylov iterations (0 for a direct solve or a converged guess)
    double residual = 0.0;  ///< final ||b - A x|| / ||b|| (-)
    bool converged = false; ///< residual <= tolerance within max_iterations
};

/// Work vectors of the Krylov solvers; sized once by resize(n).
struct KrylovWorkspace {
    Eigen::VectorXd r, r0, p, v, s, t, y, z; ///< solver-internal vectors (units of b or x)
    /// Allocates every vector for n unknowns (the only allocation).
    void resize(Eigen::Index n);
};

/// Dot product (plain loop: GCC 12 reports false maybe-uninitialized warnings inside Eigen's
/// AVX-512 reductions under -march=native).
[[nodiscard]] double dot(const Eigen::VectorXd& a, const Eigen::VectorXd& b);

/// Euclidean norm, see dot().
[[nodiscard]] double norm(const Eigen::VectorXd& a);

/// y = A x without temporaries.
void multiply(const SparseMatrix& a, const Eigen::VectorXd& x, Eigen::VectorXd& y);

/// Jacobi-preconditioned CG for SPD `a`; `x` holds the initial guess and returns the solution.
SolveStats conjugate_gradient(const SparseMatrix& a, const Eigen::VectorXd& inv_diag,
                              const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance,
                              int max_iterations, KrylovWorkspace& ws);

/// Jacobi-preconditioned BiCGSTAB for a general `a`; `x` holds the initial guess and returns the
/// solution.
SolveStats bicgstab(const SparseMatrix& a, const Eigen::VectorXd& inv_diag,
                    const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance,
                    int max_iterations, KrylovWorkspace& ws);

} // namespace kiln::heat
