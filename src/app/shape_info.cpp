// `kiln info SHAPE`; definitions of the printed quantities in docs/theory/shapes.md.

#include "app/shape_info.hpp"

#include "geometry/rotation.hpp"
#include "geometry/shape_metrics.hpp"
#include "io/shape_reader.hpp"
#include "io/shape_vtk.hpp"

#include <fmt/format.h>

namespace kiln::app {

int print_shape_info(const std::string& shape, double density, const std::string& vtk_file) {
    const auto file = io::find_shape_file(shape, io::default_shape_dirs());
    const geometry::ShapeTemplate t = io::read_shape_file(file);
    const geometry::ShapeFactors f = geometry::shape_factors(t);
    const double rho = density * t.density_factor();
    fmt::print("shape             {} ({}), {}\n", t.name, geometry::kind_name(t.shape),
               file.string());
    if (const auto* c = std::get_if<geometry::Clump>(&t.shape)) {
        fmt::print("spheres           {}; union integrated by column quadrature, volume error "
                   "estimate {:.2e} m^3 ({:.1e} relative)\n",
                   c->spheres.size(), c->volume_error, c->volume_error / c->volume);
    }
    if (const auto* p = std::get_if<geometry::ConvexPolyhedron>(&t.shape)) {
        fmt::print("polyhedron        {} vertices, {} triangles, {} edges (convex hull)\n",
                   p->vertices.size(), p->faces.size(), p->edges.size());
    }
    for (const std::string& w : t.warnings) {
        fmt::print(stderr, "kiln: warning: {}\n", w);
    }
    fmt::print("volume            {:.6e} m^3\n", t.volume);
    if (t.reference.kind != "none") {
        fmt::print("reference solid   {} of volume {:.6e} m^3; captured volume fraction {:.4f} %\n",
                   t.reference.kind, t.reference.volume(), 100.0 * t.volume / t.reference.volume());
    }
    fmt::print("density           {:g} kg/m^3{}\n", rho,
               t.density_correction ? fmt::format(" (material {:g} x density correction {:.5f})",
                                                  density, t.density_factor())
                                    : std::string());
    fmt::print("mass              {:.6e} kg\n", t.mass(density));
    fmt::print("centre of mass    body origin (template moved there)\n");
    const Vec3 inertia = t.inertia(density);
    fmt::print("principal inertia {:.6e} {:.6e} {:.6e} kg m^2 (body x, y, z)\n", inertia.x(),
               inertia.y(), inertia.z());
    // Which free rotation the step takes for this shape (docs/theory/rotation.md).
    if (geometry::spherical_top(inertia)) {
        fmt::print("rotation          spherical top: exact turn about L\n");
    } else if (const int s = geometry::symmetric_axis(inertia); s >= 0) {
        fmt::print("rotation          symmetric top about body {}: exact turn about L and spin\n",
                   "xyz"[s]);
    } else {
        fmt::print("rotation          asymmetric: symmetric splitting (second order)\n");
    }
    fmt::print("bounding radius   {:.6e} m\n", t.bounding_radius());
    fmt::print("surface area      {:.6e} m^2 (estimated error {:.1e} m^2)\n", f.surface.value,
               f.surface.error);
    fmt::print("d_volume          {:.6e} m (equivalent-volume sphere)\n", f.d_volume);
    fmt::print("d_surface         {:.6e} m (equivalent-surface sphere)\n", f.d_surface);
    fmt::print("sphericity        {:.5f} (pi d_v^2 / S)\n", f.sphericity);
    fmt::print("crosswise sphericity (pi d_v^2/4 over the shadow area, flow along a body axis)\n");
    for (int k = 0; k < 3; ++k) {
        fmt::print("  flow along {}    {:.5f} (shadow {:.6e} m^2)\n", "xyz"[k], f.crosswise[k],
                   f.projected[k]);
    }
    if (!vtk_file.empty()) {
        io::write_surface_vtp(vtk_file, {geometry::surface_mesh(t.shape, 24)});
        fmt::print("surface mesh      {} (body frame, m)\n", vtk_file);
    }
    return 0;
}

} // namespace kiln::app
