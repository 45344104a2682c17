// Principal frame of a centroidal inertia tensor.

#include "geometry/mass_properties.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace kiln::geometry {

namespace {

/// Principal moments closer than this fraction of the largest count as equal: their axes are then
/// not defined by the tensor (any frame of the degenerate subspace is principal, and the one an
/// eigen-solver returns follows the round-off of the integration, i.e. the vertex and face order).
constexpr double kDegenerateMoments = 1e-9;

/// A component of a unit vector above this size fixes its sign (robust against round-off).
constexpr double kSignComponent = 1e-6;

/// u with the sign that makes its first component larger than kSignComponent in size positive.
Vec3 fixed_sign(const Vec3& u) {
    for (int k = 0; k < 3; ++k) {
        if (std::abs(u[k]) > kSignComponent) {
            return u[k] > 0.0 ? u : Vec3(-u);
        }
    }
    return u;
}

/// Unit vector normal to the unit vector e: the input-frame axis least aligned with e (the first of
/// nearly equal ones) with its e-part removed, as a geometric tie-break.
Vec3 normal_from_input_axes(const Vec3& e) {
    const double least = e.cwiseAbs().minCoeff();
    int k = 0;
    while (std::abs(e[k]) > least + kSignComponent) {
        ++k;
    }
    const Vec3 axis = Vec3::Unit(k);
    return (axis - axis.dot(e) * e).normalized();
}

} // namespace

PrincipalFrame principal_frame(const Mat3& inertia_centroid) {
    const Eigen::SelfAdjointEigenSolver<Mat3> es(0.5 *
                                                 (inertia_centroid + inertia_centroid.transpose()));
    PrincipalFrame f;
    f.moments = es.eigenvalues(); // ascending
    f.axes = es.eigenvectors();
    const double tol = kDegenerateMoments * std::abs(f.moments[2]);
    const bool low_pair = f.moments[1] - f.moments[0] <= tol;
    const bool high_pair = f.moments[2] - f.moments[1] <= tol;
    if (low_pair && high_pair) {
        // Isotropic (cube, regular polyhedra): every frame is principal; keep the input frame.
        f.axes = Mat3::Identity();
    } else if (low_pair || high_pair) {
        // Axisymmetric inertia: only the distinct axis is defined; the two others are taken from
        // the input frame so that the result does not depend on the round-off.
        const int distinct = low_pair ? 2 : 0;
        const Vec3 e = fixed_sign(f.axes.col(distinct).normalized());
        const Vec3 u = normal_from_input_axes(e);
        if (low_pair) {
            f.axes.col(0) = u;
            f.axes.col(1) = e.cross(u);
            f.axes.col(2) = e;
        } else {
            f.axes.col(0) = e;
            f.axes.col(1) = u;
            f.axes.col(2) = e.cross(u);
        }
    } else if (f.axes.determinant() < 0.0) {
        f.axes.col(2) *= -1.0;
    }
    return f;
}

} // namespace kiln::geometry
