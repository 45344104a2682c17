#pragma once
// Shared driver of the heat validation cases (20-23): a body at uniform T_0 suddenly exposed to
// convection h to T_inf, advanced by backward Euler; theta = (T - T_inf)/(T_0 - T_inf) sampled.

#include "heat/resolved_model.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

namespace kiln::validation {

/// Centre-node and volume-mean theta at the end of a run.
struct ThetaSample {
    double centre = 0.0; ///< theta of the grid's centre cell (-)
    double mean = 0.0;   ///< volume-mean theta (-)
};

/// Runs `steps` steps of `dt` (s) from theta = 1 and returns theta after each of the `samples`
/// equally spaced checkpoints (steps must be a multiple of samples).
inline std::vector<ThetaSample> run_convection(std::shared_ptr<const heat::ThermalGrid> grid,
                                               const heat::ThermalProperties& props, double h,
                                               double dt, int steps, int samples,
                                               heat::SolverKind solver) {
    const double t0 = 1.0;
    const double t_inf = 0.0;
    const std::vector<double> hv{h};
    heat::ResolvedOperator op(grid, props, dt, hv, {solver, 1e-12, 5000});
    std::vector<double> t(static_cast<std::size_t>(grid->size()), t0);
    std::vector<ThetaSample> out;
    const int every = steps / samples;
    for (int s = 1; s <= steps; ++s) {
        (void)op.step(t, {.ambient = t_inf});
        if (s % every == 0) {
            out.push_back(
                {t[static_cast<std::size_t>(grid->centre_cell)], heat::mean_temperature(*grid, t)});
        }
    }
    return out;
}

/// Richardson extrapolation in time of first-order backward-Euler samples: 2 f(dt/2) - f(dt).
inline std::vector<ThetaSample> richardson(const std::vector<ThetaSample>& coarse,
                                           const std::vector<ThetaSample>& fine) {
    std::vector<ThetaSample> out(coarse.size());
    for (std::size_t i = 0; i < coarse.size(); ++i) {
        out[i].centre = 2.0 * fine[i].centre - coarse[i].centre;
        out[i].mean = 2.0 * fine[i].mean - coarse[i].mean;
    }
    return out;
}

/// Fastest available solver for long runs with a constant matrix.
inline heat::SolverKind direct_or_cg() {
    return heat::cholmod_available() ? heat::SolverKind::cholmod : heat::SolverKind::cg;
}

/// Appends a row "series,size,centre_error,mean_error" to convergence.csv of this case (for
/// plot_heat_convergence.py); the file is replaced by the first call of a run (`fresh`).
inline void write_convergence(const std::string& series, double size, double centre_error,
                              double mean_error, bool fresh = false) {
    const std::filesystem::path file = std::filesystem::path(KILN_RESULT_DIR) / "convergence.csv";
    std::filesystem::create_directories(KILN_RESULT_DIR);
    const bool header = fresh || !std::filesystem::exists(file);
    std::ofstream f(file, fresh ? std::ios::trunc : std::ios::app);
    if (header) {
        f << "series,size,centre_error,mean_error\n";
    }
    f.precision(10);
    f << series << ',' << size << ',' << centre_error << ',' << mean_error << '\n';
}

/// Observed order of convergence from errors e1 at size s1 and e2 at size s2.
inline double observed_order(double e1, double e2, double s1, double s2) {
    return std::log(e1 / e2) / std::log(s1 / s2);
}

} // namespace kiln::validation
