// The reflectance of one micro-primitive, Neyret 1994 §3.2: "we sample the apparent surface
// [...] selecting directly the samples that fall on the ellipsoid by evaluating the rectangle
// circumscribing the apparent ellipse (obtained from the quadratic form); moreover only half
// of the ellipse is sampled, the symmetric normals following from the ellipsoid's
// properties." Method (b) integrates the same quantity over the Gauss map instead.
#include <vtex/primitive/reflectance.h>
#include <vtex/primitive/quadrature.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <numbers>

namespace vtex::primitive {
namespace {

constexpr double kInvPi = std::numbers::inv_pi;

// The Phong terms of one facet of unit normal n, per unit irradiance, already multiplied by
// the facet's cosine to the light; the caller weights by visible area.
struct FacetShading {
    double diffuse = 0;
    double specular = 0;
};

FacetShading shadeFacet(const Vec3& n, const Vec3& light, const Vec3& view, double shininess) {
    const double cosLight = n.dot(light);
    const double cosView = n.dot(view);
    if (cosLight <= 0 || cosView <= 0) return {};
    const Vec3 mirror = 2 * cosLight * n - light;
    const double cosAlpha = std::max(0.0, mirror.dot(view));
    // pow(0, 0) is 1: a shininess of 0 is a (normalised) Lambertian lobe, as it should be.
    const double lobe = (shininess + 2) * 0.5 * kInvPi * std::pow(cosAlpha, shininess);
    return {cosLight * kInvPi, cosLight * lobe};
}

// Unit vectors pointing away from the primitive, in its own frame.
struct LocalDirections {
    Vec3 light;
    Vec3 view;
};

LocalDirections toLocal(const Ellipsoid& e, const Vec3& light, const Vec3& view) {
    return {(e.basis().transpose() * light).normalized(), (e.basis().transpose() * view).normalized()};
}

}  // namespace

ReflectanceFactors phongReflectanceApparentEllipse(const Ellipsoid& ellipsoid, const Vec3& light,
                                                   const Vec3& view, double shininess,
                                                   int samplesPerAxis) {
    // Reflectance does not depend on size: work in the ellipsoid's frame with its longest
    // semi-axis 1, so Q = diag(a⁻²) stays within [1, 1e8] whatever the scale.
    const auto [l, v] = toLocal(ellipsoid, light, view);
    const Vec3 a = ellipsoid.semiAxes() / ellipsoid.semiAxes().maxCoeff();
    const Vec3 q = a.cwiseAbs2().cwiseInverse();  // Q = diag(q)

    // The silhouette seen along v: a point p ⊥ v lies inside it iff the line p + λv meets the
    // ellipsoid, i.e. iff the discriminant (pᵀQv)² − (vᵀQv)(pᵀQp − 1) ≥ 0, which is
    // pᵀ P p ≤ 1 with P = Q − (Qv)(Qv)ᵀ / (vᵀQv).
    const Vec3 qv = q.cwiseProduct(v);
    const double vQv = v.dot(qv);
    const Mat3 P = Mat3(q.asDiagonal()) - qv * qv.transpose() / vQv;
    // Any orthonormal pair (e1, e2) ⊥ v, then the 2×2 form in that pair; its eigenvectors
    // are the axes of the apparent ellipse, its eigenvalues 1/h² for the half-lengths h.
    const Vec3 helper = std::abs(v.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
    const Vec3 e1 = v.cross(helper).normalized();
    const Vec3 e2 = v.cross(e1);
    Eigen::Matrix2d form;
    form << e1.dot(P * e1), e1.dot(P * e2), e2.dot(P * e1), e2.dot(P * e2);
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(form);
    const Eigen::Vector2d halfLengths = solver.eigenvalues().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
    const Vec3 axis1 = solver.eigenvectors()(0, 0) * e1 + solver.eigenvectors()(1, 0) * e2;
    const Vec3 axis2 = solver.eigenvectors()(0, 1) * e1 + solver.eigenvectors()(1, 1) * e2;

    // The bounding rectangle [-h₁, h₁] × [0, h₂]: the half ellipse t ≥ 0.
    const int n = std::max(2, samplesPerAxis);
    const int rows = std::max(1, n / 2);
    double diffuse = 0, specular = 0;
    long facets = 0;
    for (int j = 0; j < rows; ++j) {
        const double tUnit = (j + 0.5) / rows;  // t / h₂ in (0, 1)
        for (int i = 0; i < n; ++i) {
            const double sUnit = 2 * (i + 0.5) / n - 1;  // s / h₁ in (-1, 1)
            if (sUnit * sUnit + tUnit * tUnit >= 1) continue;
            const Vec3 p = sUnit * halfLengths[0] * axis1 + tUnit * halfLengths[1] * axis2;
            const double pQv = p.dot(qv);
            const double discriminant = std::max(0.0, pQv * pQv - vQv * (p.dot(q.cwiseProduct(p)) - 1));
            const double root = std::sqrt(discriminant);
            // The viewer is at +v: the larger root is the visible point of p. The visible point
            // of −p is the mirror image −x of the hidden point x of p (central symmetry).
            const Vec3 front = p + ((root - pQv) / vQv) * v;
            const Vec3 back = p - ((root + pQv) / vQv) * v;
            const Vec3 normalFront = q.cwiseProduct(front).normalized();
            const Vec3 normalMirror = -q.cwiseProduct(back).normalized();
            const FacetShading s1 = shadeFacet(normalFront, l, v, shininess);
            const FacetShading s2 = shadeFacet(normalMirror, l, v, shininess);
            diffuse += s1.diffuse + s2.diffuse;
            specular += s1.specular + s2.specular;
            facets += 2;
        }
    }
    if (facets == 0) return {};
    // Every grid cell has the same apparent area: the average over the visible apparent area.
    return {diffuse / double(facets), specular / double(facets)};
}

ReflectanceFactors phongReflectanceNormalQuadrature(const Ellipsoid& ellipsoid, const Vec3& light,
                                                    const Vec3& view, double shininess, int rings) {
    const auto [l, v] = toLocal(ellipsoid, light, view);
    const Vec3 a = ellipsoid.semiAxes() / ellipsoid.semiAxes().maxCoeff();
    const Vec3 inverseA = a.cwiseInverse();
    const int thetaCount = std::max(2, rings);
    const int phiCount = 2 * thetaCount;
    const QuadratureRule rule = gaussLegendre(thetaCount);

    // ∫ g(N) f(N) dN = ∫_{S²} g(N(u)) det(L) |L⁻ᵀu| du with L = diag(a), N(u) = L⁻ᵀu / |L⁻ᵀu|;
    // det(L) is a common factor of numerator and denominator and cancels.
    double diffuse = 0, specular = 0, visibleArea = 0;
    for (int i = 0; i < thetaCount; ++i) {
        const double z = rule.nodes[i];
        const double r = std::sqrt(std::max(0.0, 1 - z * z));
        for (int j = 0; j < phiCount; ++j) {
            const double phi = 2 * std::numbers::pi * (j + 0.5) / phiCount;
            const Vec3 u(r * std::cos(phi), r * std::sin(phi), z);
            const Vec3 scaledNormal = inverseA.cwiseProduct(u);
            const double jacobian = scaledNormal.norm();
            const Vec3 normal = scaledNormal / jacobian;
            const double cosView = normal.dot(v);
            if (cosView <= 0) continue;
            const double weight = rule.weights[i] * jacobian * cosView;
            visibleArea += weight;
            const FacetShading s = shadeFacet(normal, l, v, shininess);
            diffuse += weight * s.diffuse;
            specular += weight * s.specular;
        }
    }
    if (!(visibleArea > 0)) return {};
    return {diffuse / visibleArea, specular / visibleArea};
}

ReflectanceFactors reflectanceReference(const SggxMatrix& s, const Vec3& light, const Vec3& view, double shininess,
                                        int samplesPerAxis) {
    const auto ellipsoid = Ellipsoid::fromS(s.matrix());
    if (!ellipsoid) return {};
    return phongReflectanceApparentEllipse(*ellipsoid, light, view, shininess, samplesPerAxis);
}

}  // namespace vtex::primitive
