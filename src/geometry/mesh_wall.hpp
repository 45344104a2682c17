#pragma once
// Triangle-mesh walls (world frame) with a uniform cell grid of the triangles, and the contacts of
// spheres and convex polyhedra with them. The wall is one-sided: particles are on the side the
// triangle normal (right-hand rule of the vertex order) points to; a particle whose centre is
// behind a triangle's plane does not touch that triangle.
//
// Spheres: the closest point of each nearby triangle (Ericson 2005, Real-Time Collision Detection,
// Sec. 5.1.5) classifies the contact as face, edge or vertex. Contacts are then thinned by the
// feature hierarchy of the double hierarchy method (Santasusana et al. 2016, Comput. Part. Mech. 3,
// 407): an edge contact found from two triangles counts once, and is dropped when a triangle
// containing that edge has a face contact with the same sphere; a vertex contact counts once and is
// dropped when a face or edge containing the vertex is in contact. A sphere sliding across the
// shared edge of two coplanar triangles therefore sees face (r - h), edge (r - h), face (r - h):
// no second contact and no change of normal, so no bump.
//
// Polyhedra: one contact per facet (a connected set of coplanar triangles, found when the mesh is
// built), with the facet normal as the contact normal (as the seed does for every particle-wall
// contact, Oschmann 2019 L473). The overlap is the depth below the facet plane of the deepest point
// of the body inside the facet's prism (exact: the largest of the depths of the body's edges
// clipped to each triangle's prism and of the prism's corner lines clipped to the body), so a body
// sliding across the edges inside a facet keeps its overlap. The patch is the section of the body
// half way through the overlap clipped by the facet's triangles; the contact point is its centroid.
//
// Superquadrics: triangle by triangle, the deepest point s of the body below the triangle's plane
// (its support point against the normal). When s lies over the triangle, the contact is a face
// contact with the triangle normal and the plane depth (exactly the analytic plane's contact);
// when it lies over the triangle's boundary, an edge or vertex contact with the same normal and
// depth; otherwise the body may still overlap the triangle across an edge or a vertex, which
// libccd GJK/EPA between the triangle's and the body's support maps decides (the feature is the
// triangle's support along EPA's normal; the overlap is re-evaluated exactly along that normal).
// The contacts are then thinned by the same feature hierarchy as the sphere contacts.

#include "core/types.hpp"
#include "geometry/convex_contact.hpp"
#include "geometry/polyhedron_contact.hpp"

#include <array>
#include <string>
#include <vector>

namespace kiln::geometry {

/// Which feature of the mesh a contact is with.
enum class MeshFeature {
    kFace,   ///< inside a triangle (sphere, superquadric)
    kEdge,   ///< on a triangle edge (sphere, superquadric)
    kVertex, ///< at a vertex (sphere, superquadric)
    kFacet,  ///< a set of coplanar triangles (polyhedron)
};

/// One contact of a particle with a mesh wall, world frame.
struct MeshContact {
    Vec3 normal = Vec3::UnitZ(); ///< unit normal from the wall towards the particle, world frame
    double depth = 0.0;          ///< overlap (m), > 0
    Vec3 point = Vec3::Zero();   ///< contact point (m), world frame
    double patch_area = 0.0;     ///< contact patch area (m^2); polyhedra only, 0 for spheres
    MeshFeature feature = MeshFeature::kFace; ///< feature touched
    int id = -1; ///< index of the triangle, edge, vertex or facet: a stable key for contact history
};

/// A triangle mesh in the world frame with its edges, facets and a uniform cell grid.
class MeshWall {
  public:
    /// Builds the wall from vertices (m, world frame) and triangles (vertex indices; the normal by
    /// the right-hand rule points to the particles' side). Throws kiln::InputError prefixed by
    /// `where` on an empty mesh, a bad index or a triangle of zero area.
    MeshWall(std::vector<Vec3> vertices, std::vector<std::array<int, 3>> triangles,
             const std::string& where);

    /// Contacts of a sphere (centre c (m), radius r (m), world frame); `out` is cleared first.
    void sphere_contacts(const Vec3& c, double r, std::vector<MeshContact>& out) const;
    /// Contacts of a posed convex polyhedron (one per touched facet); `out` is cleared first.
    void polyhedron_contacts(const PosedPolyhedron& p, std::vector<MeshContact>& out) const;
    /// Contacts of a posed superquadric of bounding radius r (m), world frame (face, edge and
    /// vertex contacts thinned as for spheres); `out` is cleared first. Returns the number of
    /// triangles whose libccd query did not converge (those contacts are skipped).
    int superquadric_contacts(const PosedSuperquadric& s, double r,
                              std::vector<MeshContact>& out) const;

    /// Signed distance of a point x (m, world) from the nearest triangle (m): positive on the side
    /// the normals point to (the particles' side). Brute force over all triangles: for set-up
    /// checks, not for the step loop.
    [[nodiscard]] double signed_distance(const Vec3& x) const;

    /// Vertices (m), world frame.
    [[nodiscard]] const std::vector<Vec3>& vertices() const { return vertices_; }
    /// Triangles (vertex indices).
    [[nodiscard]] const std::vector<std::array<int, 3>>& triangles() const { return triangles_; }
    /// Number of facets (connected sets of coplanar triangles).
    [[nodiscard]] int facet_count() const { return static_cast<int>(facet_normals_.size()); }
    /// Side of a grid cell (m).
    [[nodiscard]] double cell_size() const { return cell_; }

  private:
    /// Triangles whose bounding boxes overlap the box [lo, hi] (m, world), sorted, unique.
    void candidates(const Vec3& lo, const Vec3& hi, std::vector<int>& out) const;
    [[nodiscard]] std::array<int, 3> cell_of(const Vec3& x) const;
    /// Flat index of cell (i, j, k).
    [[nodiscard]] std::size_t cell_index(int i, int j, int k) const;
    /// Feature hierarchy of the sphere contacts: `out` holds the face contacts and receives the
    /// edge and vertex contacts that survive (sphere radius r (m)).
    void thin(std::vector<MeshContact>& out, std::vector<MeshContact>& edges,
              std::vector<MeshContact>& verts, double r) const;
    /// Files contact m of triangle t by the Voronoi region of its closest point (0 face, 1-3 edge
    /// k-1, 4-6 vertex k-4): sets its feature and id and appends it to out, edges or verts.
    void file_by_region(MeshContact m, int t, int region, std::vector<MeshContact>& out,
                        std::vector<MeshContact>& edges, std::vector<MeshContact>& verts) const;
    /// Corner positions of triangle t (m, world).
    [[nodiscard]] std::array<Vec3, 3> corners(int t) const;

    std::vector<Vec3> vertices_;
    std::vector<std::array<int, 3>> triangles_;
    std::vector<Vec3> normals_;                     // unit triangle normals
    std::vector<std::array<int, 3>> tri_edges_;     // edge ids of each triangle (edge k: v_k v_k+1)
    std::vector<std::array<int, 2>> edges_;         // unique edges (vertex ids)
    std::vector<int> facet_of_;                     // facet of each triangle
    std::vector<Vec3> facet_normals_;               // unit facet normals
    std::vector<double> facet_offsets_;             // n . x on each facet plane (m)
    std::vector<std::vector<int>> facet_triangles_; // triangles of each facet
    Vec3 origin_ = Vec3::Zero();                    // lower corner of the grid (m)
    double cell_ = 1.0;                             // cell side (m)
    std::array<int, 3> dims_{1, 1, 1};              // cells per axis
    std::vector<int> cell_start_;                   // CSR offsets into cell_items_
    std::vector<int> cell_items_;                   // triangle ids per cell
};

} // namespace kiln::geometry
