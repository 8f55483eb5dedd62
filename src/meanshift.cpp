// SPDX-License-Identifier: LGPL-2.1-or-later
// Mean shift with a flat kernel over 2-D votes, on a grid of cells one bandwidth wide.
#include <pickdetect/meanshift.hpp>

#include "point_grid.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace pickdetect {
namespace {

constexpr int kMaxIterations = 100;
/// Convergence: a shift shorter than this share of the bandwidth ends the climb.
constexpr double kStopShift = 1e-3;

/// Sums the points within `radius` of `at` into `mean`; returns the count (0: mean not set).
/// `visit_near(at, f)` calls f(i) for every point that may lie within the radius.
template <typename VisitNear>
int window_mean(const std::vector<cv::Point2f>& points, VisitNear&& visit_near, cv::Point2d at,
                double radius, cv::Point2d& mean) {
  const double r2 = radius * radius;
  double sx = 0, sy = 0;
  int n = 0;
  visit_near(at, [&](int i) {
    const double dx = points[i].x - at.x, dy = points[i].y - at.y;
    if (dx * dx + dy * dy <= r2) {
      sx += points[i].x;
      sy += points[i].y;
      ++n;
    }
  });
  if (n > 0)
    mean = {sx / n, sy / n};
  return n;
}

template <typename VisitNear>
cv::Point2d climb(const std::vector<cv::Point2f>& points, VisitNear&& visit_near, cv::Point2d at,
                  double bandwidth, int& support) {
  support = 0;
  for (int it = 0; it < kMaxIterations; ++it) {
    cv::Point2d mean;
    const int n = window_mean(points, visit_near, at, bandwidth, mean);
    if (n == 0)
      break;
    support = n;
    const double shift = std::hypot(mean.x - at.x, mean.y - at.y);
    at = mean;
    if (shift < kStopShift * bandwidth)
      break;
  }
  return at;
}

} // namespace

std::vector<Cluster> mean_shift_clusters(const std::vector<cv::Point2f>& points, double bandwidth) {
  std::vector<Cluster> clusters;
  if (points.empty() || !(bandwidth > 0.0))
    return clusters;
  const detail::PointGrid grid(points, bandwidth);
  auto near = [&](cv::Point2d at, auto&& visit) { grid.for_neighbours(at, visit); };

  struct Peak {
    cv::Point2d at;
    int support;
  };
  // Seeds: one per occupied cell of half a bandwidth (as bin seeding does), in point order.
  std::vector<Peak> peaks;
  {
    std::unordered_map<long long, bool> seeded;
    const double half = bandwidth / 2.0;
    for (const cv::Point2f& p : points) {
      const long long k = detail::PointGrid::pack(detail::PointGrid::cell_of(p.x, half),
                                                  detail::PointGrid::cell_of(p.y, half));
      if (!seeded.emplace(k, true).second)
        continue;
      int support = 0;
      const cv::Point2d mode = climb(points, near, cv::Point2d(p.x, p.y), bandwidth, support);
      if (support > 0)
        peaks.push_back({mode, support});
    }
  }
  // Strongest first; ties broken by position so the order never depends on hashing.
  std::stable_sort(peaks.begin(), peaks.end(), [](const Peak& a, const Peak& b) {
    if (a.support != b.support)
      return a.support > b.support;
    if (a.at.x != b.at.x)
      return a.at.x < b.at.x;
    return a.at.y < b.at.y;
  });
  std::vector<Peak> kept;
  for (const Peak& p : peaks) {
    const bool near_stronger = std::any_of(kept.begin(), kept.end(), [&](const Peak& k) {
      return std::hypot(k.at.x - p.at.x, k.at.y - p.at.y) < bandwidth;
    });
    if (!near_stronger)
      kept.push_back(p);
  }

  clusters.resize(kept.size());
  for (size_t c = 0; c < kept.size(); ++c)
    clusters[c].mode =
        cv::Point2f(static_cast<float>(kept[c].at.x), static_cast<float>(kept[c].at.y));
  const double b2 = bandwidth * bandwidth;
  for (size_t i = 0; i < points.size(); ++i) {
    int best = -1;
    double best_d2 = b2;
    for (size_t c = 0; c < kept.size(); ++c) {
      const double dx = points[i].x - kept[c].at.x, dy = points[i].y - kept[c].at.y;
      const double d2 = dx * dx + dy * dy;
      if (d2 <= best_d2) {
        if (d2 == best_d2 && best >= 0)
          continue;
        best = static_cast<int>(c);
        best_d2 = d2;
      }
    }
    if (best >= 0)
      clusters[best].members.push_back(static_cast<int>(i));
  }
  clusters.erase(std::remove_if(clusters.begin(), clusters.end(),
                                [](const Cluster& c) { return c.members.empty(); }),
                 clusters.end());
  std::stable_sort(clusters.begin(), clusters.end(), [](const Cluster& a, const Cluster& b) {
    return a.members.size() > b.members.size();
  });
  return clusters;
}

cv::Point2f mean_shift_mode(const std::vector<cv::Point2f>& points, cv::Point2f start,
                            double bandwidth) {
  if (points.empty() || !(bandwidth > 0.0))
    return start;
  // One climb: scanning all the points costs less than bucketing them first.
  auto all = [&](cv::Point2d, auto&& visit) {
    for (size_t i = 0; i < points.size(); ++i)
      visit(static_cast<int>(i));
  };
  int support = 0;
  const cv::Point2d mode = climb(points, all, cv::Point2d(start.x, start.y), bandwidth, support);
  return cv::Point2f(static_cast<float>(mode.x), static_cast<float>(mode.y));
}

} // namespace pickdetect
