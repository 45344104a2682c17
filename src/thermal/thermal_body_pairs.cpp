// ThermalSystem: gas-gap conduction and neighbour radiation of pairs with at least one body
// (clump, superquadric, polyhedron). The pair's gap and nearest points come from body_gap (GJK on
// the shapes); the sphere formulas of gas_conduction.hpp and radiation.hpp are then used with an
// equivalent radius per side (docs/theory/heat.md, "Gaps between bodies").

#include "thermal/thermal_system_detail.hpp"

#include "thermal/body_gap.hpp"
#include "thermal/body_shapes.hpp"

#include "geometry/superquadric.hpp"
#include "heat/contact_conduction.hpp"
#include "heat/gas_conduction.hpp"
#include "heat/radiation.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>
#include <variant>

namespace kiln::thermal {

using namespace detail;

namespace {

/// Smallest local radius of a superquadric in the gas gap, as a fraction of its smallest
/// half-axis: the contact laws' floor at a tip (kRadiusFloor in dynamics/body_contact.cpp).
constexpr double tip_radius_floor = 0.05;

} // namespace

std::vector<int> ThermalSystem::gap_patches(const dynamics::System& sys, const Record& r,
                                            std::size_t k, const Vec3& point, const Vec3& n,
                                            double radius) const {
    const ParticleStore& p = sys.particles();
    const Template& t = *templates_[static_cast<std::size_t>(r.templ)];
    // World -> body frame (a sphere's grid: its own orientation, or the world axes).
    const Quat inv = grid_orientation(p, k, r).conjugate();
    const Vec3 x = inv * (point - p.x[k]);
    const Vec3 nb = inv * n;
    std::vector<int> out = heat::contact_patches(*t.grid, x, nb, radius);
    if (!t.spherical) {
        widen_to_one_cell(*t.grid, t.capacity, t.full_cell_capacity, x, nb, out);
    }
    return out;
}

double ThermalSystem::equivalent_radius(const dynamics::System& sys, std::size_t k,
                                        bool by_area) const {
    if (sys.particles().shape[k] < 0) {
        return sys.particles().radius[k];
    }
    const auto [volume, area] = volume_area(sys, k);
    return by_area ? std::sqrt(area / (4.0 * std::numbers::pi))
                   : std::cbrt(3.0 * volume / (4.0 * std::numbers::pi));
}

double ThermalSystem::gas_gap_radius(const dynamics::System& sys, std::size_t k,
                                     const Vec3& point) const {
    const geometry::ShapeTemplate* t = shape_of(sys, k);
    const auto* sq = t != nullptr ? std::get_if<geometry::Superquadric>(&t->shape) : nullptr;
    if (sq == nullptr) {
        return equivalent_radius(sys, k, false);
    }
    // The contact laws' rule (dynamics/body_contact.cpp, effective_radius): principal curvatures
    // at the point, each raised to at least 1 / (bounding radius) (a flat face counts as curved
    // like the body's bounding sphere), R = 1 / sqrt(k1 k2), at least 5 % of the smallest
    // half-axis (a tip).
    const ParticleStore& p = sys.particles();
    const auto kp = sq->principal_curvatures(p.q[k].conjugate() * (point - p.x[k]));
    const double k_min = 1.0 / p.radius[k];
    const double floor = tip_radius_floor * sq->half_axes.minCoeff();
    const double r = 1.0 / std::sqrt(std::max(kp[0], k_min) * std::max(kp[1], k_min));
    return std::isfinite(r) ? std::max(r, floor) : floor;
}

void ThermalSystem::body_gas_gaps(const dynamics::System& sys, std::size_t i, std::size_t j,
                                  const ContactData& base, std::vector<ContactData>& out) const {
    out.clear();
    const double k_a = spec_.materials[static_cast<std::size_t>(base.a.material)].conductivity;
    const double k_b = spec_.materials[static_cast<std::size_t>(base.b.material)].conductivity;
    // Every element pair on its own, as contacts: a clump's members are spheres, so two clumps
    // exchange through each member pair within the cut-off.
    // (Element pairs proved beyond the reach of their largest equivalent spheres are left out:
    // the test below drops them.)
    for (const BodyGap& g : element_gaps(sys, i, j, spec_.gas.cutoff)) {
        // The radius of each side in the Cheng et al. formula: a sphere's own; a clump member's
        // (its exact local shape); a superquadric's local radius of curvature at the nearest
        // point; a polyhedron's volume-equivalent sphere (an approximation: a flat face has no
        // finite local radius).
        const double r_i =
            g.member_radius_i > 0.0 ? g.member_radius_i : gas_gap_radius(sys, i, g.point_i);
        const double r_j =
            g.member_radius_j > 0.0 ? g.member_radius_j : gas_gap_radius(sys, j, g.point_j);
        const double s = r_i + r_j + g.gap; // centre distance of the two equivalent spheres
        const double reach = 2.0 * spec_.gas.cutoff * (2.0 * r_i * r_j) / (r_i + r_j);
        if (!(s > std::abs(r_i - r_j)) || g.gap > reach) {
            continue;
        }
        ContactData d = base;
        d.conductance = heat::gas_gap_conductance(r_i, r_j, s, k_a, k_b, spec_.gas);
        if (!(d.conductance > 0.0)) {
            continue;
        }
        // Resolved sides take the heat on the surface cells under the lens around the gap's
        // nearest points.
        const double lens = heat::gas_gap_radius(r_i, r_j, s, spec_.gas);
        if (d.a.templ >= 0) {
            d.patches_a = gap_patches(sys, d.a, i, g.point_i, g.normal, lens);
        }
        if (d.b.templ >= 0) {
            d.patches_b = gap_patches(sys, d.b, j, g.point_j, -g.normal, lens);
        }
        out.push_back(std::move(d));
    }
}

bool ThermalSystem::body_radiation(const dynamics::System& sys, std::size_t i, std::size_t j,
                                   double e_i, double e_j, ContactData& d, double& view_area,
                                   double& area_i, double& area_j) const {
    const BodyGap g = body_gap(sys, i, j);
    // Each side as the sphere of its surface area (a sphere: itself), the two spheres as far
    // apart as the bodies' surfaces (touching bodies: just touching), and the sphere-pair view
    // factor of radiation.hpp for them.
    const double r_i = equivalent_radius(sys, i, true);
    const double r_j = equivalent_radius(sys, j, true);
    const double gap = std::max(0.0, g.gap);
    if (gap > 2.0 * spec_.radiation_cutoff * (2.0 * r_i * r_j) / (r_i + r_j)) {
        return false; // the spheres' rule H / R <= radiation_cutoff, H half the gap
    }
    const double s = r_i + r_j + gap;
    d.conductance = heat::radiative_coefficient(r_i, r_j, s, e_i, e_j);
    view_area = heat::pair_view_area(r_i, r_j, s);
    area_i = sphere_area(r_i);
    area_j = sphere_area(r_j);
    // Resolved sides exchange over the surface facing the partner: every cell whose outward
    // normal faces it within the bounding radius of the axis through the nearest point.
    const ParticleStore& p = sys.particles();
    if (d.a.templ >= 0) {
        d.patches_a = gap_patches(sys, d.a, i, g.point_i, g.normal, p.radius[i]);
    }
    if (d.b.templ >= 0) {
        d.patches_b = gap_patches(sys, d.b, j, g.point_j, -g.normal, p.radius[j]);
    }
    return true;
}

} // namespace kiln::thermal
