#include "heat/heat_model.hpp"

#include "core/error.hpp"

namespace kiln::heat {

std::string_view to_string(HeatModel model) {
    switch (model) {
    case HeatModel::none:
        return "none";
    case HeatModel::lumped:
        return "lumped";
    case HeatModel::resolved:
        return "resolved";
    case HeatModel::automatic:
        return "auto";
    }
    return "?";
}

double biot_number(double h, double volume, double area, double conductivity) {
    KILN_ASSERT(area > 0.0 && conductivity > 0.0);
    return h * (volume / area) / conductivity;
}

HeatModel choose_model(HeatModel requested, double biot, double threshold) {
    if (requested != HeatModel::automatic) {
        return requested;
    }
    return biot < threshold ? HeatModel::lumped : HeatModel::resolved;
}

} // namespace kiln::heat
