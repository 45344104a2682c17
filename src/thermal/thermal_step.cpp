// ThermalSystem: the thermal step: exchanges of the step, the lag limit and its sub-steps, and
// the backward-Euler solves of the resolved particles.

#include "thermal/thermal_system_detail.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace kiln::thermal {

using namespace detail;

Quat ThermalSystem::grid_orientation(const ParticleStore& p, std::size_t k, const Record& r) const {
    if (p.shape[k] >= 0) {
        return p.q[k];
    }
    if (r.templ >= 0 && spec_.sphere_rotation) {
        return pool_q_[static_cast<std::size_t>(r.slot)];
    }
    return Quat::Identity();
}

void ThermalSystem::turn_spheres(const dynamics::System& sys) {
    // q <- exp(omega dt / 2) q with the world-frame angular velocity at the end of the step
    // (first order in dt: the grid only has to follow the spin, the mechanics do not read it).
    // A sphere at rest keeps its orientation bit for bit.
    const ParticleStore& p = sys.particles();
    const double dt = sys.dt();
    for (std::size_t i = 0; i < p.size(); ++i) {
        const auto id = static_cast<std::size_t>(p.id[i]);
        if (p.shape[i] >= 0 || id >= by_id_.size() || by_id_[id].templ < 0) {
            continue;
        }
        const Vec3& w = p.omega[i];
        const double rate = w.norm();
        if (!(rate > 0.0)) {
            continue;
        }
        const double half = 0.5 * rate * dt;
        const Vec3 axis = w * (std::sin(half) / rate);
        const Quat turn(std::cos(half), axis.x(), axis.y(), axis.z());
        Quat& q = pool_q_[static_cast<std::size_t>(by_id_[id].slot)];
        q = (turn * q).normalized();
    }
}

bool ThermalSystem::after_step(const dynamics::System& sys) {
    if (turning_spheres_) {
        turn_spheres(sys);
    }
    if (spec_.collision_conduction && !sys.contact_onsets().empty()) {
        // Each side's contact in its body frame now, at the step that found the impact: a body
        // (or a resolved sphere's grid) turns before the thermal step exchanges the heat.
        sync(sys); // a particle inserted in this step may already have touched
        const ParticleStore& p = sys.particles();
        index_.assign(by_id_.size(), -1);
        for (std::size_t i = 0; i < p.size(); ++i) {
            const auto id = static_cast<std::size_t>(p.id[i]);
            if (id < index_.size()) {
                index_[id] = static_cast<std::int64_t>(i);
            }
        }
        const auto side = [&](std::int64_t id, const Vec3& n, const Vec3& point, double* x,
                              double* nb) {
            if (id < 0 || static_cast<std::size_t>(id) >= index_.size() ||
                index_[static_cast<std::size_t>(id)] < 0) {
                return; // the particle left the scene: add_collisions skips it
            }
            const auto i = static_cast<std::size_t>(index_[static_cast<std::size_t>(id)]);
            // Spheres: the contact point is r n on the sphere; bodies: the element contact's.
            const Quat inv =
                grid_orientation(p, i, by_id_[static_cast<std::size_t>(id)]).conjugate();
            const Vec3 xb = inv * (p.shape[i] >= 0 ? Vec3(point - p.x[i]) : Vec3(p.radius[i] * n));
            const Vec3 nn = inv * n;
            for (int q = 0; q < 3; ++q) {
                x[q] = xb[q];
                nb[q] = nn[q];
            }
        };
        for (const dynamics::ContactOnset& e : sys.contact_onsets()) {
            PendingImpact m;
            m.onset = e;
            const Vec3 n(e.normal[0], e.normal[1], e.normal[2]);
            const Vec3 point(e.point[0], e.point[1], e.point[2]);
            side(e.id_i, n, point, m.x_i, m.n_i);
            if (e.wall < 0) {
                side(e.id_j, -n, point, m.x_j, m.n_j);
            }
            onsets_.push_back(m);
        }
    }
    if (sys.step_count() % spec_.step_multiple != 0) {
        return false;
    }
    thermal_step(sys);
    return true;
}

void ThermalSystem::thermal_step(const dynamics::System& sys) {
    sync(sys);
    const ParticleStore& p = sys.particles();

    // Conductances and patches of the exchanges (geometry fixed for the step).
    data_.clear();
    std::vector<double> g_sum(p.size(), 0.0); // W/K per particle index
    double worst = 0.0;                       // largest conductance / capacity (1/s)
    add_contacts(sys, g_sum, worst);
    add_gas_gaps(sys, g_sum, worst);
    add_radiation(sys, g_sum, worst);
    add_wall_exchanges(sys, g_sum, worst);
    add_collisions(sys, g_sum, worst);
    for (std::size_t i = 0; i < p.size(); ++i) {
        if (g_sum[i] > 0.0) {
            const Record& r = by_id_[static_cast<std::size_t>(p.id[i])];
            worst = std::max(worst, g_sum[i] / capacity_of(r));
        }
    }
    prepare_surface(sys, worst);
    // Lag limit: sub-steps (a power of two, so few operators are built) keep
    // dt_sub * worst <= lag_safety.
    const double ratio = dt_ * worst;
    int substeps = 1;
    while (ratio / substeps > lag_safety) {
        substeps *= 2;
        if (substeps > spec_.max_substeps) {
            throw RunError(sys.step_count(),
                           fmt::format("heat: the thermal step {:.3g} s is {:.3g} times the lagged "
                                       "contact-coupling limit {:.3g} s (heat capacity / contact "
                                       "conductance); more than max_substeps = {} sub-steps "
                                       "would be needed: lower [heat] step_multiple",
                                       dt_, ratio / lag_safety, lag_safety / worst,
                                       spec_.max_substeps));
        }
    }
    counters_.max_lag_ratio = std::max(counters_.max_lag_ratio, ratio);
    if (substeps > 1 && !warned_lag_) {
        warned_lag_ = true;
        warnings_.push_back(fmt::format(
            "heat: thermal step {:.3g} s exceeds the lagged contact-coupling limit {:.3g} s "
            "(heat capacity / contact conductance x {}); sub-stepping ({} sub-steps at t = {:.6g} "
            "s; later steps may use other counts)",
            dt_, lag_safety / worst, lag_safety, substeps, sys.time()));
    }
    const double dt_sub = dt_ / substeps;

    for (int s = 0; s < substeps; ++s) {
        std::fill(face_rate_.begin(), face_rate_.end(), 0.0);
        std::fill(lumped_rate_.begin(), lumped_rate_.end(), 0.0);
        add_contact_rates(dt_sub);
        step_lumped(dt_sub);
        add_surface_rates();
        solve_resolved(sys, substeps, dt_sub);
    }
    ++counters_.thermal_steps;
    counters_.substeps += substeps;
    counters_.max_substeps = std::max(counters_.max_substeps, substeps);
    counters_.contacts += static_cast<long>(data_.size());
}

void ThermalSystem::solve_resolved(const dynamics::System& sys, int substeps, double dt_sub) {
    // Resolved particles: one backward-Euler solve each with the lagged heat rates. The solves
    // are independent: threads take slots, each with its own operator (built here, outside
    // the parallel loop); the sums below run in slot order, so results do not depend on the
    // number of threads.
    const int n_slots = pool_.size();
    const int threads = std::max(1, std::min(threads_, n_slots));
    for (const auto& t : templates_) {
        for (int th = 0; th < threads; ++th) {
            operator_for(*t, substeps, th);
        }
    }
    reports_.resize(static_cast<std::size_t>(n_slots));
#pragma omp parallel for num_threads(threads) schedule(dynamic, 8)
    for (int slot = 0; slot < n_slots; ++slot) {
        int th = 0;
#ifdef _OPENMP
        th = omp_get_thread_num();
#endif
        Template& t =
            *templates_[static_cast<std::size_t>(pool_template_[static_cast<std::size_t>(slot)])];
        heat::ResolvedOperator& op = *t.ops.at({substeps, th});
        heat::BoundaryLoad load;
        load.ambient = spec_.ambient_temperature;
        load.flux = spec_.flux;
        load.heat_rate = std::span<const double>(face_rate_.data() +
                                                     face_offset_[static_cast<std::size_t>(slot)],
                                                 t.grid->boundary.size());
        reports_[static_cast<std::size_t>(slot)] =
            op.step(pool_.field(slot), load,
                    keeps_previous() ? previous_.field(slot) : std::span<double>{});
    }
    for (int slot = 0; slot < n_slots; ++slot) {
        const heat::StepReport& rep = reports_[static_cast<std::size_t>(slot)];
        const Template& t =
            *templates_[static_cast<std::size_t>(pool_template_[static_cast<std::size_t>(slot)])];
        const double* rates = face_rate_.data() + face_offset_[static_cast<std::size_t>(slot)];
        double contact_in = 0.0; // lagged contact rates: internal, not external heat
        const bool conv = stagnant_[static_cast<std::size_t>(slot)] != 0;
        const bool rad = radiating_[static_cast<std::size_t>(slot)] != 0;
        const double* rad_rates = rad_rate_.data() + face_offset_[static_cast<std::size_t>(slot)];
        const double* conv_rates = conv_rate_.data() + face_offset_[static_cast<std::size_t>(slot)];
        for (std::size_t b = 0; b < t.grid->boundary.size(); ++b) {
            contact_in += rates[b] - (conv ? conv_rates[b] : 0.0) - (rad ? rad_rates[b] : 0.0);
        }
        external_heat_ += rep.heat_in - dt_sub * contact_in;
        ++counters_.solves;
        counters_.iterations += rep.solve.iterations;
        counters_.max_iterations = std::max(counters_.max_iterations, rep.solve.iterations);
        if (!rep.solve.converged) {
            ++counters_.unconverged;
            if (!warned_solver_) {
                warned_solver_ = true;
                warnings_.push_back(
                    fmt::format("heat: a {} solve stopped at the iteration cap ({}) with relative "
                                "residual {:.3g} (tolerance {:.3g}) at t = {:.6g} s",
                                heat::to_string(spec_.solver.kind), spec_.solver.max_iterations,
                                rep.solve.residual, spec_.solver.tolerance, sys.time()));
            }
        }
    }
}

} // namespace kiln::thermal
