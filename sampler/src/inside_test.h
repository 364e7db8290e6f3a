// Point-in-closed-mesh test (CGAL's Side_of_triangle_mesh), behind a plain interface so that
// CGAL's headers and its -frounding-math stay in inside_test.cpp.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace vtex::sampler::detail {

class InsideTest {
public:
    /// `positions` and the query points share one coordinate system. Throws std::runtime_error
    /// when the triangles do not form a closed triangle mesh.
    InsideTest(const std::vector<Eigen::Vector3d>& positions,
               const std::vector<std::array<std::uint32_t, 3>>& triangles);
    ~InsideTest();
    /// Strictly inside (a point on the surface is not). Thread-safe.
    bool inside(const Eigen::Vector3d& point) const;

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

}  // namespace vtex::sampler::detail
