#pragma once
// Small vector types used everywhere. All quantities are SI; the frame (world or body) is stated
// where a vector is declared.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace kiln {

using Vec3 = Eigen::Vector3d;    ///< 3-vector, SI units, frame stated at use
using Mat3 = Eigen::Matrix3d;    ///< 3x3 matrix, frame stated at use
using Quat = Eigen::Quaterniond; ///< unit quaternion, body -> world rotation

/// Axis-aligned box [lo, hi] in the world frame (m).
struct Aabb {
    Vec3 lo = Vec3::Zero(); ///< lower corner (m)
    Vec3 hi = Vec3::Zero(); ///< upper corner (m)
    /// True when the point lies inside or on the box.
    [[nodiscard]] bool contains(const Vec3& p) const {
        return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
    }
    /// Edge lengths (m).
    [[nodiscard]] Vec3 extent() const { return hi - lo; }
};

} // namespace kiln
