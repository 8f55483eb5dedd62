// SPDX-License-Identifier: LGPL-2.1-or-later
// Mean shift with a flat kernel over 2-D votes, on a grid of cells one bandwidth wide.
#include <pickdetect/meanshift.hpp>

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace pickdetect {
namespace {

constexpr int kMaxIterations = 100;
/// Convergence: a shift shorter than this share of the bandwidth ends the climb.
constexpr double kStopShift = 1e-3;

/// Index of the cell of width `cell` holding `v`. Cells far out (or not finite: a tiny
/// bandwidth) are clamped into the last one, so that the conversion stays defined; the distance
/// tests done within a cell still hold there.
long cell_of(double v, double cell) {
  constexpr double kLast = 1 << 30;
  const double c = std::floor(v / cell);
  return static_cast<long>(c > -kLast && c < kLast ? c : c > 0 ? kLast : -kLast);
}

/// One key for two cell indices, shifted unsigned: a left shift of a negative number is
/// undefined.
long long pack(long x, long y) {
  return static_cast<long long>(static_cast<unsigned long long>(x) << 32 ^
                                static_cast<unsigned>(y));
}

/// Buckets the points on a grid of square cells `cell` pixels wide, so that the points within
/// one bandwidth of a location are found in its 3x3 neighbourhood of cells.
class Grid {
public:
  Grid(const std::vector<cv::Point2f>& points, double cell) : points_(points), cell_(cell) {
    for (size_t i = 0; i < points.size(); ++i)
      cells_[key(points[i])].push_back(static_cast<int>(i));
  }

  /// Mean of the points within `radius` of `at`; returns the count (0: mean not set).
  int window_mean(cv::Point2d at, double radius, cv::Point2d& mean) const {
    const double r2 = radius * radius;
    double sx = 0, sy = 0;
    int n = 0;
    for_neighbours(at, [&](int i) {
      const double dx = points_[i].x - at.x, dy = points_[i].y - at.y;
      if (dx * dx + dy * dy <= r2) {
        sx += points_[i].x;
        sy += points_[i].y;
        ++n;
      }
    });
    if (n > 0)
      mean = {sx / n, sy / n};
    return n;
  }

  template <typename F> void for_neighbours(cv::Point2d at, F&& visit) const {
    const long cx = cell_index(at.x), cy = cell_index(at.y);
    for (long dy = -1; dy <= 1; ++dy)
      for (long dx = -1; dx <= 1; ++dx) {
        auto it = cells_.find(pack(cx + dx, cy + dy));
        if (it != cells_.end())
          for (int i : it->second)
            visit(i);
      }
  }

private:
  long cell_index(double v) const { return cell_of(v, cell_); }
  long long key(cv::Point2f p) const { return pack(cell_index(p.x), cell_index(p.y)); }

  const std::vector<cv::Point2f>& points_;
  double cell_;
  std::unordered_map<long long, std::vector<int>> cells_;
};

cv::Point2d climb(const Grid& grid, cv::Point2d at, double bandwidth, int& support) {
  support = 0;
  for (int it = 0; it < kMaxIterations; ++it) {
    cv::Point2d mean;
    const int n = grid.window_mean(at, bandwidth, mean);
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
  const Grid grid(points, bandwidth);

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
      const long long k = pack(cell_of(p.x, half), cell_of(p.y, half));
      if (!seeded.emplace(k, true).second)
        continue;
      int support = 0;
      const cv::Point2d mode = climb(grid, cv::Point2d(p.x, p.y), bandwidth, support);
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
  const Grid grid(points, bandwidth);
  int support = 0;
  const cv::Point2d mode = climb(grid, cv::Point2d(start.x, start.y), bandwidth, support);
  return cv::Point2f(static_cast<float>(mode.x), static_cast<float>(mode.y));
}

} // namespace pickdetect
