#include "fluid/footprints.hpp"

#include "core/error.hpp"
#include "geometry/rotation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <variant>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace kiln::fluid {
namespace {

// Linear interpolation along one axis between two cell centres: weight w0 on cell c0 and w1 on
// c1. Beyond the first and last centre the boundary cell's value is taken (c0 = c1, w1 = 0).
struct AxisWeights {
    int c0;
    int c1;
    double w0;
    double w1;
};

// u: position in cell-centre units (cell c has its centre at u = c); n cells on the axis.
AxisWeights axis_weights(double u, int n) {
    if (!(u > 0.0)) {
        return {0, 0, 1.0, 0.0};
    }
    if (u >= n - 1) {
        return {n - 1, n - 1, 1.0, 0.0};
    }
    const double f = std::floor(u);
    const double t = u - f;
    const int c = static_cast<int>(f);
    return {c, c + 1, 1.0 - t, t};
}

// Sub-cell a of an axis in cell-centre units: (a + 1/2) / s - 1/2.
double sub_u(long a, int s) {
    return (static_cast<double>(a) + 0.5) / s - 0.5;
}

// The sub-cell ranges [lo, hi] scanned for a world box, clipped to the domain.
struct SubRange {
    std::array<long, 3> lo{};
    std::array<long, 3> hi{};
    bool clipped = false;
    bool empty = false;
};

SubRange sub_range(const TransferGrid& g, const Aabb& box) {
    SubRange r;
    const double h = g.sub_cell_size();
    for (int d = 0; d < 3; ++d) {
        const double top = static_cast<double>(g.cells()[d]) * g.refinement() - 1.0;
        // Sub-cells whose centres lie in [box.lo, box.hi].
        const double lo = std::ceil((box.lo[d] - g.origin()[d]) / h - 0.5);
        const double hi = std::floor((box.hi[d] - g.origin()[d]) / h - 0.5);
        r.clipped = r.clipped || box.lo[d] < g.origin()[d] ||
                    box.hi[d] > g.origin()[d] + g.cell_size() * g.cells()[d];
        r.lo[d] = static_cast<long>(std::clamp(lo, 0.0, top + 1.0));
        r.hi[d] = static_cast<long>(std::clamp(hi, -1.0, top));
        r.empty = r.empty || r.lo[d] > r.hi[d];
    }
    return r;
}

// Accumulates one particle's sub-cells, run by run along x, on a local box of fluid cells (its
// cells and one more on each side, for the interpolation stencil).
class Scan {
  public:
    Scan(const TransferGrid& g, const SubRange& r, detail::ChunkBuffer& buf) : g_(g), buf_(buf) {
        const int s = g.refinement();
        for (int d = 0; d < 3; ++d) {
            lo_[d] = std::max(0, static_cast<int>(r.lo[d] / s) - 1);
            const int hi = std::min(g.cells()[d] - 1, static_cast<int>(r.hi[d] / s) + 1);
            dim_[d] = hi - lo_[d] + 1;
        }
        const auto n = static_cast<std::size_t>(dim_[0]) * dim_[1] * dim_[2];
        if (buf_.count.size() < n) {
            buf_.count.assign(n, 0);
            buf_.stencil.assign(n, 0.0);
        }
        if (buf_.row.size() < static_cast<std::size_t>(dim_[0])) {
            buf_.row.assign(dim_[0], 0.0);
        }
    }

    // Sub-cells a0..a1 (x) of the row (b, c).
    void add_run(long a0, long a1, long b, long c);
    // x weights of sub-cells p..q of fluid cell cx, all below (lower) or all from its centre up.
    void add_row_weights(int cx, long p, long q, bool lower);
    // Writes the deposit and stencil entries (and clears the local box); returns the sub-cells.
    std::int64_t emit(double sub_volume);
    // Mean sub-cell centre (m, world frame); total() > 0.
    [[nodiscard]] Vec3 centroid() const {
        const double h = g_.sub_cell_size();
        return g_.origin() + h * (sum_ / static_cast<double>(total_) + Vec3::Constant(0.5));
    }
    [[nodiscard]] std::int64_t total() const { return total_; }

  private:
    [[nodiscard]] std::size_t local(int i, int j, int k) const {
        return static_cast<std::size_t>(i - lo_[0]) +
               static_cast<std::size_t>(dim_[0]) *
                   ((j - lo_[1]) + static_cast<std::size_t>(dim_[1]) * (k - lo_[2]));
    }

    const TransferGrid& g_;
    detail::ChunkBuffer& buf_;
    std::array<int, 3> lo_{};
    std::array<int, 3> dim_{};
    std::int64_t total_ = 0;
    Vec3 sum_ = Vec3::Zero(); // sum of sub-cell indices, per axis
};

// Adds the x weights of sub-cells r = p..q (within fluid cell cx) to the row: each splits between
// the two cell centres around it, u = (r + 1/2) / s - 1/2 in cell units from the centre of cx.
// Below the centre (2 r + 1 < s) the pair is (cx - 1, cx), from it up (cx, cx + 1); a neighbour
// beyond the grid passes its share to cx.
void Scan::add_row_weights(int cx, long p, long q, bool lower) {
    const int s = g_.refinement();
    const auto m = static_cast<double>(q - p + 1);
    const double su = m * (static_cast<double>(p + q + 1) / (2.0 * s) - 0.5); // sum of u
    const int other = lower ? cx - 1 : cx + 1;
    const double w_other = lower ? -su : su;
    const bool outside = other < 0 || other >= g_.cells()[0];
    buf_.row[cx - lo_[0]] += outside ? m : m - w_other;
    if (!outside) {
        buf_.row[other - lo_[0]] += w_other;
    }
}

void Scan::add_run(long a0, long a1, long b, long c) {
    const int s = g_.refinement();
    const auto n = a1 - a0 + 1;
    total_ += n;
    sum_ += static_cast<double>(n) * Vec3(0.5 * static_cast<double>(a0 + a1),
                                          static_cast<double>(b), static_cast<double>(c));
    const auto cy = static_cast<int>(b / s);
    const auto cz = static_cast<int>(c / s);
    const long half = s / 2; // sub-cells r < half lie below their cell's centre
    for (auto cx = static_cast<int>(a0 / s); cx <= static_cast<int>(a1 / s); ++cx) {
        const long base = static_cast<long>(cx) * s;
        const long first = std::max(a0, base) - base;
        const long last = std::min(a1, base + s - 1) - base;
        buf_.count[local(cx, cy, cz)] += last - first + 1;
        if (first < half) {
            add_row_weights(cx, first, std::min(last, half - 1), true);
        }
        if (last >= half) {
            add_row_weights(cx, std::max(first, half), last, false);
        }
    }
    // Interpolation stencil: the row's x weights spread over the 2 x 2 (y, z) neighbours.
    const int xmin = std::max(lo_[0], static_cast<int>(a0 / s) - 1);
    const int xmax = std::min(g_.cells()[0] - 1, static_cast<int>(a1 / s) + 1);
    const AxisWeights wy = axis_weights(sub_u(b, s), g_.cells()[1]);
    const AxisWeights wz = axis_weights(sub_u(c, s), g_.cells()[2]);
    const std::array<std::pair<int, double>, 2> ys{{{wy.c0, wy.w0}, {wy.c1, wy.w1}}};
    const std::array<std::pair<int, double>, 2> zs{{{wz.c0, wz.w0}, {wz.c1, wz.w1}}};
    const double* row = &buf_.row[xmin - lo_[0]];
    for (const auto& [k, wk] : zs) {
        for (const auto& [j, wj] : ys) {
            if (wj * wk == 0.0) {
                continue;
            }
            double* out = &buf_.stencil[local(xmin, j, k)];
            for (int i = 0; i <= xmax - xmin; ++i) {
                out[i] += wj * wk * row[i];
            }
        }
    }
    std::fill(buf_.row.begin() + (xmin - lo_[0]), buf_.row.begin() + (xmax - lo_[0] + 1), 0.0);
}

std::int64_t Scan::emit(double sub_volume) {
    const double inv = total_ > 0 ? 1.0 / static_cast<double>(total_) : 0.0;
    for (int k = lo_[2]; k < lo_[2] + dim_[2]; ++k) {
        for (int j = lo_[1]; j < lo_[1] + dim_[1]; ++j) {
            for (int i = lo_[0]; i < lo_[0] + dim_[0]; ++i) {
                const std::size_t l = local(i, j, k);
                const std::int32_t cell = g_.cell_index(i, j, k);
                if (buf_.count[l] > 0) {
                    const auto m = static_cast<double>(buf_.count[l]);
                    buf_.cell.push_back(cell);
                    buf_.volume.push_back(m * sub_volume);
                    buf_.weight.push_back(m * inv);
                    buf_.count[l] = 0;
                }
                if (buf_.stencil[l] != 0.0) {
                    buf_.stencil_cell.push_back(cell);
                    buf_.stencil_weight.push_back(buf_.stencil[l] * inv);
                    buf_.stencil[l] = 0.0;
                }
            }
        }
    }
    return total_;
}

// Runs of one sphere's sub-cells: per row the chord [x - w, x + w], w^2 = R^2 - dy^2 - dz^2.
void scan_sphere(const TransferGrid& g, const SphereBody& s, const Vec3& x, const SubRange& r,
                 Scan& scan) {
    const double h = g.sub_cell_size();
    const Vec3& o = g.origin();
    const double r2 = s.radius * s.radius;
    for (long c = r.lo[2]; c <= r.hi[2]; ++c) {
        const double dz = o.z() + (static_cast<double>(c) + 0.5) * h - x.z();
        for (long b = r.lo[1]; b <= r.hi[1]; ++b) {
            const double dy = o.y() + (static_cast<double>(b) + 0.5) * h - x.y();
            const double w2 = r2 - dy * dy - dz * dz;
            if (w2 < 0.0) {
                continue;
            }
            const RowRun run = chord_run(x.x(), std::sqrt(w2), o.x(), h, r.lo[0], r.hi[0]);
            if (run.first <= run.last) {
                scan.add_run(run.first, run.last, b, c);
            }
        }
    }
}

// Runs of a clump: per row the union of its members' chords, each by the sphere's rule
// (ClumpBody::rows), from the members' world centres; O(members) per row.
void scan_clump(const TransferGrid& g, const ClumpBody& body, const Vec3& x, const Mat3& rot,
                const SubRange& r, Scan& scan, detail::ChunkBuffer& buf) {
    const double h = g.sub_cell_size();
    const Vec3& o = g.origin();
    buf.centres.resize(body.spheres.size());
    for (std::size_t m = 0; m < body.spheres.size(); ++m) {
        buf.centres[m] = x + rot * body.spheres[m].centre;
    }
    for (long c = r.lo[2]; c <= r.hi[2]; ++c) {
        const double z = o.z() + (static_cast<double>(c) + 0.5) * h;
        for (long b = r.lo[1]; b <= r.hi[1]; ++b) {
            const double y = o.y() + (static_cast<double>(b) + 0.5) * h;
            body.rows(buf.centres, o.x(), h, y, z, r.lo[0], r.hi[0], buf.runs);
            for (const RowRun& rr : buf.runs) {
                scan.add_run(rr.first, rr.last, b, c);
            }
        }
    }
}

// The runs of the sub-cells a0..a1 of row (b, c) that `body` contains, testing each sub-cell's
// centre p0 + (a - a0) step (body frame).
template <class Body>
void scan_points(const Body& body, const Vec3& p0, const Vec3& step, long a0, long a1, long b,
                 long c, Scan& scan) {
    long run = -1;
    for (long a = a0; a <= a1; ++a) {
        const bool in = body.contains(p0 + static_cast<double>(a - a0) * step);
        if (in && run < 0) {
            run = a;
        } else if (!in && run >= 0) {
            scan.add_run(run, a - 1, b, c);
            run = -1;
        }
    }
    if (run >= 0) {
        scan.add_run(run, a1, b, c);
    }
}

// Runs of a convex polyhedron: each row of the world box that crosses its bounding sphere (radius
// rb) clipped by the posed face planes (clip_row, O(faces) per row); a row running along a face
// is tested sub-cell by sub-cell.
void scan_planes(const TransferGrid& g, const PlanesBody& body, double rb, const Vec3& x,
                 const Mat3& rot, const SubRange& r, Scan& scan, PosedPlanes& posed) {
    const double h = g.sub_cell_size();
    const Vec3& o = g.origin();
    pose_planes(body, rot, x, h, posed);
    const double sx = o.x() + (static_cast<double>(r.lo[0]) + 0.5) * h;
    for (long c = r.lo[2]; c <= r.hi[2]; ++c) {
        const double z = o.z() + (static_cast<double>(c) + 0.5) * h;
        for (long b = r.lo[1]; b <= r.hi[1]; ++b) {
            const double y = o.y() + (static_cast<double>(b) + 0.5) * h;
            if ((y - x.y()) * (y - x.y()) + (z - x.z()) * (z - x.z()) > rb * rb) {
                continue;
            }
            const Vec3 start(sx, y, z);
            const RowRun rr = clip_row(body, posed, start, r.hi[0] - r.lo[0]);
            if (!rr.decided) {
                const Vec3 p0 = posed.to_body * (start - x);
                scan_points(body, p0, posed.step, r.lo[0], r.hi[0], b, c, scan);
            } else if (rr.first <= rr.last) {
                scan.add_run(r.lo[0] + rr.first, r.lo[0] + rr.last, b, c);
            }
        }
    }
}

// Runs of a superquadric: every sub-cell of the row's chord of the bounding sphere (radius rb)
// tested in the body frame.
void scan_superquadric(const TransferGrid& g, const SuperquadricBody& body, double rb,
                       const Vec3& x, const Mat3& rot, const SubRange& r, Scan& scan) {
    const double h = g.sub_cell_size();
    const Vec3& o = g.origin();
    const Mat3 rt = rot.transpose();
    const Vec3 step = h * rt.col(0); // one sub-cell along world x, in the body frame
    for (long c = r.lo[2]; c <= r.hi[2]; ++c) {
        const double dz = o.z() + (static_cast<double>(c) + 0.5) * h - x.z();
        for (long b = r.lo[1]; b <= r.hi[1]; ++b) {
            const double dy = o.y() + (static_cast<double>(b) + 0.5) * h - x.y();
            const double w2 = rb * rb - dy * dy - dz * dz;
            if (w2 < 0.0) {
                continue;
            }
            const RowRun chord = chord_run(x.x(), std::sqrt(w2), o.x(), h, r.lo[0], r.hi[0]);
            const Vec3 start =
                Vec3(o.x() + (static_cast<double>(chord.first) + 0.5) * h, dy + x.y(), dz + x.z());
            const Vec3 p0 = rt * (start - x);
            scan_points(body, p0, step, chord.first, chord.last, b, c, scan);
        }
    }
}

// Stencil of a single point (m, world): trilinear weights of the cell centres around it.
void point_stencil(const TransferGrid& g, const Vec3& x, detail::ChunkBuffer& buf) {
    std::array<AxisWeights, 3> w{};
    for (int d = 0; d < 3; ++d) {
        w[d] = axis_weights((x[d] - g.origin()[d]) / g.cell_size() - 0.5, g.cells()[d]);
    }
    for (int k = 0; k < 2; ++k) {
        for (int j = 0; j < 2; ++j) {
            for (int i = 0; i < 2; ++i) {
                const double wt =
                    (i ? w[0].w1 : w[0].w0) * (j ? w[1].w1 : w[1].w0) * (k ? w[2].w1 : w[2].w0);
                if (wt != 0.0) {
                    buf.stencil_cell.push_back(g.cell_index(
                        i ? w[0].c1 : w[0].c0, j ? w[1].c1 : w[1].c0, k ? w[2].c1 : w[2].c0));
                    buf.stencil_weight.push_back(wt);
                }
            }
        }
    }
}

// One particle: its entries appended to buf, its per-particle results returned.
struct ParticleResult {
    Vec3 centroid;
    std::int64_t sub_cells;
    Placement placement;
};

ParticleResult deposit_one(const TransferGrid& g, const DepositTemplate& t, const Vec3& x,
                           const Quat& q, detail::ChunkBuffer& buf) {
    KILN_ASSERT(x.allFinite() && q.coeffs().allFinite());
    const Mat3 rot = geometry::rotation_matrix(q);
    const SubRange range = sub_range(g, world_box(t.body, x, rot));
    std::int64_t n = 0;
    Vec3 centroid = x;
    if (!range.empty) {
        Scan scan(g, range, buf);
        if (const auto* s = std::get_if<SphereBody>(&t.body)) {
            scan_sphere(g, *s, x, range, scan);
        } else if (const auto* cl = std::get_if<ClumpBody>(&t.body)) {
            scan_clump(g, *cl, x, rot, range, scan, buf);
        } else if (const auto* pl = std::get_if<PlanesBody>(&t.body)) {
            scan_planes(g, *pl, t.bounding_radius, x, rot, range, scan, buf.posed);
        } else {
            scan_superquadric(g, std::get<SuperquadricBody>(t.body), t.bounding_radius, x, rot,
                              range, scan);
        }
        if (scan.total() > 0) {
            centroid = scan.centroid();
        }
        n = scan.emit(g.sub_cell_volume());
    }
    if (n > 0) {
        return {centroid, n, range.clipped ? Placement::clipped : Placement::inside};
    }
    // No sub-cell centre inside: the true volume in the cell holding the centre, if any.
    point_stencil(g, x, buf);
    if (!g.bounds().contains(x)) {
        return {x, 0, Placement::outside};
    }
    std::array<int, 3> c{};
    for (int d = 0; d < 3; ++d) {
        const double u = std::floor((x[d] - g.origin()[d]) / g.cell_size());
        c[d] = std::clamp(static_cast<int>(u), 0, g.cells()[d] - 1);
    }
    buf.cell.push_back(g.cell_index(c[0], c[1], c[2]));
    buf.volume.push_back(t.volume);
    buf.weight.push_back(1.0);
    return {x, 0, Placement::too_small};
}

void clear(detail::ChunkBuffer& b) {
    b.begin.clear();
    b.cell.clear();
    b.volume.clear();
    b.weight.clear();
    b.stencil_begin.clear();
    b.stencil_cell.clear();
    b.stencil_weight.clear();
}

// Copies the chunks' entries into the flat arrays, chunk after chunk.
void join_chunks(std::size_t n_particles, Footprints& out) {
    std::size_t entries = 0;
    std::size_t stencils = 0;
    for (const auto& b : out.work) {
        entries += b.cell.size();
        stencils += b.stencil_cell.size();
    }
    out.begin.resize(n_particles + 1);
    out.stencil_begin.resize(n_particles + 1);
    out.cell.resize(entries);
    out.volume.resize(entries);
    out.weight.resize(entries);
    out.stencil_cell.resize(stencils);
    out.stencil_weight.resize(stencils);
    std::size_t e = 0;
    std::size_t st = 0;
    std::size_t p = 0;
    for (const auto& b : out.work) {
        for (std::size_t k = 0; k < b.begin.size(); ++k, ++p) {
            out.begin[p] = e + b.begin[k];
            out.stencil_begin[p] = st + b.stencil_begin[k];
        }
        std::copy(b.cell.begin(), b.cell.end(), out.cell.begin() + static_cast<long>(e));
        std::copy(b.volume.begin(), b.volume.end(), out.volume.begin() + static_cast<long>(e));
        std::copy(b.weight.begin(), b.weight.end(), out.weight.begin() + static_cast<long>(e));
        std::copy(b.stencil_cell.begin(), b.stencil_cell.end(),
                  out.stencil_cell.begin() + static_cast<long>(st));
        std::copy(b.stencil_weight.begin(), b.stencil_weight.end(),
                  out.stencil_weight.begin() + static_cast<long>(st));
        e += b.cell.size();
        st += b.stencil_cell.size();
    }
    out.begin[n_particles] = e;
    out.stencil_begin[n_particles] = st;
}

// Deposit entries grouped by cell (counting sort: stable, so in particle order within a cell).
void index_by_cell(Footprints& out) {
    out.cell_begin.assign(out.cells + 1, 0);
    for (const std::int32_t c : out.cell) {
        ++out.cell_begin[static_cast<std::size_t>(c) + 1];
    }
    for (std::size_t c = 0; c < out.cells; ++c) {
        out.cell_begin[c + 1] += out.cell_begin[c];
    }
    out.cell_entry.resize(out.cell.size());
    out.cell_particle.resize(out.cell.size());
    std::vector<std::size_t> next(out.cell_begin.begin(), out.cell_begin.end() - 1);
    const std::size_t n = out.begin.size() - 1;
    for (std::size_t p = 0; p < n; ++p) {
        for (std::size_t e = out.begin[p]; e < out.begin[p + 1]; ++e) {
            const std::size_t slot = next[static_cast<std::size_t>(out.cell[e])]++;
            out.cell_entry[slot] = e;
            out.cell_particle[slot] = p;
        }
    }
}

} // namespace

void compute_footprints(const TransferGrid& grid, std::span<const DepositTemplate> templates,
                        const ParticlePoses& poses, Footprints& out, int threads) {
    const std::size_t n = poses.position.size();
    KILN_ASSERT(poses.shape.size() == n && poses.orientation.size() == n);
    out.cells = grid.cell_count();
    out.centroid.resize(n);
    out.sub_cells.resize(n);
    out.placement.resize(n);
    const std::size_t chunks = (n + kFootprintChunk - 1) / kFootprintChunk;
    out.work.resize(chunks);
    const auto n_chunks = static_cast<long>(chunks);
    (void)threads;
#pragma omp parallel for num_threads(std::max(threads, 1)) schedule(dynamic, 1)
    for (long ch = 0; ch < n_chunks; ++ch) {
        detail::ChunkBuffer& buf = out.work[static_cast<std::size_t>(ch)];
        clear(buf);
        const std::size_t first = static_cast<std::size_t>(ch) * kFootprintChunk;
        const std::size_t last = std::min(n, first + kFootprintChunk);
        for (std::size_t p = first; p < last; ++p) {
            buf.begin.push_back(buf.cell.size());
            buf.stencil_begin.push_back(buf.stencil_cell.size());
            const auto s = static_cast<std::size_t>(poses.shape[p]);
            KILN_ASSERT(s < templates.size());
            const ParticleResult r =
                deposit_one(grid, templates[s], poses.position[p], poses.orientation[p], buf);
            out.centroid[p] = r.centroid;
            out.sub_cells[p] = r.sub_cells;
            out.placement[p] = r.placement;
        }
    }
    join_chunks(n, out);
    index_by_cell(out);
    out.clipped = static_cast<std::size_t>(
        std::count(out.placement.begin(), out.placement.end(), Placement::clipped));
    out.too_small = static_cast<std::size_t>(
        std::count(out.placement.begin(), out.placement.end(), Placement::too_small));
    out.outside = static_cast<std::size_t>(
        std::count(out.placement.begin(), out.placement.end(), Placement::outside));
}

} // namespace kiln::fluid
