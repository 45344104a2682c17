#include "heat/cholmod_solver.hpp"

#if KILN_HAVE_CHOLMOD
#include <cholmod.h>
#endif
#include <cstring>
#include <stdexcept>
#include <vector>

namespace kiln::heat {

#if KILN_HAVE_CHOLMOD

struct CholmodFactor::Impl {
    cholmod_common common{};
    cholmod_factor* factor = nullptr;
    cholmod_dense* x = nullptr; // output, reused by cholmod_solve2
    cholmod_dense* y = nullptr; // workspace
    cholmod_dense* e = nullptr; // workspace
    cholmod_dense b{};          // header over the caller's right-hand side
    long n = 0;
};

CholmodFactor::CholmodFactor(const SparseMatrix& a) : impl_(std::make_unique<Impl>()) {
    Impl& m = *impl_;
    cholmod_start(&m.common);
    m.common.supernodal = CHOLMOD_SIMPLICIAL;
    m.common.final_ll = 0;
    m.n = a.rows();
    // CHOLMOD wants compressed columns; for a symmetric matrix the rows of the upper triangle of
    // the CSR matrix are the columns of the lower triangle (stype = -1).
    std::vector<int> colp;
    std::vector<int> rowi;
    std::vector<double> val;
    colp.reserve(static_cast<std::size_t>(m.n + 1));
    colp.push_back(0);
    for (int i = 0; i < a.rows(); ++i) {
        for (SparseMatrix::InnerIterator it(a, i); it; ++it) {
            if (it.col() >= i) {
                rowi.push_back(static_cast<int>(it.col()));
                val.push_back(it.value());
            }
        }
        colp.push_back(static_cast<int>(rowi.size()));
    }
    cholmod_sparse s{};
    s.nrow = static_cast<size_t>(m.n);
    s.ncol = static_cast<size_t>(m.n);
    s.nzmax = rowi.size();
    s.p = colp.data();
    s.i = rowi.data();
    s.x = val.data();
    s.stype = -1;
    s.itype = CHOLMOD_INT;
    s.xtype = CHOLMOD_REAL;
    s.dtype = CHOLMOD_DOUBLE;
    s.sorted = 1;
    s.packed = 1;
    m.factor = cholmod_analyze(&s, &m.common);
    if (m.factor == nullptr || !cholmod_factorize(&s, m.factor, &m.common) ||
        m.common.status != CHOLMOD_OK) {
        const int status = m.common.status;
        cholmod_free_factor(&m.factor, &m.common);
        cholmod_finish(&m.common);
        throw std::runtime_error("heat: CHOLMOD factorisation failed (status " +
                                 std::to_string(status) + "); the heat matrix must be SPD");
    }
    m.b.nrow = static_cast<size_t>(m.n);
    m.b.ncol = 1;
    m.b.nzmax = static_cast<size_t>(m.n);
    m.b.d = static_cast<size_t>(m.n);
    m.b.xtype = CHOLMOD_REAL;
    m.b.dtype = CHOLMOD_DOUBLE;
}

CholmodFactor::~CholmodFactor() {
    Impl& m = *impl_;
    cholmod_free_dense(&m.x, &m.common);
    cholmod_free_dense(&m.y, &m.common);
    cholmod_free_dense(&m.e, &m.common);
    cholmod_free_factor(&m.factor, &m.common);
    cholmod_finish(&m.common);
}

void CholmodFactor::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
    Impl& m = *impl_;
    m.b.x = const_cast<double*>(b.data()); // CHOLMOD reads b only
    cholmod_solve2(CHOLMOD_A, m.factor, &m.b, nullptr, &m.x, nullptr, &m.y, &m.e, &m.common);
    std::memcpy(x.data(), m.x->x, static_cast<std::size_t>(m.n) * sizeof(double));
}

#else

// Built without CHOLMOD: ResolvedOperator refuses SolverKind::cholmod with an InputError before it
// would construct a factor; these definitions only complete the type.
struct CholmodFactor::Impl {};

CholmodFactor::CholmodFactor(const SparseMatrix& /*a*/) {
    throw std::logic_error("heat: kiln was built without CHOLMOD");
}

CholmodFactor::~CholmodFactor() = default;

void CholmodFactor::solve(const Eigen::VectorXd& /*b*/, Eigen::VectorXd& /*x*/) {
}

#endif

} // namespace kiln::heat
