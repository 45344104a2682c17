#include "heat/lumped_model.hpp"

#include "core/error.hpp"

namespace kiln::heat {

LumpedModel::LumpedModel(const ThermalProperties& props, double volume, double area)
    : capacity_(props.density * props.heat_capacity * volume), area_(area) {
    if (!(volume > 0.0 && area > 0.0 && props.density > 0.0 && props.heat_capacity > 0.0)) {
        throw InputError("heat: lumped particle needs volume, area, density, heat capacity > 0");
    }
}

double LumpedModel::step(double t, double dt, double h, double ambient, double flux,
                         double heat_rate) const {
    KILN_ASSERT(dt > 0.0 && h >= 0.0);
    const double ha = h * area_;
    return (capacity_ * t + dt * (ha * ambient + flux * area_ + heat_rate)) / (capacity_ + dt * ha);
}

} // namespace kiln::heat
