#include "maps/spectral_basis.h"

#include <cmath>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

namespace sage::maps {
namespace {

// Midpoint-rule quadrature of f over the box on an n x n grid.
template <typename F>
double Quadrature(double width, double height, int n, F&& f) {
  const double dx = width / n, dy = height / n;
  double sum = 0.0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) sum += f(Eigen::Vector2d((i + 0.5) * dx, (j + 0.5) * dy));
  return sum * dx * dy;
}

// The F_k are orthonormal on a non-square box: <F_k, F_l> = delta_kl. Midpoint quadrature with
// 400^2 points integrates these low-order trigonometric products to ~1e-12.
TEST(SpectralBasis, OrthonormalOnTheBox) {
  const SpectralBasis basis(7.0, 5.0, 5);
  const int n = basis.size();
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(n, n);
  const int q = 400;
  const double dx = 7.0 / q, dy = 5.0 / q;
  Eigen::VectorXd f;
  for (int i = 0; i < q; ++i) {
    for (int j = 0; j < q; ++j) {
      basis.Evaluate(Eigen::Vector2d((i + 0.5) * dx, (j + 0.5) * dy), f);
      gram.noalias() += f * f.transpose() * dx * dy;
    }
  }
  EXPECT_LT((gram - Eigen::MatrixXd::Identity(n, n)).cwiseAbs().maxCoeff(), 1e-9);
}

// phi_0 = F_0 = 1 / sqrt(area) everywhere.
TEST(SpectralBasis, ZerothFunctionIsOneOverRootArea) {
  const SpectralBasis basis(12.0, 3.0, 4);
  Eigen::VectorXd f;
  for (const Eigen::Vector2d& x : {Eigen::Vector2d(0, 0), Eigen::Vector2d(5.5, 2.9), Eigen::Vector2d(12, 3)}) {
    basis.Evaluate(x, f);
    EXPECT_NEAR(f[0], 1.0 / 6.0, 1e-15);
  }
}

// The recurrence-based evaluation matches direct cosines (relative 1e-12 even at K = 64).
TEST(SpectralBasis, RecurrenceMatchesDirectCosines) {
  const SpectralBasis basis(9.0, 4.0, 64);
  Eigen::VectorXd f;
  const Eigen::Vector2d x(3.3, 1.7);
  basis.Evaluate(x, f);
  for (int k1 : {0, 1, 17, 63}) {
    for (int k2 : {0, 5, 40, 63}) {
      const int i = SpectralBasis::Index(k1, k2, 64);
      const double direct = std::cos(k1 * M_PI * x.x() / 9.0) * std::cos(k2 * M_PI * x.y() / 4.0) / basis.Normalizer(k1, k2);
      EXPECT_NEAR(f[i], direct, 1e-12);
    }
  }
}

// The shared cos/sin tables match direct libm calls (absolute 1e-12 even at K = 64, where the
// recurrences have run longest), at the box's corners and inside, for order 1 and 2 too.
// AddScaled is sum += scale F(x) against the direct cosines (not Evaluate, which shares its
// tables): at K = 64 on a 1,096 x 730 m field, over samples all across it, 1e-12 relative.
TEST(SpectralBasis, AddScaledAccumulatesScaledFunctions) {
  const SpectralBasis basis(1096.0, 730.0, 64);
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(basis.size()), expected = sum;
  const double pi = std::acos(-1.0);
  for (int s = 0; s < 40; ++s) {
    const Eigen::Vector2d x(1096.0 * std::fmod(0.37 * s + 0.05, 1.0), 730.0 * std::fmod(0.61 * s + 0.11, 1.0));
    const double scale = 0.1 + 0.01 * s;
    basis.AddScaled(x, scale, sum);
    for (int k1 = 0; k1 < 64; ++k1)
      for (int k2 = 0; k2 < 64; ++k2) {
        const int i = SpectralBasis::Index(k1, k2, 64);
        expected[i] += scale * std::cos(k1 * pi * x.x() / 1096.0) * std::cos(k2 * pi * x.y() / 730.0) *
                       basis.InverseNormalizer(k1, k2);
      }
  }
  EXPECT_LT((sum - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff());
}

// AddScaledAll is AddScaled of each sample in turn, to the bit (the fleet metric's sums must not
// depend on how a mission's samples were batched): orders with and without a tail past the
// 16-coefficient runs, and sample counts with and without a tail past the 16-sample blocks.
TEST(SpectralBasis, AddScaledAllIsAddScaledOfEachInTurn) {
  for (const int order : {1, 13, 16, 37, 64}) {
    const SpectralBasis basis(1096.0, 730.0, order);
    for (const std::size_t count : {1u, 16u, 37u, 200u}) {
      std::vector<std::pair<Eigen::Vector2d, double>> samples;
      for (std::size_t s = 0; s < count; ++s) {
        samples.emplace_back(Eigen::Vector2d(1096.0 * std::fmod(0.37 * s + 0.05, 1.0), 730.0 * std::fmod(0.61 * s + 0.11, 1.0)),
                             0.1 + 0.003 * static_cast<double>(s % 7));
      }
      Eigen::VectorXd one_by_one = Eigen::VectorXd::LinSpaced(basis.size(), -1.0, 1.0), batched = one_by_one;
      for (const auto& [x, scale] : samples) basis.AddScaled(x, scale, one_by_one);
      basis.AddScaledAll(samples, batched);
      ASSERT_EQ(batched.size(), one_by_one.size());
      for (Eigen::Index k = 0; k < batched.size(); ++k) {
        ASSERT_EQ(batched[k], one_by_one[k]) << "order " << order << ", " << count << " samples, coefficient " << k;
      }
      EXPECT_GT((batched - Eigen::VectorXd::LinSpaced(basis.size(), -1.0, 1.0)).cwiseAbs().maxCoeff(), 0.0);
    }
  }
}

TEST(SpectralBasis, TrigonometryTablesMatchDirectCalls) {
  for (int order : {1, 2, 64}) {
    const SpectralBasis basis(9.0, 4.0, order);
    for (const Eigen::Vector2d& x : {Eigen::Vector2d(0, 0), Eigen::Vector2d(3.3, 1.7), Eigen::Vector2d(9, 4)}) {
      SpectralBasis::Trigonometry t;
      basis.EvaluateTrigonometry(x, t);
      for (int k = 0; k < order; ++k) {
        const double ax = k * M_PI * x.x() / 9.0, ay = k * M_PI * x.y() / 4.0;
        ASSERT_NEAR(t.cos_x[k], std::cos(ax), 1e-12) << "order " << order << " k " << k;
        ASSERT_NEAR(t.sin_x[k], std::sin(ax), 1e-12) << "order " << order << " k " << k;
        ASSERT_NEAR(t.cos_y[k], std::cos(ay), 1e-12) << "order " << order << " k " << k;
        ASSERT_NEAR(t.sin_y[k], std::sin(ay), 1e-12) << "order " << order << " k " << k;
      }
    }
  }
}

// 1 / h_k factors into one normaliser per dimension (to a few ulp), which the SMC step uses to
// form F_k as an outer product.
TEST(SpectralBasis, InverseNormalizersFactorPerDimension) {
  const SpectralBasis basis(7.0, 5.0, 20);
  for (int k1 = 0; k1 < 20; ++k1) {
    for (int k2 = 0; k2 < 20; ++k2) {
      const double product = basis.inverse_normalizers_x()[k1] * basis.inverse_normalizers_y()[k2];
      ASSERT_NEAR(product, basis.InverseNormalizer(k1, k2), 1e-15 * basis.InverseNormalizer(k1, k2));
      ASSERT_NEAR(basis.InverseNormalizer(k1, k2) * basis.Normalizer(k1, k2), 1.0, 1e-15);
      // h_k^2 = integral over the box of cos^2(k1 pi x / 7) cos^2(k2 pi y / 5), by the midpoint rule.
      if (k1 < 3 && k2 < 3) {
        constexpr int kCells = 400;
        double integral = 0.0;
        for (int a = 0; a < kCells; ++a)
          for (int b = 0; b < kCells; ++b) {
            const double cx = std::cos(k1 * M_PI * (a + 0.5) / kCells), cy = std::cos(k2 * M_PI * (b + 0.5) / kCells);
            integral += cx * cx * cy * cy * (7.0 / kCells) * (5.0 / kCells);
          }
        ASSERT_NEAR(basis.Normalizer(k1, k2), std::sqrt(integral), 1e-9) << k1 << ", " << k2;
      }
    }
  }
}

// grad sum_k a_k F_k against central finite differences (step 1e-6 m: error ~1e-8 relative).
TEST(SpectralBasis, GradientMatchesFiniteDifferences) {
  const SpectralBasis basis(7.0, 5.0, 20);
  Eigen::VectorXd a = Eigen::VectorXd::LinSpaced(basis.size(), -1.0, 1.0).array().sin();
  auto value = [&](const Eigen::Vector2d& x) {
    Eigen::VectorXd f;
    basis.Evaluate(x, f);
    return a.dot(f);
  };
  const double step = 1e-6;
  for (const Eigen::Vector2d& x : {Eigen::Vector2d(1.2, 3.4), Eigen::Vector2d(6.9, 0.1), Eigen::Vector2d(3.5, 2.5)}) {
    const Eigen::Vector2d g = basis.GradientOfSum(x, a);
    const double fd_x = (value(x + Eigen::Vector2d(step, 0)) - value(x - Eigen::Vector2d(step, 0))) / (2 * step);
    const double fd_y = (value(x + Eigen::Vector2d(0, step)) - value(x - Eigen::Vector2d(0, step))) / (2 * step);
    const double scale = std::max(1.0, g.norm());
    EXPECT_NEAR(g.x(), fd_x, 1e-6 * scale);
    EXPECT_NEAR(g.y(), fd_y, 1e-6 * scale);
  }
}

// Lambda_k = (1 + |k|^2)^(-3/2) and the metric is the Lambda-weighted squared error.
TEST(SpectralBasis, MetricWeightsAreSobolev) {
  const SpectralBasis basis(1.0, 1.0, 3);
  EXPECT_DOUBLE_EQ(basis.weights()[SpectralBasis::Index(2, 1, 3)], std::pow(6.0, -1.5));
  Eigen::VectorXd e = Eigen::VectorXd::Zero(9);
  e[SpectralBasis::Index(1, 1, 3)] = 2.0;
  EXPECT_NEAR(basis.Metric(e), 4.0 * std::pow(3.0, -1.5), 1e-15);
}

TEST(SpectralBasis, RejectsBadArguments) {
  EXPECT_THROW(SpectralBasis(0.0, 1.0, 4), std::invalid_argument);
  EXPECT_THROW(SpectralBasis(1.0, 1.0, 0), std::invalid_argument);
  EXPECT_THROW(SpectralBasis(1.0, 1.0, 65), std::invalid_argument);
}

}  // namespace
}  // namespace sage::maps
