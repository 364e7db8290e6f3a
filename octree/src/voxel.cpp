// Voxel records and Morton keys (octree/include/vtex/octree/voxel.h).
#include <vtex/octree/voxel.h>

#include <Eigen/Geometry>

namespace vtex::octree {
namespace {

// Spreads the low 20 bits of v so that bit i lands on bit 3i.
std::uint64_t spread3(std::uint32_t v) {
    std::uint64_t x = v & 0xFFFFFu;
    x = (x | (x << 32)) & 0x1F00000000FFFFull;
    x = (x | (x << 16)) & 0x1F0000FF0000FFull;
    x = (x | (x << 8)) & 0x100F00F00F00F00Full;
    x = (x | (x << 4)) & 0x10C30C30C30C30C3ull;
    x = (x | (x << 2)) & 0x1249249249249249ull;
    return x;
}

std::uint32_t compact3(std::uint64_t x) {
    x &= 0x1249249249249249ull;
    x = (x ^ (x >> 2)) & 0x10C30C30C30C30C3ull;
    x = (x ^ (x >> 4)) & 0x100F00F00F00F00Full;
    x = (x ^ (x >> 8)) & 0x1F0000FF0000FFull;
    x = (x ^ (x >> 16)) & 0x1F00000000FFFFull;
    x = (x ^ (x >> 32)) & 0xFFFFFull;
    return std::uint32_t(x);
}

}  // namespace

std::uint64_t mortonEncode(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    return spread3(x) | (spread3(y) << 1) | (spread3(z) << 2);
}

std::array<std::uint32_t, 3> mortonDecode(std::uint64_t key) {
    return {compact3(key), compact3(key >> 1), compact3(key >> 2)};
}

void packEllipsoid(const Ellipsoid& ellipsoid, VoxelData& voxel) {
    const Ellipsoid e = ellipsoid.normalized(Normalization::Exact);
    Mat3 basis = e.basis();
    if (basis.determinant() < 0) basis.col(0) = -basis.col(0);  // axes have no sign
    Eigen::Quaterniond q(basis);
    q.normalize();
    if (q.w() < 0) q.coeffs() = -q.coeffs();
    voxel.rotation = {float(q.x()), float(q.y()), float(q.z()), float(q.w())};
    const Vec3& a = e.semiAxes();
    constexpr double kPi = 3.14159265358979323846;
    voxel.sigma = {float(kPi * a[1] * a[2]), float(kPi * a[0] * a[2]), float(kPi * a[0] * a[1])};
}

Mat3 unpackRotation(const VoxelData& voxel) {
    Eigen::Quaterniond q(voxel.rotation[3], voxel.rotation[0], voxel.rotation[1], voxel.rotation[2]);
    if (q.norm() == 0) return Mat3::Zero();
    return q.normalized().toRotationMatrix();
}

Mat3 unpackS(const VoxelData& voxel) {
    const Mat3 R = unpackRotation(voxel);
    const Vec3 s2(double(voxel.sigma[0]) * voxel.sigma[0], double(voxel.sigma[1]) * voxel.sigma[1],
                  double(voxel.sigma[2]) * voxel.sigma[2]);
    return R * s2.asDiagonal() * R.transpose();
}

std::optional<Ellipsoid> unpackEllipsoid(const VoxelData& voxel) {
    if (voxel.isEmpty()) return std::nullopt;
    return Ellipsoid::fromS(unpackS(voxel));
}

void packIsotropic(VoxelData& voxel) {
    voxel.rotation = {0, 0, 0, 1};
    voxel.sigma = {1, 1, 1};
}

}  // namespace vtex::octree
