#include "heat/linear_solvers.hpp"

#include <algorithm>
#include <cmath>

namespace kiln::heat {

void KrylovWorkspace::resize(Eigen::Index n) {
    for (Eigen::VectorXd* vec : {&r, &r0, &p, &v, &s, &t, &y, &z}) {
        vec->setZero(n);
    }
}

double dot(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
    double sum = 0.0;
    for (Eigen::Index i = 0; i < a.size(); ++i) {
        sum += a[i] * b[i];
    }
    return sum;
}

double norm(const Eigen::VectorXd& a) {
    return std::sqrt(dot(a, a));
}

void multiply(const SparseMatrix& a, const Eigen::VectorXd& x, Eigen::VectorXd& y) {
    const int* outer = a.outerIndexPtr();
    const int* inner = a.innerIndexPtr();
    const double* val = a.valuePtr();
    for (Eigen::Index i = 0; i < a.rows(); ++i) {
        double sum = 0.0;
        for (int k = outer[i]; k < outer[i + 1]; ++k) {
            sum += val[k] * x[inner[k]];
        }
        y[i] = sum;
    }
}

void EllMatrix::assign(const SparseMatrix& a) {
    n_ = a.rows();
    int widest = 0;
    for (Eigen::Index i = 0; i < n_; ++i) {
        int count = 0;
        for (SparseMatrix::InnerIterator it(a, i); it; ++it) {
            count += it.col() != i ? 1 : 0;
        }
        widest = std::max(widest, count);
    }
    width_ = std::min(widest, 8);
    const auto n = static_cast<std::size_t>(n_);
    diag_.assign(n, 0.0);
    col_.assign(n * static_cast<std::size_t>(width_), 0);
    val_.assign(n * static_cast<std::size_t>(width_), 0.0);
    extra_row_.clear();
    extra_col_.clear();
    extra_val_.clear();
    // Column-major slots: entry k of row i at k * n + i, so a vector of rows loads contiguously.
    for (Eigen::Index i = 0; i < n_; ++i) {
        const auto row = static_cast<std::size_t>(i);
        std::size_t k = 0;
        for (SparseMatrix::InnerIterator it(a, i); it; ++it) {
            if (it.col() == i) {
                diag_[row] = it.value();
            } else if (k < static_cast<std::size_t>(width_)) {
                col_[k * n + row] = static_cast<int>(it.col());
                val_[k * n + row] = it.value();
                ++k;
            } else {
                extra_row_.push_back(static_cast<int>(i));
                extra_col_.push_back(static_cast<int>(it.col()));
                extra_val_.push_back(it.value());
            }
        }
        for (; k < static_cast<std::size_t>(width_); ++k) {
            col_[k * n + row] = static_cast<int>(i); // padding: value 0
        }
    }
}

template <int W> void EllMatrix::multiply_fixed(const double* x, double* y) const {
    const int w = W > 0 ? W : width_;
    const double* v = val_.data();
    const int* c = col_.data();
    const double* d = diag_.data();
    // Vectorised across rows (contiguous slot loads, gathers of x); with W fixed the inner loop
    // unrolls completely.
#pragma omp simd
    for (Eigen::Index i = 0; i < n_; ++i) {
        double sum = d[i] * x[i];
        for (int k = 0; k < w; ++k) {
            sum += v[k * n_ + i] * x[c[k * n_ + i]];
        }
        y[i] = sum;
    }
}

void EllMatrix::multiply(const double* x, double* y) const {
    switch (width_) {
    case 6:
        multiply_fixed<6>(x, y);
        break;
    case 7:
        multiply_fixed<7>(x, y);
        break;
    case 8:
        multiply_fixed<8>(x, y);
        break;
    default:
        multiply_fixed<0>(x, y);
        break;
    }
    for (std::size_t e = 0; e < extra_row_.size(); ++e) {
        y[extra_row_[e]] += extra_val_[e] * x[extra_col_[e]];
    }
}

SolveStats conjugate_gradient(const EllMatrix& a, const Eigen::VectorXd& inv_diag,
                              const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance,
                              int max_iterations, KrylovWorkspace& ws) {
    // Vector loops are fused by hand (the x, r, z updates with r.z and r.r in one pass), which
    // halves the memory traffic of the expression form.
    SolveStats st;
    const Eigen::Index n = a.rows();
    const double* d = inv_diag.data();
    double* xp = x.data();
    double* r = ws.r.data();
    double* z = ws.z.data();
    double* p = ws.p.data();
    double* q = ws.t.data();
    double bb = 0.0;
    double rr = 0.0;
    double rz = 0.0;
    a.multiply(xp, q);
    for (Eigen::Index i = 0; i < n; ++i) {
        r[i] = b[i] - q[i];
        z[i] = d[i] * r[i];
        p[i] = z[i];
        bb += b[i] * b[i];
        rr += r[i] * r[i];
        rz += r[i] * z[i];
    }
    if (bb == 0.0) {
        x.setZero();
        st.converged = true;
        return st;
    }
    const double target2 = tolerance * tolerance * bb;
    while (rr > target2 && st.iterations < max_iterations) {
        a.multiply(p, q);
        double pq = 0.0;
        for (Eigen::Index i = 0; i < n; ++i) {
            pq += p[i] * q[i];
        }
        const double alpha = rz / pq;
        double rz_new = 0.0;
        rr = 0.0;
        for (Eigen::Index i = 0; i < n; ++i) {
            xp[i] += alpha * p[i];
            r[i] -= alpha * q[i];
            z[i] = d[i] * r[i];
            rz_new += r[i] * z[i];
            rr += r[i] * r[i];
        }
        ++st.iterations;
        const double beta = rz_new / rz;
        rz = rz_new;
        for (Eigen::Index i = 0; i < n; ++i) {
            p[i] = z[i] + beta * p[i];
        }
    }
    st.residual = std::sqrt(rr / bb);
    st.converged = rr <= target2;
    return st;
}

SolveStats bicgstab(const EllMatrix& a, const Eigen::VectorXd& inv_diag, const Eigen::VectorXd& b,
                    Eigen::VectorXd& x, double tolerance, int max_iterations, KrylovWorkspace& ws) {
    SolveStats st;
    const double b_norm = norm(b);
    if (b_norm == 0.0) {
        x.setZero();
        st.converged = true;
        return st;
    }
    const double target = tolerance * b_norm;
    a.multiply(x.data(), ws.t.data());
    ws.r = b - ws.t;
    double r_norm = norm(ws.r);
    if (r_norm <= target) {
        st.residual = r_norm / b_norm;
        st.converged = true;
        return st;
    }
    ws.r0 = ws.r;
    double rho = 1.0;
    double alpha = 1.0;
    double omega = 1.0;
    ws.v.setZero();
    ws.p.setZero();
    while (st.iterations < max_iterations) {
        double rho_new = dot(ws.r0, ws.r);
        if (std::abs(rho_new) < 1e-30 * dot(ws.r0, ws.r0)) {
            // r has become orthogonal to the shadow residual: restart from the current residual.
            ws.r0 = ws.r;
            rho_new = dot(ws.r, ws.r);
            ws.v.setZero();
            ws.p.setZero();
            rho = alpha = omega = 1.0;
        }
        const double beta = (rho_new / rho) * (alpha / omega);
        rho = rho_new;
        ws.p = ws.r + beta * (ws.p - omega * ws.v);
        ws.y = inv_diag.cwiseProduct(ws.p);
        a.multiply(ws.y.data(), ws.v.data());
        alpha = rho / dot(ws.r0, ws.v);
        ws.s = ws.r - alpha * ws.v;
        ++st.iterations;
        if (norm(ws.s) <= target) {
            x += alpha * ws.y;
            r_norm = norm(ws.s);
            st.converged = true;
            break;
        }
        ws.z = inv_diag.cwiseProduct(ws.s);
        a.multiply(ws.z.data(), ws.t.data());
        const double tt = dot(ws.t, ws.t);
        omega = tt > 0.0 ? dot(ws.t, ws.s) / tt : 0.0;
        x += alpha * ws.y + omega * ws.z;
        ws.r = ws.s - omega * ws.t;
        r_norm = norm(ws.r);
        if (r_norm <= target) {
            st.converged = true;
            break;
        }
        if (omega == 0.0) {
            break;
        }
    }
    st.residual = r_norm / b_norm;
    return st;
}

} // namespace kiln::heat
