#pragma once
// Lumped (one temperature) particle: C dT/dt = h A (T_inf - T) + q A + Q (Oschmann et al. 2016,
// Inv. V eq. 1: dT_p/dt = sum Q / (m_p c_p)), valid for Bi = h L / k << 1 (seed L511). Backward
// Euler, like the resolved model, so the two agree exactly in the limit k -> infinity.

#include "heat/resolved_model.hpp"

namespace kiln::heat {

/// One-temperature particle of volume `volume` and surface `area`.
class LumpedModel {
  public:
    /// `volume` (m^3), `area` (m^2) of the particle. Throws InputError if not positive.
    LumpedModel(const ThermalProperties& props, double volume, double area);
    /// Returns T^{n+1} (K) after one backward-Euler step of `dt` (s) from `t` (K) with convection
    /// `h` (W/(m^2 K)) to `ambient` (K), uniform flux `flux` (W/m^2) and extra heat rate
    /// `heat_rate` (W), all into the body.
    [[nodiscard]] double step(double t, double dt, double h, double ambient, double flux,
                              double heat_rate) const;
    /// Heat capacity rho c_p V (J/K).
    [[nodiscard]] double capacity() const { return capacity_; }
    /// Surface area (m^2).
    [[nodiscard]] double area() const { return area_; }

  private:
    double capacity_;
    double area_;
};

} // namespace kiln::heat
