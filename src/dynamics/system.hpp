#pragma once
// The mechanical system: particles, walls and contacts advanced by velocity Verlet.

#include "contact/contact_law.hpp"
#include "contact/neighbour_list.hpp"
#include "core/particle_store.hpp"
#include "dynamics/body_contact.hpp"
#include "dynamics/scene_spec.hpp"
#include "geometry/oriented_box.hpp"

#include <compare>
#include <random>
#include <string>
#include <vector>

namespace kiln::dynamics {

/// Counters of the last force evaluation.
struct ContactCounters {
    long particle_contacts = 0;   ///< touching particle pairs
    long wall_contacts = 0;       ///< touching particle-wall pairs
    double elastic_energy = 0;    ///< energy stored in normal springs (J)
    double max_overlap_ratio = 0; ///< largest overlap / smaller diameter (-)
};

/// Energies of the system (J).
struct Energies {
    double kinetic = 0;    ///< sum 1/2 m v^2
    double rotational = 0; ///< sum 1/2 I omega^2
    double potential = 0;  ///< sum -m g.x (zero at the world origin)
    double elastic = 0;    ///< normal springs of all contacts
    /// Sum of all four (J).
    [[nodiscard]] double total() const { return kinetic + rotational + potential + elastic; }
};

/// Critical time-step figures computed from the materials (s).
struct TimeStepReport {
    double rayleigh = 0;     ///< smallest Rayleigh step over the particles present (s)
    double contact_time = 0; ///< shortest expected contact duration (s)
    double impact_speed = 0; ///< speed used for the Hertz estimate (m/s)
    double limit = 0;        ///< min(rayleigh, contact_time) (s)
};

/// One touching contact, for the heat coupling (collected on demand, not in the force loop).
struct ContactRecord {
    std::uint32_t i = 0;         ///< particle index (current ordering of the store)
    std::uint32_t j = 0;         ///< partner particle index, or wall index when `wall`
    bool wall = false;           ///< true for a particle-wall contact
    Vec3 point = Vec3::Zero();   ///< contact point (m, world): spheres: middle of the overlap
                                 ///< along n; bodies: the narrow phase's point of the element pair
    Vec3 normal = Vec3::UnitZ(); ///< unit normal from i towards its partner (world)
    double overlap = 0;          ///< normal overlap delta > 0 (m)
    double r_eff = 0;            ///< effective radius of curvature R* (m)
};

/// The start of a contact found by the force loop of one step (recorded only when
/// SceneSpec::record_contact_onsets is set): for spheres the pair touches at the end of the step
/// and did not at its start; for element contacts of bodies (body_forces) the element pair has no
/// record of the last step. For the heat coupling (collision conduction).
struct ContactOnset {
    std::int64_t id_i = 0;  ///< particle id of i
    std::int64_t id_j = -1; ///< particle id of the partner; -1 for a wall
    /// Wall index or -1 for a particle pair: analytic walls (SceneSpec::walls) first, then mesh
    /// walls as walls.size() + mesh wall index (recorded by body_forces, spheres included).
    std::int32_t wall = -1;
    std::int64_t step = 0;        ///< step count at the end of the step that found it (-)
    double speed = 0;             ///< normal approach speed before the impact (m/s), >= 0
    double r_eff = 0;             ///< effective radius of curvature R* (m)
    double m_eff = 0;             ///< effective mass m* (kg); the particle's mass against a wall
    double normal[3] = {0, 0, 1}; ///< unit normal from i towards its partner (world)
    /// Contact point (m, world) of an element contact of a body; 0 for sphere-kernel onsets
    /// (a sphere's contact point is its centre + R normal).
    double point[3] = {0, 0, 0};
};

/// Everything that evolves during a run: enough to continue it exactly.
struct SystemState {
    ParticleStore particles;
    std::vector<std::uint32_t> nl_offsets, nl_partners;
    std::vector<Vec3> nl_shear, nl_x_build;
    std::vector<std::int64_t> nl_ids;
    long nl_builds = 0;
    std::vector<Vec3> wall_shear;
    double time = 0;
    long step = 0;
    std::int64_t next_id = 0;
    ContactCounters counters;
    std::string rng; ///< textual state of the random stream (std::mt19937_64 operator<<)
    std::vector<std::pair<BodyContactKey, BodyContact>> body_contacts; ///< body element contacts
    NarrowPhaseCounters narrow_phase;                                  ///< counters so far
};

/// Particles, walls and contacts with a velocity-Verlet integrator.
class System {
  public:
    /// Builds the scene: materials, walls, insertion, time-step check. Throws InputError when the
    /// scene cannot be built (no room to insert, time step above the critical limit, ...).
    explicit System(const SceneSpec& spec);

    /// Advances one mechanical step of length dt.
    void step();
    /// Advances `steps` mechanical steps of length dt and returns with the state (world frame) of
    /// as many calls of step(), bit for bit. Nothing outside reads the state between these steps,
    /// so for spheres with analytic walls (no bodies, no mesh walls, no contact onsets recorded)
    /// the second half kick of one step, the first of the next, the drift, the displacement check
    /// and the clearing of forces and torques are made in one pass over the particles.
    void advance(long steps);

    /// Particle data (world frame).
    [[nodiscard]] const ParticleStore& particles() const { return p_; }
    /// Mutable particle data; call `refresh()` after changing positions or adding particles.
    ParticleStore& particles() { return p_; }
    /// Recomputes neighbour list and forces after external changes to the particles.
    void refresh();
    /// Simulated time (s).
    [[nodiscard]] double time() const { return time_; }
    /// Steps taken.
    [[nodiscard]] long step_count() const { return step_; }
    /// Mechanical time step (s).
    [[nodiscard]] double dt() const { return spec_.time_step; }
    /// Counters from the last force evaluation.
    [[nodiscard]] const ContactCounters& counters() const { return counters_; }
    /// Current energies (J).
    [[nodiscard]] Energies energies() const;
    /// Warnings produced while setting up (for the log and summary).
    [[nodiscard]] const std::vector<std::string>& warnings() const { return warnings_; }
    /// Critical time-step figures.
    [[nodiscard]] const TimeStepReport& time_step_report() const { return ts_; }
    /// The scene this system was built from.
    [[nodiscard]] const SceneSpec& spec() const { return spec_; }
    /// Threads used by the step loop (`SceneSpec::threads`, else OMP_NUM_THREADS, else 1).
    [[nodiscard]] int threads() const { return threads_; }
    /// Number of neighbour-list builds so far.
    [[nodiscard]] long neighbour_builds() const { return nl_.builds(); }
    /// Checks that positions and velocities are finite; throws RunError otherwise.
    void check_finite() const;

    /// Every touching contact of the current state (world frame): sphere-sphere pairs in
    /// neighbour-list order, then sphere-wall contacts in wall order, then the element contacts
    /// of bodies (clump members, superquadrics) from the last force evaluation in key order, one
    /// record per touching element pair with the body's particle index (a pair of clumps can
    /// give several records). Reads stored data only; the mechanics are untouched. `out` is
    /// cleared first.
    void collect_contacts(std::vector<ContactRecord>& out) const;

    /// Contacts that started during the last step() (sphere-sphere in neighbour-list chunk order,
    /// then sphere-wall in particle-unit and wall order, then element contacts of bodies with
    /// each other, analytic and mesh walls in body_forces() order); empty unless
    /// SceneSpec::record_contact_onsets is set. Overwritten by the next step (a refresh() keeps
    /// them; contacts it finds are no onsets): a consumer takes them after every step.
    [[nodiscard]] const std::vector<ContactOnset>& contact_onsets() const { return onsets_; }

    /// Copies out the full evolving state (checkpoint).
    [[nodiscard]] SystemState save_state() const;
    /// Replaces the evolving state with a saved one (restart); the run continues bit for bit.
    void restore_state(SystemState s);

    /// Adds one particle; returns its index. The neighbour list is rebuilt at the next step.
    std::size_t add_particle(int material, double radius, const Vec3& x, const Vec3& v,
                             const Vec3& omega);
    /// Adds one rigid body of template `shape` (index into SceneSpec::shapes) at centre of mass x
    /// (m, world), velocity v (m/s, world), angular velocity omega (rad/s, world) and orientation
    /// q (body -> world); returns its index.
    std::size_t add_body(int material, int shape, const Vec3& x, const Vec3& v, const Vec3& omega,
                         const Quat& q);
    /// True when the scene holds non-spherical particles.
    [[nodiscard]] bool has_bodies() const { return has_bodies_; }
    /// Element contacts involving a body (and mesh-wall contacts) from the last force evaluation
    /// (world frame: points, normals from b to a, overlaps, effective radii, forces on a), each
    /// with its key (ids, elements), in evaluation order (not key order). Built on demand from the
    /// compact member-pair histories and the table of the other contacts (valid until the next
    /// step, refresh or restore; the first read after a step fills a cache, so concurrent calls
    /// from several threads are not allowed).
    [[nodiscard]] const std::vector<BodyContactEntry>& body_contacts() const;
    /// Narrow-phase counters summed over the run (superquadric queries, fallbacks, failures).
    [[nodiscard]] const NarrowPhaseCounters& narrow_phase_counters() const { return np_; }
    /// Turns the separating-direction cache of convex pairs (and the portal search of superquadric
    /// near misses) on (the default) or off. The results are the same either way (tests, A/B).
    void use_separation_cache(bool on) { separation_cache_ = on; }
    /// Turns the memory of polyhedron pairs that touched at the last step (geometry::PlaneMemo:
    /// the common-plane search evaluates only the candidates that can still win) on (the default)
    /// or off. The results are the same bits either way (tests, A/B).
    void use_plane_memo(bool on) { plane_memo_ = on; }
    /// Resting pairs of two boxes (both single polyhedra whose faces lie along their body axes,
    /// touching at the last step, fast common plane) in vector lanes, eight pairs at a time
    /// (box_pair_contacts; on, the default), or each through element_contact (off, the route
    /// before session 29, for tests and A/B). The same contacts to round-off.
    void use_box_lanes(bool on) { box_lanes_ = on; }
    /// The law of contacts with a convex element (polyhedron, superquadric; pairs and plane or
    /// cylinder walls) in blocks of vector lanes (on, the default) or one contact at a time (off,
    /// the route before session 12, for tests and A/B). Same contacts and order; the forces agree
    /// to round-off (GCC contracts a * b + c differently in the two routes).
    void use_convex_blocks(bool on) { convex_blocks_ = on; }
    /// The member build's test of two clumps' members, and the first pass of a clump's members
    /// against a plane wall, eight members at a time in vector lanes (AVX-512 builds; on, the
    /// default) or one at a time (off, for tests and A/B). The same pairs and wall contacts in
    /// the same order, so the same bits.
    void use_member_lanes(bool on) { member_lanes_ = on; }
    /// The member build's box test (on, the default; off for tests and A/B): an entry of two
    /// polyhedra or superquadrics whose boxes along their body axes are more than a skin apart is
    /// left out of the member pairs, and the member pairs are rebuilt when a body of such an entry
    /// has moved (travel_, rotation included) half a skin since. The same contacts, so the same
    /// bits.
    void use_box_filter(bool on) {
        box_filter_ = on;
        members_valid_ = false;
    }
    /// Bodies from which the per-body passes of a step (posing, rotation), the first pass over
    /// member pairs and the law of clump member pairs run on several threads, when there are
    /// several (default 256: the lattice scenes of 343 clumps gain 1.10-1.17x with two threads,
    /// and a parallel region per pass costs more than it saves on fewer; tests set it lower to
    /// run those routes on small scenes). The results are the same bits either way.
    void use_parallel_bodies(std::size_t min_bodies) { parallel_bodies_ = min_bodies; }
    /// Turns the inner list of the sphere pair filter (a two-level Verlet list) on (the default)
    /// or off. The results are the same bits either way (tests, A/B).
    void use_inner_list(bool on) {
        use_inner_ = on;
        inner_valid_ = false;
    }
    /// Lets advance() form the elastic energy and the largest overlap ratio of the sphere contacts
    /// (pairs and walls) only at its last step, the one whose counters() and energies() can be
    /// read (on, the default), or at every step (off). Positions, velocities, forces and the
    /// counters read after a step(), advance() or refresh() are the same bits either way (tests,
    /// A/B).
    void use_energy_on_demand(bool on) { energy_on_demand_ = on; }
    /// Lets the register path of the sphere pairs take R* and m* once when every particle has the
    /// same radius and mass (on, the default; from the next list build) or per contact (off, at
    /// once). The results are the same bits either way (tests, A/B).
    void use_uniform_sizes(bool on) {
        use_uniform_ = on;
        if (!on) {
            same_radius_ = 0.0;
            same_mass_ = 0.0;
        }
    }
    /// Steps whose pair filter took the inner list, and particles found loose (their entries added
    /// to it), since construction (not saved in checkpoints; for tests and A/B).
    [[nodiscard]] long inner_list_steps() const { return inner_steps_; }
    [[nodiscard]] long inner_list_loosened() const { return inner_loosened_; }
    /// Convex pair queries that a cached or searched separating direction answered (no narrow
    /// phase), since construction or restart (not saved in checkpoints).
    [[nodiscard]] long separation_skips() const { return separation_skips_; }
    /// Box pair queries answered in vector lanes (use_box_lanes), since construction (not saved
    /// in checkpoints; for tests and A/B).
    [[nodiscard]] long box_lane_pairs() const { return box_lane_pairs_; }
    /// Member pairs and general items listed by the member builds since construction (not saved
    /// in checkpoints; for tests and A/B of use_member_lanes).
    [[nodiscard]] long member_pairs_built() const { return member_pairs_built_; }
    /// Member builds, and list entries that the box test left out of them, since construction
    /// (not saved in checkpoints; for tests and A/B of use_box_filter).
    [[nodiscard]] long member_builds() const { return member_builds_; }
    [[nodiscard]] long box_filter_drops() const { return box_filter_drops_; }

  private:
    /// Sums of one work unit (a chunk of list entries or wall candidates).
    struct ChunkTotals {
        double energy = 0;    // elastic energy of its contacts (J)
        double max_ratio = 0; // largest overlap / smaller diameter (-)
        long contacts = 0;    // touching pairs
    };

    void insert(const InsertSpec& ins);
    void place(const InsertSpec& ins, double radius, const Vec3& x);
    Quat initial_orientation(const OrientationSpec& o);
    void body_forces(ChunkTotals& pairs, ChunkTotals& walls);
    void rotate_bodies(int kicks, bool drift);
    void index_bodies();
    void check_time_step();
    void choose_filter(std::size_t pair_units);
    void finish_inner_build();
    void loosen(const std::vector<std::uint32_t>& loose);
    void compute_forces(bool kick_requested = false, bool forces_cleared = false);
    bool begin_step(int kicks);
    template <int kicks, bool clear>
    double kick_drift(std::size_t p0, std::size_t p1, bool same_size,
                      std::vector<std::uint32_t>& loose);
    template <class Law, bool direct, bool bodies, bool onsets = false>
    void pair_chunk(const Law& law, std::size_t begin, std::size_t end, ChunkTotals& t);
    void sum_pair_results(std::size_t i);
    template <class Law, bool onsets = false>
    void wall_unit(const Law& law, std::size_t p0, std::size_t p1, ChunkTotals& t);
    void half_kick(std::size_t p0, std::size_t p1);
    void rebuild_neighbours();
    void index_partners();
    void find_wall_candidates();
    /// Moves the wall histories of the last build's candidates (`old_candidates`, old indices)
    /// to the particles' new places after the store was reordered (new k <- old order[k]).
    void carry_wall_histories(const std::vector<std::uint32_t>& order,
                              const std::vector<std::vector<std::uint32_t>>& old_candidates);
    /// Makes room in wall_shear_ for every particle of the store (the stride at least doubles, so
    /// that adding particles one by one moves each history a bounded number of times).
    void grow_wall_histories();

    SceneSpec spec_;
    PairTable pairs_;
    ParticleStore p_;
    contact::NeighbourList nl_;
    // Wall histories, wall by wall: [wall * wall_stride_ + particle] (wall_stride_ >= the number
    // of particles). A wall's candidates are in increasing particle order, and those of a plane
    // wall are mostly runs of neighbouring indices (the store is sorted by cell), so the scan and
    // the law read each wall's histories nearly in sequence (SystemState keeps them particle by
    // particle).
    std::vector<Vec3> wall_shear_;
    std::size_t wall_stride_ = 0;
    // Scratch of carry_wall_histories: an all-zero array of wall_shear_'s size, the new place of
    // each particle and a flag per (wall, particle) of the new candidates (wall_shear_'s layout).
    std::vector<Vec3> wall_shear_spare_;
    std::vector<std::uint32_t> new_place_;
    std::vector<std::uint8_t> wall_mark_;
    std::vector<std::vector<std::uint32_t>> wall_candidates_;
    std::vector<int> wall_material_; // material of each analytic wall (spec_.walls order)
    // With more than one thread, pair results go to rows of `pair_result_` (force, torque on i,
    // torque on j; a chunk's touching entries in order from the chunk's first entry index, plus a
    // zero row at the end), `result_row_` maps each entry to its row or to the zero row, and each
    // particle sums its rows in list order through `as_partner_` (entries where it is the partner,
    // by particle in compressed rows).
    std::vector<double> pair_result_;
    std::vector<std::uint32_t> result_row_;
    std::vector<std::uint32_t> as_partner_offsets_, as_partner_;
    std::vector<ChunkTotals> pair_totals_, particle_totals_;
    // Per group of four list entries (bit k % 4 of byte k / 4): the entries that touched at the
    // last step's four-entry filter (simd::touching_entries), which clears the histories of those
    // that stopped touching only; all bits set after a list build or a restart (unknown).
    std::vector<std::uint8_t> touched_;
    std::vector<double> entry_rsum2_; // (r_i + r_j)^2 of each list entry (m^2), set at each build
    // The radius (m) and mass (kg) of every particle when all have the same, else 0; set at each
    // build (radii and masses do not change between builds).
    double same_radius_ = 0.0;
    double same_mass_ = 0.0;
    // Inner list of the four-entry filter (two-level Verlet list, docs/architecture.md "Inner
    // list"): per pair chunk, the list entries whose gap |x_i - x_j| - (r_i + r_j) was below
    // inner_gap_ at the positions of the filter pass that built it, and every entry of a particle
    // that has since been loose (moved more than its room, room2_), in entry order (chunk u's part
    // of the arrays starts at its first entry index, of inner_was_ at a quarter of it;
    // inner_count_[u] entries; inner_bits_ has one bit per list entry). An entry outside them has
    // both particles within g / 2 of where they were at the build, so it cannot touch, and the
    // filter tests the inner entries only.
    std::vector<std::uint32_t> inner_k_, inner_i_, inner_j_;
    std::vector<std::size_t> inner_count_;
    std::vector<double> inner_rsum2_;
    std::vector<std::uint8_t> inner_was_;
    std::vector<std::uint64_t> inner_bits_;
    std::vector<double> entry_near2_; // (r_i + r_j + inner_gap_)^2 of each list entry (m^2)
    // Per particle: (g / 2 - |x - x_build| at the inner build)^2 (m^2), infinite when loose or
    // without inner lists.
    std::vector<double> room2_;
    std::vector<std::vector<std::uint32_t>> unit_loose_; // loose particles found by the pass
    double inner_gap_ = 0;                               // m
    bool inner_valid_ = false;     // the inner lists hold every entry that can touch
    bool inner_used_ = false;      // the last filter ran on the inner lists (touched_ is stale)
    bool use_inner_ = true;        // use_inner_list()
    bool use_uniform_ = true;      // use_uniform_sizes()
    bool energy_on_demand_ = true; // use_energy_on_demand()
    bool form_counters_ = true;    // the next force evaluation forms the energy and overlap ratio
    std::size_t inner_loose_ = 0;  // loose particles since the inner build
    long inner_next_build_ = 0;    // no inner build before this step (after dropping them)
    static constexpr long inner_holdoff = 200;              // steps
    long inner_steps_ = 0;                                  // inner_list_steps()
    long inner_loosened_ = 0;                               // inner_list_loosened()
    enum class Filter : std::uint8_t { all, build, inner }; // the pair filter of this step
    Filter filter_ = Filter::all;
    int threads_ = 1;
    std::size_t parallel_bodies_ = 256; // use_parallel_bodies()
    /// Do the per-body passes of a step run on several threads (use_parallel_bodies)?
    [[nodiscard]] bool parallel_body_passes() const {
        return threads_ > 1 && bodies_.size() >= parallel_bodies_;
    }
    ContactCounters counters_;
    TimeStepReport ts_;
    std::vector<std::string> warnings_;
    std::mt19937_64 rng_;
    double time_ = 0;
    long step_ = 0;
    std::int64_t next_id_ = 0;
    bool list_valid_ = false;
    // Non-spherical particles (see docs/architecture.md, "Bodies in the run loop"): their pairs are
    // left out of the sphere kernel and evaluated element by element in body_forces().
    bool has_bodies_ = false;
    std::vector<std::uint32_t> bodies_;       // indices of the body particles
    std::vector<std::uint32_t> body_entries_; // list entries with a body on either side
    // Member pairs (clumps, spheres): the element pairs of body entries whose sphere elements are
    // within a skin of each other, in the order body_forces() evaluates them (entry, element of
    // a, element of b; a is the particle with the smaller id). An entry with a non-sphere element
    // on either side is one item with ea = eb = no_element (evaluated by the general route).
    // Rebuilt after every list build and when an element has moved more than half a skin since
    // (rotation included), so no touching member pair is missed between builds.
    struct MemberPair {
        std::uint32_t k, a, b, ea, eb; // list entry, particles, elements (indices of elements_)
    };
    static constexpr std::uint32_t no_element = 0xffffffffU;
    std::vector<MemberPair> member_pairs_;
    // build_member_pairs on several threads: each range of entries' pairs and keys (scratch).
    std::vector<std::vector<MemberPair>> range_pairs_;
    std::vector<std::vector<BodyContactKey>> range_keys_;
    std::vector<std::size_t> range_offsets_; // where each range's pairs go in member_pairs_
    // build_member_pairs: the posed members by component (x, y, z, r; each member_c_.size()
    // long), for its pair test eight members at a time (scratch).
    std::vector<double> member_cols_;
    // Per list entry of two single convex elements (polyhedra, superquadrics): a direction (unit,
    // from b's element to a's, a the particle with the smaller id, world frame) that separated them
    // at an earlier step, or zero; reset at every list build and restart (element_contact's
    // `separating`). The answers do not depend on it, only the work does.
    std::vector<Vec3> sep_dirs_;
    bool separation_cache_ = true;
    // Per list entry of two single polyhedra: the memory of its last common-plane search, read
    // when the pair touched at the last step (element_contact's `memo`). It depends on the two
    // shapes and their relative pose only, so it needs no reset at a list build or restart (a
    // memory from another pose is refilled); sized with sep_dirs_ at the list build (index_bodies).
    // The answers do not depend on it.
    std::vector<geometry::PlaneMemo> plane_memos_;
    bool plane_memo_ = true;
    // The resting box pairs of one evaluation (body_forces): their queries, per hit its pair,
    // their last step's records and their contacts (box_pair_contacts).
    bool box_lanes_ = true;
    bool member_lanes_ = true;    // use_member_lanes
    long member_pairs_built_ = 0; // member_pairs_built
    // The box test of the member build (use_box_filter): per shape, the box of a polyhedron or
    // superquadric along its body axes (half extents < 0: none, the shape takes no box test); per
    // particle, the travel_ at which a body of an entry left out may reach its partner (m;
    // +infinity: in no such entry), read against travel_ at every posing (body_forces), which then
    // rebuilds the member pairs; and per particle a mark of such bodies (scratch of the build).
    bool box_filter_ = true;
    std::vector<geometry::BodyBox> body_boxes_;
    std::vector<double> box_limit_;
    std::vector<std::uint8_t> box_marks_;
    bool box_limits_live_ = false; // some entry was left out at the last member build
    long member_builds_ = 0;       // member_builds
    long box_filter_drops_ = 0;    // box_filter_drops
    std::vector<BoxPairQuery> box_queries_;
    std::vector<std::uint32_t> box_slot_; // per hit: its pair in box_queries_, or none
    // Per particle: 1 for a single polyhedron that is a box along its body axes, its orientation
    // finite (set at the posing), else 0.
    std::vector<std::uint8_t> box_body_;
    std::vector<const BodyContact*> box_old_;
    std::vector<ElementContact> box_found_;
    // Per list entry of two single polyhedra whose cached direction proved them apart: the pose
    // of that proof (overlap along the direction, the direction's component of the centres'
    // difference, both orientations), from which a later step bounds the overlap without the
    // vertex scan (body_forces, general_entry). Valid only until the entry's direction changes:
    // cleared whenever the entry takes the full route, and at every list build (beside
    // sep_dirs_). The answers do not depend on it.
    struct SeparationProof {
        bool valid = false;
        double overlap = 0.0; // overlap along the direction at the proof (m, < 0)
        double along = 0.0;   // direction . (x_b - x_a) at the proof (m)
        Quat qa = Quat::Identity();
        Quat qb = Quat::Identity();
    };
    std::vector<SeparationProof> sep_proofs_;
    // Near misses skipped for several steps (body_forces): travel_[i] bounds how far any point of
    // polyhedron or superquadric body i has moved since the last list build (m; the centre's step
    // plus the bounding radius times the change of the rotation, |R - R0| <= 2 min |q -+ q0|, in
    // 2-norms, summed step by step and rounded upwards), brought up to the pose (travel_x_,
    // travel_q_) at every posing. apart_below_[k]: when entry k's proof holds, the overlap along
    // its direction stays below minus twice the margin while travel_[a] + travel_[b] stays below
    // this (m; -infinity: no such bound); the first pass then counts the entry as proved apart
    // without visiting it. Reset at every list build, cleared with the proof.
    std::vector<double> travel_;
    std::vector<double> travel_r_; // per particle: a polyhedron's or superquadric's bounding
                                   // radius, else 0 (m)
    std::vector<Vec3> travel_x_;
    std::vector<Quat> travel_q_;
    std::vector<double> apart_below_;
    // Per shape: the hull of a polyhedron posed in place by body_forces, or nullptr (scratch).
    std::vector<const geometry::ConvexPolyhedron*> pose_hulls_;
    // Per body-wall candidate (body_walls_): for a single polyhedron apart from a plane wall, the
    // travel_ of the body below which its deepest vertex stays above the wall by more than the
    // margin (m; -infinity: none); body_forces then skips the query, whose answer is "apart" and
    // leaves no record. Reset with body_walls_ (find_wall_candidates).
    std::vector<double> wall_apart_below_;
    bool convex_blocks_ = true; // see use_convex_blocks
    long separation_skips_ = 0;
    long box_lane_pairs_ = 0;
    // Compact histories, parallel to member_pairs_ (docs/architecture.md, "Contact records"): the
    // key of each member pair (ids, element indices in each particle; -1 for a general item), set
    // at the member build; the shear (m) and force on a (N, world) of its contact at the last
    // evaluation; and member_seen_, the evaluation (body_eval_) that last found it touching. The
    // full record of a member-pair contact is built only where it is read (body_contacts(),
    // checkpoints, re-keying); the table body_contacts_ holds the other element contacts.
    std::vector<BodyContactKey> member_keys_;
    std::vector<Vec3> member_shear_, member_force_;
    std::vector<std::int64_t> member_seen_;
    std::int64_t body_eval_ = 0; // body_forces() calls so far
    // True when last evaluation's member-pair histories are in body_contacts_ (at the start, after
    // a restart, a list rebuild or a member rebuild: fold_member_contacts), false when they are in
    // member_shear_ (after body_forces()).
    bool members_from_table_ = true;
    mutable std::vector<BodyContactEntry> contacts_view_; // body_contacts(), built on demand
    mutable bool view_valid_ = false;
    // When member_pairs_ was built: the element centres (m, world), each particle's centre (m,
    // world) and R(q) (rot_), and the farthest element centre from the particle's centre (m; 0
    // for one element) (body_forces' rebuild test).
    std::vector<Vec3> member_x_build_;
    std::vector<Vec3> body_x_build_;
    std::vector<Mat3> body_rot_build_;
    std::vector<double> member_reach_;
    bool members_valid_ = false;
    void build_member_pairs();
    // Walls within the skin of each body at the last list build: those of bodies_[b] are
    // body_walls_[body_wall_offsets_[b] .. body_wall_offsets_[b + 1]), in wall order.
    std::vector<std::uint32_t> body_wall_offsets_, body_walls_;
    // R(q) of each body (body -> world; particle index, unused for spheres): set from q at every
    // list rebuild and restart, carried by free_rotate between them (the same function of q).
    std::vector<Mat3> rot_;
    // Element contact histories in a flat table, in the order body_forces() meets them: grouped by
    // (section, list entry or particle, wall, element of a), groups in increasing order, so each
    // step finds last step's record with a forward cursor (no search). Re-grouped by key only when
    // the list or the particle order changes (rekey_body_contacts).
    struct ContactGroup {
        std::uint64_t hi = 0; // section << 32 | list entry, particle or mesh wall
        std::uint64_t lo = 0; // particle or wall << 32 | element of a
        ContactGroup() = default;
        ContactGroup(std::uint32_t section, std::uint32_t major, std::uint32_t minor,
                     std::uint32_t element)
            : hi(std::uint64_t{section} << 32 | major), lo(std::uint64_t{minor} << 32 | element) {}
        auto operator<=>(const ContactGroup&) const = default;
    };
    std::vector<BodyContactEntry> body_contacts_, next_contacts_;
    std::vector<ContactGroup> body_groups_, next_groups_;
    void rekey_body_contacts();
    /// The full records (and their groups when `groups` is given) of the last evaluation in
    /// evaluation order: the table's merged with the member pairs' (their normal, point and
    /// overlap derived from the elements only when `geometry`; shear, force and R* always).
    void merged_body_contacts(std::vector<BodyContactEntry>& out, std::vector<ContactGroup>* groups,
                              bool geometry) const;
    /// Moves the member-pair histories into the table (full records, in evaluation order).
    void fold_member_contacts(bool geometry);
    NarrowPhaseCounters np_;
    // Elements of every particle, this step; only the slots of superquadrics and polyhedra are
    // written (sphere elements live in member_c_ alone).
    std::vector<Element> elements_;
    // Centre (m, world) and radius (m) of every element of elements_, this step, 32 bytes each
    // (radius 0 for an element that is not a sphere): what the member-pair loop reads.
    struct MemberSphere {
        double x, y, z, r;
    };
    std::vector<MemberSphere> member_c_;
    std::vector<std::uint32_t> member_hits_; // this step's touching member pairs (scratch)
    // With several threads, the narrow phase of the hits between two single-element particles
    // (one of them convex) runs ahead of body_forces' serial pass, in parallel (scratch, one per
    // hit): its counts, and the contact the serial pass then hands to the law in its own order.
    // Each such query reads and writes only its own list entry's state (cached direction, proof,
    // plane memory), so the answers are the serial route's, bit for bit.
    struct NarrowCounts {
        long calls = 0;     // narrow-phase queries (np_.calls)
        long skips = 0;     // proved apart by a cached direction (separation_skips_)
        long fallbacks = 0; // np_.fallbacks
        long failures = 0;  // np_.failures
    };
    struct AheadPair {
        bool ready = false;    // computed ahead (else the serial pass runs the query)
        bool touching = false; // a contact for the law
        std::uint32_t a = 0, b = 0;
        BodyContactKey key{};
        ElementContact ec;
        const BodyContact* old = nullptr; // last step's record of the contact, or none
        double ratio = 0.0;               // overlap / ratio_size
        NarrowCounts counts;
        /// Records a contact for the law.
        void found(std::uint32_t a_in, std::uint32_t b_in, const BodyContactKey& key_in,
                   const ElementContact& ec_in, const BodyContact* old_in, double ratio_in) {
            touching = true;
            a = a_in;
            b = b_in;
            key = key_in;
            ec = ec_in;
            old = old_in;
            ratio = ratio_in;
        }
        // An entry with a clump (the general route): the narrow-phase answers of its convex
        // element pairs, in the route's order (planned: found ahead).
        bool planned = false;
        std::vector<ElementContact> plan;
    };
    std::vector<AheadPair> ahead_;
    std::vector<AheadPair> wall_ahead_; // the same for body_walls_ (a is the body, b the wall)
    // The law's answers for the clump member pairs of one block of the sphere queue (16 lanes),
    // found ahead of the serial pass on several threads (body_forces): what the serial pass's
    // flush reads to add the forces in its order, and the onset's data when it records onsets
    // (the pairs' histories are written ahead, to member_shear_ and member_force_).
    struct MemberBlock {
        static constexpr std::size_t lanes = 16;
        double f[3][lanes], ra[3][lanes], rb[3][lanes], ti[3][lanes], tj[3][lanes];
        double energy[lanes], ratio[lanes];
        double n[3][lanes], p[3][lanes], v[3][lanes], m_eff[lanes], r_eff[lanes]; // onsets
        bool is_new[lanes];
    };
    std::vector<MemberBlock> member_blocks_;
    std::vector<std::uint32_t> member_order_; // the member pairs among the hits, in order
    std::vector<std::size_t> range_counts_;   // body_forces' first pass: hits, skips per range
    // A body's elements near a plane or cylinder wall (scratch of body_forces' wall pass).
    std::vector<std::uint32_t> wall_hits_;
    // The contacts of a clump's sphere elements with one wall (body_forces' wall pass): the
    // element's index in the body and the contact; per candidate of body_walls_ when found ahead
    // on several threads (ready: found), and the serial pass's own.
    struct MemberWallContact {
        std::uint32_t j;
        ElementContact ec;
    };
    std::vector<std::vector<MemberWallContact>> clump_wall_ahead_;
    std::vector<unsigned char> clump_wall_ready_;
    std::vector<MemberWallContact> one_clump_wall_;
    std::vector<std::uint32_t> element_begin_; // particle i: [begin[i], begin[i + 1])
    // Polyhedron features per template (empty for other shapes), built once in the constructor.
    std::vector<geometry::PolyhedronFeatures> poly_features_;
    std::vector<MemberColumns> member_columns_;   // per template: a clump's members by component
    std::vector<geometry::MeshContact> mesh_buf_; // scratch of mesh-wall queries
    // Contact onsets (SceneSpec::record_contact_onsets): per pair chunk and per particle unit
    // while the force loop runs, then joined in that fixed order into onsets_.
    std::vector<std::vector<ContactOnset>> pair_onsets_, wall_onsets_;
    std::vector<ContactOnset> onsets_;
    // body_forces() of this step appends element-contact onsets (heat: collision conduction).
    bool record_body_onsets_ = false;
    /// Appends the onset of the new element contact `key` (pair, analytic or mesh wall) with normal
    /// `n` (b to a, world), contact point `point` (m, world), relative velocity of the contact
    /// point `v_rel` (a minus b, m/s), m* (kg) and R* (m) to onsets_.
    void note_body_onset(const BodyContactKey& key, const Vec3& n, const Vec3& point,
                         const Vec3& v_rel, double m_eff, double r_eff);
    /// True when contacts go through body_forces (bodies or mesh walls present).
    [[nodiscard]] bool generic_contacts() const { return has_bodies_ || !spec_.mesh_walls.empty(); }
};

} // namespace kiln::dynamics
