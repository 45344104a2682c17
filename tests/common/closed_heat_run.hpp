#pragma once
// The loop of every closed-box heat check (tests/thermal, validations 26, 28, 29): mechanical steps
// with the heat coupling after each, and at every thermal step the relative drift of the stored
// heat sum C T and the range of all cell temperatures. Shared so the tests and the validation
// cases measure conservation the same way.

#include "dynamics/system.hpp"
#include "thermal/thermal_system.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace kiln::test {

/// What a closed run measured.
struct ClosedHeatRun {
    double initial_energy = 0; ///< sum C T before the first step (J)
    double drift = 0;          ///< largest |sum C T - initial| / initial over the thermal steps (-)
    double lowest = std::numeric_limits<double>::infinity();   ///< lowest cell temperature (K)
    double highest = -std::numeric_limits<double>::infinity(); ///< highest cell temperature (K)
};

/// Runs `steps` mechanical steps of `sys` with `heat.after_step` after each; at every thermal step
/// records drift and temperature range, then calls `on_thermal_step()` (extra counts of a case).
template <class OnThermalStep>
ClosedHeatRun run_closed_heat(dynamics::System& sys, thermal::ThermalSystem& heat, long steps,
                              OnThermalStep&& on_thermal_step) {
    ClosedHeatRun r;
    r.initial_energy = heat.thermal_energy();
    for (long n = 0; n < steps; ++n) {
        sys.step();
        if (heat.after_step(sys)) {
            r.drift = std::max(r.drift, std::abs(heat.thermal_energy() - r.initial_energy) /
                                            r.initial_energy);
            const auto [lo, hi] = heat.temperature_range();
            r.lowest = std::min(r.lowest, lo);
            r.highest = std::max(r.highest, hi);
            on_thermal_step();
        }
    }
    return r;
}

/// run_closed_heat without extra counts.
inline ClosedHeatRun run_closed_heat(dynamics::System& sys, thermal::ThermalSystem& heat,
                                     long steps) {
    return run_closed_heat(sys, heat, steps, [] {});
}

} // namespace kiln::test
