// Validation 21: non-spherical bodies with uniform convection on the Cartesian cut-cell grid.
// Cube: exact solution = product of three slab series (Carslaw & Jaeger 1959 §3.11 and the
// product rule of §1.15; roots of lambda tan lambda = Bi from heat::analytic). Superquadric
// (rounded cube, e1 = e2 = 0.5): no analytic solution, compared with the finest grid. The same
// cube as a convex polyhedron turned obliquely in its grid (faces cut the cells at all angles)
// against the slab product; a three-sphere clump against its finest grid, with its volume and
// area against the geometry template's union volume and exposed area.

#include "common/cube_template.hpp"
#include "geometry/clump.hpp"
#include "geometry/shape.hpp"
#include "geometry/shape_metrics.hpp"
#include "heat/analytic.hpp"
#include "heat/cartesian_grid.hpp"
#include "heat_run.hpp"
#include "validation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <gtest/gtest.h>

namespace kiln::validation {
namespace {

const heat::ThermalProperties glass{1.4, 2225.0, 835.0}; // seed Table 1, Inv. V
constexpr double half = 0.05;                            // m, seed V-1 cube edge 0.1 m
constexpr double fo_end = 0.3;                           // alpha t / half^2
constexpr int samples = 3;

/// Box faces pass through cell centres, so volume and area are exact up to round-off.
constexpr double geometry_roundoff = 1e-12;
/// Theta error (units of T_0 - T_inf) of the cube at 24 cells across (h = L/12), Bi = 1 and 10:
/// second-order interior with half cells at the faces, ~0.5 (h/L)^2 ~ 4e-3 at the edges/corners.
constexpr double cube_tolerance = 5e-3;
/// Observed spatial order of the cube from 8 to 24 cells across: at least 1.5 (second order
/// interior, corner cells are quarter and eighth cells).
constexpr double cube_order_min = 1.5;
/// Superquadric at 16 across against the 32-across reference: same accuracy class as the cut-cell
/// sphere of case 20 at Bi = 1 (~8e-3 there at 16 across).
constexpr double superquadric_tolerance = 1e-2;

/// Turned cube (polyhedron) at 24 cells across its bounding box (h ~ L/7.5 at this turn) against
/// the slab product: the error of the cube on aligned grids at that spacing (~3e-3 at h = L/6),
/// plus the cut cells' first-order volume at the edges. Set from the measured 4.6e-3.
constexpr double turned_cube_tolerance = 6e-3;
/// Clump at 16 across against 32 across: same class as the superquadric (a crease between the
/// members adds cut cells of every shape).
constexpr double clump_tolerance = 1e-2;

double time_scale() {
    return half * half / glass.diffusivity();
}

std::vector<ThetaSample> run(const heat::Shape& shape, int n, double bi) {
    const auto g = std::make_shared<const heat::ThermalGrid>(
        heat::make_cartesian_grid(shape, {.cells_across = n}));
    const double h = bi * glass.conductivity / half;
    const double dt = fo_end * time_scale() / 150;
    return richardson(run_convection(g, glass, h, dt, 150, samples, direct_or_cg()),
                      run_convection(g, glass, h, dt / 2.0, 300, samples, direct_or_cg()));
}

double max_error(const std::vector<ThetaSample>& a, const std::vector<ThetaSample>& b) {
    double e = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        e = std::max({e, std::abs(a[i].centre - b[i].centre), std::abs(a[i].mean - b[i].mean)});
    }
    return e;
}

TEST(BodyConvection, CubeAgainstProductOfSlabSolutions) {
    reset_results();
    const heat::Shape cube = heat::Box{Vec3::Constant(half)};
    for (const double bi : {1.0, 10.0}) {
        const auto lambda = heat::analytic::slab_eigenvalues(bi, 200);
        std::vector<ThetaSample> exact;
        for (int i = 1; i <= samples; ++i) {
            const double fo = fo_end * i / samples;
            exact.push_back({std::pow(heat::analytic::slab_theta(lambda, 0.0, fo), 3),
                             std::pow(heat::analytic::slab_mean_theta(lambda, fo), 3)});
        }
        std::printf("\n  cube, Bi = h L / k = %g (Richardson in time)\n", bi);
        std::printf("  across  cells   volume err  area err    theta err  order\n");
        double prev = 0.0;
        double e8 = 0.0;
        double e24 = 0.0;
        for (const int n : {8, 12, 16, 24}) {
            const heat::ThermalGrid g = heat::make_cartesian_grid(cube, {.cells_across = n});
            const double dv = g.total_volume() / heat::exact_volume(cube) - 1.0;
            const double da = g.total_area() / heat::reference_area(cube) - 1.0;
            EXPECT_LT(std::abs(dv), geometry_roundoff);
            EXPECT_LT(std::abs(da), geometry_roundoff);
            const double e = max_error(run(cube, n, bi), exact);
            write_convergence("cube Bi=" + std::to_string(static_cast<int>(bi)), 1.0 / n, e, e,
                              bi == 1.0 && n == 8);
            std::printf("  %-6d  %-6d  %-10.2e  %-10.2e  %-9.2e  %.2f\n", n, g.size(), dv, da, e,
                        prev > 0.0 ? std::log(prev / e) / std::log(n / (n == 12   ? 8.0
                                                                        : n == 16 ? 12.0
                                                                                  : 16.0))
                                   : 0.0);
            prev = e;
            e8 = n == 8 ? e : e8;
            e24 = e;
        }
        const double order = std::log(e8 / e24) / std::log(3.0);
        record("cube Bi=" + std::to_string(static_cast<int>(bi)) + " theta error at 24 across", e24,
               0.0, cube_tolerance, "-");
        record("cube Bi=" + std::to_string(static_cast<int>(bi)) + " order 8->24", order, 2.0,
               2.0 - cube_order_min, "-");
        EXPECT_LT(e24, cube_tolerance) << bi;
        EXPECT_GT(order, cube_order_min) << bi;
    }
}

TEST(BodyConvection, SuperquadricAgainstGridConvergedReference) {
    const heat::Shape sq = heat::Superquadric{Vec3::Constant(half), 0.5, 0.5};
    const double bi = 1.0;
    const std::vector<ThetaSample> ref = run(sq, 32, bi);
    std::printf("\n  superquadric e1 = e2 = 0.5, Bi = 1, reference: 32 across\n");
    std::printf("  across  cells   volume err  area err    theta diff\n");
    double e16 = 0.0;
    double e8 = 0.0;
    for (const int n : {8, 12, 16, 24}) {
        const heat::ThermalGrid g = heat::make_cartesian_grid(sq, {.cells_across = n});
        const double dv = g.total_volume() / heat::exact_volume(sq) - 1.0;
        const double da = g.total_area() / heat::reference_area(sq) - 1.0;
        const double e = max_error(run(sq, n, bi), ref);
        write_convergence("superquadric vs 32 across", 1.0 / n, e, e);
        std::printf("  %-6d  %-6d  %-10.2e  %-10.2e  %-9.2e\n", n, g.size(), dv, da, e);
        e8 = n == 8 ? e : e8;
        e16 = n == 16 ? e : e16;
    }
    record("superquadric theta diff 16 vs 32 across", e16, 0.0, superquadric_tolerance, "-");
    EXPECT_LT(e16, superquadric_tolerance);
    EXPECT_LT(e16, e8);
}

/// The slab-product theta of the cube at the sample times (Bi = h L / k).
std::vector<ThetaSample> cube_exact(double bi) {
    const auto lambda = heat::analytic::slab_eigenvalues(bi, 200);
    std::vector<ThetaSample> exact;
    for (int i = 1; i <= samples; ++i) {
        const double fo = fo_end * i / samples;
        exact.push_back({std::pow(heat::analytic::slab_theta(lambda, 0.0, fo), 3),
                         std::pow(heat::analytic::slab_mean_theta(lambda, fo), 3)});
    }
    return exact;
}

/// Cube of half edge `a` as 12 outward triangles, every vertex turned by q.
heat::ConvexPolyhedron turned_cube(double a, const Quat& q) {
    const test::TriangleMesh m = test::cube_mesh(a, q);
    return heat::make_convex_polyhedron(m.vertices, m.triangles);
}

TEST(BodyConvection, TurnedPolyhedronCubeAgainstProductOfSlabSolutions) {
    const Quat q(Eigen::AngleAxisd(0.4, Vec3(1, 2, 3).normalized()));
    const heat::Shape cube = turned_cube(half, q);
    const double bi = 1.0;
    const std::vector<ThetaSample> exact = cube_exact(bi);
    std::printf("\n  cube as a polyhedron turned 0.4 rad about (1,2,3), Bi = 1\n");
    std::printf("  across  h/L    cells   volume err  area err    theta err\n");
    double e8 = 0.0;
    double e24 = 0.0;
    for (const int n : {8, 12, 16, 24}) {
        const heat::ThermalGrid g = heat::make_cartesian_grid(cube, {.cells_across = n});
        const double h = heat::cartesian_cell_size(cube, {.cells_across = n});
        const double dv = g.total_volume() / heat::exact_volume(cube) - 1.0;
        const double da = g.total_area() / heat::reference_area(cube) - 1.0;
        const double e = max_error(run(cube, n, bi), exact);
        write_convergence("turned polyhedron cube Bi=1", h / half, e, e);
        std::printf("  %-6d  %-5.3f  %-6d  %-10.2e  %-10.2e  %-9.2e\n", n, h / half, g.size(), dv,
                    da, e);
        // The clipped face triangulation is the exact surface: area to round-off.
        EXPECT_LT(std::abs(da), 1e-9) << n;
        e8 = n == 8 ? e : e8;
        e24 = e;
    }
    record("turned polyhedron cube theta error at 24 across", e24, 0.0, turned_cube_tolerance, "-");
    EXPECT_LT(e24, turned_cube_tolerance);
    EXPECT_LT(e24, e8);
}

/// Largest deviation of the volume-mean theta only: the centre cell of an asymmetric body holds
/// the centre of mass at a place within the cell that changes with the grid, and the field has a
/// gradient there, so its node temperature is no converging quantity.
double max_mean_error(const std::vector<ThetaSample>& a, const std::vector<ThetaSample>& b) {
    double e = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        e = std::max(e, std::abs(a[i].mean - b[i].mean));
    }
    return e;
}

TEST(BodyConvection, ClumpAgainstGridConvergedReference) {
    // Three spheres of 30 mm in a bent row (overlapping pairs, a crease at each seam), built by
    // the geometry module: body frame = principal axes at the union's centre of mass.
    const double r = 0.03;
    const geometry::ShapeTemplate t = geometry::make_template(
        "bent_row", geometry::make_clump(
                        {{Vec3(-0.04, 0, 0), r}, {Vec3(0, 0, 0), r}, {Vec3(0.03, 0.03, 0.0), r}},
                        "validation 21"));
    const auto& gc = std::get<geometry::Clump>(t.shape);
    heat::Clump c;
    for (const auto& m : gc.spheres) {
        c.centres.push_back(m.centre);
        c.radii.push_back(m.radius);
    }
    c.volume = t.volume;
    const geometry::Estimate area = geometry::surface_area(t.shape);
    c.area = area.value;
    const heat::Shape shape = c;
    const double bi = 1.0; // h r / k with the member radius r = 30 mm (so h = bi k / half)
    const auto run_clump = [&](int n) {
        const auto g = std::make_shared<const heat::ThermalGrid>(
            heat::make_cartesian_grid(shape, {.cells_across = n}));
        const double h = bi * glass.conductivity / r;
        const double dt = fo_end * r * r / glass.diffusivity() / 150;
        return richardson(run_convection(g, glass, h, dt, 150, samples, direct_or_cg()),
                          run_convection(g, glass, h, dt / 2.0, 300, samples, direct_or_cg()));
    };
    const std::vector<ThetaSample> ref = run_clump(32);
    std::printf("\n  clump of 3 spheres (r = 30 mm), Bi = 1; template volume %.6e m^3 (+- %.1e), "
                "area %.6e m^2 (+- %.1e); reference: 32 across\n",
                t.volume, gc.volume_error, area.value, area.error);
    std::printf("  across  cells   volume err  area err    mean theta diff\n");
    double e8 = 0.0;
    double e16 = 0.0;
    double prev_da = 0.0;
    for (const int n : {8, 12, 16, 24, 32}) {
        const heat::ThermalGrid g = heat::make_cartesian_grid(shape, {.cells_across = n});
        const double dv = g.total_volume() / t.volume - 1.0;
        const double da = g.total_area() / area.value - 1.0;
        const double e = n == 32 ? 0.0 : max_mean_error(run_clump(n), ref);
        if (n < 32) {
            write_convergence("clump vs 32 across", 1.0 / n, e, e);
        }
        std::printf("  %-6d  %-6d  %-10.2e  %-10.2e  %-9.2e\n", n, g.size(), dv, da, e);
        if (n > 8) {
            EXPECT_LT(std::abs(da), std::abs(prev_da)) << n; // the area converges
        }
        prev_da = da;
        e8 = n == 8 ? e : e8;
        e16 = n == 16 ? e : e16;
        if (n == 32) {
            record("clump volume error at 32 across", std::abs(dv), 0.0, 1e-3, "-");
            record("clump area error at 32 across", std::abs(da), 0.0, 1e-3, "-");
            EXPECT_LT(std::abs(dv), 1e-3);
            EXPECT_LT(std::abs(da), 1e-3);
        }
    }
    record("clump mean theta diff 16 vs 32 across", e16, 0.0, clump_tolerance, "-");
    EXPECT_LT(e16, clump_tolerance);
    EXPECT_LT(e16, e8);
}

} // namespace
} // namespace kiln::validation
