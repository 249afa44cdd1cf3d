#include "maps/spectral_basis.h"

#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace sage::maps {
namespace {

constexpr int kMaxOrder = 64;

// cos(k a) and sin(k a) for k = 0..K-1 by the Chebyshev recurrences
//   cos((k+1)a) = 2 cos a cos(ka) - cos((k-1)a),  sin likewise,
// which cost two multiply-adds per k instead of a libm call.
void CosSinTable(double a, int order, double* c, double* s) {
  c[0] = 1.0;
  s[0] = 0.0;
  if (order == 1) return;
  const double ca = std::cos(a);
  c[1] = ca;
  s[1] = std::sin(a);
  const double two_ca = 2.0 * ca;
  for (int k = 2; k < order; ++k) {
    c[k] = two_ca * c[k - 1] - c[k - 2];
    s[k] = two_ca * s[k - 1] - s[k - 2];
  }
}

}  // namespace

SpectralBasis::SpectralBasis(double width_m, double height_m, int order)
    : width_m_(width_m), height_m_(height_m), order_(order) {
  if (!(width_m > 0.0) || !(height_m > 0.0)) {
    throw std::invalid_argument("SpectralBasis: workspace must have positive width and height");
  }
  if (order < 1 || order > kMaxOrder) {
    throw std::invalid_argument("SpectralBasis: order = " + std::to_string(order) + ": must be in 1..64");
  }
  const int n = size();
  h_.resize(n);
  inv_h_.resize(n);
  lambda_.resize(n);
  kappa_x_.resize(order);
  kappa_y_.resize(order);
  for (int k = 0; k < order; ++k) {
    kappa_x_[k] = k * std::numbers::pi / width_m;
    kappa_y_[k] = k * std::numbers::pi / height_m;
  }
  const double area = width_m * height_m;
  for (int k1 = 0; k1 < order; ++k1) {
    for (int k2 = 0; k2 < order; ++k2) {
      const int i = Index(k1, k2, order);
      // h_k^2 = integral over the box of prod_j cos^2(k_j pi x_j / L_j) = area * (1/2)^(#nonzero k_j).
      double h2 = area;
      if (k1 != 0) h2 *= 0.5;
      if (k2 != 0) h2 *= 0.5;
      h_[i] = std::sqrt(h2);
      inv_h_[i] = 1.0 / h_[i];
      // Lambda_k = (1 + |k|^2)^(-(n+1)/2) with n = 2 dimensions.
      lambda_[i] = std::pow(1.0 + k1 * k1 + k2 * k2, -1.5);
    }
  }
}

void SpectralBasis::Evaluate(const Eigen::Vector2d& x, Eigen::VectorXd& f) const {
  std::array<double, kMaxOrder> cx, sx, cy, sy;
  CosSinTable(std::numbers::pi * x.x() / width_m_, order_, cx.data(), sx.data());
  CosSinTable(std::numbers::pi * x.y() / height_m_, order_, cy.data(), sy.data());
  f.resize(size());
  for (int k1 = 0; k1 < order_; ++k1) {
    const int row = k1 * order_;
    for (int k2 = 0; k2 < order_; ++k2) f[row + k2] = cx[k1] * cy[k2] * inv_h_[row + k2];
  }
}

Eigen::Vector2d SpectralBasis::GradientOfSum(const Eigen::Vector2d& x, const Eigen::VectorXd& a) const {
  std::array<double, kMaxOrder> cx, sx, cy, sy;
  CosSinTable(std::numbers::pi * x.x() / width_m_, order_, cx.data(), sx.data());
  CosSinTable(std::numbers::pi * x.y() / height_m_, order_, cy.data(), sy.data());
  // d/dx1 F_k = -(kappa1 / h_k) sin(kappa1 x1) cos(kappa2 x2), d/dx2 likewise; summed row by row
  // so each k1 costs one pass over k2.
  double gx = 0.0;
  double gy = 0.0;
  for (int k1 = 0; k1 < order_; ++k1) {
    const int row = k1 * order_;
    double row_cos = 0.0;
    double row_dsin = 0.0;
    for (int k2 = 0; k2 < order_; ++k2) {
      const double b = a[row + k2] * inv_h_[row + k2];
      row_cos += b * cy[k2];
      row_dsin += b * kappa_y_[k2] * sy[k2];
    }
    gx -= kappa_x_[k1] * sx[k1] * row_cos;
    gy -= cx[k1] * row_dsin;
  }
  return {gx, gy};
}

double SpectralBasis::Metric(const Eigen::VectorXd& coverage_error) const {
  return (lambda_.array() * coverage_error.array().square()).sum();
}

}  // namespace sage::maps
