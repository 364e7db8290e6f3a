// The inside test of --solid: CGAL's Side_of_triangle_mesh (ray parity on an AABB tree, with
// exact predicates). Its tree is built once; queries from several threads are safe (CGAL builds
// the tree under a mutex and each query seeds its own random rays).
#include "inside_test.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/helpers.h>

#include <stdexcept>

namespace vtex::sampler::detail {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;

struct InsideTest::Impl {
    Mesh mesh;
    std::unique_ptr<CGAL::Side_of_triangle_mesh<Mesh, Kernel>> side;
};

InsideTest::InsideTest(const std::vector<Eigen::Vector3d>& positions,
                       const std::vector<std::array<std::uint32_t, 3>>& triangles)
    : mImpl(std::make_unique<Impl>()) {
    std::vector<Mesh::Vertex_index> vertices;
    vertices.reserve(positions.size());
    for (const auto& p : positions) vertices.push_back(mImpl->mesh.add_vertex(Point(p.x(), p.y(), p.z())));
    for (const auto& t : triangles) {
        if (t[0] >= vertices.size() || t[1] >= vertices.size() || t[2] >= vertices.size())
            throw std::runtime_error("triangle index out of range");
        if (mImpl->mesh.add_face(vertices[t[0]], vertices[t[1]], vertices[t[2]]) == Mesh::null_face())
            throw std::runtime_error("the triangles do not form a manifold surface");
    }
    if (!CGAL::is_closed(mImpl->mesh)) throw std::runtime_error("the mesh is not closed");
    mImpl->side = std::make_unique<CGAL::Side_of_triangle_mesh<Mesh, Kernel>>(mImpl->mesh);
    (void)(*mImpl->side)(Point(0, 0, 0));  // builds the tree now, on one thread
}

InsideTest::~InsideTest() = default;

bool InsideTest::inside(const Eigen::Vector3d& p) const {
    return (*mImpl->side)(Point(p.x(), p.y(), p.z())) == CGAL::ON_BOUNDED_SIDE;
}

}  // namespace vtex::sampler::detail
