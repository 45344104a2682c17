// Stability at the extremes (issue 5): Bi from 1e-3 to 1e3 and thermal steps from 1e-6 s to 1e6 s,
// tiny (0.1 mm) and big (0.1 m) particles. The backward-Euler matrix is an M-matrix (positive
// diagonal, non-positive off-diagonals, diagonally dominant), so the discrete maximum principle
// holds: every temperature stays between the initial and the ambient value, without oscillation.
// Also: the Krylov solvers against Eigen's sparse LDL' on the same system (Eigen's own CG does
// not compile warning-free here: GCC 12 flags its AVX-512 reductions under -march=native).

#include "heat/cartesian_grid.hpp"
#include "heat/resolved_model.hpp"
#include "heat/spherical_grid.hpp"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <gtest/gtest.h>
#include <memory>
#include <vector>

namespace kiln::heat {
namespace {

/// max_i abs(a_i - b_i) / max_i abs(b_i), in plain loops (GCC 12 warns inside Eigen's AVX-512
/// reductions under -march=native).
double relative_difference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
    double d = 0.0;
    double s = 0.0;
    for (Eigen::Index i = 0; i < a.size(); ++i) {
        d = std::max(d, std::abs(a[i] - b[i]));
        s = std::max(s, std::abs(b[i]));
    }
    return d / s;
}

/// K: round-off of a solve relative to the 100 K range, with tolerance 1e-12.
constexpr double bound_slack = 1e-6;

TEST(Extremes, MaximumPrincipleForAllBiotNumbersStepsAndSizes) {
    const ThermalProperties p{1.0, 2000.0, 1000.0};
    for (const double size : {1e-4, 1e-1}) {
        const std::vector<std::shared_ptr<const ThermalGrid>> grids{
            std::make_shared<const ThermalGrid>(make_spherical_grid(size / 2.0, {6, 6, 12})),
            std::make_shared<const ThermalGrid>(make_cartesian_grid(
                Superquadric{Vec3(size / 2.0, size / 3.0, size / 4.0), 0.3, 1.5},
                {.cells_across = 10}))};
        for (const auto& g : grids) {
            for (const double bi : {1e-3, 1.0, 1e3}) {
                const std::vector<double> h{bi * p.conductivity / (size / 2.0)};
                for (const double dt : {1e-6, 1.0, 1e6}) {
                    ResolvedOperator op(g, p, dt, h, {SolverKind::cg, 1e-12, 20000});
                    std::vector<double> t(static_cast<std::size_t>(g->size()), 300.0);
                    double prev_mean = 300.0;
                    for (int s = 0; s < 5; ++s) {
                        EXPECT_TRUE(op.step(t, {.ambient = 400.0}).solve.converged);
                        const auto [lo, hi] = std::minmax_element(t.begin(), t.end());
                        EXPECT_GE(*lo, 300.0 - bound_slack)
                            << g->kind << " Bi " << bi << " dt " << dt;
                        EXPECT_LE(*hi, 400.0 + bound_slack)
                            << g->kind << " Bi " << bi << " dt " << dt;
                        // Heating is monotone: no step may cool the mean.
                        const double mean = mean_temperature(*g, t);
                        EXPECT_GE(mean, prev_mean - bound_slack);
                        prev_mean = mean;
                    }
                }
            }
        }
    }
}

TEST(Extremes, OwnKrylovSolversAgreeWithEigensLdlt) {
    const auto g = std::make_shared<const ThermalGrid>(make_cartesian_grid(
        Superquadric{Vec3(0.01, 0.008, 0.006), 0.5, 0.8}, {.cells_across = 10}));
    const std::vector<double> h{300.0};
    ResolvedOperator op(g, {1.0, 2000.0, 1000.0}, 1.0, h, {});
    const SparseMatrix& a = op.matrix();
    Eigen::VectorXd b(a.rows());
    for (Eigen::Index i = 0; i < b.size(); ++i) {
        b[i] = 1.0 + 0.01 * static_cast<double>(i % 17);
    }
    const Eigen::SparseMatrix<double> ac = a; // column-major copy for Eigen's solvers
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(ac);
    const Eigen::VectorXd ref = ldlt.solve(b);

    EllMatrix ell;
    ell.assign(a);
    Eigen::VectorXd inv_diag(a.rows());
    for (Eigen::Index i = 0; i < a.rows(); ++i) {
        inv_diag[i] = 1.0 / a.coeff(i, i);
    }
    KrylovWorkspace ws;
    ws.resize(a.rows());
    Eigen::VectorXd x_cg = Eigen::VectorXd::Zero(a.rows());
    Eigen::VectorXd x_bi = Eigen::VectorXd::Zero(a.rows());
    EXPECT_TRUE(conjugate_gradient(ell, inv_diag, b, x_cg, 1e-12, 5000, ws).converged);
    EXPECT_TRUE(bicgstab(ell, inv_diag, b, x_bi, 1e-12, 5000, ws).converged);
    // Relative: residual 1e-12 times a condition number below ~1e3 for this matrix.
    EXPECT_LT(relative_difference(x_cg, ref), 1e-9);
    EXPECT_LT(relative_difference(x_bi, ref), 1e-9);
}

} // namespace
} // namespace kiln::heat
