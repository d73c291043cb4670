// Exact quadrature rules for band-limited functions.
#pragma once
#include <vector>

#include "prt/direction_set.hpp"

namespace prt {

// Gauss-Legendre nodes and weights on [-1, 1]: exact for polynomials of degree <= 2n - 1.
struct GaussLegendre {
  std::vector<double> nodes, weights;
};
GaussLegendre gauss_legendre(int n);

// Product rule on the sphere: n Gauss-Legendre nodes in z times 2n uniform
// angles in phi. Integrates spherical polynomials of degree <= 2n - 1 exactly
// (so products of SH up to order n).
DirectionSet gauss_product_sphere(int n);

}  // namespace prt
