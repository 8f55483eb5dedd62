// SPDX-License-Identifier: LGPL-2.1-or-later
#include "geometry.hpp"

#include <algorithm>
#include <cmath>

namespace pickdetect::eval {
namespace {

double cross(const Point& a, const Point& b, const Point& p) {
  return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
}

/// Where segment p-q crosses the line through a-b (p and q on opposite sides).
Point crossing(const Point& p, const Point& q, const Point& a, const Point& b) {
  const double cp = cross(a, b, p), cq = cross(a, b, q);
  const double t = cp / (cp - cq);
  return {p.x + t * (q.x - p.x), p.y + t * (q.y - p.y)};
}

/// Keeps the part of `subject` on the left of (or on) the directed line a-b.
Polygon clip_half_plane(const Polygon& subject, const Point& a, const Point& b) {
  Polygon out;
  const size_t n = subject.size();
  out.reserve(n + 2);
  for (size_t i = 0; i < n; ++i) {
    const Point& p = subject[i];
    const Point& q = subject[(i + 1) % n];
    const double cp = cross(a, b, p), cq = cross(a, b, q);
    const bool p_in = cp >= 0.0, q_in = cq >= 0.0;
    if (p_in)
      out.push_back(p);
    if (p_in != q_in)
      out.push_back(crossing(p, q, a, b));
  }
  return out;
}

} // namespace

double signed_area(const Polygon& polygon) {
  const size_t n = polygon.size();
  if (n < 3)
    return 0.0;
  double twice = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const Point& p = polygon[i];
    const Point& q = polygon[(i + 1) % n];
    twice += p.x * q.y - q.x * p.y;
  }
  return twice / 2.0;
}

double area(const Polygon& polygon) {
  return std::abs(signed_area(polygon));
}

bool is_convex(const Polygon& polygon) {
  const size_t n = polygon.size();
  if (n < 3)
    return false;
  bool left = false, right = false;
  for (size_t i = 0; i < n; ++i) {
    const double c = cross(polygon[i], polygon[(i + 1) % n], polygon[(i + 2) % n]);
    if (c > 0.0)
      left = true;
    else if (c < 0.0)
      right = true;
  }
  return !(left && right);
}

Polygon oriented(const Polygon& polygon) {
  if (signed_area(polygon) >= 0.0)
    return polygon;
  return Polygon(polygon.rbegin(), polygon.rend());
}

bool self_intersects(const Polygon& polygon) {
  const size_t n = polygon.size();
  auto opposite = [](double a, double b) { return (a > 0.0 && b < 0.0) || (a < 0.0 && b > 0.0); };
  for (size_t i = 0; i < n; ++i) {
    const Point& a = polygon[i];
    const Point& b = polygon[(i + 1) % n];
    for (size_t j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1)
        continue; // Adjacent through the closing edge.
      const Point& c = polygon[j];
      const Point& d = polygon[(j + 1) % n];
      if (opposite(cross(a, b, c), cross(a, b, d)) && opposite(cross(c, d, a), cross(c, d, b)))
        return true;
    }
  }
  return false;
}

Polygon convex_hull(const Polygon& polygon) {
  Polygon pts = polygon;
  std::sort(pts.begin(), pts.end(),
            [](const Point& p, const Point& q) { return p.x < q.x || (p.x == q.x && p.y < q.y); });
  if (pts.size() < 3)
    return pts;
  Polygon hull(2 * pts.size());
  size_t k = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0.0)
      --k;
    hull[k++] = pts[i];
  }
  for (size_t i = pts.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0.0)
      --k;
    hull[k++] = pts[i];
  }
  hull.resize(k - 1);
  return hull;
}

Polygon normalized(const Polygon& polygon) {
  return oriented(self_intersects(polygon) ? convex_hull(polygon) : polygon);
}

double frame_area(const Polygon& polygon, double width, double height) {
  return std::max(0.0, signed_area(clip_to_frame(normalized(polygon), width, height)));
}

Polygon clip_convex(const Polygon& subject, const Polygon& clip) {
  if (subject.size() < 3 || clip.size() < 3)
    return {};
  const Polygon c = oriented(clip);
  Polygon out = subject;
  for (size_t i = 0; i < c.size() && !out.empty(); ++i)
    out = clip_half_plane(out, c[i], c[(i + 1) % c.size()]);
  return out;
}

Polygon clip_to_frame(const Polygon& polygon, double width, double height) {
  return clip_convex(polygon, {{0.0, 0.0}, {width, 0.0}, {width, height}, {0.0, height}});
}

double intersection_area(const Polygon& a, const Polygon& b) {
  if (a.size() < 3 || b.size() < 3)
    return 0.0;
  const Polygon sa = oriented(a);
  const Polygon sb = oriented(b);
  if (is_convex(sb))
    return std::max(0.0, signed_area(clip_convex(sa, sb)));
  if (is_convex(sa))
    return std::max(0.0, signed_area(clip_convex(sb, sa)));
  // Neither is convex: the fan of b's triangles, each signed, sums to b's winding number.
  double sum = 0.0;
  for (size_t i = 1; i + 1 < sb.size(); ++i) {
    const Polygon triangle{sb[0], sb[i], sb[i + 1]};
    const double orientation = signed_area(triangle);
    if (orientation == 0.0)
      continue;
    const double piece = signed_area(clip_convex(sa, triangle));
    sum += orientation > 0.0 ? piece : -piece;
  }
  return std::max(0.0, sum);
}

double Overlap::iou() const {
  const double uni = area_a + area_b - intersection;
  return uni > 0.0 ? intersection / uni : 0.0;
}

Overlap frame_overlap(const Polygon& a, const Polygon& b, double width, double height) {
  const Polygon ca = clip_to_frame(normalized(a), width, height);
  const Polygon cb = clip_to_frame(normalized(b), width, height);
  Overlap o;
  o.area_a = std::max(0.0, signed_area(ca));
  o.area_b = std::max(0.0, signed_area(cb));
  o.intersection = std::min({intersection_area(ca, cb), o.area_a, o.area_b});
  return o;
}

double distance(const Point& a, const Point& b) {
  return std::hypot(a.x - b.x, a.y - b.y);
}

} // namespace pickdetect::eval
