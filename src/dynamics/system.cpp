#include "dynamics/system.hpp"

#include "contact/contact_law.hpp"
#include "core/error.hpp"
#include "dynamics/time_step.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <limits>
#include <sstream>

namespace kiln::dynamics {

System::System(const SceneSpec& spec)
    : spec_(spec), pairs_(spec.materials, spec.pairs,
                          spec.contact.clamp_normal_force && spec.contact.rebound_restitution),
      nl_(spec.skin), rng_(spec.seed) {
    if (spec_.skin <= 0.0) {
        double rmax = 0.0;
        for (const auto& ps : spec_.particles) {
            rmax = std::max(rmax, ps.radius);
        }
        for (const auto& ins : spec_.inserts) {
            rmax = std::max(rmax, ins.size.largest());
        }
        spec_.skin = 0.2 * rmax; // 10 % of the largest diameter
        nl_ = contact::NeighbourList(spec_.skin);
    }
    for (const auto& ps : spec_.particles) {
        add_particle(ps.material, ps.radius, ps.x, ps.v, ps.omega);
    }
    for (const auto& ins : spec_.inserts) {
        insert(ins);
    }
    check_time_step();
    refresh();
}

std::size_t System::add_particle(int material, double radius, const Vec3& x, const Vec3& v,
                                 const Vec3& omega) {
    const double rho = spec_.materials.at(static_cast<std::size_t>(material)).density;
    const std::size_t i = p_.add_sphere(next_id_++, material, radius, rho, x, v, omega);
    wall_shear_.resize(p_.size() * spec_.walls.size(), Vec3::Zero());
    list_valid_ = false;
    return i;
}

void System::check_time_step() {
    if (p_.size() == 0) {
        return;
    }
    // Smallest particle per material, bounding box of the particles, fastest initial motion.
    std::vector<double> rmin(spec_.materials.size(), std::numeric_limits<double>::infinity());
    Vec3 lo = p_.x[0];
    Vec3 hi = p_.x[0];
    double vmax = 0.0;
    for (std::size_t i = 0; i < p_.size(); ++i) {
        auto& r = rmin[static_cast<std::size_t>(p_.material[i])];
        r = std::min(r, p_.radius[i]);
        lo = lo.cwiseMin(p_.x[i]);
        hi = hi.cwiseMax(p_.x[i]);
        vmax = std::max(vmax, p_.v[i].norm() + p_.omega[i].norm() * p_.radius[i]);
    }
    double speed = spec_.expected_speed;
    if (speed <= 0.0) {
        // Fall across the whole particle cloud plus the largest initial speed (closing speed of
        // two).
        speed = 2.0 * vmax + std::sqrt(2.0 * spec_.gravity.norm() * (hi - lo).norm());
    }
    ts_.impact_speed = speed;
    ts_.rayleigh = std::numeric_limits<double>::infinity();
    ts_.contact_time = std::numeric_limits<double>::infinity();
    for (std::size_t a = 0; a < rmin.size(); ++a) {
        if (!std::isfinite(rmin[a])) {
            continue;
        }
        const Material& m = spec_.materials[a];
        ts_.rayleigh =
            std::min(ts_.rayleigh,
                     rayleigh_time_step(rmin[a], m.density, m.shear_modulus(), m.poisson_ratio));
        for (std::size_t b = 0; b < rmin.size(); ++b) {
            if (!std::isfinite(rmin[b])) {
                continue;
            }
            const double r1 = rmin[a];
            const double r2 = rmin[b];
            const double m1 = m.density * 4.18879020478639 * r1 * r1 * r1;
            const double m2 = spec_.materials[b].density * 4.18879020478639 * r2 * r2 * r2;
            const double meff = m1 * m2 / (m1 + m2);
            const PairProperties& pp = pairs_.at(static_cast<int>(a), static_cast<int>(b));
            double tc = 0.0;
            if (const auto* lin = std::get_if<contact::LinearSpringDashpot>(&spec_.contact.law)) {
                tc = linear_contact_time(meff, lin->stiffness, pp.beta);
            } else {
                tc = hertz_contact_time(meff, r1 * r2 / (r1 + r2), pp.effective_modulus, speed);
            }
            ts_.contact_time = std::min(ts_.contact_time, tc);
        }
    }
    ts_.limit = std::min(ts_.rayleigh, ts_.contact_time);
    const double dt = spec_.time_step;
    const std::string figures = fmt::format("time step {:.3g} s; Rayleigh step {:.3g} s, shortest "
                                            "contact {:.3g} s (impact speed {:.3g} m/s)",
                                            dt, ts_.rayleigh, ts_.contact_time, ts_.impact_speed);
    // Fewer than 5 steps per contact, or a step above the Rayleigh step, is not a usable
    // simulation.
    const bool unsafe = dt > ts_.rayleigh || dt > ts_.contact_time / 5.0;
    if (unsafe && !spec_.allow_unsafe_time_step) {
        throw InputError("", 0, "simulation.time_step",
                         figures + "; the step must be below the Rayleigh step and a fifth of the "
                                   "contact time (set simulation.allow_unsafe_time_step = true to "
                                   "run anyway)");
    }
    if (unsafe || dt > spec_.time_step_fraction * ts_.limit) {
        warnings_.push_back(fmt::format("{}; above {} of the critical step {:.3g} s", figures,
                                        spec_.time_step_fraction, ts_.limit));
    }
}

void System::rebuild_neighbours() {
    const std::vector<std::uint32_t> order = nl_.build(p_, spec_.sort_particles);
    const std::size_t nw = spec_.walls.size();
    if (!order.empty() && nw > 0) {
        std::vector<Vec3> s(wall_shear_.size());
        for (std::size_t k = 0; k < order.size(); ++k) {
            for (std::size_t w = 0; w < nw; ++w) {
                s[k * nw + w] = wall_shear_[order[k] * nw + w];
            }
        }
        wall_shear_.swap(s);
    }
    find_wall_candidates();
    list_valid_ = true;
}

void System::find_wall_candidates() {
    // Particles within the skin of a wall. A particle further away cannot reach the wall before the
    // next rebuild: it is at most skin/2 from its position at the last build, so at most a skin
    // from where it is now.
    const std::size_t nw = spec_.walls.size();
    wall_candidates_.assign(nw, {});
    for (std::size_t w = 0; w < nw; ++w) {
        for (std::size_t i = 0; i < p_.size(); ++i) {
            const WallContact wc = std::visit(
                [&](const auto& shape) { return wall_contact(shape, p_.x[i], p_.radius[i]); },
                spec_.walls[w].shape);
            if (wc.overlap > -nl_.skin()) {
                wall_candidates_[w].push_back(static_cast<std::uint32_t>(i));
            }
        }
    }
}

void System::refresh() {
    rebuild_neighbours();
    compute_forces();
}

template <class Law> void System::pair_forces(const Law& law) {
    const auto& nb = nl_.partners();
    const auto& owner = nl_.owners();
    auto& shear = nl_.shear();
    const double dt = spec_.time_step;
    const std::size_t entries = nb.size();

    // Pass 1: which list entries touch. Branch-free, so the ~50 % unpredictable outcome costs
    // nothing; histories of pairs apart are cleared.
    active_.resize(entries);
    std::size_t n_active = 0;
    for (std::size_t k = 0; k < entries; ++k) {
        const std::uint32_t i = owner[k];
        const std::uint32_t j = nb[k];
        const double rsum = p_.radius[i] + p_.radius[j];
        const bool touch = (p_.x[i] - p_.x[j]).squaredNorm() < rsum * rsum;
        active_[n_active] = static_cast<std::uint32_t>(k);
        n_active += touch ? 1U : 0U;
        shear[k] *= touch ? 1.0 : 0.0;
    }

    // Pass 2: forces of the touching pairs, in blocks. The scalar gather only copies particle data;
    // the geometry (square root, divisions) is derived in the vectorised loop together with the
    // law, since the contacts of a block are independent; then the results are scattered.
    constexpr std::size_t block = 16;
    const double fn_floor = contact::floor_of(spec_.contact);
    const double rolling = contact::rolling_of(spec_.contact);
    contact::ContactBlock<block> c; // on the stack, so the vectoriser sees it does not alias
    double d[3][block], ri[block], rj[block], mi[block], mj[block], ratio[block];
    const bool one_pair = pairs_.size() == 1;
    if (one_pair) {
        for (std::size_t b = 0; b < block; ++b) {
            c.set_pair(b, pairs_.at(0, 0));
        }
    }
    double energy = 0.0;
    double max_ratio = 0.0;
    for (std::size_t a0 = 0; a0 < n_active; a0 += block) {
        const std::size_t m = std::min(block, n_active - a0);
        for (std::size_t b = 0; b < m; ++b) {
            const std::uint32_t k = active_[a0 + b];
            const std::uint32_t i = owner[k];
            const std::uint32_t j = nb[k];
            for (int q = 0; q < 3; ++q) {
                d[q][b] = p_.x[i][q] - p_.x[j][q];
                c.v[q][b] = p_.v[i][q] - p_.v[j][q];
                c.wi[q][b] = p_.omega[i][q];
                c.wj[q][b] = p_.omega[j][q];
                c.s[q][b] = shear[k][q];
            }
            ri[b] = p_.radius[i];
            rj[b] = p_.radius[j];
            mi[b] = p_.mass[i];
            mj[b] = p_.mass[j];
            if (!one_pair) {
                c.set_pair(b, pairs_.at(p_.material[i], p_.material[j]));
            }
        }
#pragma omp simd
        for (std::size_t b = 0; b < m; ++b) {
            const double rsum = ri[b] + rj[b];
            const double dist =
                std::sqrt(d[0][b] * d[0][b] + d[1][b] * d[1][b] + d[2][b] * d[2][b]);
            const double overlap = rsum - dist;
            for (int q = 0; q < 3; ++q) {
                c.n[q][b] = d[q][b] / dist;
            }
            c.overlap[b] = overlap;
            c.r_eff[b] = ri[b] * rj[b] / rsum;
            c.m_eff[b] = mi[b] * mj[b] / (mi[b] + mj[b]);
            c.lever_i[b] = ri[b] - 0.5 * overlap;
            c.lever_j[b] = rj[b] - 0.5 * overlap;
            ratio[b] = overlap / (2.0 * std::min(ri[b], rj[b]));
            contact::evaluate_block(law, fn_floor, rolling, c, b, dt);
        }
        for (std::size_t b = 0; b < m; ++b) {
            const std::uint32_t k = active_[a0 + b];
            const std::uint32_t i = owner[k];
            const std::uint32_t j = nb[k];
            const Vec3 f(c.f[0][b], c.f[1][b], c.f[2][b]);
            p_.force[i] += f;
            p_.force[j] -= f;
            p_.torque[i] += Vec3(c.ti[0][b], c.ti[1][b], c.ti[2][b]);
            p_.torque[j] += Vec3(c.tj[0][b], c.tj[1][b], c.tj[2][b]);
            shear[k] = Vec3(c.s[0][b], c.s[1][b], c.s[2][b]);
            energy += c.energy[b];
            max_ratio = std::max(max_ratio, ratio[b]);
        }
    }
    counters_.elastic_energy += energy;
    counters_.max_overlap_ratio = std::max(counters_.max_overlap_ratio, max_ratio);
    counters_.particle_contacts = static_cast<long>(n_active);
}

template <class Law> void System::wall_forces(const Law& law) {
    const std::size_t nw = spec_.walls.size();
    const double dt = spec_.time_step;
    for (std::size_t w = 0; w < nw; ++w) {
        const Wall& wall = spec_.walls[w];
        for (const std::uint32_t i : wall_candidates_[w]) {
            const double r = p_.radius[i];
            const WallContact wc = std::visit(
                [&](const auto& shape) { return wall_contact(shape, p_.x[i], r); }, wall.shape);
            Vec3& shear = wall_shear_[i * nw + w];
            if (wc.overlap <= 0.0) {
                shear.setZero();
                continue;
            }
            contact::ContactInput c;
            c.n = wc.n;
            c.overlap = wc.overlap;
            c.r_eff = wc.r_eff;
            c.m_eff = p_.mass[i];
            c.lever_i = r - wc.overlap;
            c.lever_j = 0.0;
            c.v_rel = p_.v[i];
            c.omega_i = p_.omega[i];
            c.omega_j = Vec3::Zero();
            const PairProperties& pp = pairs_.at(p_.material[i], wall.material);
            const contact::ContactOutput o =
                contact::evaluate(law, spec_.contact, pp, c, shear, dt);
            p_.force[i] += o.force;
            p_.torque[i] += o.torque_i;
            ++counters_.wall_contacts;
            counters_.elastic_energy += o.elastic_energy;
            counters_.max_overlap_ratio =
                std::max(counters_.max_overlap_ratio, wc.overlap / (2.0 * r));
        }
    }
}

void System::compute_forces() {
    p_.clear_forces();
    counters_ = ContactCounters{};
    std::visit(
        [&](const auto& law) {
            pair_forces(law);
            wall_forces(law);
        },
        spec_.contact.law);
}

void System::step() {
    if (!list_valid_) {
        rebuild_neighbours();
    }
    const double dt = spec_.time_step;
    const double h = 0.5 * dt;
    const Vec3 g = spec_.gravity;
    const std::size_t n = p_.size();
    for (std::size_t i = 0; i < n; ++i) {
        p_.v[i] += h * (p_.force[i] * p_.inv_mass[i] + g);
        p_.omega[i] += h * p_.inv_inertia[i] * p_.torque[i];
        p_.x[i] += dt * p_.v[i];
    }
    if (nl_.needs_rebuild(p_)) {
        rebuild_neighbours();
    }
    compute_forces();
    for (std::size_t i = 0; i < n; ++i) {
        p_.v[i] += h * (p_.force[i] * p_.inv_mass[i] + g);
        p_.omega[i] += h * p_.inv_inertia[i] * p_.torque[i];
    }
    ++step_;
    time_ = static_cast<double>(step_) * dt;
}

void System::check_finite() const {
    for (std::size_t i = 0; i < p_.size(); ++i) {
        if (!p_.x[i].allFinite() || !p_.v[i].allFinite() || !p_.omega[i].allFinite()) {
            throw RunError(step_,
                           fmt::format("particle {} has a non-finite position or velocity; the "
                                       "time step is probably too large for the contact stiffness",
                                       p_.id[i]));
        }
    }
}

Energies System::energies() const {
    Energies e;
    for (std::size_t i = 0; i < p_.size(); ++i) {
        e.kinetic += 0.5 * p_.mass[i] * p_.v[i].squaredNorm();
        e.rotational += 0.5 * p_.omega[i].squaredNorm() / p_.inv_inertia[i];
        e.potential -= p_.mass[i] * spec_.gravity.dot(p_.x[i]);
    }
    e.elastic = counters_.elastic_energy;
    return e;
}

SystemState System::save_state() const {
    SystemState s;
    s.particles = p_;
    s.nl_offsets = nl_.offsets();
    s.nl_partners = nl_.partners();
    s.nl_shear = nl_.shear();
    s.nl_x_build = nl_.positions_at_build();
    s.nl_ids = p_.id;
    s.nl_builds = nl_.builds();
    s.wall_shear = wall_shear_;
    s.time = time_;
    s.step = step_;
    s.next_id = next_id_;
    s.counters = counters_;
    std::ostringstream os;
    os << rng_;
    s.rng = os.str();
    return s;
}

void System::restore_state(SystemState s) {
    p_ = std::move(s.particles);
    nl_.restore(std::move(s.nl_offsets), std::move(s.nl_partners), std::move(s.nl_shear),
                std::move(s.nl_x_build), std::move(s.nl_ids), s.nl_builds);
    wall_shear_ = std::move(s.wall_shear);
    time_ = s.time;
    step_ = s.step;
    next_id_ = s.next_id;
    std::istringstream is(s.rng);
    is >> rng_;
    counters_ = s.counters;
    // The list is restored as it was; rebuilding it now would reorder particles and change the
    // summation order. Forces and torques of the last step are part of the store; recomputing them
    // would advance the tangential histories a second time. Either would break exact continuation.
    find_wall_candidates();
    list_valid_ = true;
}

} // namespace kiln::dynamics
