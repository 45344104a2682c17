#pragma once
// Heat in the run loop: the temperatures of every particle of a dynamics::System, advanced every
// `step_multiple` mechanical steps by the heat library (lumped or resolved per material), coupled
// through lagged contact conduction (particle-particle and particle-wall), gas-gap conduction and
// radiation between neighbouring particles (pairs from a cell search of their own at each thermal
// step; gaps of bodies from their shapes, body_gap.hpp), convection to a prescribed ambient and a
// prescribed surface flux. Theory: docs/theory/heat.md, "Coupling", "Gas-gap conduction",
// "Gaps between bodies", "Radiation".
//
// Shapes: heat templates are keyed by (material, sphere radius) for spheres and by (material, shape
// template) for bodies (clumps, superquadrics, polyhedra). Lumped bodies take volume and surface
// area from their template; resolved bodies get the Cartesian cut-cell grid of their shape.
//
// Frames: contacts come from System::collect_contacts in the world frame. For a body they are
// rotated into its body frame with the inverse of its orientation q (body -> world) before they
// reach the template grid, so its field turns with it. Spheres carry no orientation in the
// ParticleStore; a resolved sphere's grid gets one here (sphere_rotation, on by default),
// advanced every mechanical step by the sphere's angular velocity (after_step), so its field
// turns with its spin too. Without it a sphere's grid keeps the world axes.

#include "dynamics/system.hpp"
#include "heat/resolved_model.hpp"
#include "thermal/heat_spec.hpp"

#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

namespace kiln::thermal {

/// What a thermal step coupling did, accumulated over the run (for summary.json).
struct ThermalCounters {
    long thermal_steps = 0;   ///< thermal steps taken (-)
    long substeps = 0;        ///< sub-steps taken (>= thermal_steps) (-)
    int max_substeps = 0;     ///< most sub-steps in one thermal step (-)
    double max_lag_ratio = 0; ///< largest dt_thermal / lag limit seen (-); > 0.5 means sub-steps
    long solves = 0;          ///< resolved-particle linear solves (-)
    long iterations = 0;      ///< iterations of those solves (-)
    int max_iterations = 0;   ///< most iterations of one solve (-)
    long unconverged = 0;     ///< solves that hit the iteration cap (-)
    long contacts = 0;        ///< exchanging pairs (contacts, gas, radiation), summed (-)
};

/// Model actually used per material, decided at start-up.
struct MaterialChoice {
    heat::HeatModel requested = heat::HeatModel::none; ///< from the case
    heat::HeatModel used = heat::HeatModel::none;      ///< after the Biot test of "auto"
    double biot = 0;                                   ///< h L_c / k of the largest particle (-)
    int cells = 0;                                     ///< cells per particle (resolved) (-)
    std::string grid; ///< "spherical", "cartesian", both joined by '+' (spheres and bodies), or ""
};

/// A contact onset waiting for the next thermal step, with its contact in each side's body frame
/// at the step that found it (bodies turn before the thermal step; spheres: world axes).
struct PendingImpact {
    dynamics::ContactOnset onset; ///< as recorded by the System
    double x_i[3] = {0, 0, 0};    ///< contact point relative to i's centre (m, i's body frame)
    double n_i[3] = {0, 0, 1};    ///< unit normal from i towards its partner (i's body frame)
    double x_j[3] = {0, 0, 0};    ///< contact point relative to j's centre (m, j's body frame)
    double n_j[3] = {0, 0, -1};   ///< unit normal from j towards i (j's body frame); walls: unused
};

/// Everything a checkpoint needs to continue the temperatures bit for bit.
struct ThermalState {
    std::vector<double> fields;    ///< resolved fields, slot after slot (K)
    std::vector<double> lumped;    ///< lumped temperatures by slot (K)
    std::vector<std::int64_t> ids; ///< particle id of every slot record, in slot order
    double external_heat = 0;      ///< heat that entered from outside so far (J)
    ThermalCounters counters;      ///< counters so far
    /// Contact onsets taken from the System since the last thermal step (collision conduction).
    std::vector<PendingImpact> onsets;
    /// Orientation (body -> world) of every pool slot's grid as w, x, y, z: resolved spheres'
    /// own (sphere_rotation), identity for bodies (theirs is the System's). Empty: all identity.
    std::vector<double> orientations;
    /// Resolved fields one thermal step earlier (K), the layout of `fields`, kept for the
    /// extrapolated initial guess (HeatSpec::extrapolated_guess). Empty: none kept.
    std::vector<double> previous_fields;
};

/// Per-particle temperatures for output, by particle index of the store (K).
struct ParticleTemperatures {
    std::vector<double> mean;    ///< volume mean
    std::vector<double> core;    ///< centre cell (lumped: the temperature)
    std::vector<double> surface; ///< area mean of the patch surface temperatures
};

/// One resolved particle's field with its grid in world position, for field output.
struct FieldView {
    std::int64_t id = 0;                                  ///< particle id
    const heat::ThermalGrid* grid = nullptr;              ///< body-frame grid
    const heat::SphericalResolution* spherical = nullptr; ///< set for spherical grids
    std::span<const double> field;                        ///< cell temperatures (K)
    Vec3 position = Vec3::Zero();                         ///< centre (m, world)
    /// Body -> world rotation of the grid (a resolved sphere's own under sphere_rotation).
    Quat q = Quat::Identity();
};

/// The temperatures of a System and their coupling.
class ThermalSystem {
  public:
    /// Chooses the model per material, builds the templates and gives every particle of `sys` its
    /// initial temperature. Throws InputError for inconsistent data (a heated material without
    /// properties, a hot wall whose material has no conductivity, ...).
    ThermalSystem(const HeatSpec& spec, const dynamics::System& sys);
    ~ThermalSystem();
    ThermalSystem(const ThermalSystem&) = delete;
    ThermalSystem& operator=(const ThermalSystem&) = delete;

    /// Call after every mechanical step: takes the step's contact onsets (collision conduction;
    /// each turned into the body frames of that step) and a thermal step when the step count is
    /// a multiple of step_multiple. Returns true when it took a thermal step.
    bool after_step(const dynamics::System& sys);

    /// One thermal step of step_multiple * dt from the current contacts (lagged exchange) and the
    /// contact onsets taken by after_step since the last one.
    void thermal_step(const dynamics::System& sys);

    /// Thermal step length (s).
    [[nodiscard]] double time_step() const { return dt_; }
    /// Lines describing the model choice per material (for the start-up log).
    [[nodiscard]] std::vector<std::string> describe() const;
    /// The "heat" object of summary.json (a JSON object as text).
    [[nodiscard]] std::string summary_json() const;
    /// Warnings so far (lag limit, unconverged solves).
    [[nodiscard]] const std::vector<std::string>& warnings() const { return warnings_; }
    /// Choice per material.
    [[nodiscard]] const std::vector<MaterialChoice>& choices() const { return choice_; }
    /// Counters so far.
    [[nodiscard]] const ThermalCounters& counters() const { return counters_; }
    /// Impacts that exchanged heat so far (collision conduction; this process, not checkpointed).
    [[nodiscard]] long collisions() const { return collisions_; }

    /// Mean, core and surface temperature of every particle (K), by index of sys.particles();
    /// NaN for particles without a heat model.
    void particle_temperatures(const dynamics::System& sys, ParticleTemperatures& out) const;
    /// Volume-mean temperature of particle index `i` (K); NaN without a heat model.
    [[nodiscard]] double mean_temperature(const dynamics::System& sys, std::size_t i) const;
    /// Heat capacity m c_p of particle index `i` (J/K); 0 without a heat model.
    [[nodiscard]] double heat_capacity(const dynamics::System& sys, std::size_t i) const;
    /// Stored heat sum C T of all heated particles relative to 0 K (J).
    [[nodiscard]] double thermal_energy() const;
    /// Total heat capacity of the heated particles (J/K).
    [[nodiscard]] double heat_capacity() const;
    /// Heat that entered the particles from outside (convection, flux, walls) so far (J).
    [[nodiscard]] double external_heat() const { return external_heat_; }
    /// Lowest and highest cell (or lumped) temperature of all particles (K).
    [[nodiscard]] std::pair<double, double> temperature_range() const;

    /// Resolved fields to write: ids in `ids` (all resolved particles when empty).
    [[nodiscard]] std::vector<FieldView> fields(const dynamics::System& sys,
                                                const std::vector<long>& ids) const;

    /// Copies out the evolving state (checkpoint).
    [[nodiscard]] ThermalState save_state() const;
    /// Replaces the temperatures with saved ones; call after System::restore_state. Throws
    /// InputError when the state does not fit this scene.
    void restore_state(const ThermalState& s, const dynamics::System& sys);

    /// Sets the temperature of particle id `id` uniformly to `t` (K) (tests, set-ups).
    void set_temperature(std::int64_t id, double t);

  private:
    struct Template;
    struct Record {
        int material = -1;
        int templ = -1; // template index for resolved, -1 lumped
        int slot = -1;  // pool slot (resolved) or lumped index; -1 = no heat model
    };
    struct ContactData;

    void sync(const dynamics::System& sys);
    /// Turns every resolved sphere's grid by its angular velocity over one mechanical step.
    void turn_spheres(const dynamics::System& sys);
    /// Body -> world rotation of particle index k's grid (record r): a body's orientation, a
    /// resolved sphere's own (sphere_rotation), otherwise the identity (world axes).
    [[nodiscard]] Quat grid_orientation(const ParticleStore& p, std::size_t k,
                                        const Record& r) const;
    /// Patches of sphere index k (record r; none unless resolved) within `radius` (m) of the
    /// point of its surface facing the world direction `n`, found in its grid frame.
    void sphere_patches(const ParticleStore& p, std::size_t k, const Record& r, const Vec3& n,
                        double radius, std::vector<int>& out) const;
    int template_for(const dynamics::System& sys, std::size_t i);
    heat::ResolvedOperator& operator_for(Template& t, int substeps, int thread);
    [[nodiscard]] double capacity_of(const Record& r) const;
    /// Volume (m^3) and surface area (m^2) of particle index i: its sphere or its shape template.
    [[nodiscard]] std::pair<double, double> volume_area(const dynamics::System& sys,
                                                        std::size_t i) const;
    [[nodiscard]] double patch_weight(const Template& t, int patch) const;
    /// Shares `w` (any scale) of a contact's heat rate `q` (W, into the particle) over its
    /// `patches` of template `t`, with cell temperatures `field` and the partner's contact
    /// temperature `t_other` (K): temperature-weighted on Cartesian grids, by area on spherical.
    void split_weights(const Template& t, std::span<const double> field,
                       const std::vector<int>& patches, double q, double t_other,
                       std::vector<double>& w) const;
    [[nodiscard]] double patch_capacity(const Record& r, const std::vector<int>& patches) const;
    [[nodiscard]] double contact_temperature(const Record& r, const ContactData& c,
                                             bool side_j) const;
    /// Appends the gas-gap (particle-fluid-particle) exchange of every heated particle pair within
    /// the cut-off to data_, adding its conductances to `g_sum` (W/K, by particle index) and its
    /// pair rate to `worst` (1/s) for the lag limit. Nothing without gas.
    void add_gas_gaps(const dynamics::System& sys, std::vector<double>& g_sum, double& worst);
    /// Gas-gap exchanges of particle indices i and j, at least one a body (thermal_body_pairs.cpp):
    /// one copy of `base` (records set) with conductance and patches per element pair within the
    /// cut-off, into `out` (cleared first).
    void body_gas_gaps(const dynamics::System& sys, std::size_t i, std::size_t j,
                       const ContactData& base, std::vector<ContactData>& out) const;
    /// Radiative exchange of particle indices i and j with emissivities e_i, e_j, at least one a
    /// body: coefficient and patches into `d`, the pair's view area (m^2) and each side's
    /// radiating area (m^2); false beyond radiation_cutoff.
    bool body_radiation(const dynamics::System& sys, std::size_t i, std::size_t j, double e_i,
                        double e_j, ContactData& d, double& view_area, double& area_i,
                        double& area_j) const;
    /// Patches of resolved particle index k (record r) facing the world direction `n` within
    /// `radius` (m) of the axis through the world point `point` (m), widened on Cartesian grids.
    [[nodiscard]] std::vector<int> gap_patches(const dynamics::System& sys, const Record& r,
                                               std::size_t k, const Vec3& point, const Vec3& n,
                                               double radius) const;
    /// Radius (m) of particle index k in the gas-gap formula at the world point `point` on its
    /// surface (m): a superquadric's local radius of curvature 1 / sqrt(k1 k2) there (floored as
    /// the contact laws do), otherwise equivalent_radius(sys, k, false).
    [[nodiscard]] double gas_gap_radius(const dynamics::System& sys, std::size_t k,
                                        const Vec3& point) const;
    /// Radius of particle index k (m): a sphere's own; a body's volume- (by_area false) or
    /// area-equivalent (true) sphere radius.
    [[nodiscard]] double equivalent_radius(const dynamics::System& sys, std::size_t k,
                                           bool by_area) const;
    /// Takes `share` (-) of a particle's whole view from its ambient share (record r): a lumped
    /// particle's share drops by it; a resolved particle's faces in `patches` (those exchanging
    /// with the partner) drop uniformly, by share * (total area) / (area of `patches`). Clamping
    /// at 0 is the caller's.
    void take_ambient_view(const Record& r, const std::vector<int>& patches, double share);
    /// Appends the radiative exchange of every pair of heated particles with emissivities > 0
    /// within radiation_cutoff to data_ (coefficient K, W/K^4), with the linearised conductance 4 K
    /// T^3 in `g_sum` and `worst` for the lag limit. Nothing without emissivities.
    void add_radiation(const dynamics::System& sys, std::vector<double>& g_sum, double& worst);
    /// Appends the gas-gap conduction and radiation of every heated particle with every wall at a
    /// temperature within reach (wall_gas, wall_radiation; thermal_walls.cpp) to data_, with
    /// `g_sum` and `worst` as add_gas_gaps, and takes the walls' view factors from the particles'
    /// ambient shares. Call after add_radiation (which resets those shares).
    void add_wall_exchanges(const dynamics::System& sys, std::vector<double>& g_sum, double& worst);
    /// Appends one exchange per pending contact onset (collision conduction) to data_: the
    /// impact heat E of collision_conduction.hpp as the conductance E / (dt_thermal (T_j - T_i))
    /// for this thermal step, so one step moves E exactly; then clears the onsets.
    void add_collisions(const dynamics::System& sys, std::vector<double>& g_sum, double& worst);
    /// Appends the static conduction of every touching pair and hot-wall contact of the System
    /// (world-frame contacts turned into each body frame) to data_, with `g_sum` and `worst` as
    /// add_gas_gaps.
    void add_contacts(const dynamics::System& sys, std::vector<double>& g_sum, double& worst);
    /// Radiating and stagnation-corrected slots of this thermal step (radiating_, stagnant_,
    /// stag_h_ for the bodies' current orientation) and their lagged rates' share of `worst`.
    void prepare_surface(const dynamics::System& sys, double& worst);
    /// Lagged heat rates (W) of every exchange in data_ into face_rate_ / lumped_rate_ from the
    /// temperatures at the start of a sub-step of `dt_sub` (s); hot walls book external heat.
    void add_contact_rates(double dt_sub);
    /// Backward-Euler sub-step of `dt_sub` (s) of every lumped particle (implicit convection,
    /// linearised radiation to the ambient, lagged exchange rates).
    void step_lumped(double dt_sub);
    /// Adds the lagged stagnation correction and radiation to the ambient of the resolved
    /// particles to face_rate_ (per face, W).
    void add_surface_rates();
    /// One backward-Euler solve per resolved particle with face_rate_ (threads over slots), for
    /// a thermal step split into `substeps` of `dt_sub` (s); books external heat and counters.
    void solve_resolved(const dynamics::System& sys, int substeps, double dt_sub);

    HeatSpec spec_;
    double dt_ = 0;
    int threads_ = 1;                       // threads of the resolved solves (System's count)
    std::vector<heat::StepReport> reports_; // per pool slot, last sub-step
    std::vector<MaterialChoice> choice_;
    std::vector<std::string> material_names_;
    std::vector<double> density_; // kg/m^3 per material
    std::vector<std::unique_ptr<Template>> templates_;
    // Key: (material, shape template or -1, radius bits of a sphere or 0).
    std::map<std::tuple<int, int, std::uint64_t>, int> template_index_;
    std::vector<double> shape_area_; // surface area per shape template of the scene (m^2)
    std::vector<Record> by_id_;      // indexed by particle id
    std::vector<double> radius_;     // by particle id (m)
    heat::TemperaturePool pool_;
    heat::TemperaturePool previous_; // pool_ one thermal step earlier (extrapolated_guess)
    /// True when resolved solves start from the extrapolated guess (so previous_ is kept).
    [[nodiscard]] bool keeps_previous() const {
        return spec_.extrapolated_guess && spec_.solver.kind != heat::SolverKind::cholmod;
    }
    std::vector<int> pool_template_;        // template of each pool slot
    std::vector<Quat> pool_q_;              // grid orientation of each pool slot (spheres)
    bool turning_spheres_ = false;          // some resolved sphere's grid turns (sphere_rotation)
    std::vector<double> lumped_;            // lumped temperatures (K)
    std::vector<double> lumped_capacity_;   // rho c V (J/K)
    std::vector<double> lumped_area_;       // surface area (m^2)
    std::vector<double> lumped_emissivity_; // emissivity of each lumped slot (-)
    // Share of each particle's view that goes to the ambient (radiation_temperature): 1 minus the
    // view factors (A F)_ij / A_i of its radiating neighbours this thermal step, >= 0 (-).
    std::vector<double> lumped_view_; // per lumped slot
    // Resolved particles: per boundary face (face_rate_'s layout), the neighbours' view spread
    // over the faces that see them (take_ambient_view).
    std::vector<double> face_view_;
    std::vector<std::int64_t> slot_ids_; // id of each record created, in creation order
    std::vector<dynamics::ContactRecord> contacts_;
    std::vector<ContactData> data_;
    std::vector<double> face_rate_;        // heat rate per boundary face of every pool slot (W)
    std::vector<std::size_t> face_offset_; // first face of each pool slot
    // Resolved bodies under the stagnation distribution (same layout as face_rate_): h f(theta)
    // per face for the body's orientation at this thermal step (W/(m^2 K)) and its lagged
    // correction to the template's uniform h per sub-step (W).
    std::vector<double> stag_h_;
    std::vector<double> conv_rate_;
    std::vector<double> rad_rate_;    // lagged radiation to the ambient per face, this sub-step (W)
    std::vector<double> lumped_rate_; // contact heat rate per lumped slot (W)
    std::vector<char> radiating_;     // per pool slot: radiates to the ambient this thermal step
    std::vector<char> stagnant_;      // per pool slot: lagged stagnation correction this step
    std::vector<double> weights_;     // patch shares of one contact side (scratch)
    double external_heat_ = 0;
    ThermalCounters counters_;
    std::vector<std::string> warnings_;
    // Pairs summed over this process's thermal steps (summary.json; not checkpointed).
    long gas_pairs_ = 0;                // gas-gap pairs
    long radiation_pairs_ = 0;          // radiating pairs
    long collisions_ = 0;               // impacts that exchanged heat (collision conduction)
    long wall_gas_gaps_ = 0;            // particle-wall gas-gap exchanges
    long wall_radiation_ = 0;           // particle-wall radiative exchanges
    std::vector<PendingImpact> onsets_; // taken from the System, not yet exchanged
    std::vector<std::int64_t> index_;   // particle index by id (after_step's scratch)
    bool warned_lag_ = false;
    bool warned_solver_ = false;
};

} // namespace kiln::thermal
