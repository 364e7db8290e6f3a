// The stored form of the micro-primitive (primitive/include/vtex/primitive/packing.h).
#include <vtex/primitive/packing.h>

#include <Eigen/Geometry>

#include <numbers>

namespace vtex::primitive {

PackedPrimitive pack(const Ellipsoid& ellipsoid) { return pack(ellipsoid.shape()); }

PackedPrimitive pack(const EllipsoidShape& shape) {
    // Normalised to unit exact mean area (Ellipsoid::normalized(Exact)'s arithmetic on the axes).
    const EllipsoidShape e = shape.normalized();
    Mat3 basis = e.basis;
    if (basis.determinant() < 0) basis.col(0) = -basis.col(0);  // axes have no sign
    Eigen::Quaterniond q(basis);
    q.normalize();
    if (q.w() < 0) q.coeffs() = -q.coeffs();
    const Vec3& a = e.semiAxes;
    constexpr double kPi = std::numbers::pi;
    return {{float(q.x()), float(q.y()), float(q.z()), float(q.w())},
            {float(kPi * a[1] * a[2]), float(kPi * a[0] * a[2]), float(kPi * a[0] * a[1])}};
}

Mat3 unpackRotation(const std::array<float, 4>& rotation) {
    const Eigen::Quaterniond q(rotation[3], rotation[0], rotation[1], rotation[2]);
    if (q.norm() == 0) return Mat3::Zero();
    return q.normalized().toRotationMatrix();
}

SggxMatrix unpackS(const std::array<float, 4>& rotation, const std::array<float, 3>& sigma) {
    const Mat3 R = unpackRotation(rotation);
    if (R.isZero()) return {0, 0, 0, 0, 0, 0};
    const Vec3 s2 = Vec3(double(sigma[0]) * sigma[0], double(sigma[1]) * sigma[1], double(sigma[2]) * sigma[2]);
    const Mat3 S = R * s2.asDiagonal() * R.transpose();
    // Eigen's product rounds S(i, j) and S(j, i) differently in the last bit; the lower triangle
    // is the one Eigen's self-adjoint eigensolver (Ellipsoid::fromS) has always read, so it is
    // the one kept: the octree's filtered levels stay the same bit for bit.
    return {S(0, 0), S(1, 1), S(2, 2), S(1, 0), S(2, 0), S(2, 1)};
}

std::optional<Ellipsoid> unpackEllipsoid(const std::array<float, 4>& rotation, const std::array<float, 3>& sigma) {
    return Ellipsoid::fromS(unpackS(rotation, sigma).matrix());
}

}  // namespace vtex::primitive
