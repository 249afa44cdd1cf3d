#pragma once
// Cosine basis of Mathew & Mezic (2011) on the box [0, L1] x [0, L2]:
//   F_k(x) = (1/h_k) cos(k1 pi x1 / L1) cos(k2 pi x2 / L2),
//   h_k = sqrt(L1 L2 prod_{j: k_j != 0} 1/2)   so that the F_k are orthonormal on the box,
//   Lambda_k = (1 + |k|^2)^(-(n+1)/2), n = 2   (Sobolev weight of the ergodic metric).
// Coefficient k = (k1, k2), 0 <= k1, k2 < K, is stored at flat index k1 * K + k2.
#include <array>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace sage::maps {

class SpectralBasis {
 public:
  /// Largest order K accepted (per-position tables live on the stack at this length).
  static constexpr int kMaxOrder = 64;

  /// cos(kappa_k x_j) and sin(kappa_k x_j) for k = 0..K-1 at one position: the factors of F_k and
  /// of its gradient. Only the first order() entries of each table are set.
  struct Trigonometry {
    std::array<double, kMaxOrder> cos_x, sin_x, cos_y, sin_y;
  };

  /// width_m, height_m: workspace extent in metres (> 0); order: K, the number of
  /// wave numbers per dimension (>= 1), giving K^2 coefficients.
  SpectralBasis(double width_m, double height_m, int order);

  int order() const { return order_; }
  int size() const { return order_ * order_; }
  double width_m() const { return width_m_; }
  double height_m() const { return height_m_; }
  static int Index(int k1, int k2, int order) { return k1 * order + k2; }

  /// Metric weights Lambda_k, flat-indexed. Lambda_k depends on k alone, so every basis of an
  /// order reads one table (SobolevWeights): a fleet of region vehicles, each on a basis of its
  /// own, steers on one copy of it instead of one each.
  const Eigen::VectorXd& weights() const { return *lambda_; }
  /// Lambda_k = (1 + |k|^2)^(-3/2) for order K (1..kMaxOrder), flat-indexed; built once per order
  /// (thread-safe) and kept for the process's life.
  static const Eigen::VectorXd& SobolevWeights(int order);
  /// The normaliser h_k (metres) at (k1, k2): h_k takes four values (k1 = 0 or not, k2 = 0 or
  /// not), so a basis keeps those, not a K^2 table (a region vehicle's basis of its own had carried
  /// two such tables, 5 kB at K = 18, that its steps never read).
  double Normalizer(int k1, int k2) const { return h_corner_[Corner(k1, k2)]; }
  /// 1 / h_k (1/m) at (k1, k2), as 1 / Normalizer(k1, k2): F_k(x) = cos_x[k1] cos_y[k2] / h_k.
  double InverseNormalizer(int k1, int k2) const { return inv_h_corner_[Corner(k1, k2)]; }
  /// The per-dimension factors of 1 / h_k (1/sqrt(m)), indexed by k1 and k2:
  /// 1 / h_k = inverse_normalizers_x()[k1] * inverse_normalizers_y()[k2] (to rounding), so F_k is
  /// the product of one normalised cosine per dimension.
  std::span<const double> inverse_normalizers_x() const { return Table(2); }
  std::span<const double> inverse_normalizers_y() const { return Table(3); }
  /// Wave numbers kappa_j = k_j pi / L_j (rad/m) for dimension 0 (x) and 1 (y).
  std::span<const double> kappa_x() const { return Table(0); }
  std::span<const double> kappa_y() const { return Table(1); }
  /// Asks for what one SMC step reads of the basis (the per-dimension tables) to be brought into
  /// cache (maps/prefetch.h); changes nothing.
  void Prefetch() const;

  /// The cosine and sine tables at x (metres, workspace frame), by Chebyshev recurrences: one
  /// sin/cos pair per dimension whatever K. For callers that fuse F_k or its gradient into their
  /// own pass over k (the SMC step).
  void EvaluateTrigonometry(const Eigen::Vector2d& x, Trigonometry& t) const;

  /// F_k(x) for all k into f (resized to size()). x in metres, workspace frame.
  void Evaluate(const Eigen::Vector2d& x, Eigen::VectorXd& f) const;
  /// sum += scale F(x), in one pass with no F vector, F_k as the product of one normalised cosine
  /// per dimension (equal to Evaluate's to rounding; a fleet's metric accumulates a sample of
  /// every vehicle every cycle: at 10,000 vehicles and K = 64, 41 million terms).
  void AddScaled(const Eigen::Vector2d& x, double scale, Eigen::VectorXd& sum) const;
  /// AddScaled of each (x, scale) in turn, to the same bits (every coefficient takes the samples'
  /// terms in their order), a block of samples at a time: each block's cosines are formed once and
  /// the sums swept once per block, a few coefficients held in registers while the block's terms go
  /// in, instead of all K^2 sums (32 kB at K = 64) loaded and stored again for every sample.
  void AddScaledAll(std::span<const std::pair<Eigen::Vector2d, double>> samples, Eigen::VectorXd& sum) const;

  /// Gradient of sum_k a_k F_k at x (1/m times units of a). Used by the SMC law with
  /// a_k = Lambda_k (c_k - phi_k); costs O(K^2) with no allocation.
  Eigen::Vector2d GradientOfSum(const Eigen::Vector2d& x, const Eigen::VectorXd& a) const;

  /// Ergodic metric sum_k Lambda_k (c_k - phi_k)^2 of a coverage error e = c - phi.
  double Metric(const Eigen::VectorXd& coverage_error) const;

 private:
  static int Corner(int k1, int k2) { return (k1 != 0 ? 2 : 0) + (k2 != 0 ? 1 : 0); }
  std::span<const double> Table(int which) const {
    const auto n = static_cast<std::size_t>(order_);
    return {tables_.data() + static_cast<std::size_t>(which) * n, n};
  }

  double width_m_;
  double height_m_;
  int order_;
  std::array<double, 4> h_corner_{};      // h_k at (0, 0), (0, > 0), (> 0, 0), (> 0, > 0)
  std::array<double, 4> inv_h_corner_{};  // 1 / h_k at the same
  const Eigen::VectorXd* lambda_;  // SobolevWeights(order_): shared by every basis of the order
  // kappa_x, kappa_y, 1/h_x, 1/h_y, K each, in one block: what an SMC step reads of its basis is
  // one contiguous run (four allocations of their own had been four cache misses a step at 10,000
  // vehicles, each on a basis of its own).
  std::vector<double> tables_;
};

}  // namespace sage::maps
