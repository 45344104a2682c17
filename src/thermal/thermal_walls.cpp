// ThermalSystem: gas-gap conduction and radiation between heated particles and walls at a
// prescribed temperature (plane, cylinder and mesh walls), which otherwise exchange heat only by
// contact and collision conduction. Theory: docs/theory/heat.md, "Gaps and radiation to walls".
//
// Every wall is seen by a particle through one plane: a plane wall itself, the tangent plane of a
// cylinder at the point nearest the particle's centre, or the plane of a mesh wall's nearest
// feature (face, edge or vertex; one per mesh wall and particle). The particle's elements (a
// sphere, a clump's members, a convex body) find their gap to that plane (body_gap.hpp).

#include "thermal/thermal_system_detail.hpp"

#include "thermal/body_gap.hpp"

#include "heat/gas_conduction.hpp"
#include "heat/radiation.hpp"

#include <algorithm>
#include <cmath>
#include <utility>
#include <variant>
#include <vector>

namespace kiln::thermal {

using namespace detail;

namespace {

/// A wall as one particle sees it: a plane at the wall's temperature.
struct WallPlane {
    Vec3 point = Vec3::Zero();   ///< a point of the plane (m, world)
    Vec3 normal = Vec3::UnitZ(); ///< unit normal towards the particle (world)
    double temperature = 0;      ///< K
    int material = 0;            ///< material index of the wall
};

/// The view factor of a sphere to an infinite plane at any distance: a ray leaving the convex
/// sphere meets the plane exactly when it points to the plane's side, and the sphere's emission
/// is symmetric under the reflection through its centre plane parallel to the wall: F = 1/2.
constexpr double plane_view_factor = 0.5;

} // namespace

void ThermalSystem::add_wall_exchanges(const dynamics::System& sys, std::vector<double>& g_sum,
                                       double& worst) {
    const bool gas = spec_.wall_gas && spec_.gas.conductivity > 0.0;
    const bool rad = spec_.wall_radiation;
    if (!gas && !rad) {
        return;
    }
    const ParticleStore& p = sys.particles();
    const auto& walls = sys.spec().walls;
    const auto& meshes = sys.spec().mesh_walls;
    std::vector<geometry::MeshContact> hits;
    std::vector<WallPlane> planes;
    long gas_exchanges = 0;
    long radiating = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        const Record rec = by_id_[static_cast<std::size_t>(p.id[i])];
        if (rec.slot < 0) {
            continue;
        }
        const MaterialHeat& mh = spec_.materials[static_cast<std::size_t>(rec.material)];
        const bool radiates = rad && mh.emissivity > 0.0;
        if (!gas && !radiates) {
            continue;
        }
        // Radii: the bounding radius bounds every element's distance from the centre and every
        // gas-gap radius (gas_gap_radius); the area-equivalent radius is the radiation's (as for
        // body pairs).
        const double r_bound = p.radius[i];
        const double r_area = equivalent_radius(sys, i, true);
        const double reach =
            std::max(gas ? spec_.gas.cutoff * r_bound : 0.0,
                     radiates ? spec_.radiation_cutoff * std::max(r_bound, r_area) : 0.0);
        // The walls at a temperature within reach, each as one plane.
        planes.clear();
        for (std::size_t w = 0; w < walls.size(); ++w) {
            const double tw = spec_.wall_temperature[w];
            if (std::isnan(tw)) {
                continue;
            }
            WallPlane pl;
            pl.temperature = tw;
            pl.material = walls[w].material;
            if (const auto* plane = std::get_if<dynamics::PlaneWall>(&walls[w].shape)) {
                pl.point = plane->point;
                pl.normal = plane->normal;
            } else {
                // A cylinder (particles inside): its tangent plane at the point nearest the
                // centre, normal towards the axis.
                const auto& cyl = std::get<dynamics::CylinderWall>(walls[w].shape);
                Vec3 rho = p.x[i] - cyl.axis_point;
                rho -= rho.dot(cyl.axis) * cyl.axis;
                const double dist = rho.norm();
                if (!(dist > 0.0)) {
                    continue; // on the axis: no nearest point (and far from the wall)
                }
                pl.normal = -rho / dist;
                pl.point = p.x[i] + (cyl.radius - dist) * (rho / dist);
            }
            if ((p.x[i] - pl.point).dot(pl.normal) - r_bound <= reach) {
                planes.push_back(pl);
            }
        }
        for (std::size_t m = 0; m < meshes.size(); ++m) {
            const double tw = spec_.mesh_wall_temperature[m];
            if (std::isnan(tw)) {
                continue;
            }
            // The bounding sphere grown by the reach finds the features within reach; the
            // nearest (deepest) one stands for the wall.
            meshes[m].mesh->sphere_contacts(p.x[i], r_bound + reach, hits);
            if (hits.empty()) {
                continue;
            }
            const auto nearest =
                std::max_element(hits.begin(), hits.end(),
                                 [](const geometry::MeshContact& a,
                                    const geometry::MeshContact& b) { return a.depth < b.depth; });
            planes.push_back({nearest->point, nearest->normal, tw, meshes[m].material});
        }
        for (const WallPlane& pl : planes) {
            const std::vector<PlaneGap> gaps = plane_gaps(sys, i, pl.point, pl.normal);
            const Vec3 towards = -pl.normal; // from the particle to the wall
            if (gas) {
                // Cheng et al.'s tubes between the element and its mirror image in the wall, whose
                // mid-plane is the wall surface at T_w: twice the pair conductance of two equal
                // spheres 2 (R + gap) apart, whose half gap H_g is the wall gap (so the pair's
                // cut-off H_g / R applies to gap / R). Sphere elements by their radius, convex
                // bodies by gas_gap_radius at their nearest point (a superquadric's local radius
                // of curvature, a polyhedron's volume-equivalent sphere), gap 0 when overlapping.
                for (const PlaneGap& e : gaps) {
                    const bool sphere = e.member_radius > 0.0;
                    const double r = sphere ? e.member_radius : gas_gap_radius(sys, i, e.point);
                    const double gap = sphere ? e.gap : std::max(0.0, e.gap);
                    if (!(gap > -r) || gap > spec_.gas.cutoff * r) {
                        continue; // centre behind the wall, or beyond the cut-off
                    }
                    const double s = 2.0 * (r + gap);
                    ContactData d;
                    d.a = rec;
                    d.wall = true;
                    d.wall_temperature = pl.temperature;
                    d.conductance = 2.0 * heat::gas_gap_conductance(r, r, s, mh.conductivity,
                                                                    mh.conductivity, spec_.gas);
                    if (!(d.conductance > 0.0)) {
                        continue;
                    }
                    if (rec.templ >= 0) {
                        d.patches_a = gap_patches(sys, rec, i, e.point, towards,
                                                  heat::gas_gap_radius(r, r, s, spec_.gas));
                    }
                    g_sum[i] += d.conductance;
                    worst = std::max(worst, d.conductance / patch_capacity(rec, d.patches_a));
                    data_.push_back(std::move(d));
                    ++gas_exchanges;
                }
            }
            const double e_w = spec_.materials[static_cast<std::size_t>(pl.material)].emissivity;
            if (!radiates || !(e_w > 0.0)) {
                continue;
            }
            // Radiation: the particle as the sphere of its surface area A facing the plane
            // (F = 1/2 at any distance, within radiation_cutoff of the nearest element), direct
            // exchange of two grey surfaces without the reflections between them:
            // Q = e_i e_w sigma A F (T_w^4 - T^4) (exact for black surfaces).
            const auto nearest = std::min_element(
                gaps.begin(), gaps.end(),
                [](const PlaneGap& a, const PlaneGap& b) { return a.gap < b.gap; });
            if (std::max(0.0, nearest->gap) > spec_.radiation_cutoff * r_area) {
                continue;
            }
            ContactData d;
            d.a = rec;
            d.wall = true;
            d.radiative = true;
            d.wall_temperature = pl.temperature;
            const double area = sphere_area(r_area); // the body's true area
            d.conductance = mh.emissivity * e_w * heat::stefan_boltzmann * area * plane_view_factor;
            if (rec.templ >= 0) {
                // The surface facing the wall: every cell whose outward normal faces it within
                // the bounding radius of the axis through the nearest point.
                d.patches_a = gap_patches(sys, rec, i, nearest->point, towards, r_bound);
            }
            // What the particle sees of the wall it does not see of the ambient (resolved: on
            // the faces that exchange with the wall).
            take_ambient_view(rec, d.patches_a, plane_view_factor);
            const double g = heat::radiative_conductance_bound(
                d.conductance, contact_temperature(rec, d, false), pl.temperature);
            g_sum[i] += g;
            worst = std::max(worst, g / patch_capacity(rec, d.patches_a));
            data_.push_back(std::move(d));
            ++radiating;
        }
    }
    wall_gas_gaps_ += gas_exchanges;
    wall_radiation_ += radiating;
    for (double& v : lumped_view_) {
        v = std::max(0.0, v);
    }
    for (double& v : face_view_) {
        v = std::max(0.0, v);
    }
}

} // namespace kiln::thermal
