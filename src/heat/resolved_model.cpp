#include "heat/resolved_model.hpp"

#include "core/error.hpp"
#include "heat/cholmod_solver.hpp"
#include "heat/convection.hpp"

#include <algorithm>
#include <string>
#include <vector>

namespace kiln::heat {

std::string_view to_string(SolverKind kind) {
    switch (kind) {
    case SolverKind::cg:
        return "cg";
    case SolverKind::bicgstab:
        return "bicgstab";
    case SolverKind::cholmod:
        return "cholmod";
    }
    return "?";
}

bool cholmod_available() {
    return KILN_HAVE_CHOLMOD != 0;
}

ResolvedOperator::ResolvedOperator(std::shared_ptr<const ThermalGrid> grid,
                                   const ThermalProperties& props, double dt,
                                   std::span<const double> h_per_face, const SolverSettings& solver)
    : grid_(std::move(grid)), props_(props), dt_(dt), solver_(solver) {
    KILN_ASSERT(grid_ != nullptr);
    if (!(props.conductivity > 0.0 && props.density > 0.0 && props.heat_capacity > 0.0)) {
        throw InputError("heat: conductivity, density and heat capacity must be > 0");
    }
    if (!(dt > 0.0)) {
        throw InputError("heat: thermal time step must be > 0 s, got " + std::to_string(dt));
    }
    const ThermalGrid& g = *grid_;
    const std::size_t nb = g.boundary.size();
    if (!(h_per_face.empty() || h_per_face.size() == 1 || h_per_face.size() == nb)) {
        throw InputError("heat: " + std::to_string(h_per_face.size()) +
                         " heat transfer coefficients for " + std::to_string(nb) +
                         " boundary faces (give 0, 1 or one per face)");
    }
    if (solver.kind == SolverKind::cholmod && !cholmod_available()) {
        throw InputError("heat: solver \"cholmod\" requested but kiln was built without CHOLMOD");
    }
    if (!(solver.tolerance > 0.0) || solver.max_iterations < 1) {
        throw InputError("heat: solver tolerance must be > 0 and max_iterations >= 1");
    }
    const int n = g.size();
    const double k = props.conductivity;
    const double rho_c = props.density * props.heat_capacity;
    capacity_.resize(static_cast<std::size_t>(n));
    std::vector<double> diag(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
        capacity_[static_cast<std::size_t>(i)] = rho_c * g.volume[static_cast<std::size_t>(i)];
        diag[static_cast<std::size_t>(i)] = capacity_[static_cast<std::size_t>(i)] / dt;
    }
    g_surface_.assign(nb, 0.0);
    for (std::size_t f = 0; f < nb; ++f) {
        const double h = h_per_face.empty() ? 0.0 : h_per_face[h_per_face.size() == 1 ? 0 : f];
        if (h < 0.0) {
            throw InputError("heat: heat transfer coefficient must be >= 0 W/(m^2 K)");
        }
        const BoundaryFace& b = g.boundary[f];
        g_surface_[f] = heat::surface_conductance(b, h, k);
        diag[static_cast<std::size_t>(b.cell)] += g_surface_[f];
    }
    std::vector<Eigen::Triplet<double, int>> triplets;
    triplets.reserve(static_cast<std::size_t>(n) + 2 * g.links.size());
    for (const CellLink& l : g.links) {
        const double c = k * l.geometry;
        triplets.emplace_back(l.a, l.b, -c);
        triplets.emplace_back(l.b, l.a, -c);
        diag[static_cast<std::size_t>(l.a)] += c;
        diag[static_cast<std::size_t>(l.b)] += c;
    }
    for (int i = 0; i < n; ++i) {
        triplets.emplace_back(i, i, diag[static_cast<std::size_t>(i)]);
    }
    a_.resize(n, n);
    a_.setFromTriplets(triplets.begin(), triplets.end());
    a_.makeCompressed();
    ell_.assign(a_);
    inv_diag_.resize(n);
    for (int i = 0; i < n; ++i) {
        inv_diag_[i] = 1.0 / diag[static_cast<std::size_t>(i)];
    }
    rhs_.setZero(n);
    x_.setZero(n);
    work_.resize(n);
#if KILN_HAVE_CHOLMOD
    if (solver.kind == SolverKind::cholmod) {
        factor_ = std::make_unique<CholmodFactor>(a_);
    }
#endif
}

ResolvedOperator::~ResolvedOperator() = default;

double ResolvedOperator::total_capacity() const {
    double c = 0.0;
    for (const double x : capacity_) {
        c += x;
    }
    return c;
}

StepReport ResolvedOperator::step(std::span<double> temperature, const BoundaryLoad& load,
                                  std::span<double> previous) {
    const ThermalGrid& g = *grid_;
    const int n = g.size();
    KILN_ASSERT(static_cast<int>(temperature.size()) == n);
    const std::size_t nb = g.boundary.size();
    KILN_ASSERT(load.ambient_per_face.empty() || load.ambient_per_face.size() == nb);
    KILN_ASSERT(load.flux_per_face.empty() || load.flux_per_face.size() == nb);
    KILN_ASSERT(load.heat_rate.empty() || load.heat_rate.size() == nb);
    const double inv_dt = 1.0 / dt_;
    for (int i = 0; i < n; ++i) {
        rhs_[i] = capacity_[static_cast<std::size_t>(i)] * inv_dt *
                  temperature[static_cast<std::size_t>(i)];
        x_[i] = temperature[static_cast<std::size_t>(i)];
    }
    if (!previous.empty()) {
        // Initial guess extrapolated linearly in time; `previous` becomes T^n.
        KILN_ASSERT(static_cast<int>(previous.size()) == n);
        for (int i = 0; i < n; ++i) {
            const auto si = static_cast<std::size_t>(i);
            x_[i] = 2.0 * temperature[si] - previous[si];
            previous[si] = temperature[si];
        }
    }
    double explicit_in = 0.0; // W through flux and heat-rate terms
    for (std::size_t f = 0; f < nb; ++f) {
        const BoundaryFace& b = g.boundary[f];
        const double t_inf =
            load.ambient_per_face.empty() ? load.ambient : load.ambient_per_face[f];
        double q = load.flux;
        if (!load.flux_per_face.empty()) {
            q += load.flux_per_face[f];
        }
        double w = q * b.area;
        if (!load.heat_rate.empty()) {
            w += load.heat_rate[f];
        }
        explicit_in += w;
        rhs_[b.cell] += g_surface_[f] * t_inf + w;
    }
    StepReport rep;
    switch (solver_.kind) {
    case SolverKind::cg:
        rep.solve = conjugate_gradient(ell_, inv_diag_, rhs_, x_, solver_.tolerance,
                                       solver_.max_iterations, work_);
        break;
    case SolverKind::bicgstab:
        rep.solve =
            bicgstab(ell_, inv_diag_, rhs_, x_, solver_.tolerance, solver_.max_iterations, work_);
        break;
    case SolverKind::cholmod:
#if KILN_HAVE_CHOLMOD
        factor_->solve(rhs_, x_);
        ell_.multiply(x_.data(), work_.t.data());
        work_.r = rhs_ - work_.t;
        rep.solve.residual = norm(work_.r) / norm(rhs_);
        rep.solve.converged = true;
#endif
        break;
    }
    double convective_in = 0.0;
    for (std::size_t f = 0; f < nb; ++f) {
        const double t_inf =
            load.ambient_per_face.empty() ? load.ambient : load.ambient_per_face[f];
        convective_in += g_surface_[f] * (t_inf - x_[g.boundary[f].cell]);
    }
    rep.heat_in = dt_ * (convective_in + explicit_in);
    for (int i = 0; i < n; ++i) {
        temperature[static_cast<std::size_t>(i)] = x_[i];
    }
    iterations_ += rep.solve.iterations;
    ++solves_;
    return rep;
}

void ResolvedOperator::surface_temperature(std::span<const double> temperature,
                                           const BoundaryLoad& load, std::span<double> out) const {
    const ThermalGrid& g = *grid_;
    KILN_ASSERT(out.size() == g.boundary.size());
    for (std::size_t f = 0; f < g.boundary.size(); ++f) {
        const BoundaryFace& b = g.boundary[f];
        const double t_node = temperature[static_cast<std::size_t>(b.cell)];
        const double t_inf =
            load.ambient_per_face.empty() ? load.ambient : load.ambient_per_face[f];
        double q = load.flux + (load.flux_per_face.empty() ? 0.0 : load.flux_per_face[f]);
        double w = g_surface_[f] * (t_inf - t_node) + q * b.area;
        if (!load.heat_rate.empty()) {
            w += load.heat_rate[f];
        }
        out[f] = t_node + w * b.distance / (props_.conductivity * b.area);
    }
}

double mean_temperature(const ThermalGrid& grid, std::span<const double> t) {
    double sum = 0.0;
    double vol = 0.0;
    for (std::size_t i = 0; i < grid.volume.size(); ++i) {
        sum += grid.volume[i] * t[i];
        vol += grid.volume[i];
    }
    return sum / vol;
}

double stored_heat(const std::vector<double>& capacity, std::span<const double> t) {
    double e = 0.0;
    for (std::size_t i = 0; i < capacity.size(); ++i) {
        e += capacity[i] * t[i];
    }
    return e;
}

int TemperaturePool::add(int cells, double initial) {
    KILN_ASSERT(cells > 0);
    offset_.push_back(values_.size());
    count_.push_back(cells);
    values_.insert(values_.end(), static_cast<std::size_t>(cells), initial);
    return static_cast<int>(offset_.size()) - 1;
}

void TemperaturePool::assign(std::span<const double> all) {
    KILN_ASSERT(all.size() == values_.size());
    std::copy(all.begin(), all.end(), values_.begin());
}

std::span<double> TemperaturePool::field(int p) {
    const auto i = static_cast<std::size_t>(p);
    return {values_.data() + offset_[i], static_cast<std::size_t>(count_[i])};
}

std::span<const double> TemperaturePool::field(int p) const {
    const auto i = static_cast<std::size_t>(p);
    return {values_.data() + offset_[i], static_cast<std::size_t>(count_[i])};
}

} // namespace kiln::heat
