#pragma once
// Allocation-free Krylov solvers for the per-particle heat systems: Jacobi-preconditioned CG
// (Hestenes & Stiefel 1952) and BiCGSTAB (van der Vorst 1992, SIAM J. Sci. Stat. Comput. 13,
// Alg. "Bi-CGSTAB" with right preconditioning, as in Eigen's BiCGSTAB). Eigen's own solvers
// allocate their work vectors at every call; these reuse a workspace, so a thermal step never
// touches the heap. Convergence test: ||b - A x||_2 <= tolerance * ||b||_2.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

namespace kiln::heat {

/// Row-major sparse matrix (CSR) of a heat system (W/K).
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

/// The same matrix in a fixed-width row layout for fast products: the diagonal apart, up to
/// `width` off-diagonal entries per row (padded with zeros, stored slot by slot across rows), and
/// the rare longer rows' surplus (the spherical grid's centre cell) as a short list. Built once per
/// operator.
class EllMatrix {
  public:
    /// Copies `a`; the width is the largest off-diagonal count of a row, capped at 8.
    void assign(const SparseMatrix& a);
    /// y = A x (no allocation).
    void multiply(const double* x, double* y) const;
    /// Number of rows.
    [[nodiscard]] Eigen::Index rows() const { return n_; }

  private:
    template <int W> void multiply_fixed(const double* x, double* y) const;
    Eigen::Index n_ = 0;
    int width_ = 0;
    std::vector<double> diag_;
    std::vector<int> col_;
    std::vector<double> val_;
    std::vector<int> extra_row_;
    std::vector<int> extra_col_;
    std::vector<double> extra_val_;
};

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
SolveStats conjugate_gradient(const EllMatrix& a, const Eigen::VectorXd& inv_diag,
                              const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance,
                              int max_iterations, KrylovWorkspace& ws);

/// Jacobi-preconditioned BiCGSTAB for a general `a`; `x` holds the initial guess and returns the
/// solution.
SolveStats bicgstab(const EllMatrix& a, const Eigen::VectorXd& inv_diag, const Eigen::VectorXd& b,
                    Eigen::VectorXd& x, double tolerance, int max_iterations, KrylovWorkspace& ws);

} // namespace kiln::heat
