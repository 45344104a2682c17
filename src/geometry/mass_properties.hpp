#pragma once
// Mass properties of a rigid shape per unit density, and the move to the principal frame.

#include "core/types.hpp"

namespace kiln::geometry {

/// Volume and second moments of a solid per unit density, in the frame it was integrated in.
struct MassProperties {
    double volume = 0.0;                  ///< volume (m^3)
    Vec3 centroid = Vec3::Zero();         ///< centre of mass (m), integration frame
    Mat3 inertia_centroid = Mat3::Zero(); ///< inertia tensor about the centroid per unit density
                                          ///< (m^5), integration frame axes
};

/// Principal frame of a MassProperties: inertia_centroid = R diag(moments) R^T.
struct PrincipalFrame {
    Vec3 moments = Vec3::Zero();  ///< principal moments per unit density (m^5), ascending
    Mat3 axes = Mat3::Identity(); ///< columns = principal axes in the integration frame; det = +1
};

/// Eigen-decomposition of the centroidal inertia (ascending moments, right-handed axes, columns in
/// the integration frame). Equal moments (within 1e-9 of the largest) leave their axes to a
/// geometric rule instead of the round-off: all equal, the integration frame itself; two equal, the
/// distinct axis (sign: first component above 1e-6 positive) and the integration-frame axis least
/// aligned with it, made normal to it.
[[nodiscard]] PrincipalFrame principal_frame(const Mat3& inertia_centroid);

} // namespace kiln::geometry
