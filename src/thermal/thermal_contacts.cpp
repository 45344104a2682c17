// ThermalSystem: contact conduction (particle-particle and particle-wall), the patches under
// each exchange, and the lagged heat rates of every exchange of a thermal step.

#include "thermal/thermal_system_detail.hpp"

#include "thermal/body_shapes.hpp"

#include "heat/contact_conduction.hpp"

#include <algorithm>
#include <cmath>

namespace kiln::thermal {

using namespace detail;

double ThermalSystem::patch_weight(const Template& t, int patch) const {
    const heat::BoundaryFace& face = t.grid->boundary[static_cast<std::size_t>(patch)];
    // Spherical grids: by area (uniform flux over the contact patches, validation 24). Cartesian
    // cut cells: by cell heat capacity, so every patch cell warms at the same rate; by area a
    // sliver cut cell (volume fraction ~1e-4, but a full share of the surface) would receive heat
    // it cannot hold within one lagged step (found by validation 26).
    return t.spherical ? face.area : t.capacity[static_cast<std::size_t>(face.cell)];
}

void ThermalSystem::split_weights(const Template& t, std::span<const double> field,
                                  const std::vector<int>& patches, double q, double t_other,
                                  std::vector<double>& w) const {
    w.resize(patches.size());
    double total = 0.0;
    if (!t.spherical) {
        // Each cell by its capacity times how far it is from the partner's temperature on the
        // side the heat flows: a receiving cell by C_k max(0, T_other - T_k), a giving one by
        // C_k max(0, T_k - T_other). With the contact temperature the capacity mean of the same
        // cells, the drop of cell k's distance to T_other per sub-step is then at most
        // dt H / sum C_m (<= the lag limit's 0.5) times that distance: no cell crosses T_other,
        // so a donor cell at the scene's lowest temperature gives nothing (validation 29's dip).
        const double sign = q > 0.0 ? 1.0 : -1.0;
        for (std::size_t k = 0; k < patches.size(); ++k) {
            const auto cell = static_cast<std::size_t>(
                t.grid->boundary[static_cast<std::size_t>(patches[k])].cell);
            w[k] = t.capacity[cell] * std::max(0.0, sign * (t_other - field[cell]));
            total += w[k];
        }
    }
    if (!(total > 0.0)) {
        // Spherical grids (uniform flux by area: their contact temperature is the undisturbed
        // one, not a mean of these cells), or no cell on the flowing side (q = 0): as before.
        for (std::size_t k = 0; k < patches.size(); ++k) {
            w[k] = patch_weight(t, patches[k]);
        }
    }
}

double ThermalSystem::patch_capacity(const Record& r, const std::vector<int>& patches) const {
    if (r.templ < 0) {
        return lumped_capacity_[static_cast<std::size_t>(r.slot)];
    }
    const Template& t = *templates_[static_cast<std::size_t>(r.templ)];
    double c = 0.0;
    for (const int b : patches) {
        c += t.capacity[static_cast<std::size_t>(
            t.grid->boundary[static_cast<std::size_t>(b)].cell)];
    }
    return c;
}

double ThermalSystem::contact_temperature(const Record& r, const ContactData& c,
                                          bool side_b) const {
    if (r.templ < 0) {
        return lumped_[static_cast<std::size_t>(r.slot)];
    }
    const Template& t = *templates_[static_cast<std::size_t>(r.templ)];
    const std::span<const double> f = pool_.field(r.slot);
    const std::vector<int>& patches = side_b ? c.patches_b : c.patches_a;
    if (t.spherical && !c.radiative) {
        // The seed's undisturbed temperature (Inv. V L1965) along the rows under the contact.
        return heat::undisturbed_temperature(*t.grid, t.res, f, patches);
    }
    // Cartesian grids have no radial rows: the node temperature of the patch cells under the
    // contact, weighted as the heat is spread (by capacity), i.e. their mean heat content.
    double sum = 0.0;
    double weight = 0.0;
    for (const int b : patches) {
        const double w = patch_weight(t, b);
        sum += w * f[static_cast<std::size_t>(t.grid->boundary[static_cast<std::size_t>(b)].cell)];
        weight += w;
    }
    return sum / weight;
}

void ThermalSystem::add_contacts(const dynamics::System& sys, std::vector<double>& g_sum,
                                 double& worst) {
    const ParticleStore& p = sys.particles();
    const auto& mats = sys.spec().materials;
    sys.collect_contacts(contacts_);
    // The exchange of one contact (conductance, patches), from the state only; false when the
    // contact exchanges nothing (a side without heat, a wall without a temperature).
    const auto exchange = [&](const dynamics::ContactRecord& rec, ContactData& d) {
        d.wall = rec.wall;
        d.a = by_id_[static_cast<std::size_t>(p.id[rec.i])];
        if (d.a.slot < 0) {
            return false;
        }
        const double ri = p.radius[rec.i];
        const Material& mi = mats[static_cast<std::size_t>(d.a.material)];
        const MaterialHeat& hi = spec_.materials[static_cast<std::size_t>(d.a.material)];
        int mat_j = 0;
        double rj = 0.0;
        if (rec.wall) {
            // Analytic walls first, then the mesh walls (the contact keys' order).
            const std::size_t n_walls = spec_.wall_temperature.size();
            const bool mesh = rec.j >= n_walls;
            d.wall_temperature =
                mesh ? spec_.mesh_wall_temperature[rec.j - n_walls] : spec_.wall_temperature[rec.j];
            if (std::isnan(d.wall_temperature)) {
                return false;
            }
            mat_j = mesh ? sys.spec().mesh_walls[rec.j - n_walls].material
                         : sys.spec().walls[rec.j].material;
        } else {
            d.b = by_id_[static_cast<std::size_t>(p.id[rec.j])];
            if (d.b.slot < 0) {
                return false;
            }
            mat_j = d.b.material;
            rj = p.radius[rec.j];
        }
        const Material& mj = mats[static_cast<std::size_t>(mat_j)];
        const MaterialHeat& hj = spec_.materials[static_cast<std::size_t>(mat_j)];
        // Bodies (element contacts) always use the Hertz radius: the lens rule needs sphere radii.
        const bool body_i = p.shape[rec.i] >= 0;
        const bool body_j = !rec.wall && p.shape[rec.j] >= 0;
        double rc = 0.0;
        if (spec_.contact_radius == ContactRadius::hertz || body_i || body_j) {
            rc = std::sqrt(rec.r_eff * rec.overlap);
        } else if (rec.wall) {
            // Intersection circle of a sphere with a plane at depth delta.
            rc = std::sqrt(std::max(0.0, rec.overlap * (2.0 * ri - rec.overlap)));
        } else {
            rc = heat::lens_contact_radius(rec.overlap, ri, rj);
        }
        // Zhou et al.'s c = (E*_sim / E*_real)^(1/5) (seed Inv. V eq. 12) with the pair's
        // effective moduli; 1 when both materials use their real modulus.
        const double ei = hi.real_youngs_modulus > 0.0 ? hi.real_youngs_modulus : mi.youngs_modulus;
        const double ej = hj.real_youngs_modulus > 0.0 ? hj.real_youngs_modulus : mj.youngs_modulus;
        const double correction = heat::softened_modulus_correction(
            effective_modulus(mi.youngs_modulus, mi.poisson_ratio, mj.youngs_modulus,
                              mj.poisson_ratio),
            effective_modulus(ei, mi.poisson_ratio, ej, mj.poisson_ratio));
        d.conductance =
            heat::static_contact_conductance(hi.conductivity, hj.conductivity, rc, correction);
        // Patches under the contact disc, in each body frame: world offsets and normals turned
        // by q^-1 (world -> body; a resolved sphere's grid has its own orientation).
        const auto patches = [&](const Record& r, std::uint32_t k, const Vec3& n) {
            const Template& t = *templates_[static_cast<std::size_t>(r.templ)];
            const Quat inv = grid_orientation(p, k, r).conjugate();
            const Vec3 x = inv * (rec.point - p.x[k]);
            const Vec3 nb = inv * n;
            std::vector<int> out = heat::contact_patches(*t.grid, x, nb, rc);
            if (!t.spherical) {
                widen_to_one_cell(*t.grid, t.capacity, t.full_cell_capacity, x, nb, out);
            }
            return out;
        };
        if (d.a.templ >= 0) {
            d.patches_a = patches(d.a, rec.i, rec.normal);
        }
        if (!rec.wall && d.b.templ >= 0) {
            d.patches_b = patches(d.b, rec.j, -rec.normal);
        }
        return true;
    };
    // With several threads every contact's exchange is found first, in parallel (each from the
    // state only), and the loop below takes them in contact order: the same sums, the same bits.
    // A contact whose exchange threw is left to that loop, which runs it again in order.
    const std::size_t n = contacts_.size();
    std::vector<ContactData> ahead;
    std::vector<unsigned char> state; // 0: not found ahead, 1: no exchange, 2: an exchange
    if (threads_ > 1) {
        ahead.resize(n);
        state.assign(n, 0);
        const auto count = static_cast<std::ptrdiff_t>(n);
#pragma omp parallel for num_threads(threads_) schedule(dynamic, 16)
        for (std::ptrdiff_t k = 0; k < count; ++k) {
            const auto c = static_cast<std::size_t>(k);
            try {
                state[c] = exchange(contacts_[c], ahead[c]) ? 2 : 1;
            } catch (...) {
                state[c] = 0;
            }
        }
    }
    for (std::size_t c = 0; c < n; ++c) {
        const dynamics::ContactRecord& rec = contacts_[c];
        ContactData d;
        if (!state.empty() && state[c] != 0) {
            if (state[c] == 1) {
                continue;
            }
            d = std::move(ahead[c]);
        } else if (!exchange(rec, d)) {
            continue;
        }
        // The capacity that answers a lagged contact rate within one step: the whole lumped
        // particle, or the cells under the contact of a resolved one (a conservative choice: the
        // implicit conduction inside spreads the heat further during the step).
        g_sum[rec.i] += d.conductance;
        double pair_rate = d.conductance / patch_capacity(d.a, d.patches_a);
        if (!rec.wall) {
            g_sum[rec.j] += d.conductance;
            pair_rate += d.conductance / patch_capacity(d.b, d.patches_b);
        }
        worst = std::max(worst, pair_rate);
        data_.push_back(std::move(d));
    }
}

void ThermalSystem::add_contact_rates(double dt_sub) {
    std::vector<double>& weights = weights_; // patch shares of one contact side
    // Lagged contact heat rates from the temperatures at the start of the sub-step; what
    // leaves one body enters the other (the same number with the opposite sign).
    // `t_other` is the partner's contact temperature (K). Cartesian patches split by
    // temperature: see split_weights.
    const auto add = [&](const Record& r, const std::vector<int>& patches, double q,
                         double t_other) {
        if (r.templ < 0) {
            lumped_rate_[static_cast<std::size_t>(r.slot)] += q;
            return;
        }
        const Template& t = *templates_[static_cast<std::size_t>(r.templ)];
        split_weights(t, pool_.field(r.slot), patches, q, t_other, weights);
        double total = 0.0;
        std::size_t largest = 0;
        for (std::size_t k = 0; k < patches.size(); ++k) {
            total += weights[k];
            largest = weights[k] > weights[largest] ? k : largest;
        }
        double* rate = face_rate_.data() + face_offset_[static_cast<std::size_t>(r.slot)];
        double given = 0.0;
        for (std::size_t k = 0; k < patches.size(); ++k) {
            if (k != largest) {
                const double part = q * (weights[k] / total);
                rate[patches[k]] += part;
                given += part;
            }
        }
        rate[patches[largest]] += q - given; // the remainder: the parts sum to q exactly
    };
    for (const ContactData& d : data_) {
        const double ta = contact_temperature(d.a, d, false);
        const double tb = d.wall ? d.wall_temperature : contact_temperature(d.b, d, true);
        const double q = d.radiative ? d.conductance * (tb * tb * tb * tb - ta * ta * ta * ta)
                                     : d.conductance * (tb - ta); // into i
        add(d.a, d.patches_a, q, tb);
        if (d.wall) {
            external_heat_ += q * dt_sub;
        } else {
            add(d.b, d.patches_b, -q, ta);
        }
    }
}

} // namespace kiln::thermal
