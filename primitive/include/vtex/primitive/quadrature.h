/// @file
/// @brief Quadrature rules used by the micro-primitive's integrals.
#pragma once

#include <vector>

namespace vtex::primitive {

/// The n-point Gauss–Legendre rule on [-1, 1]: exact for polynomials of degree 2n − 1.
struct QuadratureRule {
    std::vector<double> nodes;
    std::vector<double> weights;
};

/// Nodes by Newton's iteration on the Legendre polynomial from the asymptotic initial guess;
/// accurate to a few ulps for n up to several thousand. n ≥ 1.
QuadratureRule gaussLegendre(int n);

}  // namespace vtex::primitive
