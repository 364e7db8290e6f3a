#include <vtex/primitive/quadrature.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <utility>

namespace vtex::primitive {
namespace {

// P_n(x) and P_{n-1}(x) by the three-term recurrence.
std::pair<double, double> legendre(int n, double x) {
    double previous = 1, current = x;
    for (int k = 2; k <= n; ++k) {
        const double next = ((2.0 * k - 1) * x * current - (k - 1.0) * previous) / k;
        previous = current;
        current = next;
    }
    return {current, previous};
}

}  // namespace

QuadratureRule gaussLegendre(int n) {
    if (n < 1) throw std::invalid_argument("gaussLegendre: n must be at least 1");
    QuadratureRule rule;
    rule.nodes.resize(n);
    rule.weights.resize(n);
    // The nodes are symmetric about 0: find the non-negative half, largest first.
    for (int i = 0; i < (n + 1) / 2; ++i) {
        double x = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5));
        double derivative = 1;
        for (int iteration = 0; iteration < 100; ++iteration) {
            const auto [pn, pnMinus1] = legendre(n, x);
            derivative = n * (pnMinus1 - x * pn) / (1 - x * x);
            const double step = pn / derivative;
            x -= step;
            if (std::abs(step) <= 1e-16 * std::max(1.0, std::abs(x))) break;
        }
        const auto [pn, pnMinus1] = legendre(n, x);
        derivative = n * (pnMinus1 - x * pn) / (1 - x * x);
        const double weight = 2 / ((1 - x * x) * derivative * derivative);
        rule.nodes[i] = -x;
        rule.nodes[n - 1 - i] = x;
        rule.weights[i] = rule.weights[n - 1 - i] = weight;
    }
    return rule;
}

}  // namespace vtex::primitive
