// SPDX-License-Identifier: LGPL-2.1-or-later
// Exact polygon areas for scoring: clipping to the frame and intersection of two outlines.
//
// Every area here is exact (up to floating point), not rasterised:
//  - clipping a polygon to a convex region (the frame rectangle, a triangle, a convex outline)
//    is Sutherland-Hodgman, which is exact in area for ANY simple subject polygon, convex or
//    not: where the true intersection falls in several pieces the output joins them by edges
//    walked there and back, which enclose no area;
//  - the intersection of two outlines clips one by the other when the other is convex, and
//    otherwise splits the other into the fan of triangles (v0, vi, vi+1) and adds their signed
//    clipped areas. The signed fan triangles add up to the polygon's winding number, so the
//    result is exact for every simple polygon (convex or not), and for self-intersecting ones
//    it is the integral of the product of both winding numbers.
// Polygons are oriented counter-clockwise (positive shoelace area) before any clip, so a
// detection's outline may come in either orientation.
// An outline whose edges cross (not a simple polygon: a degenerate homography of the RANSAC
// baselines can fold the model's outline over itself) has no meaningful area of its own; it is
// replaced by its convex hull, i.e. such a detection claims everything its outline spans.
#pragma once

#include <vector>

namespace pickdetect::eval {

struct Point {
  double x = 0.0;
  double y = 0.0;
};

using Polygon = std::vector<Point>;

/// Shoelace area, signed: positive for counter-clockwise in a y-up frame.
double signed_area(const Polygon& polygon);
/// |signed_area|.
double area(const Polygon& polygon);

/// True when every turn goes the same way (collinear vertices allowed): the polygon is convex
/// (assuming it does not wind around twice).
bool is_convex(const Polygon& polygon);

/// The polygon with positive signed area (reversed when it was negative).
Polygon oriented(const Polygon& polygon);

/// True when two edges that do not share a vertex cross properly (both strictly on both sides
/// of each other); touching or collinear edges do not count.
bool self_intersects(const Polygon& polygon);

/// Convex hull (Andrew's monotone chain), counter-clockwise, without collinear points.
Polygon convex_hull(const Polygon& polygon);

/// The polygon as scored: its convex hull when it self-intersects, then oriented.
Polygon normalized(const Polygon& polygon);

/// Area of the normalized polygon clipped to [0, width] x [0, height].
double frame_area(const Polygon& polygon, double width, double height);

/// Sutherland-Hodgman: `subject` clipped by the convex polygon `clip` (any orientation).
/// The result's area is the exact area of their intersection.
Polygon clip_convex(const Polygon& subject, const Polygon& clip);

/// `polygon` clipped to the rectangle [0, width] x [0, height].
Polygon clip_to_frame(const Polygon& polygon, double width, double height);

/// Area of the intersection of two polygons (see the notes at the top of this file).
double intersection_area(const Polygon& a, const Polygon& b);

/// Areas of two (normalized) polygons clipped to a frame and of their intersection within it.
struct Overlap {
  double area_a = 0.0;
  double area_b = 0.0;
  double intersection = 0.0;
  /// Intersection over union; 0 when the union is empty.
  double iou() const;
};

Overlap frame_overlap(const Polygon& a, const Polygon& b, double width, double height);

/// Euclidean distance between two points.
double distance(const Point& a, const Point& b);

} // namespace pickdetect::eval
