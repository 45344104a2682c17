#pragma once
// Materials and the per-pair contact properties derived from them.

#include <string>
#include <vector>

namespace kiln {

/// A solid material. Mechanical constants are SI.
struct Material {
    std::string name;            ///< unique name used in case files
    double youngs_modulus = 0;   ///< E (Pa)
    double poisson_ratio = 0;    ///< nu (-), in (-1, 0.5)
    double density = 0;          ///< rho (kg/m^3)
    double restitution = 0;      ///< normal coefficient of restitution e (-), in (0, 1]
    double friction = 0;         ///< sliding (Coulomb) friction coefficient mu (-)
    double rolling_friction = 0; ///< rolling friction coefficient mu_r (-), torque = mu_r R* |F_n|

    /// Shear modulus G = E / (2 (1 + nu)) (Pa).
    [[nodiscard]] double shear_modulus() const {
        return youngs_modulus / (2.0 * (1.0 + poisson_ratio));
    }
};

/// Explicit values for one pair of materials, overriding the mixing rule (negative = not given).
struct PairOverride {
    int a = -1;                   ///< first material index
    int b = -1;                   ///< second material index
    double restitution = -1;      ///< e of the pair (-), < 0 = use the mixing rule
    double friction = -1;         ///< mu of the pair (-), < 0 = use the mixing rule
    double rolling_friction = -1; ///< mu_r of the pair (-), < 0 = use the mixing rule
};

/// Contact properties of one (unordered) material pair, precomputed once.
struct PairProperties {
    double effective_modulus = 0; ///< E* = 1/((1-nu1^2)/E1 + (1-nu2^2)/E2) (Pa)
    double effective_shear = 0; ///< G* = 1/((2-nu1)/G1 + (2-nu2)/G2) (Pa), Di Renzo & Di Maio 2004
    double restitution = 0;     ///< e (-)
    double beta = 0;            ///< damping parameter ln e' / sqrt(ln^2 e' + pi^2) (-), <= 0
    double damping_restitution = 0; ///< e' the damping is built from (-); e unless compensated
    double friction = 0;            ///< mu (-)
    double rolling_friction = 0;    ///< mu_r (-)
};

/// Symmetric table of PairProperties for all material pairs.
class PairTable {
  public:
    PairTable() = default;
    /// Builds the table. Unset pair values are the arithmetic mean of the two materials' values.
    /// With `rebound_with_clamp`, the damping is tuned so that a binary normal impact whose contact
    /// ends where the (clamped) normal force vanishes rebounds with exactly e; a pair whose e is
    /// below what such a contact can reach throws InputError.
    PairTable(const std::vector<Material>& mats, const std::vector<PairOverride>& overrides,
              bool rebound_with_clamp = false);
    /// Properties of the pair (a, b); symmetric.
    [[nodiscard]] const PairProperties& at(int a, int b) const {
        return props_[static_cast<std::size_t>(a * n_ + b)];
    }
    /// Number of materials.
    [[nodiscard]] int size() const { return n_; }

  private:
    int n_ = 0;
    std::vector<PairProperties> props_;
};

/// beta(e) = ln e / sqrt(ln^2 e + pi^2), the damping ratio parameter of Tsuji-type damping (-).
double damping_beta(double restitution);

/// Rebound ratio of a linear or Hertz-Tsuji contact built from e' whose normal force is clamped at
/// zero, e'^(1 - (2/pi) asin|beta(e')|) (-); derivation and check in validation/02_restitution.
double clamped_rebound(double damping_restitution);

/// Lowest rebound ratio a clamped contact can reach (about 0.14) (-).
double lowest_clamped_rebound();

/// The e' whose clamped rebound ratio is `rebound` (-); NaN when `rebound` is below the lowest.
double damping_restitution_for_clamped(double rebound);

} // namespace kiln
