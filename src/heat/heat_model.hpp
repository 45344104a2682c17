#pragma once
// Which heat model a particle type uses (issue 5: none, lumped, resolved, auto). "auto" picks the
// lumped model below a Biot-number threshold: Bi = h L_c / k with L_c = V / A (Incropera et al.,
// 6th ed., §5.2, eq. 5.10: the lumped model errs by < 5 % for Bi < 0.1).

#include <string_view>

namespace kiln::heat {

/// Heat model of a particle type.
enum class HeatModel {
    none,      ///< no temperature
    lumped,    ///< one temperature per particle
    resolved,  ///< a 3D field on a template grid
    automatic, ///< lumped if Bi < threshold, else resolved
};

/// Name of a model ("none", "lumped", "resolved", "auto").
[[nodiscard]] std::string_view to_string(HeatModel model);

/// Biot number h L_c / k with L_c = volume / area (-); `h` (W/(m^2 K)), `volume` (m^3), `area`
/// (m^2), `conductivity` (W/(m K)).
[[nodiscard]] double biot_number(double h, double volume, double area, double conductivity);

/// The model actually used: `requested` unless it is automatic, then lumped for
/// biot < threshold (default 0.1) and resolved otherwise.
[[nodiscard]] HeatModel choose_model(HeatModel requested, double biot, double threshold = 0.1);

} // namespace kiln::heat
