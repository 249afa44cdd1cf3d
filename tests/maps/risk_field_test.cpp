#include "maps/risk_field.h"

#include <cmath>
#include <numbers>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <gtest/gtest.h>

namespace sage::maps {
namespace {

double GaussianDensity(const GaussianComponent& g, const Eigen::Vector2d& x) {
  const Eigen::Vector2d d = x - g.mean_m;
  return std::exp(-0.5 * d.dot(g.covariance_m2.inverse() * d)) /
         (2 * std::numbers::pi * std::sqrt(g.covariance_m2.determinant()));
}

// Midpoint quadrature of N(x) F_k(x) over [x0, x1] x [y0, y1] for all k at once.
Eigen::VectorXd QuadratureCoefficients(const SpectralBasis& basis, const GaussianComponent& g, double x0, double x1,
                                       double y0, double y1, int n) {
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(basis.size()), f;
  const double dx = (x1 - x0) / n, dy = (y1 - y0) / n;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const Eigen::Vector2d x(x0 + (i + 0.5) * dx, y0 + (j + 0.5) * dy);
      basis.Evaluate(x, f);  // cosines extend evenly and periodically beyond the box
      sum += GaussianDensity(g, x) * f;
    }
  }
  return sum * dx * dy;
}

GaussianComponent Correlated() {
  GaussianComponent g;
  g.mean_m = Eigen::Vector2d(2.6, 1.9);
  g.covariance_m2 << 0.16, 0.06, 0.06, 0.09;  // correlation 0.5
  return g;
}

// The closed form is exact for the whole-plane integral (the Gaussian mirrored into the box):
// quadrature over +-8 sigma of the plane (tail mass < 1e-14) agrees to 1e-7, the quadrature error.
TEST(RiskField, ClosedFormMatchesWholePlaneQuadrature) {
  const SpectralBasis basis(7.0, 5.0, 10);
  const GaussianComponent g = Correlated();
  const Eigen::VectorXd closed = RiskField::GaussianCoefficients(basis, g);
  const Eigen::VectorXd quad = QuadratureCoefficients(basis, g, 2.6 - 3.2, 2.6 + 3.2, 1.9 - 2.4, 1.9 + 2.4, 800);
  EXPECT_LT((closed - quad).cwiseAbs().maxCoeff(), 1e-7);
}

// Without correlation (every valve's covariance) the closed form takes its separable path: the
// same whole-plane quadrature, isotropic and not, agrees to 1e-7.
TEST(RiskField, UncorrelatedClosedFormMatchesWholePlaneQuadrature) {
  const SpectralBasis basis(7.0, 5.0, 12);
  for (const Eigen::Vector2d& sigma : {Eigen::Vector2d(0.3, 0.3), Eigen::Vector2d(0.45, 0.2)}) {
    GaussianComponent g;
    g.mean_m = Eigen::Vector2d(4.1, 2.3);
    g.covariance_m2 = sigma.cwiseAbs2().asDiagonal();
    const Eigen::VectorXd closed = RiskField::GaussianCoefficients(basis, g);
    const Eigen::VectorXd quad = QuadratureCoefficients(basis, g, 4.1 - 8 * sigma.x(), 4.1 + 8 * sigma.x(),
                                                        2.3 - 8 * sigma.y(), 2.3 + 8 * sigma.y(), 800);
    EXPECT_LT((closed - quad).cwiseAbs().maxCoeff(), 1e-7) << "sigma " << sigma.transpose();
  }
}

// Against quadrature of the box-truncated Gaussian the closed form differs by the mass outside
// the box folded back in. For a valve 1.0 m (2.5 sigma_x) from the nearest wall the folded mass
// is ~1e-2 of the total, and |F_k| <= 2 / sqrt(area), so the difference is bounded by
// 2 * outside_mass / sqrt(area); we check that bound with the outside mass computed by quadrature.
TEST(RiskField, ClosedFormMatchesBoxTruncatedQuadratureWithinFoldedMass) {
  const SpectralBasis basis(7.0, 5.0, 10);
  GaussianComponent g = Correlated();
  g.mean_m = Eigen::Vector2d(1.0, 1.2);
  const Eigen::VectorXd closed = RiskField::GaussianCoefficients(basis, g);
  const Eigen::VectorXd truncated = QuadratureCoefficients(basis, g, 0.0, 7.0, 0.0, 5.0, 700);
  const double inside_mass = truncated[0] * std::sqrt(35.0);  // F_0 = 1/sqrt(area)
  const double outside_mass = 1.0 - inside_mass;
  ASSERT_GT(outside_mass, 1e-4);  // the case is meant to have some mass outside
  const double bound = 2.0 * outside_mass / std::sqrt(35.0) + 1e-7;
  const double max_difference = (closed - truncated).cwiseAbs().maxCoeff();
  EXPECT_LT(max_difference, bound);
  EXPECT_GT(max_difference, 1e-6);  // and the truncation really is visible: the two are not the same integral
}

// phi_0 of any normalised mixture is 1 / sqrt(area), and phi_k is linear in the weights.
TEST(RiskField, WeightChangeReweightsCachedCoefficients) {
  const SpectralBasis basis(7.0, 5.0, 12);
  std::vector<GaussianComponent> parts(3);
  parts[0].mean_m = {1.5, 1.5};
  parts[1].mean_m = {5.0, 2.0};
  parts[2].mean_m = {3.0, 4.0};
  for (auto& p : parts) p.covariance_m2 = 0.09 * Eigen::Matrix2d::Identity();
  RiskField field(basis, parts);
  field.SetWeights(Eigen::Vector3d(5.5, 2.0, 2.5));
  EXPECT_NEAR(field.coefficients()[0], 1.0 / std::sqrt(35.0), 1e-12);
  EXPECT_NEAR(field.weights().sum(), 1.0, 1e-15);
  const Eigen::VectorXd expected = 0.55 * RiskField::GaussianCoefficients(basis, parts[0]) +
                                   0.20 * RiskField::GaussianCoefficients(basis, parts[1]) +
                                   0.25 * RiskField::GaussianCoefficients(basis, parts[2]);
  EXPECT_LT((field.coefficients() - expected).cwiseAbs().maxCoeff(), 1e-14);
  field.SetWeight(1, 0.0);
  EXPECT_NEAR(field.weights()[1], 0.0, 0.0);
  EXPECT_NEAR(field.weights()[0], 5.5 / 8.0, 1e-15);
}

// The density integrates to 1 over the plane (quadrature over +-6 sigma, tolerance 1e-6).
TEST(RiskField, DensityIsNormalised) {
  const SpectralBasis basis(7.0, 5.0, 2);
  std::vector<GaussianComponent> parts(2);
  parts[0] = Correlated();
  parts[1].mean_m = {4.0, 2.0};
  parts[1].covariance_m2 = 0.04 * Eigen::Matrix2d::Identity();
  RiskField field(basis, parts);
  field.SetWeights(Eigen::Vector2d(1.0, 3.0));
  double sum = 0.0;
  const int n = 600;
  const double x0 = -1.0, x1 = 8.0, y0 = -1.5, y1 = 5.5;
  const double dx = (x1 - x0) / n, dy = (y1 - y0) / n;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) sum += field.Density({x0 + (i + 0.5) * dx, y0 + (j + 0.5) * dy});
  EXPECT_NEAR(sum * dx * dy, 1.0, 1e-6);
}

TEST(RiskField, RejectsInvalidWeights) {
  const SpectralBasis basis(7.0, 5.0, 4);
  RiskField field(basis, std::vector<GaussianComponent>(2));
  EXPECT_THROW(field.SetWeights(Eigen::Vector2d(0.0, 0.0)), std::invalid_argument);
  EXPECT_THROW(field.SetWeights(Eigen::Vector2d(-1.0, 2.0)), std::invalid_argument);
  EXPECT_THROW(field.SetWeight(2, 1.0), std::out_of_range);
}

// A valve's target narrowed to a largest standard deviation: the covariance keeps its axes and
// their ratio (eigenvectors and eigenvalue ratio, from Eigen's solver: an independent computation),
// its larger eigenvalue becomes max_sigma^2 (1e-12 relative); one already narrower is kept as it is.
TEST(RiskField, NarrowedTargetKeepsItsShapeAndCapsItsWidth) {
  Eigen::Matrix2d rotated;
  rotated << 0.09, 0.03, 0.03, 0.05;  // tilted, sigma 0.33 m and 0.19 m along its axes
  const GaussianComponent valve{{3.0, 4.0}, rotated};
  const GaussianComponent narrow = NarrowedTo(valve, 0.15);
  EXPECT_EQ(narrow.mean_m, valve.mean_m);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> before(valve.covariance_m2), after(narrow.covariance_m2);
  EXPECT_NEAR(after.eigenvalues()[1], 0.15 * 0.15, 1e-12 * 0.0225);
  EXPECT_NEAR(after.eigenvalues()[0] / after.eigenvalues()[1], before.eigenvalues()[0] / before.eigenvalues()[1], 1e-12);
  EXPECT_NEAR(std::abs(after.eigenvectors().col(1).dot(before.eigenvectors().col(1))), 1.0, 1e-12);
  const GaussianComponent slim{{1.0, 1.0}, 0.01 * Eigen::Matrix2d::Identity()};  // sigma 0.1 m
  EXPECT_EQ(NarrowedTo(slim, 0.15).covariance_m2, slim.covariance_m2);
}

}  // namespace
}  // namespace sage::maps
