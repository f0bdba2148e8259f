#include "identification/identifiability.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

namespace twinsim {
namespace {

// A column below this share of the largest column's norm moves no residual.
constexpr double kIgnoredShare = 1e-9;
// Partners: the other parameters with at least this share of the weakest direction.
constexpr double kPartnerShare = 0.25;

}  // namespace

Identifiability AnalyseIdentifiability(const Eigen::MatrixXd& jacobian, const std::vector<double>& preference,
                                       double max_collinearity) {
  Identifiability out;
  const int n = static_cast<int>(jacobian.cols());
  auto weight = [&](int c) { return preference.empty() ? 1.0 : preference[static_cast<std::size_t>(c)]; };
  double largest = 0;
  for (int c = 0; c < n; ++c) largest = std::max(largest, jacobian.col(c).norm());
  for (int c = 0; c < n; ++c) {
    const double norm = jacobian.col(c).norm();
    if (!(norm > kIgnoredShare * largest)) {
      out.held.push_back({c, {}, std::numeric_limits<double>::infinity()});
    } else {
      out.kept.push_back(c);
    }
  }
  while (!out.kept.empty()) {
    Eigen::MatrixXd s(jacobian.rows(), static_cast<long>(out.kept.size()));
    for (std::size_t k = 0; k < out.kept.size(); ++k) {
      const auto col = jacobian.col(out.kept[k]);
      s.col(static_cast<long>(k)) = col / col.norm();
    }
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(s, Eigen::ComputeThinV);
    const Eigen::VectorXd& sigma = svd.singularValues();
    const long last = sigma.size() - 1;
    const double gamma = sigma[last] > 0 ? 1 / sigma[last] : std::numeric_limits<double>::infinity();
    out.collinearity = gamma;
    if (gamma <= max_collinearity) break;
    const Eigen::VectorXd v = svd.matrixV().col(last);
    long worst = 0;
    for (long k = 1; k < v.size(); ++k) {
      if (std::abs(v[k]) * weight(out.kept[static_cast<std::size_t>(k)]) >
          std::abs(v[worst]) * weight(out.kept[static_cast<std::size_t>(worst)])) {
        worst = k;
      }
    }
    HeldParameter h;
    h.column = out.kept[static_cast<std::size_t>(worst)];
    h.collinearity = gamma;
    std::vector<std::pair<double, int>> shares;
    for (long k = 0; k < v.size(); ++k) {
      if (k != worst && std::abs(v[k]) >= kPartnerShare) shares.push_back({-std::abs(v[k]), out.kept[static_cast<std::size_t>(k)]});
    }
    std::sort(shares.begin(), shares.end());
    for (const auto& [share, c] : shares) h.partners.push_back(c);
    out.held.push_back(h);
    out.kept.erase(out.kept.begin() + worst);
    if (out.kept.empty()) out.collinearity = 1;
  }
  return out;
}

Eigen::MatrixXd KeptInverseNormal(const Eigen::MatrixXd& jacobian, const std::vector<int>& kept) {
  Eigen::MatrixXd j(jacobian.rows(), static_cast<long>(kept.size()));
  for (std::size_t k = 0; k < kept.size(); ++k) j.col(static_cast<long>(k)) = jacobian.col(kept[k]);
  const Eigen::MatrixXd normal = j.transpose() * j;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(normal, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::VectorXd& sigma = svd.singularValues();
  if (sigma.size() == 0 || !(sigma[sigma.size() - 1] > 1e-12 * sigma[0])) return {};
  const Eigen::MatrixXd inv = svd.matrixV() * sigma.cwiseInverse().asDiagonal() * svd.matrixU().transpose();
  if (!inv.allFinite()) return {};
  return inv;
}

}  // namespace twinsim
