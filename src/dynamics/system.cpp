#include "dynamics/system.hpp"

#include "contact/contact_law.hpp"
#include "core/error.hpp"
#include "core/records_avx512.hpp"
#include "dynamics/omp_team.hpp"
#include "dynamics/pair_simd.hpp"
#include "dynamics/time_step.hpp"
#include "geometry/rotation.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <fmt/format.h>
#include <limits>
#include <sstream>
#include <type_traits>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace kiln::dynamics {

namespace {
// a * b + c with one rounding where the machine has FMA, as the four-particle kick
// (kick_drift_four) rounds it. Written out, so that the scalar kicks and drift round the same way
// in every build: left to the compiler, the contraction of `h * (f * m + g)` differs between
// optimisation levels (the sanitizer build did not fuse it), and with it the bits of advance()
// against step().
inline double fused(double a, double b, double c) {
#if defined(__FMA__)
    return std::fma(a, b, c);
#else
    return a * b + c;
#endif
}

// Inner gap g of the filter's inner list, as a fraction of the skin: at 0.1 (0.1 mm in the settled
// bed of bench/settled.cpp) the inner list holds 58-63 % of the entries (half of them touch) and
// few particles move g / 2 in a thousand steps (docs/performance.md, session 12).
constexpr double inner_gap_fraction = 0.1;

// Sets v to n copies of value. A list that grows by a few entries at a time would, through
// assign, take fresh memory of exactly n entries at every build (the pages' first touches cost
// about 10 us each on the project machine's VM); room for a quarter more is taken instead.
template <class T> void refill(std::vector<T>& v, std::size_t n, const T& value) {
    if (n > v.capacity()) {
        v.clear();
        v.reserve(n + n / 4);
    }
    v.assign(n, value);
}

// The displacement check's |d|^2 as the four-particle pass forms it: (dx^2 + dy^2) with rounded
// products, then dz^2 by a fused multiply-add where the machine has FMA.
inline double displacement2(const Vec3& d) {
    double sx = d[0] * d[0];
    double sy = d[1] * d[1];
#if defined(__x86_64__)
    asm("" : "+x"(sx), "+x"(sy)); // opaque: no product fused into the sum
#endif
    return fused(d[2], d[2], sx + sy);
}
} // namespace

System::System(const SceneSpec& spec)
    : spec_(spec), pairs_(spec.materials, spec.pairs,
                          spec.contact.clamp_normal_force && spec.contact.rebound_restitution),
      nl_(spec.skin), rng_(spec.seed) {
    // One thread unless asked for more: on a shared host idle-spinning OpenMP threads waiting for a
    // descheduled partner cost far more than they gain.
    threads_ = 1;
#ifdef _OPENMP
    const char* env = std::getenv("OMP_NUM_THREADS");
    if (spec_.threads > 0) {
        threads_ = spec_.threads;
    } else if (env != nullptr && *env != '\0') {
        threads_ = omp_get_max_threads();
    }
#endif
    if (spec_.skin <= 0.0) {
        double rmax = 0.0;
        for (const auto& ps : spec_.particles) {
            // A body's ParticleSpec radius is unused (0 from a case file): its template's
            // bounding radius is its size. Without it a scene of bodies had a zero skin and
            // rebuilt its neighbour list at every step.
            rmax = std::max(
                rmax, ps.shape >= 0
                          ? spec_.shapes.at(static_cast<std::size_t>(ps.shape)).bounding_radius()
                          : ps.radius);
        }
        for (const auto& ins : spec_.inserts) {
            rmax = std::max(rmax, ins.size.largest());
        }
        spec_.skin = 0.2 * rmax; // 10 % of the largest diameter
        nl_ = contact::NeighbourList(spec_.skin);
    }
    nl_.set_threads(threads_);
    for (const Wall& w : spec_.walls) {
        wall_material_.push_back(w.material);
    }
    poly_features_.resize(spec_.shapes.size());
    member_columns_.resize(spec_.shapes.size());
    body_boxes_.assign(spec_.shapes.size(), {Vec3::Zero(), Vec3::Constant(-1.0)});
    for (std::size_t k = 0; k < spec_.shapes.size(); ++k) {
        if (const auto* ph = std::get_if<geometry::ConvexPolyhedron>(&spec_.shapes[k].shape)) {
            poly_features_[k] = geometry::polyhedron_features(*ph);
            body_boxes_[k] = geometry::body_box(poly_features_[k].vertices);
        }
        if (const auto* sq = std::get_if<geometry::Superquadric>(&spec_.shapes[k].shape)) {
            body_boxes_[k] = {Vec3::Zero(), sq->half_axes}; // |x_i| <= a_i on the surface
        }
        if (const auto* c = std::get_if<geometry::Clump>(&spec_.shapes[k].shape)) {
            member_columns_[k] = member_columns(c->spheres.data(), c->spheres.size());
        }
    }
    for (const auto& ps : spec_.particles) {
        if (ps.shape >= 0) {
            add_body(ps.material, ps.shape, ps.x, ps.v, ps.omega,
                     initial_orientation(ps.orientation));
        } else {
            add_particle(ps.material, ps.radius, ps.x, ps.v, ps.omega);
        }
    }
    for (const auto& ins : spec_.inserts) {
        insert(ins);
    }
    check_time_step();
    refresh();
}

std::size_t System::add_particle(int material, double radius, const Vec3& x, const Vec3& v,
                                 const Vec3& omega) {
    const double rho = spec_.materials.at(static_cast<std::size_t>(material)).density;
    const std::size_t i = p_.add_sphere(next_id_++, material, radius, rho, x, v, omega);
    grow_wall_histories();
    list_valid_ = false;
    return i;
}

std::size_t System::add_body(int material, int shape, const Vec3& x, const Vec3& v,
                             const Vec3& omega, const Quat& q) {
    const geometry::ShapeTemplate& t = spec_.shapes.at(static_cast<std::size_t>(shape));
    const double rho = spec_.materials.at(static_cast<std::size_t>(material)).density;
    const std::size_t i = p_.add_body(next_id_++, material, shape, t.bounding_radius(), t.mass(rho),
                                      t.inertia(rho), x, v, q, omega);
    grow_wall_histories();
    has_bodies_ = true;
    list_valid_ = false;
    return i;
}

void System::grow_wall_histories() {
    const std::size_t n = p_.size();
    if (n <= wall_stride_) {
        return;
    }
    const std::size_t nw = spec_.walls.size();
    const std::size_t stride = std::max({n, 2 * wall_stride_, std::size_t{64}});
    std::vector<Vec3> grown(nw * stride, Vec3::Zero());
    for (std::size_t w = 0; w < nw; ++w) {
        std::copy_n(wall_shear_.begin() + static_cast<std::ptrdiff_t>(w * wall_stride_),
                    wall_stride_, grown.begin() + static_cast<std::ptrdiff_t>(w * stride));
    }
    wall_shear_.swap(grown);
    wall_stride_ = stride;
    wall_shear_spare_.clear(); // of the old size; carry_wall_histories sizes it again
}

Quat System::initial_orientation(const OrientationSpec& o) {
    if (!o.random) {
        return o.fixed.normalized();
    }
    // Uniform on SO(3): a normalised 4D Gaussian vector (Muller 1959, uniform on S^3).
    std::normal_distribution<double> g(0.0, 1.0);
    Quat q;
    q.w() = g(rng_);
    q.x() = g(rng_);
    q.y() = g(rng_);
    q.z() = g(rng_);
    return q.normalized();
}

void System::check_time_step() {
    if (p_.size() == 0) {
        return;
    }
    // Smallest particle per material, bounding box of the particles, fastest initial motion.
    std::vector<double> rmin(spec_.materials.size(), std::numeric_limits<double>::infinity());
    Vec3 lo = p_.x[0];
    Vec3 hi = p_.x[0];
    double vmax = 0.0;
    for (std::size_t i = 0; i < p_.size(); ++i) {
        auto& r = rmin[static_cast<std::size_t>(p_.material[i])];
        double size = p_.radius[i];
        if (p_.shape[i] >= 0) {
            // A body's contacts are as stiff as those of its smallest element.
            const auto& shape = spec_.shapes[static_cast<std::size_t>(p_.shape[i])].shape;
            if (const auto* c = std::get_if<geometry::Clump>(&shape)) {
                for (const auto& sph : c->spheres) {
                    size = std::min(size, sph.radius);
                }
            } else if (const auto* sq = std::get_if<geometry::Superquadric>(&shape)) {
                size = sq->half_axes.minCoeff();
            } else if (std::holds_alternative<geometry::ConvexPolyhedron>(shape)) {
                // The Hertz radius of polyhedron contacts (body_contact.hpp).
                size = equivalent_radius(spec_.shapes[static_cast<std::size_t>(p_.shape[i])]);
            }
        }
        r = std::min(r, size);
        lo = lo.cwiseMin(p_.x[i]);
        hi = hi.cwiseMax(p_.x[i]);
        vmax = std::max(vmax, p_.v[i].norm() + p_.omega[i].norm() * p_.radius[i]);
    }
    double speed = spec_.expected_speed;
    if (speed <= 0.0) {
        // Fall across the whole particle cloud plus the largest initial speed (closing speed of
        // two).
        speed = 2.0 * vmax + std::sqrt(2.0 * spec_.gravity.norm() * (hi - lo).norm());
    }
    ts_.impact_speed = speed;
    ts_.rayleigh = std::numeric_limits<double>::infinity();
    ts_.contact_time = std::numeric_limits<double>::infinity();
    for (std::size_t a = 0; a < rmin.size(); ++a) {
        if (!std::isfinite(rmin[a])) {
            continue;
        }
        const Material& m = spec_.materials[a];
        ts_.rayleigh =
            std::min(ts_.rayleigh,
                     rayleigh_time_step(rmin[a], m.density, m.shear_modulus(), m.poisson_ratio));
        for (std::size_t b = 0; b < rmin.size(); ++b) {
            if (!std::isfinite(rmin[b])) {
                continue;
            }
            const double r1 = rmin[a];
            const double r2 = rmin[b];
            const double m1 = m.density * 4.18879020478639 * r1 * r1 * r1;
            const double m2 = spec_.materials[b].density * 4.18879020478639 * r2 * r2 * r2;
            const double meff = m1 * m2 / (m1 + m2);
            const PairProperties& pp = pairs_.at(static_cast<int>(a), static_cast<int>(b));
            double tc = 0.0;
            if (const auto* lin = std::get_if<contact::LinearSpringDashpot>(&spec_.contact.law)) {
                tc = linear_contact_time(meff, lin->stiffness, pp.beta);
            } else {
                tc = hertz_contact_time(meff, r1 * r2 / (r1 + r2), pp.effective_modulus, speed);
            }
            ts_.contact_time = std::min(ts_.contact_time, tc);
        }
    }
    ts_.limit = std::min(ts_.rayleigh, ts_.contact_time);
    const double dt = spec_.time_step;
    const std::string figures = fmt::format("time step {:.3g} s; Rayleigh step {:.3g} s, shortest "
                                            "contact {:.3g} s (impact speed {:.3g} m/s)",
                                            dt, ts_.rayleigh, ts_.contact_time, ts_.impact_speed);
    // Fewer than 5 steps per contact, or a step above the Rayleigh step, is not a usable
    // simulation.
    const bool unsafe = dt > ts_.rayleigh || dt > ts_.contact_time / 5.0;
    if (unsafe && !spec_.allow_unsafe_time_step) {
        throw InputError("", 0, "simulation.time_step",
                         figures + "; the step must be below the Rayleigh step and a fifth of the "
                                   "contact time (set simulation.allow_unsafe_time_step = true to "
                                   "run anyway)");
    }
    if (unsafe || dt > spec_.time_step_fraction * ts_.limit) {
        warnings_.push_back(fmt::format("{}; above {} of the critical step {:.3g} s", figures,
                                        spec_.time_step_fraction, ts_.limit));
    }
}

void System::rebuild_neighbours() {
    const std::vector<std::uint32_t> order = nl_.build(p_, spec_.sort_particles);
    index_partners();
    std::vector<std::vector<std::uint32_t>> old_candidates;
    old_candidates.swap(wall_candidates_);
    find_wall_candidates();
    if (!order.empty() && !spec_.walls.empty()) {
        carry_wall_histories(order, old_candidates);
    }
    list_valid_ = true;
}

void System::carry_wall_histories(const std::vector<std::uint32_t>& order,
                                  const std::vector<std::vector<std::uint32_t>>& old_candidates) {
    // Only the candidates of the last build can hold a wall history: the others were not tested
    // since it, and a candidate's history is cleared at every step it does not touch. So the
    // histories of those candidates are moved to their particles' new places, and only if the
    // particle is a candidate of the same wall again (one that is not is more than a skin from the
    // wall, its history is stale). The rest of the array stays zero, and so does the spare array,
    // which takes the place of wall_shear_: every moved history is zeroed where it was.
    const std::size_t n = p_.size();
    const std::size_t nw = spec_.walls.size();
    new_place_.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
        new_place_[order[k]] = static_cast<std::uint32_t>(k);
    }
    const std::size_t stride = wall_stride_;
    wall_mark_.assign(nw * stride, 0);
    for (std::size_t w = 0; w < nw; ++w) {
        for (const std::uint32_t i : wall_candidates_[w]) {
            wall_mark_[w * stride + i] = 1;
        }
    }
    wall_shear_spare_.resize(wall_shear_.size(), Vec3::Zero());
    for (std::size_t w = 0; w < std::min(nw, old_candidates.size()); ++w) {
        for (const std::uint32_t i : old_candidates[w]) {
            Vec3& s = wall_shear_[w * stride + i];
            const std::size_t to = w * stride + new_place_[i];
            if (wall_mark_[to] != 0) {
                wall_shear_spare_[to] = s;
            }
            s.setZero();
        }
    }
    wall_shear_.swap(wall_shear_spare_);
}

void System::index_bodies() {
    bodies_.clear();
    body_entries_.clear();
    members_valid_ = false; // the list or the particle order changed
    has_bodies_ = false;
    rot_.resize(p_.size());
    for (std::size_t i = 0; i < p_.size(); ++i) {
        if (p_.shape[i] >= 0) {
            bodies_.push_back(static_cast<std::uint32_t>(i));
            rot_[i] = geometry::unit_rotation_matrix(p_.q[i]); // q is kept normalised
            has_bodies_ = true;
        }
    }
    if (!has_bodies_) {
        sep_dirs_.clear();
        sep_proofs_.clear();
        apart_below_.clear();
        return;
    }
    const auto& nb = nl_.partners();
    const auto& owner = nl_.owners();
    refill(sep_dirs_, nb.size(), Vec3(Vec3::Zero()));  // the entries changed: no cached direction
    refill(sep_proofs_, nb.size(), SeparationProof{}); // nor a proof along one
    // A memory is checked against the pair's shapes and relative pose before it is read, so the
    // entries keep theirs (and their storage): a memory of another pair is refilled.
    // (Never shrunk: the memories past the list's end are not read, and keep their storage.)
    if (plane_memos_.size() < nb.size()) {
        if (nb.size() > plane_memos_.capacity()) {
            plane_memos_.reserve(nb.size() + nb.size() / 4);
        }
        plane_memos_.resize(nb.size());
    }
    refill(apart_below_, nb.size(), -std::numeric_limits<double>::infinity());
    travel_.assign(p_.size(), 0.0); // every bound read against it goes too
    std::fill(wall_apart_below_.begin(), wall_apart_below_.end(),
              -std::numeric_limits<double>::infinity());
    travel_x_ = p_.x;
    travel_r_.assign(p_.size(), 0.0);
    for (const std::uint32_t i : bodies_) {
        const auto s = static_cast<std::size_t>(p_.shape[i]);
        if (s < poly_features_.size() && !poly_features_[s].edges.empty()) {
            travel_r_[i] = poly_features_[s].radius;
        } else if (std::holds_alternative<geometry::Superquadric>(spec_.shapes[s].shape)) {
            travel_r_[i] = p_.radius[i]; // for the box test of the member build only
        }
    }
    travel_q_ = p_.q;
    for (std::size_t k = 0; k < nb.size(); ++k) {
        if (p_.shape[owner[k]] >= 0 || p_.shape[nb[k]] >= 0) {
            body_entries_.push_back(static_cast<std::uint32_t>(k));
        }
    }
}

void System::index_partners() {
    // For each particle, the list entries where it is the partner, in increasing entry order.
    const auto& nb = nl_.partners();
    // The filters hand particles and list entries as 32-bit byte offsets of records.
    KILN_ASSERT(std::max(p_.size(), nb.size()) <
                std::numeric_limits<std::uint32_t>::max() / simd::record_bytes);
    as_partner_offsets_.assign(p_.size() + 1, 0);
    for (const std::uint32_t j : nb) {
        ++as_partner_offsets_[j + 1];
    }
    for (std::size_t i = 0; i < p_.size(); ++i) {
        as_partner_offsets_[i + 1] += as_partner_offsets_[i];
    }
    as_partner_.resize(nb.size());
    std::vector<std::uint32_t> fill(as_partner_offsets_.begin(), as_partner_offsets_.end() - 1);
    for (std::size_t k = 0; k < nb.size(); ++k) {
        as_partner_[fill[nb[k]]++] = static_cast<std::uint32_t>(k);
    }
    touched_.assign((nb.size() + 3) / 4, 0x0F); // unknown: the next filter clears as before
    entry_rsum2_.resize(nb.size());
    entry_near2_.resize(nb.size());
    inner_gap_ = inner_gap_fraction * nl_.skin();
    for (std::size_t k = 0; k < nb.size(); ++k) {
        const double rsum = p_.radius[nl_.owners()[k]] + p_.radius[nb[k]];
        entry_rsum2_[k] = rsum * rsum;
        entry_near2_[k] = (rsum + inner_gap_) * (rsum + inner_gap_);
    }
    // One radius and one mass for every particle: the register path takes R* and m* once.
    same_radius_ = 0.0;
    same_mass_ = 0.0;
    if (use_uniform_ && !p_.radius.empty() &&
        std::all_of(p_.radius.begin(), p_.radius.end(),
                    [&](double r) { return r == p_.radius.front(); }) &&
        std::all_of(p_.mass.begin(), p_.mass.end(),
                    [&](double m) { return m == p_.mass.front(); })) {
        same_radius_ = p_.radius.front();
        same_mass_ = p_.mass.front();
    }
    inner_valid_ = false;
    inner_used_ = false;
    room2_.assign(p_.size(), std::numeric_limits<double>::infinity());
    index_bodies();
    rekey_body_contacts(); // the list or the particle order changed
}

namespace {

/// Appends to `out`, in increasing order, the spheres i of [b0, b1) (shape < 0) whose overlap
/// with the plane, r_i - (x_i - point).normal, exceeds -skin (m, world frame).
void plane_candidates(const PlaneWall& w, const ParticleStore& p, std::size_t b0, std::size_t b1,
                      double skin, std::vector<std::uint32_t>& out) {
#if defined(__AVX512F__)
    std::size_t m = out.size();
    // Eight particles at a time, the hits compressed into place (no branch per particle). A
    // rounding difference from the scalar test can only matter a skin away from the wall, where
    // a particle cannot touch it before the next build.
    out.resize(m + (b1 - b0) + 16);
    const __m512d px = _mm512_set1_pd(w.point[0]);
    const __m512d py = _mm512_set1_pd(w.point[1]);
    const __m512d pz = _mm512_set1_pd(w.point[2]);
    const __m512d nx = _mm512_set1_pd(w.normal[0]);
    const __m512d ny = _mm512_set1_pd(w.normal[1]);
    const __m512d nz = _mm512_set1_pd(w.normal[2]);
    const __m512d lim = _mm512_set1_pd(-skin);
    const __m512i lane = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 0, 0, 0, 0, 0, 0, 0, 0);
    for (std::size_t i = b0; i < b1; i += 8) {
        const auto k = static_cast<unsigned>(std::min<std::size_t>(8, b1 - i));
        const auto rec = static_cast<__mmask8>((1U << k) - 1U);
        const Columns8 c = load_columns8(p.x.data() + i, k);
        const __m512d d = _mm512_fmadd_pd(
            _mm512_sub_pd(c.z, pz), nz,
            _mm512_fmadd_pd(_mm512_sub_pd(c.y, py), ny, _mm512_mul_pd(_mm512_sub_pd(c.x, px), nx)));
        const __m512d overlap = _mm512_sub_pd(_mm512_maskz_loadu_pd(rec, p.radius.data() + i), d);
        const __mmask16 sphere = _mm512_mask_cmplt_epi32_mask(
            rec, _mm512_maskz_loadu_epi32(rec, p.shape.data() + i), _mm512_setzero_si512());
        const auto hit = static_cast<__mmask16>(
            _mm512_mask_cmp_pd_mask(static_cast<__mmask8>(sphere), overlap, lim, _CMP_GT_OQ));
        const __m512i idx = _mm512_add_epi32(_mm512_set1_epi32(static_cast<int>(i)), lane);
        _mm512_storeu_si512(out.data() + m, _mm512_maskz_compress_epi32(hit, idx));
        m += static_cast<std::size_t>(__builtin_popcount(hit));
    }
    out.resize(m);
#else
    for (std::size_t i = b0; i < b1; ++i) {
        if (p.shape[i] < 0 && wall_contact(w, p.x[i], p.radius[i]).overlap > -skin) {
            out.push_back(static_cast<std::uint32_t>(i));
        }
    }
#endif
}

} // namespace

void System::find_wall_candidates() {
    // Particles within the skin of a wall. A particle further away cannot reach the wall before the
    // next rebuild: it is at most skin/2 from its position at the last build, so at most a skin
    // from where it is now.
    const std::size_t nw = spec_.walls.size();
    wall_candidates_.resize(nw);
    for (auto& cand : wall_candidates_) {
        cand.clear();
    }
    // Particles in blocks that stay in the L1 cache while every wall tests them (one variant
    // dispatch per wall and block); each wall's candidates stay in increasing index order.
    constexpr std::size_t span = 512;
    for (std::size_t b0 = 0; b0 < p_.size(); b0 += span) {
        const std::size_t b1 = std::min(p_.size(), b0 + span);
        for (std::size_t w = 0; w < nw; ++w) {
            std::vector<std::uint32_t>& cand = wall_candidates_[w];
            if (const auto* plane = std::get_if<PlaneWall>(&spec_.walls[w].shape)) {
                plane_candidates(*plane, p_, b0, b1, nl_.skin(), cand);
                continue;
            }
            std::visit(
                [&](const auto& shape) {
                    for (std::size_t i = b0; i < b1; ++i) {
                        if (p_.shape[i] < 0 &&
                            wall_contact(shape, p_.x[i], p_.radius[i]).overlap > -nl_.skin()) {
                            cand.push_back(static_cast<std::uint32_t>(i)); // bodies: body_forces()
                        }
                    }
                },
                spec_.walls[w].shape);
        }
    }
    // Bodies: the same test with the bounding sphere, body by body (body_forces() loops so).
    body_wall_offsets_.assign(bodies_.size() + 1, 0);
    body_walls_.clear();
    for (std::size_t b = 0; b < bodies_.size(); ++b) {
        const std::uint32_t i = bodies_[b];
        for (std::size_t w = 0; w < nw; ++w) {
            const WallContact wc = std::visit(
                [&](const auto& shape) { return wall_contact(shape, p_.x[i], p_.radius[i]); },
                spec_.walls[w].shape);
            if (wc.overlap > -nl_.skin()) {
                body_walls_.push_back(static_cast<std::uint32_t>(w));
            }
        }
        body_wall_offsets_[b + 1] = static_cast<std::uint32_t>(body_walls_.size());
    }
    wall_apart_below_.assign(body_walls_.size(), -std::numeric_limits<double>::infinity());
}

void System::refresh() {
    rebuild_neighbours();
    form_counters_ = true;
    compute_forces();
}

namespace {

constexpr std::size_t block = 16;               // contacts evaluated together by the vectorised law
constexpr std::size_t pair_chunk_size = 1024;   // list entries per work unit
constexpr std::size_t particle_unit_size = 512; // particles per work unit
constexpr std::size_t row = 9;                  // doubles per pair result: f, torque_i, torque_j
// The four-entry filter keeps one byte of flags per group of four entries from a chunk's start.
static_assert(pair_chunk_size % 4 == 0);

// Keeps v when `keep`, else sets it to zero, with a bit mask: written as a multiplication by 0 or 1
// it became a branch, mispredicted half of the time in the contact filter.
inline void keep_or_clear(Vec3& v, bool keep) {
    const std::uint64_t mask = std::uint64_t{0} - static_cast<std::uint64_t>(keep);
    for (int q = 0; q < 3; ++q) {
        v[q] = std::bit_cast<double>(std::bit_cast<std::uint64_t>(v[q]) & mask);
    }
}

} // namespace

// Work units have a fixed size, so the contacts of a unit, the blocks they are evaluated in and the
// order of every sum do not depend on the number of threads.
template <class Law, bool direct, bool bodies, bool onsets>
void System::pair_chunk(const Law& law, std::size_t begin, std::size_t end, ChunkTotals& t) {
    // Local pointers, as the compiler would otherwise reload each array's address per contact.
    const std::uint32_t* __restrict nb = nl_.partners().data();
    const std::uint32_t* __restrict owner = nl_.owners().data();
    Vec3* __restrict shear = nl_.shear().data();
    const Vec3* __restrict x = p_.x.data();
    const Vec3* __restrict vel = p_.v.data();
    const Vec3* __restrict omega = p_.omega.data();
    const double* __restrict radius = p_.radius.data();
    const double* __restrict mass = p_.mass.data();
    const std::int32_t* __restrict shape = p_.shape.data();
    Vec3* __restrict force = p_.force.data();
    Vec3* __restrict torque = p_.torque.data();
    const double dt = spec_.time_step;
    const auto zero_row = static_cast<std::uint32_t>(nl_.partners().size());

    // Which entries touch. Branch-free, so the ~50 % unpredictable outcome costs nothing;
    // histories of pairs apart are cleared.
    // Their list entries as byte offsets of histories (simd::record_bytes times the entry).
    std::uint32_t active[pair_chunk_size];
    std::size_t n_active = 0;
#ifdef __AVX2__
    std::uint32_t active_i[pair_chunk_size]; // their owners and partners, for the register path
    std::uint32_t active_j[pair_chunk_size];
    const simd::ActiveList act{active, active_i, active_j};
    const simd::PairArrays arrays{owner,
                                  nb,
                                  shear,
                                  x,
                                  vel,
                                  omega,
                                  radius,
                                  mass,
                                  force,
                                  torque,
                                  direct ? nullptr : pair_result_.data(),
                                  touched_.data(),
                                  entry_rsum2_.data(),
                                  same_radius_,
                                  same_mass_};
#endif
    std::size_t k_first = begin; // entries before it were filtered four at a time
#if defined(__AVX2__) && defined(__FMA__)
    if constexpr (!bodies) {
        std::uint32_t* rows = direct ? nullptr : result_row_.data();
        if (filter_ == Filter::all) {
            k_first =
                simd::touching_entries<!direct>(arrays, begin, end, act, n_active, rows, zero_row);
        } else {
            const std::size_t u = begin / pair_chunk_size;
            simd::InnerChunk in{inner_k_.data() + begin,
                                inner_i_.data() + begin,
                                inner_j_.data() + begin,
                                inner_rsum2_.data() + begin,
                                inner_was_.data() + begin / 4,
                                entry_near2_.data(),
                                inner_count_[u]};
            if (filter_ == Filter::inner) {
                simd::inner_touching_entries<!direct>(arrays, in, begin, act, n_active, rows,
                                                      zero_row);
                k_first = begin + (end - begin) / 4 * 4; // the full filter's first entry left
            } else {
                k_first = simd::touching_entries<!direct, true>(arrays, begin, end, act, n_active,
                                                                rows, zero_row, &in);
                inner_count_[u] = in.count;
            }
        }
    }
#endif
    for (std::size_t k = k_first; k < end; ++k) {
        const std::uint32_t i = owner[k];
        const std::uint32_t j = nb[k];
        const double rsum = radius[i] + radius[j];
        bool touch = simd::squared_distance(x[i], x[j]) < rsum * rsum;
        if constexpr (bodies) {
            // Both -1 (spheres) keeps the sign bit; a body (index >= 0) on either side clears it.
            touch = touch && (shape[i] & shape[j]) < 0;
        }
        active[n_active] = static_cast<std::uint32_t>(k) * simd::record_bytes;
#ifdef __AVX2__
        active_i[n_active] = i * simd::record_bytes;
        active_j[n_active] = j * simd::record_bytes;
#endif
        if constexpr (!direct) {
            // Rows of a chunk are its touching entries in order, from the chunk's first row.
            result_row_[k] = touch ? static_cast<std::uint32_t>(begin + n_active) : zero_row;
        }
        n_active += touch ? 1U : 0U;
        keep_or_clear(shear[k], touch);
    }

    // Forces of the touching pairs, in blocks. The scalar gather only copies particle data; the
    // geometry (square root, divisions) is derived in the vectorised loop together with the law,
    // since the contacts of a block are independent; then the results are scattered (one thread)
    // or stored in the chunk's rows (several threads).
    const double fn_floor = contact::floor_of(spec_.contact);
    const double rolling = contact::rolling_of(spec_.contact);
    contact::ContactBlock<block> c; // on the stack, so the vectoriser sees it does not alias
    double d[3][block], ri[block], rj[block], mi[block], mj[block], ratio[block];
    const bool one_pair = pairs_.size() == 1;
    if (one_pair) {
        for (std::size_t b = 0; b < block; ++b) {
            c.set_pair(b, pairs_.at(0, 0));
        }
    }
    double energy = 0.0;
    double max_ratio = 0.0;
    if constexpr (onsets) {
        // Contact starts: touching now, apart at the start of the step. The drift was
        // x^(n+1) = x^n + dt v^(n+1/2) with the velocities read here (the closing half kick comes
        // after the forces), so the start-of-step separation is d - dt (v_i - v_j) and v^(n+1/2)
        // is the velocity before the impact. Only reads: the forces are those of a run without
        // recording, bit for bit.
        for (std::size_t a = 0; a < n_active; ++a) {
            const std::uint32_t k = active[a] / simd::record_bytes;
            const std::uint32_t i = owner[k];
            const std::uint32_t j = nb[k];
            const double rsum = radius[i] + radius[j];
            double dq[3];
            double before = 0.0;
            double dist2 = 0.0;
            double closing = 0.0;
            for (int q = 0; q < 3; ++q) {
                dq[q] = x[i][q] - x[j][q];
                const double vq = vel[i][q] - vel[j][q];
                const double e = dq[q] - dt * vq;
                before += e * e;
                dist2 += dq[q] * dq[q];
                closing += vq * dq[q];
            }
            if (before >= rsum * rsum) {
                const double dist = std::sqrt(dist2);
                ContactOnset e;
                e.id_i = p_.id[i];
                e.id_j = p_.id[j];
                e.speed = std::max(0.0, -closing / dist);
                e.r_eff = radius[i] * radius[j] / rsum;
                e.m_eff = mass[i] * mass[j] / (mass[i] + mass[j]);
                for (int q = 0; q < 3; ++q) {
                    e.normal[q] = -dq[q] / dist; // d runs from j to i
                }
                pair_onsets_[begin / pair_chunk_size].push_back(e);
            }
        }
    }
    std::size_t a_first = 0; // entries before it were evaluated in registers, several at a time
#ifdef __AVX2__
    a_first = simd::contact_groups<Law, direct>(law, pairs_, p_.material.data(), fn_floor, rolling,
                                                dt, arrays, act, n_active, begin, energy, max_ratio,
                                                form_counters_);
#endif
    for (std::size_t a0 = a_first; a0 < n_active; a0 += block) {
        const std::size_t m = std::min(block, n_active - a0);
        for (std::size_t b = 0; b < m; ++b) {
            const std::uint32_t k = active[a0 + b] / simd::record_bytes;
            const std::uint32_t i = owner[k];
            const std::uint32_t j = nb[k];
            for (int q = 0; q < 3; ++q) {
                d[q][b] = x[i][q] - x[j][q];
                c.v[q][b] = vel[i][q] - vel[j][q];
                c.wi[q][b] = omega[i][q];
                c.wj[q][b] = omega[j][q];
                c.s[q][b] = shear[k][q];
            }
            ri[b] = radius[i];
            rj[b] = radius[j];
            mi[b] = mass[i];
            mj[b] = mass[j];
            if (!one_pair) {
                c.set_pair(b, pairs_.at(p_.material[i], p_.material[j]));
            }
        }
#pragma omp simd
        for (std::size_t b = 0; b < m; ++b) {
            const double rsum = ri[b] + rj[b];
            const double dist =
                std::sqrt(d[0][b] * d[0][b] + d[1][b] * d[1][b] + d[2][b] * d[2][b]);
            const double overlap = rsum - dist;
            for (int q = 0; q < 3; ++q) {
                c.n[q][b] = d[q][b] / dist;
            }
            c.overlap[b] = overlap;
            c.r_eff[b] = ri[b] * rj[b] / rsum;
            c.m_eff[b] = mi[b] * mj[b] / (mi[b] + mj[b]);
            c.lever_i[b] = ri[b] - 0.5 * overlap;
            c.lever_j[b] = rj[b] - 0.5 * overlap;
            ratio[b] = overlap / (2.0 * std::min(ri[b], rj[b]));
            contact::evaluate_block(law, fn_floor, rolling, c, b, dt);
        }
        for (std::size_t b = 0; b < m; ++b) {
            const std::uint32_t k = active[a0 + b] / simd::record_bytes;
            if constexpr (direct) {
                const std::uint32_t i = owner[k];
                const std::uint32_t j = nb[k];
                const Vec3 f(c.f[0][b], c.f[1][b], c.f[2][b]);
                force[i] += f;
                force[j] -= f;
                torque[i] += Vec3(c.ti[0][b], c.ti[1][b], c.ti[2][b]);
                torque[j] += Vec3(c.tj[0][b], c.tj[1][b], c.tj[2][b]);
            } else {
                double* r = &pair_result_[row * (begin + a0 + b)];
                for (int q = 0; q < 3; ++q) {
                    r[q] = c.f[q][b];
                    r[3 + q] = c.ti[q][b];
                    r[6 + q] = c.tj[q][b];
                }
            }
            shear[k] = Vec3(c.s[0][b], c.s[1][b], c.s[2][b]);
            energy += c.energy[b];
            max_ratio = std::max(max_ratio, ratio[b]);
        }
    }
    t.energy = energy;
    t.max_ratio = max_ratio;
    t.contacts = static_cast<long>(n_active);
}

// Sums the pair results of particle i in increasing list-entry order, the order in which the
// one-thread scatter adds them: entries where i is the partner come first (their owners have lower
// indices, the list being built with j > i), then i's own row. Hence the same bits for any number
// of threads.
void System::sum_pair_results(std::size_t i) {
    const auto& offsets = nl_.offsets();
    const double* res = pair_result_.data();
    double f0 = 0.0;
    double f1 = 0.0;
    double f2 = 0.0;
    double t0 = 0.0;
    double t1 = 0.0;
    double t2 = 0.0;
    for (std::uint32_t a = as_partner_offsets_[i]; a < as_partner_offsets_[i + 1]; ++a) {
        const double* r = res + row * result_row_[as_partner_[a]];
        f0 -= r[0];
        f1 -= r[1];
        f2 -= r[2];
        t0 += r[6];
        t1 += r[7];
        t2 += r[8];
    }
    for (std::uint32_t k = offsets[i]; k < offsets[i + 1]; ++k) {
        const double* r = res + row * result_row_[k];
        f0 += r[0];
        f1 += r[1];
        f2 += r[2];
        t0 += r[3];
        t1 += r[4];
        t2 += r[5];
    }
    p_.force[i] = Vec3(f0, f1, f2);
    p_.torque[i] = Vec3(t0, t1, t2);
}

// Wall contacts of the particles [p0, p1): the same blocked law with the wall as body j (at rest,
// infinite mass). Contacts are collected wall by wall, so each particle receives its wall forces in
// wall order, and units of particles can run in parallel.
template <class Law, bool onsets>
void System::wall_unit(const Law& law, std::size_t p0, std::size_t p1, ChunkTotals& t) {
    const std::size_t nw = spec_.walls.size();
    const double dt = spec_.time_step;
    const double fn_floor = contact::floor_of(spec_.contact);
    const double rolling = contact::rolling_of(spec_.contact);
    constexpr std::size_t capacity = 512;
    WallContact geo[capacity];
    std::uint32_t active[capacity];
    std::uint32_t wall_of[capacity];
    std::size_t n_active = 0;

    // Evaluates the collected contacts and adds their forces.
    const auto flush = [&] {
#ifdef __AVX2__
        // Four at a time in registers, with the register path's variant of the law.
        const simd::PairArrays arrays{
            nullptr,         nullptr,          nullptr,        p_.x.data(),     p_.v.data(),
            p_.omega.data(), p_.radius.data(), p_.mass.data(), p_.force.data(), p_.torque.data(),
            nullptr,         nullptr,          nullptr,        same_radius_,    same_mass_};
        simd::wall_contacts(law, pairs_, p_.material.data(), wall_material_.data(), fn_floor,
                            rolling, dt, geo, active, wall_of, n_active, wall_stride_, arrays,
                            wall_shear_.data(), t.energy, t.max_ratio, form_counters_);
#else
        // In blocks with the branch-free law.
        contact::ContactBlock<block> c;
        double ratio[block];
        for (std::size_t b = 0; b < block; ++b) {
            c.lever_j[b] = 0.0;
            for (int q = 0; q < 3; ++q) {
                c.wj[q][b] = 0.0;
            }
        }
        for (std::size_t a0 = 0; a0 < n_active; a0 += block) {
            const std::size_t m = std::min(block, n_active - a0);
            for (std::size_t b = 0; b < m; ++b) {
                const std::uint32_t i = active[a0 + b];
                const WallContact& g = geo[a0 + b];
                const std::uint32_t w = wall_of[a0 + b];
                const Vec3& s = wall_shear_[w * wall_stride_ + i];
                for (int q = 0; q < 3; ++q) {
                    c.n[q][b] = g.n[q];
                    c.v[q][b] = p_.v[i][q];
                    c.wi[q][b] = p_.omega[i][q];
                    c.s[q][b] = s[q];
                }
                c.overlap[b] = g.overlap;
                c.r_eff[b] = g.r_eff;
                c.m_eff[b] = p_.mass[i];
                c.lever_i[b] = p_.radius[i] - g.overlap;
                ratio[b] = g.overlap / (2.0 * p_.radius[i]);
                c.set_pair(b, pairs_.at(p_.material[i], spec_.walls[w].material));
            }
#pragma omp simd
            for (std::size_t b = 0; b < m; ++b) {
                contact::evaluate_block(law, fn_floor, rolling, c, b, dt);
            }
            for (std::size_t b = 0; b < m; ++b) {
                const std::uint32_t i = active[a0 + b];
                p_.force[i] += Vec3(c.f[0][b], c.f[1][b], c.f[2][b]);
                p_.torque[i] += Vec3(c.ti[0][b], c.ti[1][b], c.ti[2][b]);
                wall_shear_[wall_of[a0 + b] * wall_stride_ + i] =
                    Vec3(c.s[0][b], c.s[1][b], c.s[2][b]);
                t.energy += c.energy[b];
                t.max_ratio = std::max(t.max_ratio, ratio[b]);
            }
        }
#endif
        t.contacts += static_cast<long>(n_active);
        n_active = 0;
    };

    for (std::size_t w = 0; w < nw; ++w) {
        // Candidates are sorted by particle index.
        const auto& cand = wall_candidates_[w];
        const auto lo = std::lower_bound(cand.begin(), cand.end(), p0);
        const auto hi = std::lower_bound(lo, cand.end(), p1);
        // Local pointers and count: through the members and the count that flush() shares, GCC
        // loaded the arrays' addresses and the count again at every candidate.
        const Vec3* __restrict x = p_.x.data();
        const double* __restrict radius = p_.radius.data();
        Vec3* __restrict history = wall_shear_.data() + w * wall_stride_;
        const auto wall = static_cast<std::uint32_t>(w);
        std::visit(
            [&](const auto& shape) {
                for (auto it = lo; it != hi;) {
                    if (n_active == capacity) {
                        flush();
                    }
                    // As many candidates as the arrays have room for.
                    const auto stop =
                        it + std::min<std::ptrdiff_t>(
                                 hi - it, static_cast<std::ptrdiff_t>(capacity - n_active));
                    std::size_t m = n_active;
                    for (; it != stop; ++it) {
                        const std::uint32_t i = *it;
                        const WallContact g = wall_contact(shape, x[i], radius[i]);
                        const bool touch = g.overlap > 0.0;
                        if constexpr (onsets) {
                            // Touching now, apart at the start of the step (x - dt v, as for
                            // pairs).
                            if (touch &&
                                !(wall_contact(shape, x[i] - dt * p_.v[i], radius[i]).overlap >
                                  0.0)) {
                                ContactOnset e;
                                e.id_i = p_.id[i];
                                e.wall = static_cast<std::int32_t>(w);
                                e.speed = std::max(0.0, -p_.v[i].dot(g.n));
                                e.r_eff = g.r_eff;
                                e.m_eff = p_.mass[i];
                                for (int q = 0; q < 3; ++q) {
                                    e.normal[q] = -g.n[q];
                                }
                                wall_onsets_[p0 / particle_unit_size].push_back(e);
                            }
                        }
                        geo[m] = g;
                        active[m] = i;
                        wall_of[m] = wall;
                        m += touch ? 1U : 0U;
                        keep_or_clear(history[i], touch);
                    }
                    n_active = m;
                }
            },
            spec_.walls[w].shape);
    }
    flush();
}

void System::half_kick(std::size_t p0, std::size_t p1) {
    const double h = 0.5 * spec_.time_step;
    const Vec3 g = spec_.gravity;
    // Local pointers: the compiler reloaded each array's address at every particle otherwise.
    Vec3* __restrict v = p_.v.data();
    Vec3* __restrict w = p_.omega.data();
    const Vec3* __restrict f = p_.force.data();
    const Vec3* __restrict t = p_.torque.data();
    const double* __restrict inv_m = p_.inv_mass.data();
    const double* __restrict inv_i = p_.inv_inertia.data();
    for (std::size_t i = p0; i < p1; ++i) {
        const double hi = h * inv_i[i];
        for (int q = 0; q < 3; ++q) {
            v[i][q] = fused(h, fused(f[i][q], inv_m[i], g[q]), v[i][q]);
            w[i][q] = fused(hi, t[i][q], w[i][q]);
        }
    }
}

void System::note_body_onset(const BodyContactKey& key, const Vec3& n, const Vec3& point,
                             const Vec3& v_rel, double m_eff, double r_eff) {
    ContactOnset e;
    e.id_i = key.a;
    if (key.b >= 0) {
        e.id_j = key.b;
    } else {
        // heat: analytic wall w, or mesh wall m as walls.size() + m (the key's wall order).
        e.wall = static_cast<std::int32_t>(-1 - key.b);
    }
    e.step = step_ + 1; // the step counter advances after the forces
    // v_rel is v^(n+1/2) of the contact point, before the contact force acted (as for spheres).
    e.speed = std::max(0.0, -v_rel.dot(n));
    e.r_eff = r_eff;
    e.m_eff = m_eff;
    for (int q = 0; q < 3; ++q) {
        e.normal[q] = -n[q]; // n runs from b to a
        e.point[q] = point[q];
    }
    onsets_.push_back(e);
}

// The pair filter of this step (filter_): the inner lists while they are valid, else every entry,
// building new inner lists (not within inner_holdoff steps of the last ones being dropped, so that
// a moving bed does not pay a build at every step). After a filter on the inner lists, touched_
// is stale and set to unknown.
void System::choose_filter([[maybe_unused]] std::size_t pair_units) {
    filter_ = Filter::all;
#if defined(__AVX2__) && defined(__FMA__)
    if (!has_bodies_ && inner_gap_ > 0.0 && use_inner_) {
        if (inner_valid_) {
            filter_ = Filter::inner;
        } else if (step_ >= inner_next_build_) {
            filter_ = Filter::build;
            const std::size_t entries = nl_.partners().size();
            inner_k_.resize(entries);
            inner_i_.resize(entries);
            inner_j_.resize(entries);
            inner_rsum2_.resize(entries);
            inner_was_.resize(entries / 4 + 1);
            inner_count_.assign(pair_units, 0);
        }
    }
#endif
    if (filter_ != Filter::inner && inner_used_) {
        std::fill(touched_.begin(), touched_.end(), std::uint8_t{0x0F});
    }
}

// After a filter pass that built the inner lists: the bitmap of their entries, and each particle's
// room, (g / 2 - |x - x_build|)^2 with g the inner gap less a margin of 1e-6 of it for the
// round-off of distances and displacements (about 1e-16 of the coordinates). A particle that moves
// more than its room from x_build is loose (the one pass reports it, loosen()): it may then have
// moved more than g / 2 since this build. A particle with no room is loose at once.
void System::finish_inner_build() {
    const std::size_t entries = nl_.partners().size();
    inner_bits_.assign(entries / 64 + 1, 0);
    for (std::size_t u = 0; u < inner_count_.size(); ++u) {
        const std::uint32_t* k = inner_k_.data() + u * pair_chunk_size;
        for (std::size_t c = 0; c < inner_count_[u]; ++c) {
            inner_bits_[k[c] / 64] |= std::uint64_t{1} << (k[c] % 64);
        }
    }
    inner_loose_ = 0;
    const double half = 0.5 * inner_gap_ * (1.0 - 1e-6);
    const Vec3* x_build = nl_.positions_at_build().data();
    std::vector<std::uint32_t> loose;
    for (std::size_t i = 0; i < p_.size(); ++i) {
        const double room = half - std::sqrt(displacement2(p_.x[i] - x_build[i]));
        room2_[i] = room * room;
        if (!(room > 0.0)) {
            loose.push_back(static_cast<std::uint32_t>(i));
        }
    }
    inner_valid_ = true;
    loosen(loose);
}

// Adds every list entry of the loose particles `loose` to the inner lists (bitmap, then the compact
// arrays of the chunks concerned, in entry order, their touched flags unknown); their rooms become
// infinite. Too many loose particles drop the inner lists instead.
void System::loosen(const std::vector<std::uint32_t>& loose) {
    if (loose.empty() || !inner_valid_) {
        return;
    }
    inner_loose_ += loose.size();
    inner_loosened_ += static_cast<long>(loose.size());
    if (inner_loose_ > p_.size() / 256 + 8) {
        inner_valid_ = false;
        inner_next_build_ = step_ + inner_holdoff;
        std::fill(room2_.begin(), room2_.end(), std::numeric_limits<double>::infinity());
        return;
    }
    const std::size_t entries = nl_.partners().size();
    // The chunks' tails (fewer than four entries after the last group) are filtered one at a time
    // anyway: they stay out of the inner lists.
    const auto filtered_in_groups = [&](std::size_t k) {
        const std::size_t begin = k / pair_chunk_size * pair_chunk_size;
        const std::size_t end = std::min(entries, begin + pair_chunk_size);
        return k < begin + (end - begin) / 4 * 4;
    };
    std::vector<std::uint8_t> dirty(inner_count_.size(), 0);
    const auto add = [&](std::size_t k) {
        if (filtered_in_groups(k)) {
            inner_bits_[k / 64] |= std::uint64_t{1} << (k % 64);
            dirty[k / pair_chunk_size] = 1;
        }
    };
    const auto& offsets = nl_.offsets();
    for (const std::uint32_t i : loose) {
        room2_[i] = std::numeric_limits<double>::infinity();
        for (std::uint32_t k = offsets[i]; k < offsets[i + 1]; ++k) {
            add(k);
        }
        for (std::uint32_t a = as_partner_offsets_[i]; a < as_partner_offsets_[i + 1]; ++a) {
            add(as_partner_[a]);
        }
    }
    const auto& owner = nl_.owners();
    const auto& nb = nl_.partners();
    for (std::size_t u = 0; u < dirty.size(); ++u) {
        if (dirty[u] == 0) {
            continue;
        }
        const std::size_t begin = u * pair_chunk_size;
        const std::size_t end = std::min(entries, begin + pair_chunk_size);
        std::size_t c = begin;
        for (std::size_t word = begin / 64; word * 64 < end; ++word) {
            // begin is a multiple of 64 and the bits of the chunk's tail are never set.
            for (std::uint64_t bits = inner_bits_[word]; bits != 0; bits &= bits - 1) {
                const std::size_t k = word * 64 + static_cast<std::size_t>(std::countr_zero(bits));
                inner_k_[c] = static_cast<std::uint32_t>(k);
                inner_i_[c] = owner[k] * simd::record_bytes;
                inner_j_[c] = nb[k] * simd::record_bytes;
                inner_rsum2_[c] = entry_rsum2_[k];
                ++c;
            }
        }
        inner_count_[u] = c - begin;
        std::fill_n(inner_was_.begin() + static_cast<std::ptrdiff_t>(begin / 4), (end - begin) / 4,
                    std::uint8_t{0x0F});
    }
}

void System::compute_forces(bool kick_requested, bool forces_cleared) {
    // With bodies, their contacts are added after the sphere loop (body_forces), so the kick waits.
    const bool kick = kick_requested && !generic_contacts();
    const std::size_t n = p_.size();
    const std::size_t entries = nl_.partners().size();
    const bool direct = threads_ == 1;
    const bool no_sphere_pairs = has_bodies_ && body_entries_.size() == entries;
    const std::size_t pair_units = (entries + pair_chunk_size - 1) / pair_chunk_size;
    const std::size_t particle_units = (n + particle_unit_size - 1) / particle_unit_size;
    pair_totals_.assign(pair_units, ChunkTotals{});
    particle_totals_.assign(particle_units, ChunkTotals{});
    // Contact onsets only at a step (a refresh has no start-of-step positions); bodies' element
    // contacts are recorded in body_forces().
    const bool record = spec_.record_contact_onsets && kick_requested;
    if (record) {
        onsets_.clear(); // heat: a refresh keeps the last step's onsets for after_step
        pair_onsets_.resize(pair_units);
        wall_onsets_.resize(particle_units);
        for (auto& v : pair_onsets_) {
            v.clear();
        }
        for (auto& v : wall_onsets_) {
            v.clear();
        }
    }
    choose_filter(pair_units);
    if (direct) {
        if (!forces_cleared) {
            p_.clear_forces();
        }
    } else {
        pair_result_.resize(row * (entries + 1));
        std::fill_n(pair_result_.end() - row, row, 0.0); // the zero row
        result_row_.resize(entries);
    }

    std::visit(
        [&](const auto& law) {
            using Law = std::decay_t<decltype(law)>;
            detail::in_team(threads_, [&] {
        // Pair contacts by chunks of list entries.
#pragma omp for schedule(static)
                for (std::size_t u = 0; u < pair_units; ++u) {
                    const std::size_t begin = u * pair_chunk_size;
                    if (no_sphere_pairs) {
                        // Every entry has a body (body_forces): nothing to evaluate here, and
                        // their histories in the list stay zero (no rows: the particle pass
                        // below clears the forces instead of summing zero rows).
                        continue;
                    }
                    const std::size_t end = std::min(entries, begin + pair_chunk_size);
                    if (has_bodies_ && record) {
                        if (direct) {
                            pair_chunk<Law, true, true, true>(law, begin, end, pair_totals_[u]);
                        } else {
                            pair_chunk<Law, false, true, true>(law, begin, end, pair_totals_[u]);
                        }
                    } else if (has_bodies_) {
                        if (direct) {
                            pair_chunk<Law, true, true>(law, begin, end, pair_totals_[u]);
                        } else {
                            pair_chunk<Law, false, true>(law, begin, end, pair_totals_[u]);
                        }
                    } else if (record) {
                        if (direct) {
                            pair_chunk<Law, true, false, true>(law, begin, end, pair_totals_[u]);
                        } else {
                            pair_chunk<Law, false, false, true>(law, begin, end, pair_totals_[u]);
                        }
                    } else if (direct) {
                        pair_chunk<Law, true, false>(law, begin, end, pair_totals_[u]);
                    } else {
                        pair_chunk<Law, false, false>(law, begin, end, pair_totals_[u]);
                    }
                }
            // Per particle: pair results summed (several threads), walls, half kick.
#pragma omp for schedule(static)
                for (std::size_t u = 0; u < particle_units; ++u) {
                    const std::size_t p0 = u * particle_unit_size;
                    const std::size_t p1 = std::min(n, p0 + particle_unit_size);
                    if (!direct && no_sphere_pairs) {
                        for (std::size_t i = p0; i < p1; ++i) { // the sum of zero rows
                            p_.force[i] = Vec3::Zero();
                            p_.torque[i] = Vec3::Zero();
                        }
                    } else if (!direct) {
                        for (std::size_t i = p0; i < p1; ++i) {
                            sum_pair_results(i);
                        }
                    }
                    if (record) {
                        wall_unit<Law, true>(law, p0, p1, particle_totals_[u]);
                    } else {
                        wall_unit(law, p0, p1, particle_totals_[u]);
                    }
                    if (kick) {
                        half_kick(p0, p1);
                    }
                }
            });
        },
        spec_.contact.law);

    if (record) {
        for (const auto* part : {&pair_onsets_, &wall_onsets_}) {
            for (const auto& v : *part) {
                onsets_.insert(onsets_.end(), v.begin(), v.end());
            }
        }
        for (ContactOnset& e : onsets_) {
            e.step = step_ + 1; // the step counter advances after the forces
        }
    }

    inner_used_ = filter_ == Filter::inner;
    inner_steps_ += inner_used_ ? 1 : 0;
    if (filter_ == Filter::build) {
        finish_inner_build();
    }

    // Bodies: element contacts in a fixed serial order, then the kick of every particle.
    ChunkTotals body_pairs;
    ChunkTotals body_walls;
    if (generic_contacts()) {
        record_body_onsets_ = record;
        body_forces(body_pairs, body_walls);
        record_body_onsets_ = false;
        if (kick_requested) {
            detail::in_team(threads_, [&] {
#pragma omp for schedule(static)
                for (std::size_t u = 0; u < particle_units; ++u) {
                    const std::size_t p0 = u * particle_unit_size;
                    half_kick(p0, std::min(n, p0 + particle_unit_size));
                }
            });
            rotate_bodies(1, false);
        }
    }

    // Sums in a fixed order, whatever the number of threads.
    counters_ = ContactCounters{};
    for (const ChunkTotals& t : pair_totals_) {
        counters_.particle_contacts += t.contacts;
        counters_.elastic_energy += t.energy;
        counters_.max_overlap_ratio = std::max(counters_.max_overlap_ratio, t.max_ratio);
    }
    for (const ChunkTotals& t : particle_totals_) {
        counters_.wall_contacts += t.contacts;
        counters_.elastic_energy += t.energy;
        counters_.max_overlap_ratio = std::max(counters_.max_overlap_ratio, t.max_ratio);
    }
    counters_.particle_contacts += body_pairs.contacts;
    counters_.wall_contacts += body_walls.contacts;
    counters_.elastic_energy += body_pairs.energy + body_walls.energy;
    counters_.max_overlap_ratio =
        std::max({counters_.max_overlap_ratio, body_pairs.max_ratio, body_walls.max_ratio});
}

namespace {

#if defined(__AVX2__) && defined(__FMA__)
// An empty asm makes a value opaque to the compiler, so that a product is rounded before the sum
// that follows it (no fused multiply-add: the scalar code's rounding, see kick_drift_four).
inline __m256d rounded(__m256d a) {
    asm("" : "+x"(a));
    return a;
}

// kick_drift on four particles, whose Vec3 records are twelve consecutive doubles: three registers
// per field, lane pattern (x0 y0 z0 x1 | y1 z1 x2 y2 | z2 x3 y3 z3). Per-particle scalars are
// spread to that pattern; every double sees the operations of the scalar loop in the same order
// (the same fused multiply-adds, as GCC contracts that loop): v = fma(h, fma(f, 1/m, g), v) per
// kick, w = fma(h / I, t, w), x = fma(dt, v, x); the squared displacement is fma(dz, dz, dx dx + dy
// dy) with both products rounded. Returns the squared displacements of the four.
template <int kicks, bool clear>
inline __m256d kick_drift_four(double* __restrict x, double* __restrict v, double* __restrict w,
                               double* __restrict f, double* __restrict t,
                               const double* __restrict inv_m, const double* __restrict inv_i,
                               const double* __restrict x_build, double h, double dt,
                               const __m256d g[3]) {
    const __m256d m4 = _mm256_loadu_pd(inv_m);
    const __m256d hi4 = _mm256_mul_pd(_mm256_set1_pd(h), _mm256_loadu_pd(inv_i));
    const __m256d m[3] = {_mm256_permute4x64_pd(m4, 0x40), _mm256_permute4x64_pd(m4, 0xA5),
                          _mm256_permute4x64_pd(m4, 0xFE)};
    const __m256d hi[3] = {_mm256_permute4x64_pd(hi4, 0x40), _mm256_permute4x64_pd(hi4, 0xA5),
                           _mm256_permute4x64_pd(hi4, 0xFE)};
    const __m256d hh = _mm256_set1_pd(h);
    const __m256d dd = _mm256_set1_pd(dt);
    __m256d d[3];
    for (int r = 0; r < 3; ++r) {
        const __m256d a = _mm256_fmadd_pd(_mm256_loadu_pd(f + 4 * r), m[r], g[r]);
        __m256d vr = _mm256_loadu_pd(v + 4 * r);
        __m256d wr = _mm256_loadu_pd(w + 4 * r);
        const __m256d tr = _mm256_loadu_pd(t + 4 * r);
        for (int k = 0; k < kicks; ++k) {
            vr = _mm256_fmadd_pd(hh, a, vr);
            wr = _mm256_fmadd_pd(hi[r], tr, wr);
        }
        _mm256_storeu_pd(v + 4 * r, vr);
        _mm256_storeu_pd(w + 4 * r, wr);
        if constexpr (clear) {
            _mm256_storeu_pd(f + 4 * r, _mm256_setzero_pd());
            _mm256_storeu_pd(t + 4 * r, _mm256_setzero_pd());
        }
        const __m256d xr = _mm256_fmadd_pd(dd, vr, _mm256_loadu_pd(x + 4 * r));
        _mm256_storeu_pd(x + 4 * r, xr);
        d[r] = _mm256_sub_pd(xr, _mm256_loadu_pd(x_build + 4 * r));
    }
    // Columns of d: (x0 y0 x2 y2), (y1 z1 y3 z3), (z0 x1 z2 x3), then x, y and z of the four.
    const __m256d t0 = _mm256_blend_pd(d[0], d[1], 0b1100);
    const __m256d t1 = _mm256_blend_pd(d[1], d[2], 0b1100);
    const __m256d t2 = _mm256_permute2f128_pd(d[0], d[2], 0x21);
    const __m256d dx = _mm256_blend_pd(t0, t2, 0b1010);
    const __m256d dy = _mm256_shuffle_pd(t0, t1, 0b0101);
    const __m256d dz = _mm256_blend_pd(t2, t1, 0b1010);
    return _mm256_fmadd_pd(
        dz, dz, _mm256_add_pd(rounded(_mm256_mul_pd(dx, dx)), rounded(_mm256_mul_pd(dy, dy))));
}
#endif

} // namespace

// Half kicks, drift and displacement check of the particles [p0, p1) in one pass. kicks = 2 is the
// second half kick of the last step followed by the first of this one, each rounded as its own
// pass (half_kick) rounds it, so the bits are those of two passes. With `clear`, forces and torques
// are zeroed after their last read. Returns the largest squared displacement since the list build
// (m^2; 0 unless `same_size`; NaN ignored); with `same_size`, appends to `loose` the particles
// whose squared displacement exceeds their room (room2_, the inner lists). Four particles at a
// time with AVX2.
template <int kicks, bool clear>
double System::kick_drift(std::size_t p0, std::size_t p1, bool same_size,
                          std::vector<std::uint32_t>& loose) {
    const double dt = spec_.time_step;
    const double h = 0.5 * dt;
    const Vec3 g = spec_.gravity;
    Vec3* __restrict x = p_.x.data();
    Vec3* __restrict v = p_.v.data();
    Vec3* __restrict w = p_.omega.data();
    Vec3* __restrict f = p_.force.data();
    Vec3* __restrict t = p_.torque.data();
    const double* __restrict inv_m = p_.inv_mass.data();
    const double* __restrict inv_i = p_.inv_inertia.data();
    const Vec3* __restrict x_build = nl_.positions_at_build().data();
    const double* __restrict room2 = room2_.data();
    double largest = 0.0;
    std::size_t i = p0;
#if defined(__AVX2__) && defined(__FMA__)
    static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 records are packed");
    if (same_size) {
        const __m256d gl[3] = {_mm256_setr_pd(g[0], g[1], g[2], g[0]),
                               _mm256_setr_pd(g[1], g[2], g[0], g[1]),
                               _mm256_setr_pd(g[2], g[0], g[1], g[2])};
        __m256d big = _mm256_setzero_pd();
        for (; i + 4 <= p1; i += 4) {
            // max(a, b) gives b when a is NaN: NaN ignored, as the comparison it replaced did.
            const __m256d s2 = kick_drift_four<kicks, clear>(
                x[i].data(), v[i].data(), w[i].data(), f[i].data(), t[i].data(), inv_m + i,
                inv_i + i, x_build[i].data(), h, dt, gl);
            big = _mm256_max_pd(s2, big);
            const auto out = static_cast<unsigned>(
                _mm256_movemask_pd(_mm256_cmp_pd(s2, _mm256_loadu_pd(room2 + i), _CMP_GT_OQ)));
            if (out != 0U) {
                for (unsigned l = 0; l < 4; ++l) {
                    if (((out >> l) & 1U) != 0U) {
                        loose.push_back(static_cast<std::uint32_t>(i + l));
                    }
                }
            }
        }
        alignas(32) double lanes[4];
        _mm256_store_pd(lanes, big);
        largest = std::max({lanes[0], lanes[1], lanes[2], lanes[3]});
    }
#endif
    for (; i < p1; ++i) {
        // Copies in registers: through memory, each kick waited for the last one's store.
        Vec3 vi = v[i];
        Vec3 wi = w[i];
        const Vec3 fi = f[i];
        const Vec3 ti = t[i];
        const double mi = inv_m[i];
        const double hi = h * inv_i[i];
        for (int k = 0; k < kicks; ++k) {
            for (int q = 0; q < 3; ++q) {
                vi[q] = fused(h, fused(fi[q], mi, g[q]), vi[q]);
                wi[q] = fused(hi, ti[q], wi[q]);
            }
        }
        v[i] = vi;
        w[i] = wi;
        if constexpr (clear) {
            f[i].setZero();
            t[i].setZero();
        }
        Vec3 xi;
        for (int q = 0; q < 3; ++q) {
            xi[q] = fused(dt, vi[q], x[i][q]);
        }
        x[i] = xi;
        if (same_size) {
            const double d2 = displacement2(xi - x_build[i]);
            largest = d2 > largest ? d2 : largest;
            if (d2 > room2[i]) {
                loose.push_back(static_cast<std::uint32_t>(i));
            }
        }
    }
    return largest;
}

// The start of a step: bodies kick their angular momentum and rotate (`kicks` half kicks of L),
// then `kicks` half kicks (1, or 2 when the last step left its second one to this pass), drift,
// displacement check and, on one thread, the clearing of forces and torques, in one pass over the
// particles; the list is rebuilt when a particle moved more than half the skin. Returns whether
// the forces and torques were cleared.
bool System::begin_step(int kicks) {
    if (!list_valid_) {
        rebuild_neighbours();
    }
    const std::size_t n = p_.size();
    const bool same_size = nl_.positions_at_build().size() == n && nl_.offsets().size() == n + 1;
    const double lim2 = 0.25 * nl_.skin() * nl_.skin();
    const std::size_t units = (n + particle_unit_size - 1) / particle_unit_size;
    // The rotation reads the torques before the pass below clears them. The pass leaves a body's
    // omega as it is (its inv_inertia is 0: omega + 0 * torque), so the order of the two changes
    // no bit. With several threads the particle sums set the forces (nothing to clear).
    if (has_bodies_) {
        rotate_bodies(kicks, true);
    }
    const bool clear = threads_ == 1;
    KILN_ASSERT(kicks == 1 || kicks == 2);
    double largest = 0.0; // squared displacement since the list build (m^2)
    unit_loose_.resize(units);
    detail::in_team(threads_, [&] {
#pragma omp for schedule(static) reduction(max : largest)
        for (std::size_t u = 0; u < units; ++u) {
            const std::size_t p0 = u * particle_unit_size;
            const std::size_t p1 = std::min(n, p0 + particle_unit_size);
            std::vector<std::uint32_t>& loose = unit_loose_[u];
            loose.clear();
            double d2 = 0.0;
            if (kicks == 2) {
                d2 = clear ? kick_drift<2, true>(p0, p1, same_size, loose)
                           : kick_drift<2, false>(p0, p1, same_size, loose);
            } else {
                d2 = clear ? kick_drift<1, true>(p0, p1, same_size, loose)
                           : kick_drift<1, false>(p0, p1, same_size, loose);
            }
            largest = std::max(largest, d2);
        }
    });

    if (!same_size || largest > lim2) {
        rebuild_neighbours(); // drops the inner lists
    } else {
        for (const auto& loose : unit_loose_) {
            loosen(loose);
        }
    }
    return clear;
}

void System::step() {
    const bool cleared = begin_step(1);
    form_counters_ = true;
    compute_forces(true, cleared);
    ++step_;
    time_ = static_cast<double>(step_) * spec_.time_step;
}

void System::advance(long steps) {
    // Recorded onsets are read after each step. Bodies and mesh walls add their forces after the
    // sphere pass (body_forces): their second half kick waits for the next begin_step as the
    // spheres' does, and the omega of a body between two steps, which nobody reads, is not formed.
    if (steps < 2 || spec_.record_contact_onsets) {
        for (long s = 0; s < steps; ++s) {
            step();
        }
        return;
    }
    for (long s = 0; s < steps; ++s) {
        const bool last = s + 1 == steps;
        // The second half kick of every step but the last waits for the next step's pass. The
        // counters of the steps before the last cannot be read: the spheres' elastic energy and
        // largest overlap ratio are not formed (use_energy_on_demand).
        const bool cleared = begin_step(s == 0 ? 1 : 2);
        form_counters_ = last || !energy_on_demand_;
        compute_forces(last, cleared);
        ++step_;
        time_ = static_cast<double>(step_) * spec_.time_step;
    }
    form_counters_ = true;
}

void System::collect_contacts(std::vector<ContactRecord>& out) const {
    out.clear();
    KILN_ASSERT(list_valid_);
    const auto& nb = nl_.partners();
    const auto& owner = nl_.owners();
    // The same touch test as pair_chunk (squared distance below the squared radius sum).
    for (std::size_t k = 0; k < nb.size(); ++k) {
        const std::uint32_t i = owner[k];
        const std::uint32_t j = nb[k];
        if (p_.shape[i] >= 0 || p_.shape[j] >= 0) {
            continue; // pairs with a body: from body_contacts_ below
        }
        const double rsum = p_.radius[i] + p_.radius[j];
        const Vec3 d = p_.x[j] - p_.x[i];
        const double d2 = simd::squared_distance(p_.x[i], p_.x[j]);
        if (!(d2 < rsum * rsum) || d2 == 0.0) {
            continue;
        }
        const double dist = std::sqrt(d2);
        ContactRecord c;
        c.i = i;
        c.j = j;
        c.normal = d / dist;
        c.overlap = rsum - dist;
        c.point = p_.x[i] + (p_.radius[i] - 0.5 * c.overlap) * c.normal;
        c.r_eff = p_.radius[i] * p_.radius[j] / rsum;
        out.push_back(c);
    }
    for (std::size_t w = 0; w < spec_.walls.size(); ++w) {
        for (const std::uint32_t i : wall_candidates_[w]) {
            const WallContact g = std::visit(
                [&](const auto& shape) { return wall_contact(shape, p_.x[i], p_.radius[i]); },
                spec_.walls[w].shape);
            if (!(g.overlap > 0.0)) {
                continue;
            }
            ContactRecord c;
            c.i = i;
            c.j = static_cast<std::uint32_t>(w);
            c.wall = true;
            c.normal = -g.n;
            c.overlap = g.overlap;
            c.point = p_.x[i] + (p_.radius[i] - 0.5 * g.overlap) * c.normal;
            c.r_eff = g.r_eff;
            out.push_back(c);
        }
    }
    if (!generic_contacts()) {
        return; // no bodies and no mesh walls: nothing in body_contacts_
    }
    // Contacts with mesh walls carry the wall index walls.size() + mesh index (the key order of
    // body contacts), so `j` of such a record is not an index into spec_.walls.
    // Element contacts of bodies from the last force evaluation, in key order (ids, elements):
    // one record per touching element pair, carrying the body (particle) index. Their normal runs
    // from b to a; a record's normal runs from i = a to its partner, hence the sign change.
    std::int64_t max_id = 0;
    for (const std::int64_t id : p_.id) {
        max_id = std::max(max_id, id);
    }
    std::vector<std::uint32_t> index(static_cast<std::size_t>(max_id) + 1, 0);
    for (std::size_t i = 0; i < p_.size(); ++i) {
        index[static_cast<std::size_t>(p_.id[i])] = static_cast<std::uint32_t>(i);
    }
    // The table is in evaluation order; records go out in key order, as before the flat table.
    const std::vector<BodyContactEntry>& table = body_contacts();
    std::vector<std::uint32_t> by_key(table.size());
    for (std::size_t k = 0; k < by_key.size(); ++k) {
        by_key[k] = static_cast<std::uint32_t>(k);
    }
    std::sort(by_key.begin(), by_key.end(),
              [&](std::uint32_t l, std::uint32_t r) { return table[l].key < table[r].key; });
    for (const std::uint32_t k : by_key) {
        const BodyContactKey& key = table[k].key;
        const BodyContact& bc = table[k].contact;
        ContactRecord c;
        c.i = index[static_cast<std::size_t>(key.a)];
        c.wall = key.b < 0;
        c.j = c.wall ? static_cast<std::uint32_t>(-1 - key.b)
                     : index[static_cast<std::size_t>(key.b)];
        c.point = bc.point;
        c.normal = -bc.normal;
        c.overlap = bc.overlap;
        c.r_eff = bc.r_eff;
        out.push_back(c);
    }
}

void System::check_finite() const {
    for (std::size_t i = 0; i < p_.size(); ++i) {
        if (!p_.x[i].allFinite() || !p_.v[i].allFinite() || !p_.omega[i].allFinite()) {
            throw RunError(step_,
                           fmt::format("particle {} has a non-finite position or velocity; the "
                                       "time step is probably too large for the contact stiffness",
                                       p_.id[i]));
        }
    }
}

Energies System::energies() const {
    Energies e;
    for (std::size_t i = 0; i < p_.size(); ++i) {
        e.kinetic += 0.5 * p_.mass[i] * p_.v[i].squaredNorm();
        e.rotational += p_.shape[i] >= 0
                            ? geometry::rotational_energy(p_.q[i], p_.ang_mom[i], p_.inertia[i])
                            : 0.5 * p_.omega[i].squaredNorm() / p_.inv_inertia[i];
        e.potential -= p_.mass[i] * spec_.gravity.dot(p_.x[i]);
    }
    e.elastic = counters_.elastic_energy;
    return e;
}

SystemState System::save_state() const {
    SystemState s;
    s.particles = p_;
    s.nl_offsets = nl_.offsets();
    s.nl_partners = nl_.partners();
    s.nl_shear = nl_.shear();
    s.nl_x_build = nl_.positions_at_build();
    s.nl_ids = p_.id;
    s.nl_builds = nl_.builds();
    // Particle by particle ([particle * n_walls + wall]), whatever the stride.
    const std::size_t nw = spec_.walls.size();
    s.wall_shear.assign(p_.size() * nw, Vec3::Zero());
    for (std::size_t w = 0; w < nw; ++w) {
        for (std::size_t i = 0; i < p_.size(); ++i) {
            s.wall_shear[i * nw + w] = wall_shear_[w * wall_stride_ + i];
        }
    }
    s.time = time_;
    s.step = step_;
    s.next_id = next_id_;
    s.counters = counters_;
    std::ostringstream os;
    os << rng_;
    s.rng = os.str();
    s.body_contacts.reserve(body_contacts().size());
    for (const BodyContactEntry& e : body_contacts()) {
        s.body_contacts.emplace_back(e.key, e.contact);
    }
    std::sort(s.body_contacts.begin(), s.body_contacts.end(),
              [](const auto& l, const auto& r) { return l.first < r.first; });
    s.narrow_phase = np_;
    return s;
}

void System::restore_state(SystemState s) {
    p_ = std::move(s.particles);
    nl_.restore(std::move(s.nl_offsets), std::move(s.nl_partners), std::move(s.nl_shear),
                std::move(s.nl_x_build), std::move(s.nl_ids), s.nl_builds);
    const std::size_t nw = spec_.walls.size();
    wall_stride_ = p_.size();
    wall_shear_.assign(nw * wall_stride_, Vec3::Zero());
    wall_shear_spare_.clear();
    for (std::size_t w = 0; w < nw; ++w) {
        for (std::size_t i = 0; i < wall_stride_; ++i) {
            wall_shear_[w * wall_stride_ + i] = s.wall_shear[i * nw + w];
        }
    }
    time_ = s.time;
    step_ = s.step;
    next_id_ = s.next_id;
    std::istringstream is(s.rng);
    is >> rng_;
    counters_ = s.counters;
    body_contacts_.clear();
    for (const auto& [key, contact] : s.body_contacts) {
        body_contacts_.push_back({key, contact});
    }
    members_from_table_ = true; // the restored table holds every history
    view_valid_ = false;
    np_ = s.narrow_phase;
    // The list is restored as it was; rebuilding it now would reorder particles and change the
    // summation order. Forces and torques of the last step are part of the store; recomputing them
    // would advance the tangential histories a second time. Either would break exact continuation.
    index_partners();
    find_wall_candidates();
    list_valid_ = true;
}

} // namespace kiln::dynamics
