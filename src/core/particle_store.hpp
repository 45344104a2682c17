#pragma once
// Particles as structure-of-arrays: one contiguous array per field, all indexed by particle index.
// Indices change when the store is re-sorted for locality; `id` is the stable identity.

#include "core/types.hpp"

#include <cstdint>
#include <vector>

namespace kiln {

/// Per-particle state. Vectors are in the world frame, SI units. Spheres use the first block of
/// fields only; non-spherical bodies (shape >= 0) also carry an orientation and world angular
/// momentum, `radius` is then the bounding radius about the centre of mass and `omega` is derived
/// from (q, ang_mom) after every update.
struct ParticleStore {
    std::vector<std::int64_t> id;       ///< stable particle identity (never reused)
    std::vector<std::int32_t> material; ///< index into the material table
    std::vector<double> radius;         ///< sphere radius (m)
    std::vector<double> mass;           ///< mass (kg)
    std::vector<double> inv_mass;       ///< 1/mass (1/kg)
    std::vector<double>
        inv_inertia;          ///< 1/moment of inertia of a sphere, 1/(2/5 m r^2) (1/(kg m^2))
    std::vector<Vec3> x;      ///< centre position (m, world)
    std::vector<Vec3> v;      ///< velocity (m/s, world)
    std::vector<Vec3> omega;  ///< angular velocity (rad/s, world)
    std::vector<Vec3> force;  ///< total force of the current step (N, world)
    std::vector<Vec3> torque; ///< total torque about the centre (N m, world)
    std::vector<std::int32_t> shape; ///< shape template index of a body, -1 for a sphere
    std::vector<Quat> q;             ///< orientation, body -> world (identity for spheres)
    std::vector<Vec3> ang_mom;       ///< angular momentum (kg m^2/s, world); bodies only
    std::vector<Vec3> inertia;       ///< principal moments (kg m^2, body frame); bodies only

    /// Number of particles.
    [[nodiscard]] std::size_t size() const { return x.size(); }

    /// Appends a solid sphere of density `density` (kg/m^3); returns its index.
    std::size_t add_sphere(std::int64_t pid, std::int32_t mat, double r, double density,
                           const Vec3& pos, const Vec3& vel, const Vec3& ang_vel);

    /// Appends a rigid body of template `shape_index` with bounding radius r (m), mass (kg),
    /// principal inertia (kg m^2, body frame), orientation q0 (body -> world) and world angular
    /// velocity; returns its index.
    std::size_t add_body(std::int64_t pid, std::int32_t mat, std::int32_t shape_index, double r,
                         double m, const Vec3& principal_inertia, const Vec3& pos, const Vec3& vel,
                         const Quat& q0, const Vec3& ang_vel);

    /// Reorders every field so that new index k holds old index order[k].
    void permute(const std::vector<std::uint32_t>& order);

    /// Sets force and torque to zero for all particles.
    void clear_forces();
};

/// Applies `order` (new k <- old order[k]) to one array; used by every module owning per-particle
/// data.
template <class T>
void permute_array(std::vector<T>& a, const std::vector<std::uint32_t>& order,
                   std::vector<T>& scratch) {
    scratch.resize(order.size());
    for (std::size_t k = 0; k < order.size(); ++k) {
        scratch[k] = a[order[k]];
    }
    a.swap(scratch);
}

} // namespace kiln
