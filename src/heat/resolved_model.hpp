#pragma once
// Resolved (3D) conduction inside one particle template, backward Euler in time (the seed's
// "simple implicit" scheme, Oschmann 2019 Ch. 4 eq. 43, whose printed difference T^{n+1} - T^{n+1}
// is a typo for T^{n+1} - T^n). For cell i with heat capacity C_i = rho c V_i:
//   C_i (T_i^{n+1} - T_i^n) / dt = sum_j k g_ij (T_j^{n+1} - T_i^{n+1})
//                                 + G_b (T_inf,b - T_i^{n+1}) + q_b A_b + Q_b,
// with G_b = A_b / (1/h_b + d_b/k) the series conductance node -> surface -> fluid (the Robin
// condition k dT/dn = h (T_inf - T_s) of the seed's eq. 49 with the surface temperature eliminated;
// the seed's FD form eq. 50 evaluates h T at the old level, a typo: here it is implicit). The
// matrix A = C/dt + K + diag(G_b) is symmetric positive definite, so CG and Cholesky apply;
// BiCGSTAB, which the seed uses for its non-symmetric FD operator, is offered for comparison.
// Everything that changes per particle or per step (ambient temperature, flux, contact heat rates)
// enters the right-hand side only: the matrix, and a CHOLMOD factor of it, belong to the template.

#include "heat/linear_solvers.hpp"
#include "heat/thermal_grid.hpp"

#include <memory>
#include <span>
#include <string_view>
#include <vector>

namespace kiln::heat {

class CholmodFactor;

/// Constant thermal properties of a particle material.
struct ThermalProperties {
    double conductivity = 1.0;  ///< k (W/(m K))
    double density = 1000.0;    ///< rho (kg/m^3)
    double heat_capacity = 1.0; ///< c_p (J/(kg K))
    /// Thermal diffusivity k / (rho c_p) (m^2/s).
    [[nodiscard]] double diffusivity() const { return conductivity / (density * heat_capacity); }
};

/// Linear solver of the resolved model.
enum class SolverKind {
    cg,       ///< Jacobi-preconditioned conjugate gradients (the matrix is SPD)
    bicgstab, ///< Jacobi-preconditioned BiCGSTAB (the seed's choice)
    cholmod,  ///< CHOLMOD factorisation once per operator, then two triangular solves per step
};

/// Name of a solver kind ("cg", "bicgstab", "cholmod").
[[nodiscard]] std::string_view to_string(SolverKind kind);
/// True when this build has CHOLMOD.
[[nodiscard]] bool cholmod_available();

/// Solver choice and stopping rule.
struct SolverSettings {
    SolverKind kind = SolverKind::cg; ///< which solver
    double tolerance = 1e-10;         ///< relative residual ||b - A x|| / ||b|| (-), iterative only
    int max_iterations = 1000;        ///< iteration cap, iterative only
};

/// Boundary data of one particle for one step, per boundary face of the grid (body frame).
/// Empty spans mean "use the uniform value".
struct BoundaryLoad {
    double ambient = 0.0;                       ///< uniform ambient temperature T_inf (K)
    std::span<const double> ambient_per_face{}; ///< T_inf per face (K), overrides `ambient`
    double flux = 0.0;                          ///< uniform heat flux into the body (W/m^2)
    std::span<const double> flux_per_face{};    ///< flux into the body per face (W/m^2), added
    std::span<const double> heat_rate{};        ///< external heat rate into each face's cell (W),
                                                ///< e.g. lagged contact conduction
};

/// What one step did.
struct StepReport {
    SolveStats solve;     ///< linear-solver outcome
    double heat_in = 0.0; ///< heat that entered through the surface during the step (J)
};

/// The assembled backward-Euler operator of one template grid, material, time step and
/// convection coefficients. Owns its solver workspace: use one operator per thread.
class ResolvedOperator {
  public:
    /// Builds A = C/dt + K + diag(G_b). `h_per_face` (W/(m^2 K)) has one entry per boundary face,
    /// or a single entry for a uniform coefficient, or is empty for an insulated surface.
    /// Throws InputError for non-positive properties or time step, or a wrong `h_per_face` size.
    ResolvedOperator(std::shared_ptr<const ThermalGrid> grid, const ThermalProperties& props,
                     double dt, std::span<const double> h_per_face, const SolverSettings& solver);
    ~ResolvedOperator();
    ResolvedOperator(const ResolvedOperator&) = delete;
    ResolvedOperator& operator=(const ResolvedOperator&) = delete;

    /// Advances `temperature` (K, one value per cell) by one step dt; the old field is the
    /// initial guess of iterative solvers. If `previous` (K, the field one step earlier) is given,
    /// the guess is extrapolated linearly, 2 T^n - T^{n-1}, and `previous` is overwritten with T^n
    /// (costs a second field per particle, saves iterations when the field changes smoothly).
    /// Allocation-free.
    StepReport step(std::span<double> temperature, const BoundaryLoad& load,
                    std::span<double> previous = {});

    /// Surface temperature of every boundary patch (K) after a step, from the node-to-surface
    /// split of the patch's heat rate: T_s = T_node + (G_b (T_inf - T_node) + q A + Q) d / (k A)
    /// (T_node where d = 0). `out` has one entry per patch. For output and contact temperatures.
    void surface_temperature(std::span<const double> temperature, const BoundaryLoad& load,
                             std::span<double> out) const;

    /// The grid (body frame).
    [[nodiscard]] const ThermalGrid& grid() const { return *grid_; }
    /// Time step (s).
    [[nodiscard]] double time_step() const { return dt_; }
    /// Material properties.
    [[nodiscard]] const ThermalProperties& properties() const { return props_; }
    /// The system matrix (W/K).
    [[nodiscard]] const SparseMatrix& matrix() const { return a_; }
    /// Node-to-fluid conductance G_b of each boundary face (W/K).
    [[nodiscard]] const std::vector<double>& surface_conductance() const { return g_surface_; }
    /// Heat capacity rho c_p V of each cell (J/K).
    [[nodiscard]] const std::vector<double>& cell_capacity() const { return capacity_; }
    /// Total heat capacity (J/K).
    [[nodiscard]] double total_capacity() const;
    /// Total iterations and solves since construction (for run summaries).
    [[nodiscard]] long total_iterations() const { return iterations_; }
    /// Number of steps taken since construction.
    [[nodiscard]] long total_solves() const { return solves_; }

  private:
    std::shared_ptr<const ThermalGrid> grid_;
    ThermalProperties props_;
    double dt_;
    SolverSettings solver_;
    std::vector<double> capacity_;  // J/K per cell
    std::vector<double> g_surface_; // W/K per boundary face
    SparseMatrix a_;
    EllMatrix ell_;
    Eigen::VectorXd inv_diag_;
    Eigen::VectorXd rhs_;
    Eigen::VectorXd x_;
    KrylovWorkspace work_;
    std::unique_ptr<CholmodFactor> factor_;
    long iterations_ = 0;
    long solves_ = 0;
};

/// Volume-weighted mean temperature (K) of a field on `grid`.
[[nodiscard]] double mean_temperature(const ThermalGrid& grid, std::span<const double> t);

/// Stored heat sum_i C_i T_i relative to 0 K (J) for capacities `capacity` (J/K).
[[nodiscard]] double stored_heat(const std::vector<double>& capacity, std::span<const double> t);

/// Per-particle temperature storage: every particle's field lives in one flat array; a particle
/// is an offset and a cell count (body-frame grid of its template).
class TemperaturePool {
  public:
    /// Appends a field of `cells` values set to `initial` (K); returns the particle's slot.
    int add(int cells, double initial);
    /// The field of slot `p` (K).
    [[nodiscard]] std::span<double> field(int p);
    /// The field of slot `p` (K), read-only.
    [[nodiscard]] std::span<const double> field(int p) const;
    /// Number of slots.
    [[nodiscard]] int size() const { return static_cast<int>(offset_.size()); }
    /// All values (K).
    [[nodiscard]] const std::vector<double>& values() const { return values_; }
    /// Sets all values (K), slot after slot, as values() lists them; `all` has values().size().
    void assign(std::span<const double> all);

  private:
    std::vector<double> values_;
    std::vector<std::size_t> offset_;
    std::vector<int> count_;
};

} // namespace kiln::heat
