#include "heat/linear_solvers.hpp"

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

SolveStats conjugate_gradient(const SparseMatrix& a, const Eigen::VectorXd& inv_diag,
                              const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance,
                              int max_iterations, KrylovWorkspace& ws) {
    // Loops are fused by hand (three passes per iteration: A p with p.Ap; the x, r, z updates with
    // r.z and r.r; the new direction), which halves the memory traffic of the expression form.
    SolveStats st;
    const Eigen::Index n = a.rows();
    const int* outer = a.outerIndexPtr();
    const int* inner = a.innerIndexPtr();
    const double* val = a.valuePtr();
    const double* d = inv_diag.data();
    double* xp = x.data();
    double* r = ws.r.data();
    double* z = ws.z.data();
    double* p = ws.p.data();
    double* q = ws.t.data();
    double bb = 0.0;
    double rr = 0.0;
    double rz = 0.0;
    for (Eigen::Index i = 0; i < n; ++i) {
        double sum = 0.0;
        for (int k = outer[i]; k < outer[i + 1]; ++k) {
            sum += val[k] * xp[inner[k]];
        }
        r[i] = b[i] - sum;
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
        double pq = 0.0;
        for (Eigen::Index i = 0; i < n; ++i) {
            double sum = 0.0;
            for (int k = outer[i]; k < outer[i + 1]; ++k) {
                sum += val[k] * p[inner[k]];
            }
            q[i] = sum;
            pq += p[i] * sum;
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

SolveStats bicgstab(const SparseMatrix& a, const Eigen::VectorXd& inv_diag,
                    const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance,
                    int max_iterations, KrylovWorkspace& ws) {
    SolveStats st;
    const double b_norm = norm(b);
    if (b_norm == 0.0) {
        x.setZero();
        st.converged = true;
        return st;
    }
    const double target = tolerance * b_norm;
    multiply(a, x, ws.t);
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
        multiply(a, ws.y, ws.v);
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
        multiply(a, ws.z, ws.t);
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
