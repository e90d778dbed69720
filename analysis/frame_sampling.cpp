#include "analysis/frame_sampling.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace tbdr {

namespace {

double squared_distance(const std::vector<double>& a, const std::vector<double>& b) {
  double d = 0;
  for (std::size_t i = 0; i < a.size(); ++i) d += (a[i] - b[i]) * (a[i] - b[i]);
  return d;
}

/// The frames' features scaled to unit standard deviation (constant ones dropped).
std::vector<std::vector<double>> standardised(const std::vector<std::vector<double>>& rows) {
  const std::size_t n = rows.size(), f = rows.front().size();
  std::vector<std::vector<double>> out(n);
  for (std::size_t j = 0; j < f; ++j) {
    double mean = 0;
    for (const auto& r : rows) mean += r[j];
    mean /= static_cast<double>(n);
    double var = 0;
    for (const auto& r : rows) var += (r[j] - mean) * (r[j] - mean);
    const double sd = std::sqrt(var / static_cast<double>(n));
    if (!(sd > 1e-12 * std::max(1.0, std::abs(mean)))) continue;
    for (std::size_t i = 0; i < n; ++i) out[i].push_back((rows[i][j] - mean) / sd);
  }
  return out;
}

/// k-means over `points` (indices into them are the group members): returns each point's group.
std::vector<std::size_t> kmeans(const std::vector<std::vector<double>>& points, std::size_t k) {
  const std::size_t n = points.size();
  const std::size_t dims = points.front().size();
  std::vector<std::vector<double>> centres;
  // First centre: the point nearest the mean; then each farthest from the centres so far.
  std::vector<double> mean(dims, 0.0);
  for (const auto& p : points) {
    for (std::size_t d = 0; d < dims; ++d) mean[d] += p[d] / static_cast<double>(n);
  }
  std::size_t first = 0;
  for (std::size_t i = 1; i < n; ++i) {
    if (squared_distance(points[i], mean) < squared_distance(points[first], mean)) first = i;
  }
  centres.push_back(points[first]);
  std::vector<double> nearest(n);
  for (std::size_t i = 0; i < n; ++i) nearest[i] = squared_distance(points[i], centres[0]);
  while (centres.size() < k) {
    std::size_t far = 0;
    for (std::size_t i = 1; i < n; ++i) {
      if (nearest[i] > nearest[far]) far = i;
    }
    if (!(nearest[far] > 0)) break;  // fewer distinct points than groups
    centres.push_back(points[far]);
    for (std::size_t i = 0; i < n; ++i) nearest[i] = std::min(nearest[i], squared_distance(points[i], centres.back()));
  }
  std::vector<std::size_t> group(n, 0);
  for (int round = 0; round < kSamplingMaxRounds; ++round) {
    bool moved = false;
    for (std::size_t i = 0; i < n; ++i) {
      std::size_t best = 0;
      for (std::size_t c = 1; c < centres.size(); ++c) {
        if (squared_distance(points[i], centres[c]) < squared_distance(points[i], centres[best])) best = c;
      }
      moved = moved || best != group[i];
      group[i] = best;
    }
    if (!moved) break;
    std::vector<std::vector<double>> sum(centres.size(), std::vector<double>(dims, 0.0));
    std::vector<std::size_t> count(centres.size(), 0);
    for (std::size_t i = 0; i < n; ++i) {
      ++count[group[i]];
      for (std::size_t d = 0; d < dims; ++d) sum[group[i]][d] += points[i][d];
    }
    for (std::size_t c = 0; c < centres.size(); ++c) {
      if (count[c] == 0) continue;  // an emptied group keeps its centre (and stays empty)
      for (std::size_t d = 0; d < dims; ++d) centres[c][d] = sum[c][d] / static_cast<double>(count[c]);
    }
  }
  return group;
}

}  // namespace

SamplingPlan plan_sampling(const std::vector<std::vector<double>>& signatures, std::size_t representatives) {
  const std::size_t n = signatures.size();
  if (n == 0 || representatives == 0) throw std::invalid_argument("plan_sampling: no frames or no representatives");
  for (const auto& s : signatures) {
    if (s.size() != signatures.front().size()) throw std::invalid_argument("plan_sampling: signatures of different lengths");
  }
  SamplingPlan plan;
  plan.group_of.assign(n, 0);
  const std::size_t cold = std::min(kSampledColdFrames, n);
  const std::size_t drain = n > kSampledColdFrames + kSampledDrainFrames ? kSampledDrainFrames : 0;
  auto add_group = [&plan](std::size_t representative, std::size_t members) {
    plan.representative.push_back(representative);
    plan.members.push_back(members);
  };
  std::vector<std::size_t> order;  // the frames k-means groups
  for (std::size_t i = 0; i < n; ++i) {
    if (i < cold || i >= n - drain || representatives >= n) {
      plan.group_of[i] = plan.groups();
      add_group(i, 1);
    } else {
      order.push_back(i);
    }
  }
  if (!order.empty()) {
    const std::size_t k = std::max<std::size_t>(1, representatives > cold + drain ? representatives - cold - drain : 1);
    std::vector<std::vector<double>> rows;
    for (std::size_t i : order) rows.push_back(signatures[i]);
    const std::vector<std::vector<double>> points = standardised(rows);
    const std::vector<std::size_t> group = points.front().empty() ? std::vector<std::size_t>(order.size(), 0) : kmeans(points, k);
    const std::size_t groups = *std::max_element(group.begin(), group.end()) + 1;
    for (std::size_t g = 0; g < groups; ++g) {
      // Members, centre, and the member nearest the centre (ties: the lower frame).
      std::vector<std::size_t> members;
      for (std::size_t m = 0; m < order.size(); ++m) {
        if (group[m] == g) members.push_back(m);
      }
      if (members.empty()) continue;
      std::size_t best = members.front();
      if (!points.front().empty()) {
        std::vector<double> centre(points.front().size(), 0.0);
        for (std::size_t m : members) {
          for (std::size_t d = 0; d < centre.size(); ++d) centre[d] += points[m][d] / static_cast<double>(members.size());
        }
        for (std::size_t m : members) {
          if (squared_distance(points[m], centre) < squared_distance(points[best], centre)) best = m;
        }
      }
      for (std::size_t m : members) plan.group_of[order[m]] = plan.groups();
      add_group(order[best], members.size());
    }
  }
  // Each group's mean and standard deviation of each feature over its frames.
  const std::size_t features = signatures.front().size();
  plan.feature_mean.assign(plan.groups(), std::vector<double>(features, 0.0));
  plan.feature_sd.assign(plan.groups(), std::vector<double>(features, 0.0));
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t g = plan.group_of[i];
    for (std::size_t j = 0; j < features; ++j) plan.feature_mean[g][j] += signatures[i][j] / static_cast<double>(plan.members[g]);
  }
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t g = plan.group_of[i];
    for (std::size_t j = 0; j < features; ++j) {
      const double d = signatures[i][j] - plan.feature_mean[g][j];
      plan.feature_sd[g][j] += d * d / static_cast<double>(plan.members[g]);
    }
  }
  for (auto& sd : plan.feature_sd) {
    for (double& v : sd) v = std::sqrt(v);
  }
  return plan;
}

namespace {

/// The least-squares slope of y on x and the squared correlation, or nothing when x does not vary.
struct Fit {
  double slope = 0;
  double r2 = -1;
};
Fit least_squares(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    mx += x[i] / n;
    my += y[i] / n;
  }
  double sxx = 0, syy = 0, sxy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxx += (x[i] - mx) * (x[i] - mx);
    syy += (y[i] - my) * (y[i] - my);
    sxy += (x[i] - mx) * (y[i] - my);
  }
  if (!(sxx > 0)) return {};
  return {sxy / sxx, syy > 0 ? sxy * sxy / (sxx * syy) : 0.0};
}

}  // namespace

SampledTotal extrapolate(const SamplingPlan& plan, const std::vector<std::vector<double>>& signatures,
                         const std::vector<double>& measured) {
  if (measured.size() != plan.groups()) throw std::invalid_argument("extrapolate: one value per group");
  SampledTotal t;
  for (std::size_t g = 0; g < plan.groups(); ++g) t.total += static_cast<double>(plan.members[g]) * measured[g];
  // The feature that predicts the figure best over the representatives (not the cold or drain
  // frames, whose figures their state sets, not what they draw).
  const std::size_t n_frames = plan.group_of.size();
  std::vector<std::size_t> fitted;
  for (std::size_t g = 0; g < plan.groups(); ++g) {
    const std::size_t r = plan.representative[g];
    if (r >= kSampledColdFrames && r + kSampledDrainFrames < n_frames) fitted.push_back(g);
  }
  const std::size_t features = signatures.empty() ? 0 : signatures.front().size();
  double slope = 0, best_r2 = -1;
  if (fitted.size() >= 3) {
    std::vector<double> y;
    for (std::size_t g : fitted) y.push_back(measured[g]);
    for (std::size_t j = 0; j < features; ++j) {
      std::vector<double> x;
      for (std::size_t g : fitted) x.push_back(signatures.at(plan.representative[g]).at(j));
      const Fit f = least_squares(x, y);
      if (f.r2 > best_r2) {
        best_r2 = f.r2;
        slope = f.slope;
        t.fitted_feature = static_cast<int>(j);
      }
    }
  }
  double variance = 0;
  for (std::size_t g = 0; g < plan.groups(); ++g) {
    const double n = static_cast<double>(plan.members[g]);
    double sigma = 0;  // the figure's standard deviation over the group's frames, predicted
    if (t.fitted_feature >= 0) {
      sigma = std::abs(slope) * plan.feature_sd[g][static_cast<std::size_t>(t.fitted_feature)];
    } else {
      for (std::size_t j = 0; j < features; ++j) {
        const double mean = std::abs(plan.feature_mean[g][j]);
        if (mean > 0) sigma = std::max(sigma, plan.feature_sd[g][j] / mean * std::abs(measured[g]));
      }
    }
    // Var(n x y_r) for a member drawn at random: n^2 sigma^2 (n - 1) / n.
    variance += n * n * sigma * sigma * (n - 1) / n;
  }
  t.error_pct = std::abs(t.total) > 0 ? 200.0 * std::sqrt(variance) / std::abs(t.total) : 0.0;
  return t;
}

}  // namespace tbdr
