#pragma once
// A scene as plain data: what a case file describes, after validation and with defaults filled in.
// Building a System from it is the only way scenes are set up, from files and from tests alike.

#include "contact/contact_law.hpp"
#include "core/material.hpp"
#include "core/types.hpp"
#include "dynamics/wall.hpp"
#include "geometry/shape.hpp"

#include <cstdint>
#include <random>
#include <vector>

namespace kiln::dynamics {

/// Distribution of particle radii.
struct SizeDistribution {
    enum class Kind { constant, uniform, normal, discrete };
    Kind kind = Kind::constant;
    double radius = 0;           ///< constant radius (m)
    double min = 0;              ///< lower bound for uniform and (truncation of) normal (m)
    double max = 0;              ///< upper bound for uniform and (truncation of) normal (m)
    double mean = 0;             ///< mean radius of the normal distribution (m)
    double stddev = 0;           ///< standard deviation of the normal distribution (m)
    std::vector<double> values;  ///< radii of the discrete distribution (m)
    std::vector<double> weights; ///< relative number weights of the discrete distribution (-)

    /// Largest radius the distribution can return (m).
    [[nodiscard]] double largest() const;
    /// Draws one radius (m).
    double sample(std::mt19937_64& rng) const;
};

/// Initial orientation of non-spherical particles.
struct OrientationSpec {
    bool random = false;           ///< uniformly random orientation (from the scene's stream)
    Quat fixed = Quat::Identity(); ///< used when not random: body -> world
};

/// Effective radius R* of a contact with a superquadric (docs/theory/contact.md, "Effective
/// radius"). Other contacts (sphere elements, polyhedra) have a constant R* either way.
enum class BodyRadius {
    first_touch, ///< local curvature at the first step of the contact, kept while it lasts
                 ///< (default)
    per_step     ///< local curvature at the current contact point, re-evaluated every step
};

/// Narrow-phase method for pairs involving a superquadric (geometry/convex_contact.hpp) or two
/// polyhedra (geometry/polyhedron_contact.hpp).
enum class NarrowPhase {
    newton, ///< superquadrics: Newton on the sphere of directions, warm-started from the last
            ///< normal; polyhedra: the exact fast common plane (default)
    gjk_epa ///< libccd GJK + EPA
};

/// Particles inserted at start-up in a box region.
struct InsertSpec {
    enum class Kind { lattice, random };
    Kind kind = Kind::random;
    int material = 0;             ///< material index
    Aabb region;                  ///< particles lie entirely inside (m, world)
    long count = 0;               ///< number of particles (lattice: at most, 0 = fill)
    SizeDistribution size;        ///< radii
    double spacing = 0;           ///< lattice spacing (m), 0 = 2 r_max
    Vec3 velocity = Vec3::Zero(); ///< initial velocity (m/s, world)
    Vec3 omega = Vec3::Zero();    ///< initial angular velocity (rad/s, world)
    int shape = -1;               ///< index into SceneSpec::shapes; -1 = spheres of `size`
    OrientationSpec orientation;  ///< initial orientation of bodies
};

/// One explicitly placed particle.
struct ParticleSpec {
    ParticleSpec() = default;
    /// A sphere: material index, radius (m), centre (m), velocity (m/s), angular velocity
    /// (rad/s), all world frame.
    ParticleSpec(int mat, double r, const Vec3& pos, const Vec3& vel, const Vec3& ang_vel)
        : material(mat), radius(r), x(pos), v(vel), omega(ang_vel) {}

    int material = 0;            ///< material index
    double radius = 0;           ///< radius (m)
    Vec3 x = Vec3::Zero();       ///< centre (m, world)
    Vec3 v = Vec3::Zero();       ///< velocity (m/s, world)
    Vec3 omega = Vec3::Zero();   ///< angular velocity (rad/s, world)
    int shape = -1;              ///< index into SceneSpec::shapes; -1 = a sphere of `radius`
    OrientationSpec orientation; ///< initial orientation of a body
};

/// The mechanical scene.
struct SceneSpec {
    std::vector<Material> materials; ///< material table
    std::vector<PairOverride> pairs; ///< explicit pair values
    contact::ContactModel contact;   ///< contact model
    double skin = 0;                 ///< neighbour-list skin (m), 0 = 10 % of the largest diameter
    bool sort_particles = true;      ///< reorder particles by cell at each list build
    int threads = 0;         ///< threads of the step loop; 0 = the OpenMP default (OMP_NUM_THREADS)
    std::vector<Wall> walls; ///< walls
    std::vector<MeshWallSpec> mesh_walls; ///< triangle-mesh walls (after `walls` in contact keys)
    std::vector<InsertSpec> inserts;      ///< insertion blocks, in order
    std::vector<ParticleSpec> particles;  ///< explicitly placed particles (inserted first)
    Vec3 gravity = Vec3(0, 0, -9.81);     ///< gravitational acceleration (m/s^2, world)
    double time_step = 0;                 ///< mechanical time step (s)
    std::uint64_t seed = 1;               ///< seed of the random stream
    double time_step_fraction =
        0.1; ///< warn when dt > this fraction of min(Rayleigh, contact time)
    bool allow_unsafe_time_step = false; ///< turn the "dt above critical" error into a warning
    double expected_speed = 0; ///< largest impact speed for the Hertz estimate (m/s), 0 = estimate
    std::vector<geometry::ShapeTemplate> shapes;      ///< templates of the non-spherical particles
    NarrowPhase narrow_phase = NarrowPhase::newton;   ///< method for superquadric pairs
    BodyRadius body_radius = BodyRadius::first_touch; ///< R* of superquadric contacts
    /// Record the start of every contact with another particle or an analytic wall, spheres and
    /// bodies (System::contact_onsets; for collision conduction). Off: the force loop runs the
    /// same code as without heat.
    bool record_contact_onsets = false;
};

} // namespace kiln::dynamics
