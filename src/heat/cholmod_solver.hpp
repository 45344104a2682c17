#pragma once
// Adapter to SuiteSparse CHOLMOD (Chen, Davis, Hager & Rajamanickam 2008, ACM TOMS 35:22): the
// SPD heat matrix is analysed and factorised once (simplicial LDL', which limits.md Part B
// measured 2x faster than supernodal at ~1000 unknowns); each solve then reuses CHOLMOD's
// output and work buffers, so no allocation happens after the first solve.
// Without CHOLMOD (KILN_HAVE_CHOLMOD = 0) the class exists but cannot be constructed.

#include "heat/linear_solvers.hpp"

#include <memory>

namespace kiln::heat {

/// A factorisation of one SPD matrix, reused for every solve with that matrix.
class CholmodFactor {
  public:
    /// Analyses and factorises the SPD matrix `a` (W/K). Throws std::runtime_error if CHOLMOD
    /// reports the matrix is not positive definite.
    explicit CholmodFactor(const SparseMatrix& a);
    ~CholmodFactor();
    CholmodFactor(const CholmodFactor&) = delete;
    CholmodFactor& operator=(const CholmodFactor&) = delete;
    /// Solves A x = b; `b` and `x` have the matrix dimension. Not thread-safe (one factor per
    /// thread: CHOLMOD's common workspace is shared state).
    void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x);

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace kiln::heat
