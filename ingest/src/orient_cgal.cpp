// Outward orientation of closed meshes with CGAL Polygon Mesh Processing. Its own translation
// unit, linked into vtex_ingest only, because CGAL adds -frounding-math and is slow to compile.
#include "detail.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/helpers.h>

namespace vtex::ingest::detail {

std::optional<std::vector<char>> computeOutwardFlips(const std::vector<Eigen::Vector3d>& points,
                                                     const std::vector<std::array<std::uint32_t, 3>>& triangles) {
    namespace PMP = CGAL::Polygon_mesh_processing;
    using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
    using Point = Kernel::Point_3;
    using Mesh = CGAL::Surface_mesh<Point>;

    std::vector<Point> soupPoints;
    soupPoints.reserve(points.size());
    for (const auto& p : points) soupPoints.emplace_back(p.x(), p.y(), p.z());
    std::vector<std::array<std::size_t, 3>> soup(triangles.size());
    for (std::size_t t = 0; t < triangles.size(); ++t)
        soup[t] = {triangles[t][0], triangles[t][1], triangles[t][2]};

    // Consistent orientation of the soup. It returns false (and duplicates points) where the
    // soup is not an orientable manifold; then vtex keeps the file's winding.
    if (!PMP::orient_polygon_soup(soupPoints, soup) || soupPoints.size() != points.size()) return std::nullopt;

    Mesh mesh;
    PMP::polygon_soup_to_polygon_mesh(soupPoints, soup, mesh);
    if (mesh.number_of_faces() != triangles.size() || mesh.number_of_vertices() != points.size() ||
        !CGAL::is_closed(mesh))
        return std::nullopt;
    // Each connected component (and nested shells) made to bound a volume, normals outward.
    PMP::orient_to_bound_a_volume(mesh);

    // Face t of the mesh is soup polygon t and vertex i is point i (polygon_soup_to_polygon_mesh
    // adds both in order). A face is flipped when its cycle is the odd permutation of the input.
    std::vector<char> flips(triangles.size(), 0);
    for (std::size_t t = 0; t < triangles.size(); ++t) {
        const Mesh::Face_index face(static_cast<Mesh::size_type>(t));
        const auto h = mesh.halfedge(face);
        const std::size_t a = mesh.target(mesh.prev(h)), b = mesh.target(h);
        const auto& in = triangles[t];
        // (a, b) is a directed edge of the oriented face; it is one of the input's directed
        // edges when the orientation agrees.
        const bool same = (a == in[0] && b == in[1]) || (a == in[1] && b == in[2]) || (a == in[2] && b == in[0]);
        flips[t] = same ? 0 : 1;
    }
    return flips;
}

}  // namespace vtex::ingest::detail
