// Non-spherical particles in the step loop: element contacts of pairs involving a body, body-wall
// contacts, and the rotation update. See docs/architecture.md ("Bodies in the run loop") and
// docs/theory/contact.md ("Non-spherical contacts").

#include "dynamics/system.hpp"

#include "dynamics/omp_team.hpp"
#include "geometry/rotation.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <exception>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

namespace kiln::dynamics {

namespace {

/// Lanes of body_forces' sphere queue (pairs of sphere elements, and sphere elements against
/// plane or cylinder walls).
constexpr std::size_t queue_lanes = 16;

/// The sphere queue's lanes (world frame): the law's block, and the raw data of queued sphere
/// pairs (element centres ca and cb, radii, body centres, velocities and masses, R* of the first
/// touch (0: none), ratio scale), then their geometry (contact point, lever arms from the centres
/// of mass, overlap ratio).
struct SphereLanes {
    static constexpr std::size_t L = queue_lanes;
    contact::ContactBlock<L> cb;
    double ca[3][L], cb_[3][L], xa[3][L], xb[3][L], va[3][L], vb[3][L];
    double rada[L], radb[L], ma[L], mb[L], r0[L], size[L];
    double p[3][L], ra[3][L], rb[3][L], ratio[L];
    bool is_new[L]; // the contact is new this step (heat: impact onsets)
};

/// The contacts of a clump's sphere elements mc[0..n_el) with the wall shape ws, in element order,
/// into `out` as {element index in the body, contact}: first, from one pass without branches,
/// every element that is not a sphere and the sphere elements closer to touching than 1e-9 of
/// their radius (far above the round-off of the overlap; a branch per member was mispredicted
/// often), then the exact test (`hits`: scratch). Throws for an element that is not a sphere (a
/// body of several elements is a clump of spheres). One out-of-line instance, called by the
/// serial pass and by the threads ahead of it, so that both give the same bits. `lanes`: the
/// first pass against a plane eight members at a time (AVX-512 builds; System::use_member_lanes).
template <class Member, class Hit>
[[gnu::noinline]] void clump_wall_contacts(const WallShape& ws, const Member* mc,
                                           std::uint32_t n_el, std::vector<std::uint32_t>& hits,
                                           std::vector<Hit>& out, bool lanes) {
    out.clear();
    hits.resize(n_el);
    std::size_t n_wh = 0;
    std::visit(
        [&](const auto& s) {
            std::uint32_t* h = hits.data();
            std::uint32_t j = 0;
#if defined(__AVX512F__)
            // A plane: eight members at a time, read as four vectors of two members each and
            // turned into columns; the members that pass listed in order. Whatever the rounding
            // of this distance, the exact test below decides (the 1e-9 margin is far above it).
            if constexpr (std::is_same_v<std::decay_t<decltype(s)>, PlaneWall> &&
                          sizeof(Member) == 4 * sizeof(double)) {
                const std::uint32_t in_lanes = lanes ? n_el : 0;
                const auto* raw = reinterpret_cast<const double*>(mc);
                const __m512i pick_xy = _mm512_setr_epi64(0, 4, 8, 12, 1, 5, 9, 13);
                const __m512i pick_zr = _mm512_setr_epi64(2, 6, 10, 14, 3, 7, 11, 15);
                const __m512i low = _mm512_setr_epi64(0, 1, 2, 3, 8, 9, 10, 11);
                const __m512i high = _mm512_setr_epi64(4, 5, 6, 7, 12, 13, 14, 15);
                const __m512d nx = _mm512_set1_pd(s.normal.x());
                const __m512d ny = _mm512_set1_pd(s.normal.y());
                const __m512d nz = _mm512_set1_pd(s.normal.z());
                const __m512d px = _mm512_set1_pd(s.point.x());
                const __m512d py = _mm512_set1_pd(s.point.y());
                const __m512d pz = _mm512_set1_pd(s.point.z());
                const __m512d margin = _mm512_set1_pd(-1e-9);
                const __m512d zero = _mm512_setzero_pd();
                for (; j + 8 <= in_lanes; j += 8) {
                    const double* q = raw + 4 * static_cast<std::size_t>(j);
                    const __m512d m01 = _mm512_loadu_pd(q);      // x0 y0 z0 r0 x1 y1 z1 r1
                    const __m512d m23 = _mm512_loadu_pd(q + 8);  // members 2, 3
                    const __m512d m45 = _mm512_loadu_pd(q + 16); // members 4, 5
                    const __m512d m67 = _mm512_loadu_pd(q + 24); // members 6, 7
                    const __m512d xy03 = _mm512_permutex2var_pd(m01, pick_xy, m23);
                    const __m512d zr03 = _mm512_permutex2var_pd(m01, pick_zr, m23);
                    const __m512d xy47 = _mm512_permutex2var_pd(m45, pick_xy, m67);
                    const __m512d zr47 = _mm512_permutex2var_pd(m45, pick_zr, m67);
                    const __m512d x = _mm512_permutex2var_pd(xy03, low, xy47);
                    const __m512d y = _mm512_permutex2var_pd(xy03, high, xy47);
                    const __m512d z = _mm512_permutex2var_pd(zr03, low, zr47);
                    const __m512d r = _mm512_permutex2var_pd(zr03, high, zr47);
                    const __m512d d =
                        _mm512_fmadd_pd(_mm512_sub_pd(z, pz), nz,
                                        _mm512_fmadd_pd(_mm512_sub_pd(y, py), ny,
                                                        _mm512_mul_pd(_mm512_sub_pd(x, px), nx)));
                    const __m512d ov = _mm512_sub_pd(r, d);
                    const __mmask8 near =
                        _mm512_cmp_pd_mask(r, zero, _CMP_NGT_UQ) |
                        _mm512_cmp_pd_mask(ov, _mm512_mul_pd(margin, r), _CMP_GT_OQ);
                    for (unsigned m = near; m != 0; m &= m - 1) {
                        h[n_wh++] = j + static_cast<std::uint32_t>(std::countr_zero(m));
                    }
                }
            }
#endif
            for (; j < n_el; ++j) {
                const double ov = wall_contact(s, Vec3(mc[j].x, mc[j].y, mc[j].z), mc[j].r).overlap;
                const bool near = !(mc[j].r > 0.0) || ov > -1e-9 * mc[j].r;
                h[n_wh] = j;
                n_wh += static_cast<std::size_t>(near);
            }
        },
        ws);
    for (std::size_t k = 0; k < n_wh; ++k) {
        const std::uint32_t j = hits[k];
        const Member& ms = mc[j];
        if (!(ms.r > 0.0)) {
            throw std::logic_error("body_forces: a convex element in a body of several elements");
        }
        const Vec3 centre(ms.x, ms.y, ms.z);
        const WallContact wc =
            std::visit([&](const auto& s) { return wall_contact(s, centre, ms.r); }, ws);
        if (!(wc.overlap > 0.0)) {
            continue;
        }
        ElementContact ec; // element_wall_contact's sphere case
        ec.touching = true;
        ec.overlap = wc.overlap;
        ec.normal = wc.n;
        ec.point = centre - (ms.r - 0.5 * wc.overlap) * wc.n;
        ec.r_eff = wc.r_eff;
        out.push_back({j, ec});
    }
}

/// The first `queued` lanes of `q` through the law (`raw`: sphere pairs, whose geometry is
/// derived first from the raw data, in vector lanes). One out-of-line instance per law, called by
/// the serial pass and by the threads that run the member pairs ahead of it, so that both give
/// the same bits (GCC contracts a * b + c into FMAs per inlined copy).
template <class Law>
[[gnu::noinline]] void evaluate_sphere_lanes(const Law& law, double fn_floor, double rolling,
                                             double dt, SphereLanes& q, std::size_t queued,
                                             bool raw) {
    contact::ContactBlock<queue_lanes>& cb = q.cb;
    if (raw) {
#pragma omp simd
        for (std::size_t k = 0; k < queued; ++k) {
            const double d0 = q.ca[0][k] - q.cb_[0][k];
            const double d1 = q.ca[1][k] - q.cb_[1][k];
            const double d2 = q.ca[2][k] - q.cb_[2][k];
            const double dist = std::sqrt(d0 * d0 + d1 * d1 + d2 * d2);
            const double rsum = q.rada[k] + q.radb[k];
            const double overlap = rsum - dist;
            const double inv = 1.0 / dist;
            const double n[3] = {d0 * inv, d1 * inv, d2 * inv};
            const double to_point = q.radb[k] - 0.5 * overlap;
            double ra[3], rb[3];
            for (int c = 0; c < 3; ++c) {
                q.p[c][k] = q.cb_[c][k] + to_point * n[c];
                ra[c] = q.p[c][k] - q.xa[c][k];
                rb[c] = q.p[c][k] - q.xb[c][k];
                q.ra[c][k] = ra[c];
                q.rb[c][k] = rb[c];
                cb.n[c][k] = n[c];
            }
            const double(&wa)[3][queue_lanes] = cb.wi;
            const double(&wb)[3][queue_lanes] = cb.wj;
            // v_a + w_a x r_a - v_b - w_b x r_b: the velocity of the contact point
            cb.v[0][k] = q.va[0][k] + (wa[1][k] * ra[2] - wa[2][k] * ra[1]) - q.vb[0][k] -
                         (wb[1][k] * rb[2] - wb[2][k] * rb[1]);
            cb.v[1][k] = q.va[1][k] + (wa[2][k] * ra[0] - wa[0][k] * ra[2]) - q.vb[1][k] -
                         (wb[2][k] * rb[0] - wb[0][k] * rb[2]);
            cb.v[2][k] = q.va[2][k] + (wa[0][k] * ra[1] - wa[1][k] * ra[0]) - q.vb[2][k] -
                         (wb[0][k] * rb[1] - wb[1][k] * rb[0]);
            cb.overlap[k] = overlap;
            const double r_geo = q.rada[k] * q.radb[k] / rsum;
            cb.r_eff[k] = q.r0[k] > 0.0 ? q.r0[k] : r_geo;
            cb.m_eff[k] = q.ma[k] * q.mb[k] / (q.ma[k] + q.mb[k]);
            q.ratio[k] = overlap / q.size[k];
        }
    }
#pragma omp simd
    for (std::size_t k = 0; k < queued; ++k) {
        contact::evaluate_block(law, fn_floor, rolling, cb, k, dt);
    }
}

/// Smallest element size of a contact, for the overlap ratio.
double ratio_size(const Element& a, const Element* b) {
    return 2.0 * std::min(a.min_size, b ? b->min_size : a.min_size);
}

} // namespace

void System::rotate_bodies(int kicks, bool drift) {
    // `kicks` half kicks of the world angular momentum (2: the second of the last step, whose
    // omega nobody read, and the first of this one, each rounded as its own pass), then (drift)
    // the free rotation over the step by the symmetric splitting of geometry/rotation.hpp; omega
    // (world frame) is derived from (q, L) for the contacts.
    const double h = 0.5 * spec_.time_step;
    // One rotation matrix per body and step: it turns L into the body frame for the free
    // rotation (bodies eight at a time in vector lanes), is then replaced by that of the new q,
    // and gives omega (no quaternion-vector products).
    //
    // Bodies by runs of `run` (a multiple of the rotation's eight lanes, so every body keeps its
    // lane and batch): every body's update reads and writes only its own state, so the runs may
    // go to several threads with the same bits. Only with enough bodies: a parallel region per
    // step costs more than the rotation of a few hundred bodies (docs/performance.md).
    constexpr std::size_t run = 64;
    static_assert(run % 8 == 0, "runs of whole batches of the free rotation");
    const std::size_t n = bodies_.size();
    const auto runs = static_cast<std::ptrdiff_t>((n + run - 1) / run);
    const bool parallel = parallel_body_passes();
    detail::in_team(parallel ? threads_ : 1, [&] {
        // The arrays and counts as the thread's own locals: read through the members (or
        // references), every store of a body's state (Eigen's vector stores may alias anything)
        // made the loops load the arrays' addresses and `kicks` again.
        const std::uint32_t* const index = bodies_.data();
        Vec3* const ang_mom = p_.ang_mom.data();
        const Vec3* const torque = p_.torque.data();
        const Vec3* const inertia = p_.inertia.data();
        Quat* const q = p_.q.data();
        Mat3* const rot = rot_.data();
        Vec3* const omega = p_.omega.data();
        const double dt = spec_.time_step;
        const int n_kicks = kicks;
        const double half_dt = h;
#pragma omp for schedule(static)
        for (std::ptrdiff_t r = 0; r < runs; ++r) {
            const std::size_t b0 = static_cast<std::size_t>(r) * run;
            const std::size_t b1 = std::min(n, b0 + run);
            for (std::size_t b = b0; b < b1; ++b) {
                const std::uint32_t i = index[b];
                for (int k = 0; k < n_kicks; ++k) {
                    geometry::kick_angular_momentum(ang_mom[i], torque[i], half_dt);
                }
            }
            if (drift) {
                geometry::free_rotate_bodies(index + b0, b1 - b0, q, rot, ang_mom, inertia, dt);
                for (std::size_t b = b0; b < b1; ++b) {
                    const std::uint32_t i = index[b];
                    rot[i] = geometry::unit_rotation_matrix(q[i]);
                }
            }
            for (std::size_t b = b0; b < b1; ++b) {
                const std::uint32_t i = index[b];
                omega[i] = geometry::angular_velocity_world(rot[i], ang_mom[i], inertia[i]);
            }
        }
    });
}

void System::rekey_body_contacts() {
    // Groups of the evaluation order of body_forces(): pairs {0, list entry, 0, element of a},
    // plane walls {1, particle, wall, element}, mesh walls {2, mesh wall, particle, element}. A
    // record whose pair left the list (it cannot be touching) is dropped. Member-pair records are
    // folded into the table first: they are keyed by ids, not by the old list or particle order.
    fold_member_contacts(true);
    view_valid_ = false;
    body_groups_.clear();
    if (body_contacts_.empty()) {
        return;
    }
    constexpr std::uint32_t none = std::numeric_limits<std::uint32_t>::max();
    std::int64_t max_id = 0;
    for (const std::int64_t id : p_.id) {
        max_id = std::max(max_id, id);
    }
    std::vector<std::uint32_t> index(static_cast<std::size_t>(max_id) + 1, none);
    for (std::size_t i = 0; i < p_.size(); ++i) {
        index[static_cast<std::size_t>(p_.id[i])] = static_cast<std::uint32_t>(i);
    }
    const auto index_of = [&](std::int64_t id) {
        return id >= 0 && id <= max_id ? index[static_cast<std::size_t>(id)] : none;
    };
    const auto& offsets = nl_.offsets();
    const auto& nb = nl_.partners();
    const auto entry_of = [&](std::uint32_t i, std::uint32_t j) {
        for (std::uint32_t k = offsets[i]; k < offsets[i + 1]; ++k) {
            if (nb[k] == j) {
                return k;
            }
        }
        return none;
    };
    const auto n_walls = static_cast<std::int64_t>(spec_.walls.size());
    std::vector<std::pair<ContactGroup, std::uint32_t>> order;
    order.reserve(body_contacts_.size());
    for (std::size_t r = 0; r < body_contacts_.size(); ++r) {
        const BodyContactKey& key = body_contacts_[r].key;
        const std::uint32_t ia = index_of(key.a);
        if (ia == none) {
            continue;
        }
        const auto ea = static_cast<std::uint32_t>(key.ea);
        ContactGroup g{};
        if (key.b >= 0) {
            const std::uint32_t ib = index_of(key.b);
            std::uint32_t k = ib == none ? none : entry_of(ia, ib);
            k = k == none && ib != none ? entry_of(ib, ia) : k;
            if (k == none) {
                continue;
            }
            g = {0, k, 0, ea};
        } else if (-1 - key.b < n_walls) {
            g = {1, ia, static_cast<std::uint32_t>(-1 - key.b), ea};
        } else {
            g = {2, static_cast<std::uint32_t>(-1 - key.b - n_walls), ia, ea};
        }
        order.emplace_back(g, static_cast<std::uint32_t>(r));
    }
    std::stable_sort(order.begin(), order.end(),
                     [](const auto& l, const auto& r) { return l.first < r.first; });
    next_contacts_.clear();
    for (const auto& [g, r] : order) {
        next_contacts_.push_back(body_contacts_[r]);
        body_groups_.push_back(g);
    }
    body_contacts_.swap(next_contacts_);
}

const std::vector<BodyContactEntry>& System::body_contacts() const {
    if (!view_valid_) {
        merged_body_contacts(contacts_view_, nullptr, true);
        view_valid_ = true;
    }
    return contacts_view_;
}

void System::merged_body_contacts(std::vector<BodyContactEntry>& out,
                                  std::vector<ContactGroup>* groups, bool geometry) const {
    // The records of the table and those of the member pairs touching at the last evaluation,
    // merged in evaluation order: member pairs are in list order (entry, element of a, element of
    // b), as the groups of the table, which holds every other contact.
    out.clear();
    if (groups != nullptr) {
        groups->clear();
    }
    std::size_t r = 0;
    const auto emit_table = [&] {
        out.push_back(body_contacts_[r]);
        if (groups != nullptr) {
            groups->push_back(body_groups_[r]);
        }
        ++r;
    };
    if (!members_from_table_) {
        for (std::size_t i = 0; i < member_pairs_.size(); ++i) {
            if (member_seen_[i] != body_eval_) {
                continue; // not touching at the last evaluation
            }
            const MemberPair& m = member_pairs_[i];
            const BodyContactKey& key = member_keys_[i];
            const ContactGroup g(0, m.k, 0, static_cast<std::uint32_t>(key.ea));
            while (r < body_groups_.size() &&
                   (body_groups_[r] < g ||
                    (body_groups_[r] == g && body_contacts_[r].key.eb < key.eb))) {
                emit_table();
            }
            // The geometry as the flush of body_forces derives it (same expressions and order).
            const MemberSphere& A = member_c_[m.ea];
            const MemberSphere& B = member_c_[m.eb];
            const double rsum = A.r + B.r;
            BodyContact c;
            c.shear = member_shear_[i];
            c.force = member_force_[i];
            c.r_eff = A.r * B.r / rsum;
            if (geometry) {
                const double d0 = A.x - B.x;
                const double d1 = A.y - B.y;
                const double d2 = A.z - B.z;
                const double dist = std::sqrt(d0 * d0 + d1 * d1 + d2 * d2);
                const double overlap = rsum - dist;
                const double inv = 1.0 / dist;
                const double n[3] = {d0 * inv, d1 * inv, d2 * inv};
                const double to_point = B.r - 0.5 * overlap;
                c.normal = Vec3(n[0], n[1], n[2]);
                c.point = Vec3(B.x + to_point * n[0], B.y + to_point * n[1], B.z + to_point * n[2]);
                c.overlap = overlap;
            }
            out.push_back({key, c});
            if (groups != nullptr) {
                groups->push_back(g);
            }
        }
    }
    while (r < body_groups_.size()) {
        emit_table();
    }
}

void System::fold_member_contacts(bool geometry) {
    if (members_from_table_) {
        return;
    }
    merged_body_contacts(next_contacts_, &next_groups_, geometry);
    body_contacts_.swap(next_contacts_);
    body_groups_.swap(next_groups_);
    next_contacts_.clear(); // body_forces() may be filling the next table after this
    next_groups_.clear();
    members_from_table_ = true;
    view_valid_ = false;
}

void System::build_member_pairs() {
    // Elements are posed (body_forces); every body entry becomes its member pairs within a skin, or
    // one general item when an element of either side is not a sphere. The histories of the old
    // member pairs are in the table when this runs (fold_member_contacts).
    member_pairs_.clear();
    member_keys_.clear();
    const auto& nb = nl_.partners();
    const auto& owner = nl_.owners();
    const double skin = nl_.skin();
    const auto all_spheres = [&](std::uint32_t i) {
        for (std::uint32_t e = element_begin_[i]; e < element_begin_[i + 1]; ++e) {
            if (!(member_c_[e].r > 0.0)) {
                return false;
            }
        }
        return true;
    };
#if defined(__AVX512F__)
    // The posed members by component, for lane_pairs.
    const bool lanes = member_lanes_;
    const std::size_t n_members_all = member_c_.size();
    member_cols_.resize(lanes ? 4 * n_members_all : 0);
    for (std::size_t e = 0; lanes && e < n_members_all; ++e) {
        member_cols_[e] = member_c_[e].x;
        member_cols_[n_members_all + e] = member_c_[e].y;
        member_cols_[2 * n_members_all + e] = member_c_[e].z;
        member_cols_[3 * n_members_all + e] = member_c_[e].r;
    }
    // Member e0's column entries onward: x, y, z, r of the members e0, e0 + 1, ...
    struct Columns {
        const double *x, *y, *z, *r;
    };
    const auto columns = [&](std::uint32_t e0) {
        const double* x = member_cols_.data() + e0;
        return Columns{x, x + n_members_all, x + 2 * n_members_all, x + 3 * n_members_all};
    };
    // The lanes in use of a group of eight from member j of n on (all but past the end).
    const auto group_mask = [](std::uint32_t n, std::uint32_t j) {
        return static_cast<__mmask8>(n - j >= 8 ? 0xffU : (1U << (n - j)) - 1U);
    };
    // Bit j set when member j of body i can reach body `other` (near_members' test, below; its
    // margin of 1e-9 of the reach keeps it conservative whatever the rounding), for a body of at
    // most 64 members.
    const auto near_bits = [&](std::uint32_t i, std::uint32_t other) {
        const std::uint32_t i0 = element_begin_[i];
        const std::uint32_t n_i = element_begin_[i + 1] - i0;
        const Columns c = columns(i0);
        const __m512d ox = _mm512_set1_pd(p_.x[other].x());
        const __m512d oy = _mm512_set1_pd(p_.x[other].y());
        const __m512d oz = _mm512_set1_pd(p_.x[other].z());
        const __m512d ro = _mm512_set1_pd(p_.radius[other] + skin);
        const __m512d widen = _mm512_set1_pd(1.0 + 1e-9);
        std::uint64_t bits = 0;
        for (std::uint32_t j = 0; j < n_i; j += 8) {
            const __mmask8 lanes_in = group_mask(n_i, j);
            const __m512d dx = _mm512_sub_pd(_mm512_maskz_loadu_pd(lanes_in, c.x + j), ox);
            const __m512d dy = _mm512_sub_pd(_mm512_maskz_loadu_pd(lanes_in, c.y + j), oy);
            const __m512d dz = _mm512_sub_pd(_mm512_maskz_loadu_pd(lanes_in, c.z + j), oz);
            const __m512d d2 =
                _mm512_fmadd_pd(dz, dz, _mm512_fmadd_pd(dy, dy, _mm512_mul_pd(dx, dx)));
            const __m512d reach =
                _mm512_mul_pd(_mm512_add_pd(_mm512_maskz_loadu_pd(lanes_in, c.r + j), ro), widen);
            bits |= static_cast<std::uint64_t>(_mm512_mask_cmp_pd_mask(
                        lanes_in, d2, _mm512_mul_pd(reach, reach), _CMP_LT_OQ))
                    << j;
        }
        return bits;
    };
    // The double loop below over near_a x near_b for bodies of at most 64 members (their near
    // members as bits, from near_bits): per near member of a, b's members eight at a time from
    // their columns (b's slots are contiguous), the double loop's test in each lane, then the
    // pairs with b's near members among those that pass, in the double loop's order. The test's
    // numbers are those of the scalar form as GCC compiles Eigen's squaredNorm there (dx^2 + dy^2
    // rounded twice, then dz^2 fused in) and (A.r + B.r) + skin squared; written with the
    // rounding-mode forms of the add and multiply, which GCC does not fuse into FMAs as it would
    // the plain ones.
    const auto lane_pairs = [&](std::uint32_t k, std::uint32_t a, std::uint32_t b,
                                std::uint64_t bits_a, std::uint64_t near_bits_b,
                                std::vector<MemberPair>& pairs, std::vector<BodyContactKey>& keys) {
        const std::uint32_t a0 = element_begin_[a];
        const std::uint32_t b0 = element_begin_[b];
        const std::uint32_t nb_e = element_begin_[b + 1] - b0;
        const Columns c = columns(b0);
        constexpr int mode = _MM_FROUND_CUR_DIRECTION;
        constexpr __mmask8 all = 0xff; // (the maskz forms: GCC 12's unmasked ones warn)
        const __m512d skin_v = _mm512_set1_pd(skin);
        for (; bits_a != 0; bits_a &= bits_a - 1) {
            const std::uint32_t ea = a0 + static_cast<std::uint32_t>(std::countr_zero(bits_a));
            const MemberSphere& A = member_c_[ea];
            const __m512d ax = _mm512_set1_pd(A.x);
            const __m512d ay = _mm512_set1_pd(A.y);
            const __m512d az = _mm512_set1_pd(A.z);
            const __m512d ar = _mm512_set1_pd(A.r);
            std::uint64_t hits = 0;
            for (std::uint32_t j = 0; j < nb_e; j += 8) {
                const __mmask8 lanes_in = group_mask(nb_e, j);
                const __m512d dx = _mm512_maskz_sub_round_pd(
                    all, ax, _mm512_maskz_loadu_pd(lanes_in, c.x + j), mode);
                const __m512d dy = _mm512_maskz_sub_round_pd(
                    all, ay, _mm512_maskz_loadu_pd(lanes_in, c.y + j), mode);
                const __m512d dz = _mm512_maskz_sub_round_pd(
                    all, az, _mm512_maskz_loadu_pd(lanes_in, c.z + j), mode);
                const __m512d xy =
                    _mm512_maskz_add_round_pd(all, _mm512_maskz_mul_round_pd(all, dx, dx, mode),
                                              _mm512_maskz_mul_round_pd(all, dy, dy, mode), mode);
                const __m512d d2 = _mm512_fmadd_pd(dz, dz, xy);
                const __m512d reach = _mm512_maskz_add_round_pd(
                    all,
                    _mm512_maskz_add_round_pd(all, ar, _mm512_maskz_loadu_pd(lanes_in, c.r + j),
                                              mode),
                    skin_v, mode);
                const __mmask8 in = _mm512_mask_cmp_pd_mask(
                    lanes_in, d2, _mm512_maskz_mul_round_pd(all, reach, reach, mode), _CMP_LT_OQ);
                hits |= static_cast<std::uint64_t>(in) << j;
            }
            for (hits &= near_bits_b; hits != 0; hits &= hits - 1) {
                const auto j = static_cast<std::uint32_t>(std::countr_zero(hits));
                const std::uint32_t eb = b0 + j;
                pairs.push_back({k, a, b, ea, eb});
                keys.push_back({p_.id[a], p_.id[b], static_cast<std::int32_t>(ea - a0),
                                static_cast<std::int32_t>(j)});
            }
        }
    };
#endif
    // The box test (use_box_filter): an entry of two polyhedra or superquadrics (in any mix; a
    // superquadric's box is its half axes) whose boxes along their body axes are more than a skin
    // apart cannot touch while neither body moves half a skin (travel_, which bounds the motion of
    // every point of such a body, rotation included): it is left out, its bodies marked, and
    // body_forces rebuilds the member pairs before either has moved that far.
    // Such entries are near misses of bounding spheres: of a flat plate in a settled pile, about
    // two in three list entries. travel_ must be current (it is, after index_bodies, at every
    // posing).
    const bool box_test = box_filter_ && travel_.size() == p_.size();
    box_marks_.assign(box_test ? p_.size() : 0, 0);
    const auto boxes_apart = [&](std::uint32_t a, std::uint32_t b) {
        if (p_.shape[a] < 0 || p_.shape[b] < 0) {
            return false;
        }
        const geometry::BodyBox& ba = body_boxes_[static_cast<std::size_t>(p_.shape[a])];
        const geometry::BodyBox& bb = body_boxes_[static_cast<std::size_t>(p_.shape[b])];
        if (ba.half.x() < 0.0 || bb.half.x() < 0.0) {
            return false;
        }
        return geometry::boxes_apart(p_.x[a] + rot_[a] * ba.centre, rot_[a], ba.half,
                                     p_.x[b] + rot_[b] * bb.centre, rot_[b], bb.half, skin);
    };
    // The member pairs of list entry k, appended to `pairs` and `keys` (near_a, near_b: scratch).
    const auto entry_pairs = [&](std::uint32_t k, std::vector<MemberPair>& pairs,
                                 std::vector<BodyContactKey>& keys,
                                 std::vector<std::uint32_t>& near_a,
                                 std::vector<std::uint32_t>& near_b) {
        std::uint32_t a = owner[k];
        std::uint32_t b = nb[k];
        if (p_.id[a] > p_.id[b]) {
            std::swap(a, b);
        }
        if (!all_spheres(a) || !all_spheres(b)) {
            if (box_test && boxes_apart(a, b)) {
                std::atomic_ref<std::uint8_t>(box_marks_[a]).store(1, std::memory_order_relaxed);
                std::atomic_ref<std::uint8_t>(box_marks_[b]).store(1, std::memory_order_relaxed);
                std::atomic_ref<long>(box_filter_drops_).fetch_add(1, std::memory_order_relaxed);
                return;
            }
            pairs.push_back({k, a, b, no_element, no_element});
            keys.push_back({p_.id[a], p_.id[b], -1, -1});
            return;
        }
        // Members of each side that can reach the other body at all: a member pair within the
        // skin has |A - x_b| < r_A + skin + R_b (R_b: b's bounding radius, which covers every
        // member's sphere), so members beyond that (widened by 1e-9 against round-off) pair
        // with nothing. The pairs are those of the full double loop, in its order.
        const auto near_members = [&](std::uint32_t i, std::uint32_t other,
                                      std::vector<std::uint32_t>& out) {
            out.clear();
            const Vec3& xo = p_.x[other];
            const double ro = p_.radius[other] + skin;
            for (std::uint32_t e = element_begin_[i]; e < element_begin_[i + 1]; ++e) {
                const MemberSphere& m = member_c_[e];
                const double reach = (m.r + ro) * (1.0 + 1e-9);
                if ((Vec3(m.x, m.y, m.z) - xo).squaredNorm() < reach * reach) {
                    out.push_back(e);
                }
            }
        };
        const std::uint32_t na = element_begin_[a + 1] - element_begin_[a];
        const std::uint32_t nb_e = element_begin_[b + 1] - element_begin_[b];
        if (na * nb_e > 2 * (na + nb_e)) { // the pre-selection pays (not for dimers: 4 vs 8)
#if defined(__AVX512F__)
            if (lanes && na <= 64 && nb_e <= 64) { // the same, in lanes
                const std::uint64_t bits_a = near_bits(a, b);
                const std::uint64_t bits_b = bits_a != 0 ? near_bits(b, a) : 0;
                if (bits_b != 0) {
                    lane_pairs(k, a, b, bits_a, bits_b, pairs, keys);
                }
                return;
            }
#endif
            near_members(a, b, near_a);
            if (near_a.empty()) {
                return;
            }
            near_members(b, a, near_b);
        } else {
            near_a.resize(na);
            std::iota(near_a.begin(), near_a.end(), element_begin_[a]);
            near_b.resize(nb_e);
            std::iota(near_b.begin(), near_b.end(), element_begin_[b]);
        }
        for (const std::uint32_t ea : near_a) {
            for (const std::uint32_t eb : near_b) {
                const MemberSphere& A = member_c_[ea];
                const MemberSphere& B = member_c_[eb];
                const double reach = A.r + B.r + skin;
                if ((Vec3(A.x, A.y, A.z) - Vec3(B.x, B.y, B.z)).squaredNorm() < reach * reach) {
                    pairs.push_back({k, a, b, ea, eb});
                    keys.push_back({p_.id[a], p_.id[b],
                                    static_cast<std::int32_t>(ea - element_begin_[a]),
                                    static_cast<std::int32_t>(eb - element_begin_[b])});
                }
            }
        }
    };
    // With several threads, ranges of entries in parallel, each into its own lists, joined in
    // range order: the pairs of the serial loop, in its order (whatever the ranges).
    const std::size_t n_entries = body_entries_.size();
    const std::size_t range =
        std::clamp<std::size_t>(n_entries / (8 * static_cast<std::size_t>(threads_)), 64, 1024);
    const bool parallel = parallel_body_passes() && n_entries > range;
    if (!parallel) {
        std::vector<std::uint32_t> near_a;
        std::vector<std::uint32_t> near_b;
        for (const std::uint32_t k : body_entries_) {
            entry_pairs(k, member_pairs_, member_keys_, near_a, near_b);
        }
    } else {
        const std::size_t n_ranges = (n_entries + range - 1) / range;
        range_pairs_.resize(n_ranges);
        range_keys_.resize(n_ranges);
        range_offsets_.resize(n_ranges + 1);
        const auto ranges = static_cast<std::ptrdiff_t>(n_ranges);
#pragma omp parallel num_threads(threads_)
        {
            std::vector<std::uint32_t> near_a;
            std::vector<std::uint32_t> near_b;
            // Ranges of clumps at a wall or deep in a bed differ in work: taken one by one.
#pragma omp for schedule(dynamic, 1)
            for (std::ptrdiff_t r = 0; r < ranges; ++r) {
                const auto ru = static_cast<std::size_t>(r);
                range_pairs_[ru].clear();
                range_keys_[ru].clear();
                const std::size_t end = std::min(n_entries, (ru + 1) * range);
                for (std::size_t e = ru * range; e < end; ++e) {
                    entry_pairs(body_entries_[e], range_pairs_[ru], range_keys_[ru], near_a,
                                near_b);
                }
            }
            // Joined in range order, each range copied to its place in parallel.
#pragma omp single
            {
                range_offsets_[0] = 0;
                for (std::size_t r = 0; r < n_ranges; ++r) {
                    range_offsets_[r + 1] = range_offsets_[r] + range_pairs_[r].size();
                }
                member_pairs_.resize(range_offsets_[n_ranges]);
                member_keys_.resize(range_offsets_[n_ranges]);
            }
#pragma omp for schedule(static)
            for (std::ptrdiff_t r = 0; r < ranges; ++r) {
                const auto ru = static_cast<std::size_t>(r);
                const auto at = static_cast<std::ptrdiff_t>(range_offsets_[ru]);
                std::copy(range_pairs_[ru].begin(), range_pairs_[ru].end(),
                          member_pairs_.begin() + at);
                std::copy(range_keys_[ru].begin(), range_keys_[ru].end(),
                          member_keys_.begin() + at);
            }
        }
    }
    member_pairs_built_ += static_cast<long>(member_pairs_.size());
    ++member_builds_;
    // The travel at which a body of an entry left out must have the member pairs rebuilt.
    box_limits_live_ = false;
    box_limit_.assign(p_.size(), std::numeric_limits<double>::infinity());
    for (std::size_t i = 0; i < box_marks_.size(); ++i) {
        if (box_marks_[i] != 0) {
            box_limit_[i] = travel_[i] + 0.5 * skin;
            box_limits_live_ = true;
        }
    }
    // The poses of this build, for body_forces' rebuild test: every element centre, and per
    // particle its centre, R and farthest element centre.
    member_x_build_.resize(member_c_.size());
    body_x_build_.assign(p_.x.begin(), p_.x.end());
    body_rot_build_.assign(rot_.begin(), rot_.end());
    member_reach_.assign(p_.size(), 0.0);
    const auto n_particles = static_cast<std::ptrdiff_t>(p_.size());
    detail::in_team(parallel ? threads_ : 1, [&] {
#pragma omp for schedule(static)
        for (std::ptrdiff_t ii = 0; ii < n_particles; ++ii) {
            const auto i = static_cast<std::size_t>(ii);
            double far2 = 0.0;
            for (std::uint32_t e = element_begin_[i]; e < element_begin_[i + 1]; ++e) {
                member_x_build_[e] = Vec3(member_c_[e].x, member_c_[e].y, member_c_[e].z);
                far2 = std::max(far2, (member_x_build_[e] - p_.x[i]).squaredNorm());
            }
            member_reach_[i] = std::sqrt(far2);
        }
    });
    // The pairs' histories start empty (written on the threads, as the pairs were found).
    const std::size_t n_pairs = member_pairs_.size();
    member_shear_.resize(n_pairs);
    member_force_.resize(n_pairs);
    member_seen_.resize(n_pairs);
    const auto n_pairs_s = static_cast<std::ptrdiff_t>(n_pairs);
    detail::in_team(parallel ? threads_ : 1, [&] {
#pragma omp for schedule(static)
        for (std::ptrdiff_t k = 0; k < n_pairs_s; ++k) {
            const auto ku = static_cast<std::size_t>(k);
            member_shear_[ku] = Vec3::Zero();
            member_force_[ku] = Vec3::Zero();
            member_seen_[ku] = -1;
        }
    });
    members_valid_ = true;
}

void System::body_forces(ChunkTotals& pair_totals, ChunkTotals& wall_totals) {
    // This evaluation's number; body_eval_ stays that of the last one until the end, so that
    // fold_member_contacts below still finds last step's member-pair records.
    const std::int64_t eval = body_eval_ + 1;
    view_valid_ = false;
    next_contacts_.clear();
    next_groups_.clear();
    // Last step's records are met in the order they were stored: a cursor `at` only moves
    // forward (the serial pass's is `cursor`; a pass ahead of it keeps its own).
    const auto record_from = [&](std::size_t& at, const ContactGroup& g,
                                 std::int32_t eb) -> const BodyContact* {
        while (at < body_groups_.size() && body_groups_[at] < g) {
            ++at;
        }
        for (std::size_t r = at; r < body_groups_.size() && body_groups_[r] == g; ++r) {
            if (body_contacts_[r].key.eb == eb) {
                return &body_contacts_[r].contact;
            }
        }
        return nullptr;
    };
    std::size_t cursor = 0;
    const auto find_old = [&](const ContactGroup& g, std::int32_t eb) {
        return record_from(cursor, g, eb);
    };
    const double dt = spec_.time_step;
    const auto is_convex = [](const Element& e) { return e.kind != Element::Kind::sphere; };
    const bool first_touch = spec_.body_radius == BodyRadius::first_touch;
    // Does a contact keep the R* of its first step (first_touch, and it has one)? Then the
    // contact's R* is read from `old`, and the narrow phase need not compute it.
    const auto keeps_radius = [first_touch](const BodyContact* old) {
        return first_touch && old != nullptr && old->r_eff > 0.0;
    };
    // Elements of every particle, posed once per step: centre and radius of every element in
    // member_c_ (radius 0: not a sphere), the full Element in elements_ only for superquadrics
    // and polyhedra (the slots of sphere elements are not written: element() builds those).
    // The elements are written in place at a running index: member_c_ keeps its size from step
    // to step (it only grows, when particles are added), so it is neither cleared nor filled (a
    // push_back per member was most of a clump scene's posing).
    // The elements' slots first (a clump's members, one for any other particle), then every
    // particle posed into its own slots: the posing of one particle reads and writes nothing of
    // another's, so with enough bodies it runs on several threads, with the same bits.
    element_begin_.resize(p_.size() + 1);
    std::size_t n_elements = 0;
    for (std::size_t i = 0; i < p_.size(); ++i) {
        element_begin_[i] = static_cast<std::uint32_t>(n_elements);
        const int s = p_.shape[i];
        const std::size_t members =
            s >= 0 ? member_columns_[static_cast<std::size_t>(s)].n : std::size_t{0};
        n_elements += members > 0 ? members : 1;
    }
    element_begin_[p_.size()] = static_cast<std::uint32_t>(n_elements);
    member_c_.resize(n_elements);
    if (elements_.size() < n_elements) {
        elements_.resize(n_elements);
    }
    // Per shape: the hull of a polyhedron with its features (posed below in place, as
    // append_elements would pose it), else nullptr (every other shape takes append_elements or,
    // a clump, pose_members). Looked up once per step, not through the template per particle.
    pose_hulls_.assign(spec_.shapes.size(), nullptr);
    for (std::size_t s = 0; s < spec_.shapes.size(); ++s) {
        const auto* hull = std::get_if<geometry::ConvexPolyhedron>(&spec_.shapes[s].shape);
        if (hull != nullptr && s < poly_features_.size() && !poly_features_[s].edges.empty()) {
            pose_hulls_[s] = hull;
        }
    }
    box_body_.resize(p_.size());
    std::size_t n_convex = 0;        // particles of one convex element (polyhedron, superquadric)
    bool unexpected = false;         // a particle that is not a clump posed as several elements
    std::exception_ptr posing_error; // the first exception of the posing, if any
    const auto n_particles = static_cast<std::ptrdiff_t>(p_.size());
    detail::in_team(parallel_body_passes() ? threads_ : 1, [&] {
#pragma omp for schedule(static, 64) reduction(+ : n_convex) reduction(|| : unexpected)
        for (std::ptrdiff_t pi = 0; pi < n_particles; ++pi) {
            const auto i = static_cast<std::size_t>(pi);
            const std::size_t e0 = element_begin_[i];
            MemberSphere* out = member_c_.data() + e0;
            box_body_[i] = 0;
            const int shape = p_.shape[i];
            if (shape < 0) { // a sphere
                *out = {p_.x[i].x(), p_.x[i].y(), p_.x[i].z(), p_.radius[i]};
                continue;
            }
            const auto si = static_cast<std::size_t>(shape);
            if (const geometry::ConvexPolyhedron* hull = pose_hulls_[si]; hull != nullptr) {
                // A polyhedron, as append_elements poses it.
                const geometry::PolyhedronFeatures& f = poly_features_[si];
                Element& E = elements_[e0];
                E = Element{
                    Element::Kind::polyhedron, p_.x[i], p_.radius[i], nullptr, p_.q[i], f.inradius};
                E.poly = &f;
                E.hull = hull;
                E.r_equiv = f.r_equiv;
                *out = {p_.x[i].x(), p_.x[i].y(), p_.x[i].z(), 0.0};
                box_body_[i] =
                    f.box && f.box->aligned && std::isfinite(p_.q[i].squaredNorm()) ? 1 : 0;
                ++n_convex;
                continue;
            }
            const geometry::ShapeTemplate* t = &spec_.shapes[si];
            if (std::holds_alternative<geometry::Clump>(t->shape)) { // as append_elements
                static_assert(sizeof(MemberSphere) == 4 * sizeof(double), "x, y, z, r packed");
                pose_members(p_.x[i], rot_[i],
                             member_columns_[static_cast<std::size_t>(p_.shape[i])],
                             reinterpret_cast<double*>(out));
                continue;
            }
            const geometry::PolyhedronFeatures* features =
                !poly_features_[static_cast<std::size_t>(p_.shape[i])].edges.empty()
                    ? &poly_features_[static_cast<std::size_t>(p_.shape[i])]
                    : nullptr;
            thread_local std::vector<Element> pose_buf; // scratch of posing one particle
            pose_buf.clear();
            try { // an exception may not leave a parallel region: it is thrown after the loop
                append_elements(t, features, p_.x[i], p_.q[i], rot_[i], p_.radius[i], pose_buf);
            } catch (...) {
#pragma omp critical(kiln_posing_error)
                if (!posing_error) {
                    posing_error = std::current_exception();
                }
                continue;
            }
            if (pose_buf.size() != 1) {
                unexpected = true;
                continue;
            }
            const Element& E = pose_buf[0];
            const bool sphere = E.kind == Element::Kind::sphere;
            *out = {E.centre.x(), E.centre.y(), E.centre.z(), sphere ? E.radius : 0.0};
            if (!sphere) {
                elements_[e0] = E;
                ++n_convex;
            }
        }
    });
    if (posing_error) {
        std::rethrow_exception(posing_error);
    }
    if (unexpected) {
        throw std::logic_error("body_forces: a particle that is not a clump has one element");
    }
    // travel_ brought up to this pose (system.hpp), in a loop of its own over the bodies (inside
    // the posing loop above its chain of operations waited on that loop's branches). Only
    // polyhedra and superquadrics read it (the latter in the member build's box test only):
    // travel_r_ is 0 for the other bodies.
    bool box_reached = false; // a body of an entry left out by the box test may reach it
    if (travel_.size() == p_.size()) {
        const bool limits = box_limits_live_ && box_limit_.size() == p_.size();
        for (const std::uint32_t i : bodies_) {
            const Vec3 dx = p_.x[i] - travel_x_[i];
            const double minus = (p_.q[i].coeffs() - travel_q_[i].coeffs()).squaredNorm();
            const double plus = (p_.q[i].coeffs() + travel_q_[i].coeffs()).squaredNorm();
            const double step =
                (dx.norm() + 2.0 * travel_r_[i] * std::sqrt(std::min(minus, plus))) * (1.0 + 1e-9);
            travel_[i] = (travel_[i] + step) * (1.0 + 1e-15); // >= the exact sum
            box_reached |= limits && travel_[i] >= box_limit_[i];
            travel_x_[i] = p_.x[i];
            travel_q_[i] = p_.q[i];
        }
    }
    if (elements_.size() < member_c_.size()) {
        elements_.resize(member_c_.size());
    }
    // Element e of this step (world frame).
    const auto element = [&](std::uint32_t e) -> Element {
        const MemberSphere& c = member_c_[e];
        if (c.r > 0.0) {
            return {
                Element::Kind::sphere, Vec3(c.x, c.y, c.z), c.r, nullptr, Quat::Identity(), c.r};
        }
        return elements_[e];
    };

    std::visit(
        [&](const auto& law) {
            // The one place where an element contact's record of this step is created, in
            // evaluation order (`old` nullptr: the contact is new this step). Returns its slot in
            // the next table. Sphere pairs fill their geometry (normal, point, overlap, R*) in at
            // the flush of their block; every record gets its shear and force there or in apply.
            const auto record = [&](const BodyContactKey& key, const ContactGroup& g,
                                    const BodyContact& rec, const BodyContact* old) {
                static_cast<void>(old); // where a hook on new contacts goes
                next_contacts_.push_back({key, rec});
                next_groups_.push_back(g);
                return static_cast<std::uint32_t>(next_contacts_.size() - 1);
            };
            // One element contact: the law at the contact point with the velocity of that point;
            // force on a, reaction on b (b < 0: a wall, at rest with infinite mass).
            // `old`: the contact's record of the last step, or nullptr (a new one); the record of
            // this step is appended to the next table under group `g`.
            const auto apply = [&](std::uint32_t a, long b, const BodyContactKey& key,
                                   const ContactGroup& g, const ElementContact& ec,
                                   const BodyContact* old, int material_b, double ratio,
                                   ChunkTotals& t) {
                const Vec3 ra = ec.point - p_.x[a];
                Vec3 v_rel = p_.v[a] + p_.omega[a].cross(ra);
                double m_eff = p_.mass[a];
                Vec3 rb = Vec3::Zero();
                if (b >= 0) {
                    const auto j = static_cast<std::uint32_t>(b);
                    rb = ec.point - p_.x[j];
                    v_rel -= p_.v[j] + p_.omega[j].cross(rb);
                    m_eff = p_.mass[a] * p_.mass[j] / (p_.mass[a] + p_.mass[j]);
                }
                // R*: with first_touch, the value of the contact's first step (constant R* makes
                // the Hertz force the gradient of a potential; docs/theory/contact.md). Contacts
                // without a superquadric have a constant R* anyway.
                const double r_eff = keeps_radius(old) ? old->r_eff : ec.r_eff;
                // Lever arms 0: v_rel is already the velocity of the contact point. The angular
                // velocities only feed the rolling resistance (a couple, torque_i and torque_j).
                const Vec3 wb = b >= 0 ? p_.omega[static_cast<std::uint32_t>(b)] : Vec3::Zero();
                if (record_body_onsets_ && old == nullptr) { // heat: impact onset (system.cpp)
                    note_body_onset(key, ec.normal, ec.point, v_rel, m_eff, r_eff);
                }
                contact::ContactInput in{ec.normal, ec.overlap, r_eff,       m_eff, 0.0,
                                         0.0,       v_rel,      p_.omega[a], wb};
                Vec3 shear = old ? old->shear : Vec3::Zero();
                const contact::ContactOutput out = contact::evaluate(
                    law, spec_.contact, pairs_.at(p_.material[a], material_b), in, shear, dt);
                p_.force[a] += out.force;
                p_.torque[a] += ra.cross(out.force) + out.torque_i;
                if (b >= 0) {
                    const auto j = static_cast<std::uint32_t>(b);
                    p_.force[j] -= out.force;
                    p_.torque[j] += out.torque_j - rb.cross(out.force);
                }
                record(key, g,
                       BodyContact{shear, ec.normal, ec.point, ec.overlap, r_eff, out.force}, old);
                t.energy += out.elastic_energy;
                t.max_ratio = std::max(t.max_ratio, ratio);
                ++t.contacts;
            };

            // Two sphere elements (clump members, spheres), or a sphere element and a plane or
            // cylinder wall: queued in blocks of `block` contacts. Sphere pairs queue their raw
            // data (centres, radii, body velocities); the geometry (distance, normal, contact
            // point, lever arms, velocity of the contact point) is derived in vector lanes, then
            // the law runs through the vectorised kernel of the sphere loop (contact_law.hpp), and
            // forces and torques about each body's centre of mass are added in the order the
            // contacts were met. The record's slot in the next table is taken when the contact is
            // met, so the table keeps its order; its geometry is filled in at the flush.
            constexpr std::size_t block = queue_lanes;
            static_assert(block == MemberBlock::lanes, "a member block is one flush of the queue");
            SphereLanes lanes;
            contact::ContactBlock<block>& cb = lanes.cb;
            // q_slot: the record's slot in the next table, or member_slot | the member pair's index
            // (its history goes to member_shear_ and member_force_, no record).
            constexpr std::uint32_t member_slot = 0x80000000U;
            std::uint32_t q_a[block], q_b[block], q_slot[block];
            std::size_t queued = 0;
            bool raw_pairs = true; // the queue holds sphere pairs (raw) or wall contacts (posed)
            ChunkTotals* queue_totals = &pair_totals; // where flush() counts the queued contacts
            const double fn_floor = contact::floor_of(spec_.contact);
            const double rolling = contact::rolling_of(spec_.contact);
            for (std::size_t q = 0; q < block; ++q) {
                cb.lever_i[q] = 0.0; // v is already the velocity of the contact point
                cb.lever_j[q] = 0.0;
            }
            // Contacts of a convex element (polyhedron, superquadric) with another element or a
            // plane or cylinder wall, geometry known from the narrow phase (normal, overlap, point,
            // R*): queued in a block of their own with the velocity of the contact point, the law
            // in vector lanes, forces and torques added in the order met. This block is flushed
            // before every flush of the sphere queue above, so every force is added in the order
            // of the one-contact route (`apply`: a convex contact as soon as met, the pending
            // sphere contacts at their flush). The results equal that route's to round-off only:
            // GCC contracts a * b + c into FMAs per call site (test
            // Polyhedra.ConvexBlocksAgreeWithTheOneContactRoute; docs/performance.md, session 12).
            contact::ContactBlock<block> xb;
            std::uint32_t x_a[block], x_b[block], x_slot[block];
            bool x_new[block];
            double x_ra[3][block], x_rb[3][block], x_ratio[block];
            std::size_t x_queued = 0;
            for (std::size_t q = 0; q < block; ++q) {
                xb.lever_i[q] = 0.0;
                xb.lever_j[q] = 0.0;
            }
            const auto flush_convex = [&] {
#pragma omp simd
                for (std::size_t q = 0; q < x_queued; ++q) {
                    contact::evaluate_block(law, fn_floor, rolling, xb, q, dt);
                }
                // Arrays and totals as locals: through the members every store (Eigen's vector
                // stores may alias anything) made the loop load them again. The totals add up in
                // the same order.
                Vec3* const force = p_.force.data();
                Vec3* const torque = p_.torque.data();
                BodyContactEntry* const entries = next_contacts_.data();
                const bool onsets = record_body_onsets_;
                double energy = queue_totals->energy;
                double max_ratio = queue_totals->max_ratio;
                for (std::size_t q = 0; q < x_queued; ++q) {
                    const std::uint32_t a = x_a[q];
                    const std::uint32_t b = x_b[q];
                    const Vec3 f(xb.f[0][q], xb.f[1][q], xb.f[2][q]);
                    const Vec3 ra(x_ra[0][q], x_ra[1][q], x_ra[2][q]);
                    force[a] += f;
                    torque[a] += ra.cross(f) + Vec3(xb.ti[0][q], xb.ti[1][q], xb.ti[2][q]);
                    if (b != no_element) { // a wall takes no reaction
                        const Vec3 rb(x_rb[0][q], x_rb[1][q], x_rb[2][q]);
                        force[b] -= f;
                        torque[b] += Vec3(xb.tj[0][q], xb.tj[1][q], xb.tj[2][q]) - rb.cross(f);
                    }
                    BodyContactEntry& entry = entries[x_slot[q]];
                    entry.contact.shear = Vec3(xb.s[0][q], xb.s[1][q], xb.s[2][q]);
                    entry.contact.force = f;
                    if (onsets && x_new[q]) { // heat: impact onset (system.cpp)
                        note_body_onset(entry.key, entry.contact.normal, entry.contact.point,
                                        Vec3(xb.v[0][q], xb.v[1][q], xb.v[2][q]), xb.m_eff[q],
                                        entry.contact.r_eff);
                    }
                    energy += xb.energy[q];
                    max_ratio = std::max(max_ratio, x_ratio[q]);
                }
                queue_totals->energy = energy;
                queue_totals->max_ratio = max_ratio;
                queue_totals->contacts += static_cast<long>(x_queued);
                x_queued = 0;
            };
            // Queues the touching contact ec of an element of a with an element of b (b < 0: a
            // plane or cylinder wall, at rest with infinite mass): the inputs of the law by the
            // expressions of `apply` (world frame; lever arms from the centres of mass).
            const auto queue_convex = [&](std::uint32_t a, long b, const BodyContactKey& key,
                                          const ContactGroup& g, const ElementContact& ec,
                                          const BodyContact* old, int material_b, double ratio) {
                const Vec3 ra = ec.point - p_.x[a];
                Vec3 v_rel = p_.v[a] + p_.omega[a].cross(ra);
                double m_eff = p_.mass[a];
                Vec3 rb = Vec3::Zero();
                Vec3 wb = Vec3::Zero();
                if (b >= 0) {
                    const auto j = static_cast<std::uint32_t>(b);
                    rb = ec.point - p_.x[j];
                    v_rel -= p_.v[j] + p_.omega[j].cross(rb);
                    m_eff = p_.mass[a] * p_.mass[j] / (p_.mass[a] + p_.mass[j]);
                    wb = p_.omega[j];
                }
                const double r_eff = keeps_radius(old) ? old->r_eff : ec.r_eff;
                const std::size_t q = x_queued;
                for (int c = 0; c < 3; ++c) {
                    xb.n[c][q] = ec.normal[c];
                    xb.v[c][q] = v_rel[c];
                    xb.wi[c][q] = p_.omega[a][c];
                    xb.wj[c][q] = wb[c];
                    xb.s[c][q] = old != nullptr ? old->shear[c] : 0.0;
                    x_ra[c][q] = ra[c];
                    x_rb[c][q] = rb[c];
                }
                xb.overlap[q] = ec.overlap;
                xb.r_eff[q] = r_eff;
                xb.m_eff[q] = m_eff;
                xb.set_pair(q, pairs_.at(p_.material[a], material_b));
                x_a[q] = a;
                x_b[q] = b >= 0 ? static_cast<std::uint32_t>(b) : no_element;
                x_new[q] = old == nullptr;
                x_ratio[q] = ratio;
                x_slot[q] = record(
                    key, g,
                    BodyContact{Vec3::Zero(), ec.normal, ec.point, ec.overlap, r_eff, Vec3::Zero()},
                    old);
                if (++x_queued == block) {
                    flush_convex();
                }
            };
            // Member pairs whose law ran ahead of the serial pass (members_ahead, below): one
            // MemberBlock per flush of the queue, taken in order by flush().
            bool members_ahead = false;
            std::size_t next_block = 0;
            const auto flush = [&] {
                flush_convex(); // contacts met before the pending sphere contacts go first
                const MemberBlock* pre = nullptr;
                if (raw_pairs && members_ahead && queued > 0) {
                    pre = &member_blocks_[next_block++];
                } else {
                    evaluate_sphere_lanes(law, fn_floor, rolling, dt, lanes, queued, raw_pairs);
                }
                // The law's answers: the lanes', or those found ahead.
                using Rows = const double(*)[block];
                const Rows f_q = pre != nullptr ? pre->f : cb.f;
                const Rows ra_q = pre != nullptr ? pre->ra : lanes.ra;
                const Rows rb_q = pre != nullptr ? pre->rb : lanes.rb;
                const Rows ti_q = pre != nullptr ? pre->ti : cb.ti;
                const Rows tj_q = pre != nullptr ? pre->tj : cb.tj;
                const Rows n_q = pre != nullptr ? pre->n : cb.n;
                const Rows p_q = pre != nullptr ? pre->p : lanes.p;
                const Rows v_q = pre != nullptr ? pre->v : cb.v;
                const double* energy_q = pre != nullptr ? pre->energy : cb.energy;
                const double* ratio_q = pre != nullptr ? pre->ratio : lanes.ratio;
                const double* m_eff_q = pre != nullptr ? pre->m_eff : cb.m_eff;
                const double* r_eff_q = pre != nullptr ? pre->r_eff : cb.r_eff;
                const bool* new_q = pre != nullptr ? pre->is_new : lanes.is_new;
                for (std::size_t q = 0; q < queued; ++q) {
                    const std::uint32_t a = q_a[q];
                    const std::uint32_t b = q_b[q];
                    const Vec3 f(f_q[0][q], f_q[1][q], f_q[2][q]);
                    const Vec3 ra(ra_q[0][q], ra_q[1][q], ra_q[2][q]);
                    p_.force[a] += f;
                    p_.torque[a] += ra.cross(f) + Vec3(ti_q[0][q], ti_q[1][q], ti_q[2][q]);
                    if (b != no_element) { // a wall takes no reaction
                        const Vec3 rb(rb_q[0][q], rb_q[1][q], rb_q[2][q]);
                        p_.force[b] -= f;
                        p_.torque[b] += Vec3(tj_q[0][q], tj_q[1][q], tj_q[2][q]) - rb.cross(f);
                    }
                    if (raw_pairs && (q_slot[q] & member_slot) != 0) { // a member pair
                        const std::uint32_t i = q_slot[q] & ~member_slot;
                        if (pre == nullptr) { // else written ahead
                            member_shear_[i] = Vec3(cb.s[0][q], cb.s[1][q], cb.s[2][q]);
                            member_force_[i] = f;
                        }
                        if (record_body_onsets_ && new_q[q]) { // heat: impact onset
                            note_body_onset(member_keys_[i], Vec3(n_q[0][q], n_q[1][q], n_q[2][q]),
                                            Vec3(p_q[0][q], p_q[1][q], p_q[2][q]),
                                            Vec3(v_q[0][q], v_q[1][q], v_q[2][q]), m_eff_q[q],
                                            r_eff_q[q]);
                        }
                        queue_totals->energy += energy_q[q];
                        queue_totals->max_ratio = std::max(queue_totals->max_ratio, ratio_q[q]);
                        ++queue_totals->contacts;
                        continue;
                    }
                    // The record in one pass: sphere pairs fill in their geometry here too (the
                    // law reads but does not change n, overlap, r_eff, v and m_eff). Only from
                    // the lanes: the member blocks hold member pairs alone.
                    BodyContact& rec = next_contacts_[q_slot[q]].contact;
                    rec.shear = Vec3(cb.s[0][q], cb.s[1][q], cb.s[2][q]);
                    rec.force = f;
                    if (raw_pairs) {
                        rec.normal = Vec3(cb.n[0][q], cb.n[1][q], cb.n[2][q]);
                        rec.point = Vec3(lanes.p[0][q], lanes.p[1][q], lanes.p[2][q]);
                        rec.overlap = cb.overlap[q];
                        rec.r_eff = cb.r_eff[q];
                        if (record_body_onsets_ && lanes.is_new[q]) { // heat: impact onset
                            note_body_onset(next_contacts_[q_slot[q]].key, rec.normal, rec.point,
                                            Vec3(cb.v[0][q], cb.v[1][q], cb.v[2][q]), cb.m_eff[q],
                                            rec.r_eff);
                        }
                    }
                    queue_totals->energy += cb.energy[q];
                    queue_totals->max_ratio = std::max(queue_totals->max_ratio, lanes.ratio[q]);
                    ++queue_totals->contacts;
                }
                queued = 0;
            };
            // Queues the contact of sphere element A of body a with a plane or cylinder wall
            // (ec: element_wall_contact, touching); walls are at rest with infinite mass. Only
            // after the sphere pairs are flushed (raw_pairs false).
            const auto queue_wall = [&](std::uint32_t a, double size, const ElementContact& ec,
                                        int material_w, const BodyContactKey& key,
                                        const ContactGroup& g, const BodyContact* old) {
                const double r_eff = keeps_radius(old) ? old->r_eff : ec.r_eff;
                const Vec3 ra = ec.point - p_.x[a];
                const Vec3 v_rel = p_.v[a] + p_.omega[a].cross(ra);
                const std::size_t q = queued;
                for (int c = 0; c < 3; ++c) {
                    cb.n[c][q] = ec.normal[c];
                    cb.v[c][q] = v_rel[c];
                    cb.wi[c][q] = p_.omega[a][c];
                    cb.wj[c][q] = 0.0;
                    cb.s[c][q] = old != nullptr ? old->shear[c] : 0.0;
                    lanes.ra[c][q] = ra[c];
                }
                cb.overlap[q] = ec.overlap;
                cb.r_eff[q] = r_eff;
                cb.m_eff[q] = p_.mass[a];
                if (record_body_onsets_ && old == nullptr) { // heat: impact onset (system.cpp)
                    note_body_onset(key, ec.normal, ec.point, v_rel, p_.mass[a], r_eff);
                }
                cb.set_pair(q, pairs_.at(p_.material[a], material_w));
                q_a[q] = a;
                q_b[q] = no_element;
                lanes.ratio[q] = ec.overlap / size;
                q_slot[q] = record(
                    key, g,
                    BodyContact{Vec3::Zero(), ec.normal, ec.point, ec.overlap, r_eff, Vec3::Zero()},
                    old);
                if (++queued == block) {
                    flush();
                }
            };
            // Lane q of `L`: the raw data of the pair of sphere elements A (of a) and B (of b).
            // `shear`: the last step's history (nullptr: a new contact); `r0`: R* of the first
            // touch, or 0. Writes only L (the threads that run member pairs ahead fill their own).
            const auto fill_lane = [&](SphereLanes& L, std::size_t q, std::uint32_t a,
                                       std::uint32_t b, const MemberSphere& A,
                                       const MemberSphere& B, const Vec3* shear, double r0) {
                L.ca[0][q] = A.x;
                L.ca[1][q] = A.y;
                L.ca[2][q] = A.z;
                L.cb_[0][q] = B.x;
                L.cb_[1][q] = B.y;
                L.cb_[2][q] = B.z;
                for (int c = 0; c < 3; ++c) {
                    L.xa[c][q] = p_.x[a][c];
                    L.xb[c][q] = p_.x[b][c];
                    L.va[c][q] = p_.v[a][c];
                    L.vb[c][q] = p_.v[b][c];
                    L.cb.wi[c][q] = p_.omega[a][c];
                    L.cb.wj[c][q] = p_.omega[b][c];
                    L.cb.s[c][q] = shear != nullptr ? (*shear)[c] : 0.0;
                }
                L.rada[q] = A.r;
                L.radb[q] = B.r;
                L.ma[q] = p_.mass[a];
                L.mb[q] = p_.mass[b];
                L.r0[q] = r0;
                L.size[q] = 2.0 * std::min(A.r, B.r); // ratio_size of two sphere elements
                L.is_new[q] = shear == nullptr;
                L.cb.set_pair(q, pairs_.at(p_.material[a], p_.material[b]));
            };
            // Queues the contact of sphere elements A (of a) and B (of b), centres closer than the
            // sum of their radii (and distinct), into `slot` (q_slot); shear and r0 as fill_lane.
            const auto queue_spheres = [&](std::uint32_t a, std::uint32_t b, const MemberSphere& A,
                                           const MemberSphere& B, std::uint32_t slot,
                                           const Vec3* shear, double r0) {
                fill_lane(lanes, queued, a, b, A, B, shear, r0);
                q_a[queued] = a;
                q_b[queued] = b;
                q_slot[queued] = slot;
                if (++queued == block) {
                    flush();
                }
            };

            // Pairs: the particle with the smaller id is a, so keys and histories do not depend
            // on the list's owner/partner order. The general route for entry k (a and b already
            // ordered): bounding spheres, the elements of each that reach the other, then every
            // element pair through the narrow phase (sphere pairs through the queue). An entry of
            // two single-element particles, one of them convex, takes single_query below.
            //
            // Does entry (a, b) take single_query: one element on each side, at least one of them
            // not a sphere (polyhedron, superquadric)? Its query reads the poses and last step's
            // records, and writes only the entry's own state (cached direction, proof, near-miss
            // bound, plane memory), so it may run ahead of the serial pass on another thread.
            const auto single_convex = [&](std::uint32_t a, std::uint32_t b) {
                const std::uint32_t a0 = element_begin_[a];
                const std::uint32_t b0 = element_begin_[b];
                return element_begin_[a + 1] - a0 == 1 && element_begin_[b + 1] - b0 == 1 &&
                       (!(member_c_[a0].r > 0.0) || !(member_c_[b0].r > 0.0));
            };
            // The general route's bounding-sphere tests of the element pair (A of particle a, B
            // of particle b), in its order: B within a's bounding sphere, A within b's, the
            // elements' spheres. True: apart.
            const auto spheres_apart = [&](const Element& A, const Element& B, std::uint32_t a,
                                           std::uint32_t b) {
                const double rb = B.radius + p_.radius[a];
                if (!((B.centre - p_.x[a]).squaredNorm() < rb * rb)) {
                    return true;
                }
                const double rab = A.radius + p_.radius[b];
                if ((A.centre - p_.x[b]).squaredNorm() >= rab * rab) {
                    return true;
                }
                const double re = A.radius + B.radius;
                return (A.centre - B.centre).squaredNorm() >= re * re;
            };
            // Warm start of the narrow phase of elements A and B (`old`: their contact's record
            // of the last step, or none): the last normal, else the line of centres, in `warm`.
            // Only pairs with a superquadric read it (a square root and a division saved for
            // every polyhedron query): false, and `warm` is not set, for the others.
            const auto warm_start = [](const Element& A, const Element& B, const BodyContact* old,
                                       Vec3& warm) {
                if (A.kind != Element::Kind::superquadric &&
                    B.kind != Element::Kind::superquadric) {
                    return false;
                }
                warm = Vec3::UnitZ();
                const Vec3 guess = old != nullptr ? old->normal : Vec3(A.centre - B.centre);
                if (guess.squaredNorm() > 0.0) {
                    warm = guess.normalized();
                }
                return true;
            };
            // The query of entry k (single_convex): the general route's bounding-sphere tests,
            // the cached direction's proof, the narrow phase. The counts go to out.counts, a
            // contact for the law to `out` (touching). `lookup(g, eb)`: last step's record
            // (find_old in the serial pass, old_record ahead of it).
            const auto single_query = [&](std::uint32_t k, std::uint32_t a, std::uint32_t b,
                                          const auto& lookup, AheadPair& out) {
                out.counts = {};
                out.touching = false;
                NarrowCounts& n = out.counts;
                const double rsum = p_.radius[a] + p_.radius[b];
                if ((p_.x[a] - p_.x[b]).squaredNorm() >= rsum * rsum) {
                    return;
                }
                const std::uint32_t a0 = element_begin_[a];
                const std::uint32_t b0 = element_begin_[b];
                // Two polyhedra with a cached direction (apart at their last query): the
                // bounding-sphere tests below, in their order, then the cached direction's test
                // as element_contact runs it, without assembling the query (most such entries
                // are near misses proved apart here). The entry keeps the direction that
                // separated the pair last (docs/architecture.md, "Separating directions"); it
                // only saves work, the answer is the same without it.
                if (separation_cache_ && sep_dirs_[k].squaredNorm() > 0.0) {
                    const Element& A = elements_[a0];
                    const Element& B = elements_[b0];
                    if (!(member_c_[a0].r > 0.0) && !(member_c_[b0].r > 0.0) &&
                        A.kind == Element::Kind::polyhedron &&
                        B.kind == Element::Kind::polyhedron) {
                        if (spheres_apart(A, B, a, b)) {
                            return; // no contact, no history
                        }
                        if (lookup(ContactGroup(0, k, 0, 0), 0) == nullptr) {
                            // The proof of an earlier step, moved to this pose: a vertex's height
                            // along the direction m changes by at most the body's rotation
                            // since (|R - R0| <= 2 min |q -+ q0|) times its farthest vertex, so
                            // overlap <= overlap0 + m.(x_b - x_a) - along0 + r_a |dR_a| +
                            // r_b |dR_b|. Below minus the margin the pair is apart (the bound's
                            // round-off is ~1e-14 of the sizes against a margin of 1e-10), as the
                            // vertex scan would prove; above it the scan runs and renews it.
                            const Vec3& m = sep_dirs_[k];
                            SeparationProof& proof = sep_proofs_[k];
                            const double along = m.dot(p_.x[b] - p_.x[a]);
                            const double margin = polyhedra_separation_margin(A, B);
                            // Two boxes take the exact overlap along m (the closed form of a
                            // box's height costs about what the bound does): the larger gap
                            // keeps the pair skipped for longer (apart_below_), and the answer
                            // is the same, the bound being an upper bound of that overlap.
                            const bool boxes = A.poly->box && B.poly->box;
                            if (proof.valid && !boxes) {
                                // (One root of the smaller square: the same number as the
                                // smaller of the two norms, the root being monotone and
                                // correctly rounded.)
                                const auto turn = [](const Quat& q, const Quat& q0) {
                                    const double minus = (q.coeffs() - q0.coeffs()).squaredNorm();
                                    const double plus = (q.coeffs() + q0.coeffs()).squaredNorm();
                                    return 2.0 * std::sqrt(std::min(minus, plus)) * (1.0 + 1e-9);
                                };
                                const double bound = proof.overlap + (along - proof.along) +
                                                     A.poly->radius * turn(A.q, proof.qa) +
                                                     B.poly->radius * turn(B.q, proof.qb);
                                if (bound < -margin) {
                                    ++n.calls; // the counts of element_contact's answer
                                    ++n.skips;
                                    apart_below_[k] =
                                        travel_[a] + travel_[b] - bound - 2.0 * margin;
                                    return;
                                }
                            }
                            double overlap = 0.0;
                            if (polyhedra_apart_along(A, B, m, overlap)) {
                                proof = {true, overlap, along, A.q, B.q};
                                ++n.calls;
                                ++n.skips;
                                apart_below_[k] = travel_[a] + travel_[b] - overlap - 2.0 * margin;
                                return;
                            }
                        }
                    }
                }
                sep_proofs_[k].valid = false; // the full route may change the direction
                apart_below_[k] = -std::numeric_limits<double>::infinity();
                const Element A = element(a0);
                const Element B = element(b0);
                if (spheres_apart(A, B, a, b)) {
                    return; // no contact, no history
                }
                const BodyContactKey key{p_.id[a], p_.id[b], 0, 0};
                const BodyContact* old = lookup(ContactGroup(0, k, 0, 0), key.eb);
                Vec3 warm;
                const bool wants_warm = warm_start(A, B, old, warm);
                Vec3* sep = nullptr;
                if (separation_cache_) {
                    sep = &sep_dirs_[k];
                    if (old != nullptr) { // touching at the last step: no search
                        sep->setZero();
                        sep = nullptr;
                    }
                }
                geometry::PlaneMemo* memo = nullptr;
                if (plane_memo_ && old != nullptr && A.kind == Element::Kind::polyhedron &&
                    B.kind == Element::Kind::polyhedron) {
                    memo = &plane_memos_[k];
                }
                // R* only where it is read: apply and queue_convex keep the first step's with
                // first_touch.
                const bool radius = !keeps_radius(old);
                const ElementContact ec =
                    element_contact(A, B, spec_.narrow_phase, wants_warm ? &warm : nullptr, sep,
                                    old != nullptr, memo, radius);
                ++n.calls;
                n.skips += ec.proved_apart ? 1 : 0;
                n.fallbacks += ec.fell_back ? 1 : 0;
                n.failures += ec.converged ? 0 : 1;
                if (ec.touching) {
                    out.found(a, b, key, ec, old, ec.overlap / ratio_size(A, &B));
                }
            };
            // A contact found by single_query or wall_query to the law, in the serial order
            // (b: the other particle, or -1 for a wall; `t`: the totals apply counts it in).
            // A touching contact of a convex element to the law: the convex block's queue, or
            // `apply` at once without it (arguments as apply's).
            const auto to_law = [&](std::uint32_t a, long b, const BodyContactKey& key,
                                    const ContactGroup& g, const ElementContact& ec,
                                    const BodyContact* old, int material, double ratio,
                                    ChunkTotals& t) {
                if (convex_blocks_) {
                    queue_convex(a, b, key, g, ec, old, material, ratio);
                } else {
                    apply(a, b, key, g, ec, old, material, ratio, t);
                }
            };
            const auto hand_over = [&](const AheadPair& s, long b, const ContactGroup& g,
                                       int material, ChunkTotals& t) {
                to_law(s.a, b, s.key, g, s.ec, s.old, material, s.ratio, t);
            };
            // The counts and the contact of a single_query, taken in the serial order.
            const auto take_single = [&](std::uint32_t k, const AheadPair& s) {
                np_.calls += s.counts.calls;
                separation_skips_ += s.counts.skips;
                np_.fallbacks += s.counts.fallbacks;
                np_.failures += s.counts.failures;
                if (!s.touching) {
                    return;
                }
                hand_over(s, s.b, ContactGroup(0, k, 0, 0), p_.material[s.b], pair_totals);
            };
            // The contact of box pair i (box_pair_contacts, ahead of the serial pass) of entry k,
            // taken in the serial order as take_single takes single_query's: one narrow-phase
            // call, the contact to the law.
            const auto take_box = [&](const MemberPair& m, std::uint32_t i) {
                ++np_.calls;
                const ElementContact& ec = box_found_[i];
                if (!ec.touching) {
                    return;
                }
                const BodyContactKey key{p_.id[m.a], p_.id[m.b], 0, 0};
                const double ratio = ec.overlap / ratio_size(*box_queries_[i].a, box_queries_[i].b);
                to_law(m.a, m.b, key, ContactGroup(0, m.k, 0, 0), ec, box_old_[i], p_.material[m.b],
                       ratio, pair_totals);
            };
            AheadPair one; // the serial pass's single_query
            // The general route of entry k. `lookup(g, eb)`: last step's record (find_old in the
            // serial pass). `plan`: nullptr in the serial route, which runs the narrow phase of
            // each convex element pair (a clump's member against a convex body) itself. Ahead of
            // the serial pass (`planning`) only those narrow phases run, in the loop's order,
            // and their answers are appended to *plan; the serial pass then takes them from
            // *plan (`planning` false) in the same order, with everything else as without.
            const auto general_entry = [&](std::uint32_t k, std::uint32_t a, std::uint32_t b,
                                           const auto& lookup, std::vector<ElementContact>* plan,
                                           bool planning) {
                if (single_convex(a, b)) {
                    single_query(k, a, b, lookup, one);
                    take_single(k, one);
                    return;
                }
                const double rsum = p_.radius[a] + p_.radius[b];
                if ((p_.x[a] - p_.x[b]).squaredNorm() >= rsum * rsum) {
                    return;
                }
                const std::uint32_t a0 = element_begin_[a];
                const std::uint32_t b0 = element_begin_[b];
                sep_proofs_[k].valid = false; // the full route may change the direction
                apart_below_[k] = -std::numeric_limits<double>::infinity();
                std::size_t next = 0; // the next answer of *plan the serial pass takes
                // Elements of b that reach into a's bounding sphere (a clump pair touches with a
                // few of its members: 12 x 12 candidate pairs become about 2 x 2); per thread,
                // as the planning runs on several.
                thread_local std::vector<std::uint32_t> near_b;
                near_b.clear();
                for (std::uint32_t eb = b0; eb < element_begin_[b + 1]; ++eb) {
                    const Element B = element(eb);
                    const double rb = B.radius + p_.radius[a];
                    if ((B.centre - p_.x[a]).squaredNorm() < rb * rb) {
                        near_b.push_back(eb);
                    }
                }
                if (near_b.empty()) {
                    return;
                }
                for (std::uint32_t ea = a0; ea < element_begin_[a + 1]; ++ea) {
                    const Element A = element(ea);
                    const double rab = A.radius + p_.radius[b];
                    if ((A.centre - p_.x[b]).squaredNorm() >= rab * rab) {
                        continue;
                    }
                    const ContactGroup g(0, k, 0, ea - a0);
                    for (const std::uint32_t eb : near_b) {
                        const Element B = element(eb);
                        const double re = A.radius + B.radius;
                        if ((A.centre - B.centre).squaredNorm() >= re * re) {
                            continue; // bounding spheres apart: no contact, no history
                        }
                        const BodyContactKey key{p_.id[a], p_.id[b],
                                                 static_cast<std::int32_t>(ea - a0),
                                                 static_cast<std::int32_t>(eb - b0)};
                        const BodyContact* old = lookup(g, key.eb);
                        const bool convex = is_convex(A) || is_convex(B);
                        if (!convex) {
                            if (planning) {
                                continue;
                            }
                            if (members_ahead) { // would enter a queue block found ahead
                                throw std::logic_error(
                                    "body_forces: two sphere elements in a general entry");
                            }
                            if (A.centre != B.centre) { // coincident centres: no normal
                                // R*: with first_touch, that of the contact's first step (the
                                // same for spheres)
                                queue_spheres(a, b, member_c_[ea], member_c_[eb],
                                              record(key, g, BodyContact{}, old),
                                              old != nullptr ? &old->shear : nullptr,
                                              first_touch && old != nullptr ? old->r_eff : 0.0);
                            }
                            continue;
                        }
                        ElementContact ec;
                        if (plan != nullptr && !planning) {
                            ec = (*plan)[next++]; // found ahead, in this order
                        } else {
                            Vec3 warm;
                            const bool wants_warm = warm_start(A, B, old, warm);
                            // A clump's member against a convex body: no cached direction nor
                            // plane memory (those are per entry, for single elements).
                            // R* only where it is read: apply and queue_convex keep the first
                            // step's with first_touch.
                            const bool radius = !keeps_radius(old);
                            ec = element_contact(A, B, spec_.narrow_phase,
                                                 wants_warm ? &warm : nullptr, nullptr,
                                                 old != nullptr, nullptr, radius);
                            if (planning) {
                                plan->push_back(ec);
                                continue;
                            }
                        }
                        ++np_.calls;
                        separation_skips_ += ec.proved_apart ? 1 : 0;
                        np_.fallbacks += ec.fell_back ? 1 : 0;
                        np_.failures += ec.converged ? 0 : 1;
                        if (ec.touching) {
                            to_law(a, b, key, g, ec, old, p_.material[b],
                                   ec.overlap / ratio_size(A, &B), pair_totals);
                        }
                    }
                }
            };

            // Member pairs in the order of the general route (entry, element of a, element of
            // b): the same contacts, the same evaluation order and so the same bits, without the
            // per-step bounding-sphere search inside each clump pair. A touching pair of sphere
            // elements implies the bounding-sphere tests the general route makes.
            // Rebuilt when an element has moved by more than half the skin since the member
            // build. With more than four elements per particle on average, per particle first a
            // bound of its elements' displacements, |dx| + |R - R0|_2 r (r: its farthest
            // element centre), widened by 1e-9, and only a particle whose bound passes half the
            // skin has its elements' displacements taken: the test reads two poses per particle,
            // not every element (a pass over every element was a tenth of a 36-sphere clump
            // run), and answers as that pass does. With fewer, the pass is the cheaper.
            bool moved = !members_valid_ || member_x_build_.size() != member_c_.size() ||
                         body_x_build_.size() != p_.size() || box_reached;
            const double quarter = 0.25 * nl_.skin() * nl_.skin();
            // The displacements of elements [e0, e1): does one pass half the skin? (Without an
            // early exit: vector lanes.)
            const auto beyond = [&](std::size_t e0, std::size_t e1) {
                const MemberSphere* c = member_c_.data();
                const Vec3* x0 = member_x_build_.data();
                double worst = 0.0;
#pragma omp simd reduction(max : worst)
                for (std::size_t e = e0; e < e1; ++e) {
                    const double d0 = c[e].x - x0[e].x();
                    const double d1 = c[e].y - x0[e].y();
                    const double d2 = c[e].z - x0[e].z();
                    worst = std::max(worst, d0 * d0 + d1 * d1 + d2 * d2);
                }
                return worst > quarter;
            };
            if (!moved && member_c_.size() <= 4 * p_.size()) {
                moved = beyond(0, member_c_.size()); // few elements per particle: all of them
            } else if (!moved) {
                const double half = 0.5 * nl_.skin();
                for (std::size_t i = 0; i < p_.size() && !moved; ++i) {
                    double d = (p_.x[i] - body_x_build_[i]).norm();
                    if (member_reach_[i] > 0.0) {
                        // |R - R0|_2 = |R - R0|_F / sqrt(2) for two rotations (R0^T R - I has
                        // the singular values 2 sin(theta/2) twice and 0); 1e-12 for matrices
                        // orthogonal to round-off only.
                        d += ((rot_[i] - body_rot_build_[i]).norm() * std::sqrt(0.5) + 1e-12) *
                             member_reach_[i];
                    }
                    if (d * (1.0 + 1e-9) > half) {
                        moved = beyond(element_begin_[i], element_begin_[i + 1]);
                    }
                }
            }
            if (moved) {
                // The histories of the old member pairs go into the table (keyed), where this
                // step's member pairs find them; only shear and R* are read from them.
                fold_member_contacts(false);
                build_member_pairs();
            }
            // Last step's histories of member pairs: in the table (after a member or list rebuild,
            // or a restart), else in member_shear_ (member_seen_: the evaluation that last found
            // the pair touching).
            const bool from_table = members_from_table_;
            // First pass, without branches: the indices of the member pairs that touch (centres
            // closer than the sum of the radii, and distinct: coincident centres have no normal)
            // and of the general items whose bodies' bounding spheres may overlap, in list order.
            // About one member pair in four touches, so a branch per pair was mispredicted often.
            // A general item is a hit when the centres are closer than the sum of the bounding
            // radii widened by 1e-9 of it: general_entry's own test (unchanged) decides, this one
            // only drops the entries it would return from at once (most polyhedron entries), so a
            // difference of round-off between the two expressions cannot drop a contact.
            // A general hit whose near-miss bound still holds (apart_below_, a sound bound of
            // the overlap along its cached direction below minus twice the margin, so the proof
            // or the vertex scan in general_entry would answer "apart") is not visited: it is
            // only counted as general_entry counts it (its bounding-sphere test, by the same
            // expression, then a call and a separation skip: the bound is cleared by the full
            // route, so the pair had no contact at the last step).
            const std::size_t n_members = member_pairs_.size();
            member_hits_.resize(n_members);
            std::size_t n_hits = 0;
            std::size_t n_skipped = 0; // skipped near misses that general_entry would count
            // The pass over items [i0, i1): their hits written from member_hits_[i0] on (a hit's
            // index is never below the count before it, so a range writes only within itself),
            // their count to nh, the counted skips to ns.
            const auto first_pass = [&](std::size_t i0, std::size_t i1, std::size_t& nh,
                                        std::size_t& ns) {
                const MemberPair* mp = member_pairs_.data();
                const MemberSphere* c = member_c_.data();
                const Vec3* x = p_.x.data();
                const double* rad = p_.radius.data();
                const double* travel = travel_.data();
                const double* below = apart_below_.data();
                const bool skips = separation_cache_ && !apart_below_.empty();
                std::uint32_t* hits = member_hits_.data() + i0;
                std::size_t n_h = 0;
                std::size_t n_s = 0;
                for (std::size_t i = i0; i < i1; ++i) {
                    const bool general = mp[i].ea == no_element;
                    bool hit = false;
                    if (general) { // the same kind for runs of items: predicted
                        const Vec3& pa = x[mp[i].a];
                        const Vec3& pb = x[mp[i].b];
                        const double rs = (rad[mp[i].a] + rad[mp[i].b]) * (1.0 + 1e-9);
                        const double d0 = pa.x() - pb.x();
                        const double d1 = pa.y() - pb.y();
                        const double d2 = pa.z() - pb.z();
                        hit = d0 * d0 + d1 * d1 + d2 * d2 < rs * rs;
                        if (skips) {
                            const bool skip =
                                hit & (travel[mp[i].a] + travel[mp[i].b] < below[mp[i].k]);
                            // single_query's own test (one for two single polyhedra: each
                            // element's centre and radius are its body's)
                            const double rsum = rad[mp[i].a] + rad[mp[i].b];
                            const bool counted = (pa - pb).squaredNorm() < rsum * rsum;
                            n_s += static_cast<std::size_t>(skip & counted);
                            hit = hit & !skip;
                        }
                    } else {
                        const MemberSphere& A = c[mp[i].ea];
                        const MemberSphere& B = c[mp[i].eb];
                        const double re = A.r + B.r;
                        const double d0 = A.x - B.x;
                        const double d1 = A.y - B.y;
                        const double d2 = A.z - B.z;
                        const double dd = d0 * d0 + d1 * d1 + d2 * d2;
                        hit = (dd < re * re) & (dd != 0.0);
                    }
                    hits[n_h] = static_cast<std::uint32_t>(i);
                    n_h += static_cast<std::size_t>(hit);
                }
                nh = n_h;
                ns = n_s;
            };
            // With several threads and enough bodies, the pass runs over ranges of items in
            // parallel, and each range's hits are moved down after those of the ranges before
            // it: the same list, in the same order (whatever the ranges: a few per thread, of 256
            // to 4096 items).
            const std::size_t pass_range = std::clamp<std::size_t>(
                n_members / (4 * static_cast<std::size_t>(threads_)), 256, 4096);
            if (parallel_body_passes() && n_members > pass_range) {
                const std::size_t n_ranges = (n_members + pass_range - 1) / pass_range;
                range_counts_.resize(2 * n_ranges);
                const auto ranges = static_cast<std::ptrdiff_t>(n_ranges);
#pragma omp parallel for num_threads(threads_) schedule(static)
                for (std::ptrdiff_t r = 0; r < ranges; ++r) {
                    const std::size_t i0 = static_cast<std::size_t>(r) * pass_range;
                    first_pass(i0, std::min(n_members, i0 + pass_range),
                               range_counts_[2 * static_cast<std::size_t>(r)],
                               range_counts_[2 * static_cast<std::size_t>(r) + 1]);
                }
                for (std::size_t r = 0; r < n_ranges; ++r) { // moved down: to <= from
                    const auto from = static_cast<std::ptrdiff_t>(r * pass_range);
                    const auto nh = static_cast<std::ptrdiff_t>(range_counts_[2 * r]);
                    std::copy(member_hits_.begin() + from, member_hits_.begin() + from + nh,
                              member_hits_.begin() + static_cast<std::ptrdiff_t>(n_hits));
                    n_hits += range_counts_[2 * r];
                    n_skipped += range_counts_[2 * r + 1];
                }
            } else {
                first_pass(0, n_members, n_hits, n_skipped);
            }
            np_.calls += static_cast<long>(n_skipped);
            separation_skips_ += static_cast<long>(n_skipped);
            // With several threads, the queries of the single_convex entries and the narrow
            // phases of the other general entries (a clump against a convex body) run first, in
            // parallel, and the serial pass below takes their answers in its order. Each reads
            // the poses and last step's records (found by a search of the sorted table instead
            // of the serial pass's cursor) and writes only its own entry's state, so the answers
            // do not depend on the threads or their order. A query that throws is left to the
            // serial pass, which runs it again in order.
            const auto old_record = [&](const ContactGroup& g,
                                        std::int32_t eb) -> const BodyContact* {
                auto r = std::lower_bound(body_groups_.begin(), body_groups_.end(), g);
                for (; r != body_groups_.end() && *r == g; ++r) {
                    const auto i = static_cast<std::size_t>(r - body_groups_.begin());
                    if (body_contacts_[i].key.eb == eb) {
                        return &body_contacts_[i].contact;
                    }
                }
                return nullptr;
            };
            // With several threads and enough bodies, the law of the member pairs among the hits
            // runs ahead of the serial pass, block by block: the blocks are those the serial
            // pass's queue flushes (only member pairs enter it before the walls: a general entry
            // has a convex element in every element pair), each evaluated by the same code
            // (evaluate_sphere_lanes) from the same inputs, so the answers are the same bits;
            // the serial pass adds the forces in its order. Each block reads the poses and last
            // step's histories (member_shear_, or the table by a search) and writes only its own
            // MemberBlock.
            members_ahead = parallel_body_passes();
            next_block = 0;
            if (members_ahead) {
                member_order_.clear();
                for (std::size_t h = 0; h < n_hits; ++h) {
                    if (member_pairs_[member_hits_[h]].ea != no_element) {
                        member_order_.push_back(member_hits_[h]);
                    }
                }
                const std::size_t n_order = member_order_.size();
                member_blocks_.resize((n_order + block - 1) / block);
                const auto n_blocks = static_cast<std::ptrdiff_t>(member_blocks_.size());
                const bool onsets = record_body_onsets_;
#pragma omp parallel for num_threads(threads_) schedule(static)
                for (std::ptrdiff_t bi = 0; bi < n_blocks; ++bi) {
                    thread_local SphereLanes own; // zero-initialised: lever arms 0
                    const std::size_t m0 = static_cast<std::size_t>(bi) * block;
                    const std::size_t count = std::min(block, n_order - m0);
                    for (std::size_t q = 0; q < count; ++q) {
                        const std::uint32_t i = member_order_[m0 + q];
                        const MemberPair& m = member_pairs_[i];
                        const Vec3* shear = nullptr;
                        double r0 = 0.0;
                        if (from_table) { // as the serial branch below, by a search
                            const BodyContactKey& key = member_keys_[i];
                            const BodyContact* old = old_record(
                                ContactGroup(0, m.k, 0, static_cast<std::uint32_t>(key.ea)),
                                key.eb);
                            shear = old != nullptr ? &old->shear : nullptr;
                            r0 = first_touch && old != nullptr ? old->r_eff : 0.0;
                        } else if (member_seen_[i] == body_eval_) {
                            shear = &member_shear_[i];
                        }
                        fill_lane(own, q, m.a, m.b, member_c_[m.ea], member_c_[m.eb], shear, r0);
                    }
                    evaluate_sphere_lanes(law, fn_floor, rolling, dt, own, count, true);
                    // The pairs' own histories here (each pair is in one block only, and its
                    // old history was read above); the flush adds the forces.
                    for (std::size_t q = 0; q < count; ++q) {
                        const std::uint32_t i = member_order_[m0 + q];
                        member_shear_[i] = Vec3(own.cb.s[0][q], own.cb.s[1][q], own.cb.s[2][q]);
                        member_force_[i] = Vec3(own.cb.f[0][q], own.cb.f[1][q], own.cb.f[2][q]);
                        member_seen_[i] = eval;
                    }
                    MemberBlock& out = member_blocks_[static_cast<std::size_t>(bi)];
                    for (int c = 0; c < 3; ++c) {
                        std::copy_n(own.cb.f[c], count, out.f[c]);
                        std::copy_n(own.ra[c], count, out.ra[c]);
                        std::copy_n(own.rb[c], count, out.rb[c]);
                        std::copy_n(own.cb.ti[c], count, out.ti[c]);
                        std::copy_n(own.cb.tj[c], count, out.tj[c]);
                    }
                    std::copy_n(own.cb.energy, count, out.energy);
                    std::copy_n(own.ratio, count, out.ratio);
                    std::copy_n(own.is_new, count, out.is_new);
                    if (onsets) {
                        for (int c = 0; c < 3; ++c) {
                            std::copy_n(own.cb.n[c], count, out.n[c]);
                            std::copy_n(own.p[c], count, out.p[c]);
                            std::copy_n(own.cb.v[c], count, out.v[c]);
                        }
                        std::copy_n(own.cb.m_eff, count, out.m_eff);
                        std::copy_n(own.cb.r_eff, count, out.r_eff);
                    }
                }
            }
            // (Only when there are convex bodies: a scene of clumps and spheres has no narrow
            // phase to run ahead, and the parallel region would cost more than it saves.)
            const bool ahead = threads_ > 1 && n_convex > 0 && n_hits > 1;
            // Resting pairs of two boxes go ahead of the serial pass too, on any number of
            // threads: their narrow phase eight pairs at a time in vector lanes (use_box_lanes).
            const bool boxes_ahead =
                box_lanes_ && n_convex > 1 && spec_.narrow_phase == NarrowPhase::newton;
            if (ahead) {
                ahead_.resize(n_hits);
                for (AheadPair& s : ahead_) {
                    s.ready = false;
                    s.planned = false;
                }
            }
            // box_slot_[h]: hit h's pair among the box pairs below, or none (its own route).
            constexpr std::uint32_t no_box = 0xffffffffU;
            if (boxes_ahead) {
                box_slot_.assign(n_hits, no_box);
                // The pairs: one polyhedron on each side, both boxes along their body axes,
                // touching at the last step (a record) and without a cached direction, past
                // single_query's tests up to its narrow phase (the others, and a pair that fails
                // one, take single_query in the serial pass). The contacts to single_query's
                // results, in hit order.
                // Last step's records: the hits come in the serial pass's order, so a cursor of
                // the box pass's own walks the table as find_old's does.
                std::size_t seek = 0;
                box_queries_.clear();
                box_old_.clear();
                for (std::size_t h = 0; h < n_hits; ++h) {
                    const MemberPair& m = member_pairs_[member_hits_[h]];
                    // Two single polyhedra, boxes along their body axes, finite orientations
                    // (box_body_, from the posing; single_convex holds for them).
                    if (m.ea != no_element || (box_body_[m.a] & box_body_[m.b]) == 0 ||
                        (separation_cache_ && sep_dirs_[m.k].squaredNorm() > 0.0)) {
                        continue;
                    }
                    // single_query's bounding-sphere tests: for single polyhedra (element centre
                    // and radius those of the body) the three of spheres_apart are this one.
                    const double rsum = p_.radius[m.a] + p_.radius[m.b];
                    if ((p_.x[m.a] - p_.x[m.b]).squaredNorm() >= rsum * rsum) {
                        continue;
                    }
                    const Element& A = elements_[element_begin_[m.a]];
                    const Element& B = elements_[element_begin_[m.b]];
                    // The common plane's own first tests: finite poses, bounding spheres.
                    const double dist = (B.centre - A.centre).norm();
                    if (!std::isfinite(dist) || dist > A.poly->radius + B.poly->radius) {
                        continue;
                    }
                    const BodyContact* old = record_from(seek, ContactGroup(0, m.k, 0, 0), 0);
                    if (old == nullptr) {
                        continue;
                    }
                    // The cached direction and proof as single_query leaves them after its
                    // narrow phase; the contact goes to the law in the serial pass (take_box).
                    sep_proofs_[m.k].valid = false;
                    apart_below_[m.k] = -std::numeric_limits<double>::infinity();
                    box_slot_[h] = static_cast<std::uint32_t>(box_queries_.size());
                    box_queries_.push_back({&A, &B, &rot_[m.a], &rot_[m.b]});
                    box_old_.push_back(old);
                }
                box_found_.resize(box_queries_.size());
                box_lane_pairs_ += static_cast<long>(box_queries_.size());
                // In runs of 64 pairs (whole batches of eight), on the threads where there are
                // several: each pair's answer depends on its own inputs only.
                constexpr std::size_t box_run = 64;
                const auto box_runs =
                    static_cast<std::ptrdiff_t>((box_queries_.size() + box_run - 1) / box_run);
                detail::in_team(ahead ? threads_ : 1, [&] {
#pragma omp for schedule(static)
                    for (std::ptrdiff_t r = 0; r < box_runs; ++r) {
                        const std::size_t p0 = static_cast<std::size_t>(r) * box_run;
                        box_pair_contacts(box_queries_.data() + p0,
                                          std::min(box_run, box_queries_.size() - p0),
                                          box_found_.data() + p0);
                    }
                });
            }
            if (ahead) {
                const auto hits = static_cast<std::ptrdiff_t>(n_hits);
#pragma omp parallel for num_threads(threads_) schedule(dynamic, 16)
                for (std::ptrdiff_t h = 0; h < hits; ++h) {
                    AheadPair& s = ahead_[static_cast<std::size_t>(h)];
                    const MemberPair& m = member_pairs_[member_hits_[static_cast<std::size_t>(h)]];
                    if (m.ea != no_element || (boxes_ahead && box_slot_[h] != no_box)) {
                        continue;
                    }
                    try {
                        if (single_convex(m.a, m.b)) {
                            single_query(m.k, m.a, m.b, old_record, s);
                            s.ready = true;
                        } else {
                            s.plan.clear();
                            general_entry(m.k, m.a, m.b, old_record, &s.plan, true);
                            s.planned = true;
                        }
                    } catch (...) {
                        s.ready = false;
                        s.planned = false;
                    }
                }
            }
            // The memories of the general items a few hits ahead are fetched into the cache
            // (each entry's memory and its block of values lie apart in memory; their loads were
            // the hottest lines of the memory's route): the structs `fetch_ahead` hits ahead, the
            // blocks (their addresses read from the structs fetched) half as far.
            constexpr std::size_t fetch_ahead = 8;
            const auto fetch_memo = [&](std::size_t h, bool values) {
                if (ahead || h >= n_hits) {
                    return; // the queries ran ahead: their memories were read there
                }
                const MemberPair& m = member_pairs_[member_hits_[h]];
                if (m.ea != no_element || m.k >= plane_memos_.size()) {
                    return;
                }
                const geometry::PlaneMemo& pm = plane_memos_[m.k];
                if (!values) {
                    const char* p = reinterpret_cast<const char*>(&pm);
                    for (std::size_t off = 0; off < sizeof(geometry::PlaneMemo); off += 64) {
                        __builtin_prefetch(p + off);
                    }
                    if (m.k < sep_dirs_.size()) {
                        __builtin_prefetch(&sep_dirs_[m.k]);
                        const char* q = reinterpret_cast<const char*>(&sep_proofs_[m.k]);
                        __builtin_prefetch(q);
                        __builtin_prefetch(q + sizeof(SeparationProof) - 1);
                    }
                    return;
                }
                if (pm.valid) {
                    const char* p = reinterpret_cast<const char*>(pm.values.data());
                    const std::size_t bytes = pm.values.size() * sizeof(double);
                    for (std::size_t off = 0; off < bytes; off += 64) {
                        __builtin_prefetch(p + off);
                    }
                }
            };
            for (std::size_t h = 0; h < std::min(fetch_ahead, n_hits); ++h) {
                fetch_memo(h, false);
            }
            for (std::size_t h = 0; h < std::min(fetch_ahead / 2, n_hits); ++h) {
                fetch_memo(h, true);
            }
            for (std::size_t h = 0; h < n_hits; ++h) {
                fetch_memo(h + fetch_ahead, false);
                fetch_memo(h + fetch_ahead / 2, true);
                const MemberPair& m = member_pairs_[member_hits_[h]];
                if (m.ea == no_element) {
                    if (boxes_ahead && box_slot_[h] != no_box) {
                        take_box(m, box_slot_[h]);
                    } else if (ahead && ahead_[h].ready) {
                        take_single(m.k, ahead_[h]);
                    } else if (ahead && ahead_[h].planned) {
                        general_entry(m.k, m.a, m.b, find_old, &ahead_[h].plan, false);
                    } else {
                        general_entry(m.k, m.a, m.b, find_old, nullptr, false);
                    }
                    continue;
                }
                const std::uint32_t i = member_hits_[h];
                if (members_ahead) { // its law ran ahead: flush() takes the answers
                    q_a[queued] = m.a;
                    q_b[queued] = m.b;
                    q_slot[queued] = member_slot | i;
                    if (++queued == block) {
                        flush();
                    }
                    continue;
                }
                const Vec3* shear = nullptr;
                double r0 = 0.0; // a sphere pair's R* is the same at every step
                if (from_table) {
                    const BodyContactKey& key = member_keys_[i];
                    const BodyContact* old = find_old(
                        ContactGroup(0, m.k, 0, static_cast<std::uint32_t>(key.ea)), key.eb);
                    shear = old != nullptr ? &old->shear : nullptr;
                    r0 = first_touch && old != nullptr ? old->r_eff : 0.0;
                } else if (member_seen_[i] == body_eval_) {
                    shear = &member_shear_[i];
                }
                member_seen_[i] = eval;
                queue_spheres(m.a, m.b, member_c_[m.ea], member_c_[m.eb], member_slot | i, shear,
                              r0);
            }

            flush();
            if (members_ahead && next_block != member_blocks_.size()) {
                throw std::logic_error("body_forces: member blocks found ahead left untaken");
            }
            raw_pairs = false;
            queue_totals = &wall_totals;

            // Walls, body by body and wall by wall: only those within the skin at the last list
            // build can be reached (as for spheres, find_wall_candidates).
            //
            // Does body a's bounding sphere reach into wall shape ws?
            const auto within_reach = [&](std::uint32_t a, const WallShape& ws) {
                const WallContact bound = std::visit(
                    [&](const auto& s) { return wall_contact(s, p_.x[a], p_.radius[a]); }, ws);
                return bound.overlap > 0.0;
            };
            // The query of candidate c (body a, wall w) of a body whose one element is convex
            // (polyhedron, superquadric): the bounding-sphere test, the near-miss bound, the
            // narrow phase; a contact for the law goes to `out` (touching). It writes only the
            // candidate's own state (wall_apart_below_), so it may run ahead of the serial pass
            // on another thread, as single_query does.
            const auto wall_query = [&](std::uint32_t c, std::uint32_t a, std::uint32_t w,
                                        const auto& lookup, AheadPair& out) {
                out.touching = false;
                const WallShape& ws = spec_.walls[w].shape;
                if (!within_reach(a, ws)) {
                    return;
                }
                const std::uint32_t ea = element_begin_[a];
                const Element& A = elements_[ea];
                // A single polyhedron whose deepest vertex was above this plane wall by more
                // than the margin: it is still, as long as the body has moved less than that
                // height since (travel_; the wall is at rest).
                if (travel_[a] < wall_apart_below_[c]) {
                    return;
                }
                // A superquadric's R* (a curvature tensor and an eigen-solve) only where it is
                // read: with first_touch, at a contact's first step.
                const bool lazy = first_touch && A.kind == Element::Kind::superquadric;
                ElementContact ec = element_wall_contact(A, ws, !lazy);
                if (!ec.touching) {
                    if (A.kind == Element::Kind::polyhedron) {
                        wall_apart_below_[c] = travel_[a] + ec.wall_gap - 1e-9 * A.radius;
                    }
                    return;
                }
                const BodyContactKey key{p_.id[a], -1 - static_cast<std::int64_t>(w), 0, 0};
                const BodyContact* old = lookup(ContactGroup{1, a, w, 0}, key.eb);
                if (lazy && !keeps_radius(old)) {
                    ec = element_wall_contact(A, ws);
                }
                out.found(a, w, key, ec, old, ec.overlap / ratio_size(A, nullptr));
            };
            // The contact of a wall_query, taken in the serial order.
            const auto take_wall = [&](const AheadPair& s) {
                if (!s.touching) {
                    return;
                }
                hand_over(s, -1, ContactGroup{1, s.a, s.b, 0}, spec_.walls[s.b].material,
                          wall_totals);
            };
            // Does body a take wall_query: one element, not a sphere?
            const auto convex_body = [&](std::uint32_t a) {
                const std::uint32_t a0 = element_begin_[a];
                return element_begin_[a + 1] - a0 == 1 && !(member_c_[a0].r > 0.0);
            };
            // The contacts of a body of sphere elements (a clump) with wall w, into `out` (empty
            // when its bounding sphere does not reach the wall): clump_wall_contacts, `hits` its
            // scratch. Reads the poses only, so it may run ahead of the serial pass.
            const auto clump_wall_query = [&](std::uint32_t a, std::uint32_t w,
                                              std::vector<std::uint32_t>& hits,
                                              std::vector<MemberWallContact>& out) {
                const WallShape& ws = spec_.walls[w].shape;
                if (!within_reach(a, ws)) {
                    out.clear();
                    return;
                }
                const std::uint32_t a0 = element_begin_[a];
                clump_wall_contacts(ws, member_c_.data() + a0, element_begin_[a + 1] - a0, hits,
                                    out, member_lanes_);
            };
            // The contacts of clump_wall_query for body a and wall w, to the law in the serial
            // order.
            const auto take_clump_wall = [&](std::uint32_t a, std::uint32_t w,
                                             const std::vector<MemberWallContact>& hits) {
                const std::uint32_t a0 = element_begin_[a];
                for (const MemberWallContact& h : hits) {
                    const BodyContactKey key{p_.id[a], -1 - static_cast<std::int64_t>(w),
                                             static_cast<std::int32_t>(h.j), 0};
                    const ContactGroup g{1, a, w, h.j};
                    queue_wall(a, 2.0 * member_c_[a0 + h.j].r, h.ec, spec_.walls[w].material, key,
                               g, find_old(g, key.eb));
                }
            };
            // With several threads, the wall queries of convex bodies run ahead, in parallel, and
            // so does the geometry of clumps at walls (clump_wall_contacts; the law stays in the
            // serial pass's queue), with enough bodies (as the other passes of a clump step).
            const std::size_t n_candidates = body_walls_.size();
            const bool walls_ahead =
                threads_ > 1 && (n_convex > 0 || parallel_body_passes()) && n_candidates > 1;
            if (walls_ahead) {
                wall_ahead_.resize(n_candidates);
                clump_wall_ahead_.resize(n_candidates);
                clump_wall_ready_.resize(n_candidates);
                const auto n_bodies = static_cast<std::ptrdiff_t>(bodies_.size());
#pragma omp parallel num_threads(threads_)
                {
                    std::vector<std::uint32_t> hits; // clump_wall_contacts' scratch
#pragma omp for schedule(dynamic, 16)
                    for (std::ptrdiff_t bi = 0; bi < n_bodies; ++bi) {
                        const auto i = static_cast<std::size_t>(bi);
                        const std::uint32_t a = bodies_[i];
                        const bool convex = convex_body(a);
                        for (std::uint32_t c = body_wall_offsets_[i]; c < body_wall_offsets_[i + 1];
                             ++c) {
                            AheadPair& s = wall_ahead_[c];
                            s.ready = false;
                            clump_wall_ready_[c] = 0;
                            const std::uint32_t w = body_walls_[c];
                            try {
                                if (convex) {
                                    wall_query(c, a, w, old_record, s);
                                    s.ready = true;
                                    continue;
                                }
                                clump_wall_query(a, w, hits, clump_wall_ahead_[c]);
                                clump_wall_ready_[c] = 1;
                            } catch (...) { // left to the serial pass, which runs it again
                                s.ready = false;
                                clump_wall_ready_[c] = 0;
                            }
                        }
                    }
                }
            }
            AheadPair one_wall; // the serial pass's wall_query
            for (std::size_t bi = 0; bi < bodies_.size(); ++bi) {
                const std::uint32_t a = bodies_[bi];
                const bool convex = convex_body(a);
                for (std::uint32_t c = body_wall_offsets_[bi]; c < body_wall_offsets_[bi + 1];
                     ++c) {
                    const std::uint32_t w = body_walls_[c];
                    if (walls_ahead && wall_ahead_[c].ready) {
                        take_wall(wall_ahead_[c]);
                        continue;
                    }
                    if (convex) {
                        wall_query(c, a, w, find_old, one_wall);
                        take_wall(one_wall);
                        continue;
                    }
                    if (walls_ahead && clump_wall_ready_[c] != 0) {
                        take_clump_wall(a, w, clump_wall_ahead_[c]);
                        continue;
                    }
                    clump_wall_query(a, w, wall_hits_, one_clump_wall_);
                    take_clump_wall(a, w, one_clump_wall_);
                }
            }
            flush();

            // Mesh walls, wall by wall and particle by particle (spheres too: a sphere may touch
            // several features, each with its own history keyed by feature kind and id).
            const auto n_walls = static_cast<std::int64_t>(spec_.walls.size());
            for (std::size_t m = 0; m < spec_.mesh_walls.size(); ++m) {
                const MeshWallSpec& mw = spec_.mesh_walls[m];
                for (std::uint32_t a = 0; a < p_.size(); ++a) {
                    const std::uint32_t a0 = element_begin_[a];
                    for (std::uint32_t ea = a0; ea < element_begin_[a + 1]; ++ea) {
                        const Element A = element(ea);
                        if (A.kind == Element::Kind::polyhedron) {
                            mw.mesh->polyhedron_contacts({A.poly, A.centre, A.q}, mesh_buf_);
                        } else if (A.kind == Element::Kind::sphere) {
                            mw.mesh->sphere_contacts(A.centre, A.radius, mesh_buf_);
                        } else {
                            ++np_.calls;
                            np_.failures += mw.mesh->superquadric_contacts({A.sq, A.centre, A.q},
                                                                           A.radius, mesh_buf_);
                        }
                        for (const geometry::MeshContact& mc : mesh_buf_) {
                            ElementContact ec;
                            ec.touching = true;
                            ec.overlap = mc.depth;
                            ec.normal = mc.normal;
                            ec.point = mc.point;
                            const BodyContactKey key{
                                p_.id[a], -1 - n_walls - static_cast<std::int64_t>(m),
                                static_cast<std::int32_t>(ea - a0),
                                (static_cast<std::int32_t>(mc.feature) << 28) | mc.id};
                            const ContactGroup g{2, static_cast<std::uint32_t>(m), a, ea - a0};
                            const BodyContact* old = find_old(g, key.eb);
                            // Flat wall: sphere radius, the polyhedron's equivalent sphere, or
                            // the superquadric's R* at its deepest point (with first_touch only
                            // at the contact's first step, the one read).
                            if (!keeps_radius(old)) {
                                ec.r_eff = flat_wall_radius(A, mc.normal);
                            }
                            apply(a, -1, key, g, ec, old, mw.material,
                                  ec.overlap / ratio_size(A, nullptr), wall_totals);
                        }
                    }
                }
            }
        },
        spec_.contact.law);
    // The table now holds the contacts other than member pairs; those are in member_shear_.
    members_from_table_ = false;
    body_eval_ = eval;
    body_contacts_.swap(next_contacts_);
    body_groups_.swap(next_groups_);
}

} // namespace kiln::dynamics
