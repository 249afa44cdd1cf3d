#include "maps/spectral_basis.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <string>

#include "maps/prefetch.h"
#include "maps/simd_clones.h"

namespace sage::maps {
namespace {

// cos(k a) and sin(k a), k = 0..K-1, for a = a_x and a = a_y, by the Chebyshev recurrences
//   cos((k+1)a) = 2 cos a cos(ka) - cos((k-1)a),  sin likewise,
// which cost a multiply and a subtract per k instead of a libm call. Each recurrence is one
// dependent chain, so its latency, not its arithmetic, sets the cost: the four run side by side
// on locals (no reload through the tables, which the compiler must assume may alias).
void CosSinTables(double a_x, double a_y, int order, SpectralBasis::Trigonometry& t) {
  t.cos_x[0] = t.cos_y[0] = 1.0;
  t.sin_x[0] = t.sin_y[0] = 0.0;
  if (order == 1) return;
  double cx0 = 1.0, sx0 = 0.0, cx1 = std::cos(a_x), sx1 = std::sin(a_x);
  double cy0 = 1.0, sy0 = 0.0, cy1 = std::cos(a_y), sy1 = std::sin(a_y);
  t.cos_x[1] = cx1;
  t.sin_x[1] = sx1;
  t.cos_y[1] = cy1;
  t.sin_y[1] = sy1;
  const double two_cx = 2.0 * cx1, two_cy = 2.0 * cy1;
  for (int k = 2; k < order; ++k) {
    const double cx2 = two_cx * cx1 - cx0, sx2 = two_cx * sx1 - sx0;
    const double cy2 = two_cy * cy1 - cy0, sy2 = two_cy * sy1 - sy0;
    t.cos_x[k] = cx2;
    t.sin_x[k] = sx2;
    t.cos_y[k] = cy2;
    t.sin_y[k] = sy2;
    cx0 = cx1, cx1 = cx2, sx0 = sx1, sx1 = sx2;
    cy0 = cy1, cy1 = cy2, sy0 = sy1, sy1 = sy2;
  }
}

}  // namespace

const Eigen::VectorXd& SpectralBasis::SobolevWeights(int order) {
  if (order < 1 || order > kMaxOrder) {
    throw std::invalid_argument("SpectralBasis::SobolevWeights: order = " + std::to_string(order) + ": must be in 1..64");
  }
  // Never destroyed: a basis with static storage may outlive any other static here.
  static auto* const tables = new std::array<Eigen::VectorXd, kMaxOrder + 1>;
  static auto* const built = new std::array<std::once_flag, kMaxOrder + 1>;
  Eigen::VectorXd& lambda = (*tables)[static_cast<std::size_t>(order)];
  std::call_once((*built)[static_cast<std::size_t>(order)], [&] {
    lambda.resize(order * order);
    for (int k1 = 0; k1 < order; ++k1) {
      for (int k2 = 0; k2 < order; ++k2) {
        // Lambda_k = (1 + |k|^2)^(-(n+1)/2) with n = 2 dimensions.
        lambda[Index(k1, k2, order)] = std::pow(1.0 + k1 * k1 + k2 * k2, -1.5);
      }
    }
  });
  return lambda;
}

SpectralBasis::SpectralBasis(double width_m, double height_m, int order)
    : width_m_(width_m), height_m_(height_m), order_(order) {
  if (!(width_m > 0.0) || !(height_m > 0.0)) {
    throw std::invalid_argument("SpectralBasis: workspace must have positive width and height");
  }
  if (order < 1 || order > kMaxOrder) {
    throw std::invalid_argument("SpectralBasis: order = " + std::to_string(order) + ": must be in 1..64");
  }
  lambda_ = &SobolevWeights(order);
  const auto n = static_cast<std::size_t>(order);
  tables_.resize(4 * n);
  double* kappa_x = tables_.data();
  double* kappa_y = kappa_x + n;
  double* inv_h_x = kappa_y + n;
  double* inv_h_y = inv_h_x + n;
  for (int k = 0; k < order; ++k) {
    kappa_x[k] = k * std::numbers::pi / width_m;
    kappa_y[k] = k * std::numbers::pi / height_m;
    // h_k = h_x[k1] h_y[k2], h_x[k1]^2 = integral_0^L1 cos^2(k1 pi x / L1) dx = L1 (1/2 if k1 != 0).
    inv_h_x[k] = 1.0 / std::sqrt(k == 0 ? width_m : 0.5 * width_m);
    inv_h_y[k] = 1.0 / std::sqrt(k == 0 ? height_m : 0.5 * height_m);
  }
  // h_k^2 = integral over the box of prod_j cos^2(k_j pi x_j / L_j) = area * (1/2)^(#nonzero k_j):
  // four values, at (k1, k2) = (0, 0), (0, > 0), (> 0, 0), (> 0, > 0).
  const double area = width_m * height_m;
  for (int corner = 0; corner < 4; ++corner) {
    double h2 = area;
    if (corner >= 2) h2 *= 0.5;
    if (corner % 2 == 1) h2 *= 0.5;
    h_corner_[static_cast<std::size_t>(corner)] = std::sqrt(h2);
    inv_h_corner_[static_cast<std::size_t>(corner)] = 1.0 / h_corner_[static_cast<std::size_t>(corner)];
  }
}

void SpectralBasis::EvaluateTrigonometry(const Eigen::Vector2d& x, Trigonometry& t) const {
  CosSinTables(std::numbers::pi * x.x() / width_m_, std::numbers::pi * x.y() / height_m_, order_, t);
}

void SpectralBasis::Evaluate(const Eigen::Vector2d& x, Eigen::VectorXd& f) const {
  Trigonometry t;
  EvaluateTrigonometry(x, t);
  const auto& cx = t.cos_x;
  const auto& cy = t.cos_y;
  f.resize(size());
  // 1 / h_k from its four values, not the K^2 table: a region's vehicle has a basis of its own, and
  // at 10,000 vehicles reading its table for every look at a valve was a stream of cache misses.
  for (int k1 = 0; k1 < order_; ++k1) {
    const int row = k1 * order_;
    const double first = InverseNormalizer(k1, 0), rest = order_ > 1 ? InverseNormalizer(k1, 1) : 0.0;
    f[row] = cx[k1] * cy[0] * first;
    for (int k2 = 1; k2 < order_; ++k2) f[row + k2] = cx[k1] * cy[k2] * rest;
  }
}

// F_k(x) = (cos(kappa1 x1) / h_x[k1]) (cos(kappa2 x2) / h_y[k2]): the normalised y cosines once,
// then one multiply-add a term. Every term is its own element (no reduction), so the AVX2 clone
// (maps/simd_clones.h) gives the same bits as the SSE2 one, 4,096 terms a sample at K = 64.
SAGE_AVX2_CLONES void SpectralBasis::AddScaled(const Eigen::Vector2d& x, double scale, Eigen::VectorXd& sum) const {
  Trigonometry t;
  EvaluateTrigonometry(x, t);
  const double* inv_h_x = inverse_normalizers_x().data();
  const double* inv_h_y = inverse_normalizers_y().data();
  std::array<double, kMaxOrder> y;
  for (int k2 = 0; k2 < order_; ++k2) y[k2] = t.cos_y[k2] * inv_h_y[k2];
  double* out = sum.data();
  for (int k1 = 0; k1 < order_; ++k1) {
    double* row = out + k1 * order_;
    const double c1 = scale * (t.cos_x[k1] * inv_h_x[k1]);
    for (int k2 = 0; k2 < order_; ++k2) row[k2] += c1 * y[k2];
  }
}

SAGE_AVX2_CLONES void SpectralBasis::AddScaledAll(std::span<const std::pair<Eigen::Vector2d, double>> samples,
                                                   Eigen::VectorXd& sum) const {
  // Factors of a block of samples: x's scaled cosines by k1 (each k1's run over the block
  // contiguous) and y's by sample, 2 x 16 x 64 doubles (16 kB): they and the sums' few
  // coefficients in flight stay in L1, where AddScaled streamed all K^2 sums per sample (at 10,000
  // vehicles the metric's helper thread shares a core with the vehicles' and found them in L2).
  constexpr std::size_t kBlock = 16;
  constexpr int kLanes = 16;  // coefficients of a row held across the block (four AVX2 registers)
  alignas(64) std::array<std::array<double, kBlock>, kMaxOrder> xs;
  alignas(64) std::array<std::array<double, kMaxOrder>, kBlock> ys;
  double* out = sum.data();
  const double* inv_h_x = inverse_normalizers_x().data();
  const double* inv_h_y = inverse_normalizers_y().data();
  for (std::size_t begin = 0; begin < samples.size(); begin += kBlock) {
    const std::size_t m = std::min(kBlock, samples.size() - begin);
    for (std::size_t s = 0; s < m; ++s) {
      const auto& [x, scale] = samples[begin + s];
      Trigonometry t;
      EvaluateTrigonometry(x, t);
      // The factors exactly as AddScaled forms them: c1 = scale (cos_x / h_x), y = cos_y / h_y.
      for (int k1 = 0; k1 < order_; ++k1) xs[k1][s] = scale * (t.cos_x[k1] * inv_h_x[k1]);
      for (int k2 = 0; k2 < order_; ++k2) ys[s][k2] = t.cos_y[k2] * inv_h_y[k2];
    }
    for (int k1 = 0; k1 < order_; ++k1) {
      double* row = out + k1 * order_;
      const double* c = xs[k1].data();
      int k2 = 0;
      for (; k2 + kLanes <= order_; k2 += kLanes) {
        std::array<double, kLanes> acc;
        for (int j = 0; j < kLanes; ++j) acc[j] = row[k2 + j];
        for (std::size_t s = 0; s < m; ++s) {
          const double* y = ys[s].data() + k2;
          for (int j = 0; j < kLanes; ++j) acc[j] += c[s] * y[j];
        }
        for (int j = 0; j < kLanes; ++j) row[k2 + j] = acc[j];
      }
      for (; k2 < order_; ++k2) {
        double acc = row[k2];
        for (std::size_t s = 0; s < m; ++s) acc += c[s] * ys[s][k2];
        row[k2] = acc;
      }
    }
  }
}

Eigen::Vector2d SpectralBasis::GradientOfSum(const Eigen::Vector2d& x, const Eigen::VectorXd& a) const {
  Trigonometry t;
  EvaluateTrigonometry(x, t);
  const auto& cx = t.cos_x;
  const auto& sx = t.sin_x;
  const auto& cy = t.cos_y;
  const auto& sy = t.sin_y;
  const double* kappa_x = this->kappa_x().data();
  const double* kappa_y = this->kappa_y().data();
  // d/dx1 F_k = -(kappa1 / h_k) sin(kappa1 x1) cos(kappa2 x2), d/dx2 likewise; summed row by row
  // so each k1 costs one pass over k2.
  double gx = 0.0;
  double gy = 0.0;
  for (int k1 = 0; k1 < order_; ++k1) {
    const int row = k1 * order_;
    double row_cos = 0.0;
    double row_dsin = 0.0;
    const double first = InverseNormalizer(k1, 0), rest = InverseNormalizer(k1, 1);
    for (int k2 = 0; k2 < order_; ++k2) {
      const double b = a[row + k2] * (k2 == 0 ? first : rest);
      row_cos += b * cy[k2];
      row_dsin += b * kappa_y[k2] * sy[k2];
    }
    gx -= kappa_x[k1] * sx[k1] * row_cos;
    gy -= cx[k1] * row_dsin;
  }
  return {gx, gy};
}

double SpectralBasis::Metric(const Eigen::VectorXd& coverage_error) const {
  return (lambda_->array() * coverage_error.array().square()).sum();
}

void SpectralBasis::Prefetch() const {
  PrefetchBytes(tables_.data(), sizeof(double) * tables_.size());
}

}  // namespace sage::maps
