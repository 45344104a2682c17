#include "core/particle_store.hpp"

#include <algorithm>
#include <numbers>

namespace kiln {

std::size_t ParticleStore::add_sphere(std::int64_t pid, std::int32_t mat, double r, double density,
                                      const Vec3& pos, const Vec3& vel, const Vec3& ang_vel) {
    const double m = density * 4.0 / 3.0 * std::numbers::pi * r * r * r;
    id.push_back(pid);
    material.push_back(mat);
    radius.push_back(r);
    mass.push_back(m);
    inv_mass.push_back(1.0 / m);
    inv_inertia.push_back(1.0 / (0.4 * m * r * r));
    x.push_back(pos);
    v.push_back(vel);
    omega.push_back(ang_vel);
    force.emplace_back(Vec3::Zero());
    torque.emplace_back(Vec3::Zero());
    shape.push_back(-1);
    q.emplace_back(Quat::Identity());
    const double i_sphere = 0.4 * m * r * r;
    ang_mom.emplace_back(i_sphere * ang_vel);
    inertia.emplace_back(Vec3::Constant(i_sphere));
    return x.size() - 1;
}

std::size_t ParticleStore::add_body(std::int64_t pid, std::int32_t mat, std::int32_t shape_index,
                                    double r, double m, const Vec3& principal_inertia,
                                    const Vec3& pos, const Vec3& vel, const Quat& q0,
                                    const Vec3& ang_vel) {
    id.push_back(pid);
    material.push_back(mat);
    radius.push_back(r);
    mass.push_back(m);
    inv_mass.push_back(1.0 / m);
    // Zero: the sphere kick leaves omega alone; bodies are turned through (q, ang_mom).
    inv_inertia.push_back(0.0);
    x.push_back(pos);
    v.push_back(vel);
    omega.push_back(ang_vel);
    force.emplace_back(Vec3::Zero());
    torque.emplace_back(Vec3::Zero());
    shape.push_back(shape_index);
    const Quat qn = q0.normalized();
    q.push_back(qn);
    // L_world = R diag(I) R^T omega_world.
    const Mat3 rot = qn.toRotationMatrix();
    ang_mom.emplace_back(rot * (principal_inertia.asDiagonal() * (rot.transpose() * ang_vel)));
    inertia.push_back(principal_inertia);
    return x.size() - 1;
}

void ParticleStore::permute(const std::vector<std::uint32_t>& order) {
    {
        std::vector<std::int64_t> s;
        permute_array(id, order, s);
    }
    {
        std::vector<std::int32_t> s;
        permute_array(material, order, s);
    }
    std::vector<double> sd;
    permute_array(radius, order, sd);
    permute_array(mass, order, sd);
    permute_array(inv_mass, order, sd);
    permute_array(inv_inertia, order, sd);
    std::vector<Vec3> sv;
    permute_array(x, order, sv);
    permute_array(v, order, sv);
    permute_array(omega, order, sv);
    permute_array(force, order, sv);
    permute_array(torque, order, sv);
    permute_array(ang_mom, order, sv);
    permute_array(inertia, order, sv);
    // A store of spheres only has shape -1 and the identity orientation everywhere (see the
    // header): reordering those two arrays would change nothing.
    if (std::any_of(shape.begin(), shape.end(), [](std::int32_t s) { return s != -1; })) {
        std::vector<std::int32_t> s;
        permute_array(shape, order, s);
        std::vector<Quat> sq;
        permute_array(q, order, sq);
    }
}

void ParticleStore::clear_forces() {
    for (auto& f : force) {
        f.setZero();
    }
    for (auto& t : torque) {
        t.setZero();
    }
}

} // namespace kiln
