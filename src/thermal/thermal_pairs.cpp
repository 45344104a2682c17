// ThermalSystem: exchanges between neighbours that need not touch or that only touched briefly:
// gas-gap conduction and radiation between nearby particles (pairs with a body:
// thermal_body_pairs.cpp), and the heat of each impact (collision conduction).

#include "thermal/thermal_system_detail.hpp"

#include "thermal/body_shapes.hpp"

#include "core/error.hpp"
#include "heat/collision_conduction.hpp"
#include "heat/contact_conduction.hpp"
#include "heat/gas_conduction.hpp"
#include "heat/radiation.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

namespace kiln::thermal {

using namespace detail;

void ThermalSystem::sphere_patches(const ParticleStore& p, std::size_t k, const Record& r,
                                   const Vec3& n, double radius, std::vector<int>& out) const {
    if (r.templ < 0) {
        return;
    }
    const Vec3 nb = grid_orientation(p, k, r).conjugate() * n;
    out = heat::contact_patches(*templates_[static_cast<std::size_t>(r.templ)]->grid,
                                p.radius[k] * nb, nb, radius);
}

void ThermalSystem::add_gas_gaps(const dynamics::System& sys, std::vector<double>& g_sum,
                                 double& worst) {
    if (!(spec_.gas.conductivity > 0.0)) {
        return;
    }
    // Heated particles (radius 0 hides the others from the pair search): spheres by their radius,
    // bodies by their bounding radius, which finds every pair within reach of the equivalent
    // radii body_gas_gap uses (those are never larger). The search is a cell list of its own at
    // each thermal step, so the cut-off does not depend on the neighbour list's skin (by default
    // 0.2 R, well below the seed's gap cut-off of R).
    const ParticleStore& p = sys.particles();
    std::vector<double> r(p.size(), 0.0);
    for (std::size_t i = 0; i < p.size(); ++i) {
        if (by_id_[static_cast<std::size_t>(p.id[i])].slot >= 0) {
            r[i] = p.radius[i];
        }
    }
    long pairs = 0;
    const std::vector<heat::NearPair> near = heat::near_sphere_pairs(p.x, r, spec_.gas.cutoff);
    const auto base_of = [&](const heat::NearPair& np) {
        ContactData d;
        d.a = by_id_[static_cast<std::size_t>(p.id[np.i])];
        d.b = by_id_[static_cast<std::size_t>(p.id[np.j])];
        return d;
    };
    const auto with_body = [&](const heat::NearPair& np) {
        return p.shape[np.i] >= 0 || p.shape[np.j] >= 0;
    };
    // With several threads the exchanges of the pairs with a body (GJK gaps, patches) are found
    // first, in parallel: body_gas_gaps reads the state only, so each pair's answer is the one
    // of the loop below, which takes them in pair order (the same sums, the same bits).
    // (Only when a pair has a body: sphere pairs have nothing to find ahead.)
    std::vector<std::vector<ContactData>> ahead;
    std::vector<unsigned char> ready;
    if (threads_ > 1 && std::any_of(near.begin(), near.end(), with_body)) {
        ahead.resize(near.size());
        ready.assign(near.size(), 0);
        const auto n_near = static_cast<std::ptrdiff_t>(near.size());
#pragma omp parallel for num_threads(threads_) schedule(dynamic, 8)
        for (std::ptrdiff_t k = 0; k < n_near; ++k) {
            const heat::NearPair& np = near[static_cast<std::size_t>(k)];
            if (!with_body(np)) {
                continue;
            }
            try {
                body_gas_gaps(sys, np.i, np.j, base_of(np), ahead[static_cast<std::size_t>(k)]);
                ready[static_cast<std::size_t>(k)] = 1;
            } catch (...) { // left to the loop below, which runs it again in order
            }
        }
    }
    std::vector<ContactData> element_data; // the exchanges of one pair with a body
    for (std::size_t k = 0; k < near.size(); ++k) {
        const heat::NearPair& np = near[k];
        ContactData d = base_of(np);
        if (with_body(np)) {
            if (!ready.empty() && ready[k] != 0) {
                element_data.swap(ahead[k]);
            } else {
                body_gas_gaps(sys, np.i, np.j, d, element_data);
            }
            for (ContactData& e : element_data) {
                g_sum[np.i] += e.conductance;
                g_sum[np.j] += e.conductance;
                worst = std::max(worst, e.conductance / patch_capacity(e.a, e.patches_a) +
                                            e.conductance / patch_capacity(e.b, e.patches_b));
                data_.push_back(std::move(e));
                ++pairs;
            }
            continue;
        }
        const Vec3 between = p.x[np.j] - p.x[np.i];
        const double s = between.norm();
        const double k_a = spec_.materials[static_cast<std::size_t>(d.a.material)].conductivity;
        const double k_b = spec_.materials[static_cast<std::size_t>(d.b.material)].conductivity;
        d.conductance = heat::gas_gap_conductance(r[np.i], r[np.j], s, k_a, k_b, spec_.gas);
        if (!(d.conductance > 0.0)) {
            continue;
        }
        // Resolved spheres take the heat on the patches under the lens r <= r_sf around the
        // line of centres, turned into each sphere's grid frame.
        const Vec3 n = between / s;
        const double lens = heat::gas_gap_radius(r[np.i], r[np.j], s, spec_.gas);
        sphere_patches(p, np.i, d.a, n, lens, d.patches_a);
        sphere_patches(p, np.j, d.b, -n, lens, d.patches_b);
        g_sum[np.i] += d.conductance;
        g_sum[np.j] += d.conductance;
        worst = std::max(worst, d.conductance / patch_capacity(d.a, d.patches_a) +
                                    d.conductance / patch_capacity(d.b, d.patches_b));
        data_.push_back(std::move(d));
        ++pairs;
    }
    gas_pairs_ += pairs;
}

void ThermalSystem::add_radiation(const dynamics::System& sys, std::vector<double>& g_sum,
                                  double& worst) {
    const ParticleStore& p = sys.particles();
    const auto emissivity = [&](const Record& rec) {
        return spec_.materials[static_cast<std::size_t>(rec.material)].emissivity;
    };
    // Ambient view shares: the whole surface unless neighbours take part of it (below).
    lumped_view_.assign(lumped_.size(), 1.0);
    face_view_.assign(face_rate_.size(), 1.0);
    // Heated particles with an emissivity (others radius 0: left out of the search); bodies by
    // the larger of their bounding radius and area-equivalent radius (body_radiation's radius).
    std::vector<double> r(p.size(), 0.0);
    bool any = false;
    for (std::size_t i = 0; i < p.size(); ++i) {
        const Record& rec = by_id_[static_cast<std::size_t>(p.id[i])];
        if (rec.slot >= 0 && emissivity(rec) > 0.0) {
            r[i] = p.shape[i] < 0 ? p.radius[i]
                                  : std::max(p.radius[i], equivalent_radius(sys, i, true));
            any = true;
        }
    }
    if (!any) {
        return;
    }
    long pairs = 0;
    const std::vector<heat::NearPair> near =
        heat::near_sphere_pairs(p.x, r, spec_.radiation_cutoff);
    const auto base_of = [&](const heat::NearPair& np) {
        ContactData d;
        d.radiative = true;
        d.a = by_id_[static_cast<std::size_t>(p.id[np.i])];
        d.b = by_id_[static_cast<std::size_t>(p.id[np.j])];
        return d;
    };
    const auto with_body = [&](const heat::NearPair& np) {
        return p.shape[np.i] >= 0 || p.shape[np.j] >= 0;
    };
    // A pair with a body: its exchange (GJK gap, view, patches), found by body_radiation (which
    // reads the state only); with several threads first for every pair, in parallel, then taken
    // in pair order by the loop below (the same sums, the same bits).
    struct BodyView {
        ContactData d;
        double af = 0.0, area_i = 0.0, area_j = 0.0;
        bool exchanges = false;
        bool ready = false;
    };
    const auto body_view = [&](const heat::NearPair& np, BodyView& v) {
        v.d = base_of(np);
        v.exchanges = body_radiation(sys, np.i, np.j, emissivity(v.d.a), emissivity(v.d.b), v.d,
                                     v.af, v.area_i, v.area_j);
    };
    std::vector<BodyView> ahead;
    if (threads_ > 1 && std::any_of(near.begin(), near.end(), with_body)) {
        ahead.resize(near.size());
        const auto n_near = static_cast<std::ptrdiff_t>(near.size());
#pragma omp parallel for num_threads(threads_) schedule(dynamic, 8)
        for (std::ptrdiff_t k = 0; k < n_near; ++k) {
            const heat::NearPair& np = near[static_cast<std::size_t>(k)];
            BodyView& v = ahead[static_cast<std::size_t>(k)];
            if (!with_body(np)) {
                continue;
            }
            try {
                body_view(np, v);
                v.ready = true;
            } catch (...) { // left to the loop below, which runs it again in order
            }
        }
    }
    BodyView one; // the serial route's
    for (std::size_t k = 0; k < near.size(); ++k) {
        const heat::NearPair& np = near[k];
        ContactData d = base_of(np);
        if (with_body(np)) {
            BodyView* found = &one;
            if (!ahead.empty() && ahead[k].ready) {
                found = &ahead[k];
            } else {
                body_view(np, one);
            }
            BodyView& v = *found;
            if (!v.exchanges) {
                continue;
            }
            d = std::move(v.d);
            const double af = v.af;
            const double area_i = v.area_i;
            const double area_j = v.area_j;
            take_ambient_view(d.a, d.patches_a, af / area_i);
            take_ambient_view(d.b, d.patches_b, af / area_j);
            const double g =
                heat::radiative_conductance_bound(d.conductance, contact_temperature(d.a, d, false),
                                                  contact_temperature(d.b, d, true));
            g_sum[np.i] += g;
            g_sum[np.j] += g;
            worst = std::max(worst, g / patch_capacity(d.a, d.patches_a) +
                                        g / patch_capacity(d.b, d.patches_b));
            data_.push_back(std::move(d));
            ++pairs;
            continue;
        }
        const Vec3 between = p.x[np.j] - p.x[np.i];
        const double s = between.norm();
        // Overlapping (touching) spheres radiate as if just touching.
        const double apart = std::max(s, r[np.i] + r[np.j]);
        d.conductance =
            heat::radiative_coefficient(r[np.i], r[np.j], apart, emissivity(d.a), emissivity(d.b));
        // The pair's view area (A F)_ij, for the ambient shares below.
        const double af = heat::pair_view_area(r[np.i], r[np.j], apart);
        // Resolved spheres exchange over the hemisphere facing the partner (in each sphere's
        // grid frame): its area-weighted cell temperature, and the heat spread over it.
        const Vec3 n = between / s;
        sphere_patches(p, np.i, d.a, n, r[np.i], d.patches_a);
        sphere_patches(p, np.j, d.b, -n, r[np.j], d.patches_b);
        // What each sees of the partner, it does not see of the ambient (sum of view factors 1;
        // resolved: on the faces that exchange with it).
        take_ambient_view(d.a, d.patches_a, af / sphere_area(r[np.i]));
        take_ambient_view(d.b, d.patches_b, af / sphere_area(r[np.j]));
        // Lag limit with the linearised conductance at the hotter side's current temperature.
        const double g = heat::radiative_conductance_bound(
            d.conductance, contact_temperature(d.a, d, false), contact_temperature(d.b, d, true));
        g_sum[np.i] += g;
        g_sum[np.j] += g;
        worst = std::max(worst, g / patch_capacity(d.a, d.patches_a) +
                                    g / patch_capacity(d.b, d.patches_b));
        data_.push_back(std::move(d));
        ++pairs;
    }
    radiation_pairs_ += pairs;
    for (double& v : lumped_view_) {
        v = std::max(0.0, v); // a crowded bed (the centre estimate of F is low, so rare)
    }
    for (double& v : face_view_) {
        v = std::max(0.0, v);
    }
}

void ThermalSystem::take_ambient_view(const Record& r, const std::vector<int>& patches,
                                      double share) {
    if (r.templ < 0) {
        lumped_view_[static_cast<std::size_t>(r.slot)] -= share;
        return;
    }
    // Resolved: the faces that exchange with the partner give up their ambient view, uniformly
    // by area, so that their area sum is share * (total area), the same total as a uniform
    // reduction. A black face then loses to partner and ambient together what it would lose to
    // an ambient at the partner's temperature: the exchange is spread over the same faces by area.
    const std::vector<heat::BoundaryFace>& faces =
        templates_[static_cast<std::size_t>(r.templ)]->grid->boundary;
    double* view = face_view_.data() + face_offset_[static_cast<std::size_t>(r.slot)];
    double area = 0.0;
    for (const heat::BoundaryFace& f : faces) {
        area += f.area;
    }
    double facing = 0.0;
    for (const int b : patches) {
        facing += faces[static_cast<std::size_t>(b)].area;
    }
    if (!(facing > 0.0)) {
        for (double* v = view; v != view + faces.size(); ++v) {
            *v -= share; // no patch area (not expected): the whole surface, as a lumped particle
        }
        return;
    }
    const double drop = share * area / facing;
    for (const int b : patches) {
        view[b] -= drop;
    }
}

void ThermalSystem::add_collisions(const dynamics::System& sys, std::vector<double>& g_sum,
                                   double& worst) {
    if (onsets_.empty()) {
        return;
    }
    const ParticleStore& p = sys.particles();
    const auto& mats = sys.spec().materials;
    std::vector<std::int64_t> index(by_id_.size(), -1); // particle index by id (lag limit)
    for (std::size_t i = 0; i < p.size(); ++i) {
        index[static_cast<std::size_t>(p.id[i])] = static_cast<std::int64_t>(i);
    }
    const auto record_of = [&](std::int64_t id) {
        const auto k = static_cast<std::size_t>(id);
        return k < by_id_.size() && index[k] >= 0 ? by_id_[k] : Record{};
    };
    long taken = 0;
    for (const PendingImpact& impact : onsets_) {
        const dynamics::ContactOnset& e = impact.onset;
        ContactData d;
        d.a = record_of(e.id_i);
        if (d.a.slot < 0 || !(e.speed > 0.0)) {
            continue; // no heat model (or the particle left), or no approach
        }
        int mat_j = 0;
        if (e.wall >= 0) {
            // Analytic walls first, then the mesh walls (the onset's wall order).
            d.wall = true;
            const auto w = static_cast<std::size_t>(e.wall);
            const std::size_t n_walls = spec_.wall_temperature.size();
            const bool mesh = w >= n_walls;
            d.wall_temperature =
                mesh ? spec_.mesh_wall_temperature[w - n_walls] : spec_.wall_temperature[w];
            if (std::isnan(d.wall_temperature)) {
                continue; // adiabatic wall
            }
            mat_j =
                mesh ? sys.spec().mesh_walls[w - n_walls].material : sys.spec().walls[w].material;
        } else {
            d.b = record_of(e.id_j);
            if (d.b.slot < 0) {
                continue;
            }
            mat_j = d.b.material;
        }
        const auto side = [&](int m) {
            const MaterialHeat& h = spec_.materials[static_cast<std::size_t>(m)];
            return heat::ImpactSide{density_[static_cast<std::size_t>(m)], h.specific_heat,
                                    h.conductivity};
        };
        // The impact itself with the real moduli (real_youngs_modulus where given): duration and
        // contact radius are physical, as the static law's c maps its radius to the real one.
        const Material& mi = mats[static_cast<std::size_t>(d.a.material)];
        const Material& mj = mats[static_cast<std::size_t>(mat_j)];
        const double ei_real =
            spec_.materials[static_cast<std::size_t>(d.a.material)].real_youngs_modulus;
        const double ej_real = spec_.materials[static_cast<std::size_t>(mat_j)].real_youngs_modulus;
        const double e_eff =
            effective_modulus(ei_real > 0.0 ? ei_real : mi.youngs_modulus, mi.poisson_ratio,
                              ej_real > 0.0 ? ej_real : mj.youngs_modulus, mj.poisson_ratio);
        double energy = 0.0; // J into i per kelvin of T_j - T_i
        double rc = 0.0;
        try {
            const double tc = heat::hertz_impact_duration(e.m_eff, e_eff, e.r_eff, e.speed);
            rc = heat::hertz_impact_radius(e.m_eff, e_eff, e.r_eff, e.speed);
            energy = heat::impact_heat(side(d.a.material), side(mat_j), tc, rc, 0.0, 1.0);
        } catch (const InputError& err) {
            throw RunError(sys.step_count(),
                           fmt::format("{} (impact of particle {} at step {}, {:.3g} m/s)",
                                       err.what(), e.id_i, e.step, e.speed));
        }
        // Exchanged over this thermal step as a lagged conductance: with one sub-step the heat
        // moved is E (T_j - T_i) with the temperatures at the start of the step.
        d.conductance = energy / dt_;
        // Resolved particles: the patches under the impact's contact disc around the contact
        // point, in each body frame of the step that found it (after_step).
        const auto patches = [&](const Record& r, const double* xp, const double* np) {
            const Template& t = *templates_[static_cast<std::size_t>(r.templ)];
            const Vec3 x(xp[0], xp[1], xp[2]);
            const Vec3 nb(np[0], np[1], np[2]);
            std::vector<int> out = heat::contact_patches(*t.grid, x, nb, rc);
            if (!t.spherical) {
                widen_to_one_cell(*t.grid, t.capacity, t.full_cell_capacity, x, nb, out);
            }
            return out;
        };
        if (d.a.templ >= 0) {
            d.patches_a = patches(d.a, impact.x_i, impact.n_i);
        }
        if (!d.wall && d.b.templ >= 0) {
            d.patches_b = patches(d.b, impact.x_j, impact.n_j);
        }
        const auto ia = static_cast<std::size_t>(index[static_cast<std::size_t>(e.id_i)]);
        g_sum[ia] += d.conductance;
        double pair_rate = d.conductance / patch_capacity(d.a, d.patches_a);
        if (!d.wall) {
            g_sum[static_cast<std::size_t>(index[static_cast<std::size_t>(e.id_j)])] +=
                d.conductance;
            pair_rate += d.conductance / patch_capacity(d.b, d.patches_b);
        }
        worst = std::max(worst, pair_rate);
        data_.push_back(std::move(d));
        ++taken;
    }
    collisions_ += taken;
    onsets_.clear();
}
} // namespace kiln::thermal
