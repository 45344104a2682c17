// Principal frame of a centroidal inertia tensor.

#include "geometry/mass_properties.hpp"

#include <Eigen/Eigenvalues>

namespace kiln::geometry {

PrincipalFrame principal_frame(const Mat3& inertia_centroid) {
    const Eigen::SelfAdjointEigenSolver<Mat3> es(0.5 *
                                                 (inertia_centroid + inertia_centroid.transpose()));
    PrincipalFrame f;
    f.moments = es.eigenvalues(); // ascending
    f.axes = es.eigenvectors();
    if (f.axes.determinant() < 0.0) {
        f.axes.col(2) *= -1.0;
    }
    return f;
}

} // namespace kiln::geometry
