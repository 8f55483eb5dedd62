// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: SIFT descriptors held as bytes for the kd-tree's search.
//
// OpenCV's SIFT rounds each of a descriptor's 128 values to a whole number from 0 to 255 and
// hands them over as floats. Held as bytes they take a quarter of the memory, which is what a
// kd-tree's search mostly waits for (a leaf's row read from memory), and their squared L2
// distance is a sum of whole numbers below 2^24 (128 * 255^2), which a float holds exactly in any
// order of summation: the search over bytes finds the same neighbours at the same distances as
// the search over the floats (docs/performance.md).
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/flann.hpp>

#include <cstddef>

namespace pickdetect::detail {

/// Whether every value of `m` (CV_32F) is a whole number from 0 to 255, as OpenCV's SIFT
/// gives them: only then do bytes hold the descriptors exactly.
inline bool whole_bytes(const cv::Mat& m) {
  if (m.type() != CV_32F)
    return false;
  for (int r = 0; r < m.rows; ++r) {
    const float* row = m.ptr<float>(r);
    for (int c = 0; c < m.cols; ++c) {
      const float v = row[c];
      if (!(v >= 0.f && v <= 255.f) || v != static_cast<float>(static_cast<int>(v)))
        return false;
    }
  }
  return true;
}

/// Squared L2 distance between two byte rows of `size` values, summed 16 bytes at a time with
/// OpenCV's universal intrinsics (a whole number, exact). With kMayStop, once the sum of the
/// first 16 values, then of the first 32 or 64, passes `stop`, that part sum is returned instead
/// (the whole is larger still): most pairs of descriptors lie far apart, and an exhaustive search
/// within a radius need not sum them to the end.
template <bool kMayStop> int summed_squares(const uchar* a, const uchar* b, size_t size, int stop) {
  size_t i = 0;
  int total = 0;
#if CV_SIMD128
  cv::v_int32x4 sum = cv::v_setzero_s32();
  for (; i + 16 <= size; i += 16) {
    const cv::v_uint8x16 d = cv::v_absdiff(cv::v_load(a + i), cv::v_load(b + i));
    cv::v_uint16x8 low, high;
    cv::v_expand(d, low, high);
    const cv::v_int16x8 l = cv::v_reinterpret_as_s16(low);
    const cv::v_int16x8 h = cv::v_reinterpret_as_s16(high);
    sum += cv::v_dotprod(l, l) + cv::v_dotprod(h, h);
    if (kMayStop && (i == 0 || i == 16 || i == 48) && i + 16 < size) {
      const int part = cv::v_reduce_sum(sum);
      if (part > stop)
        return part;
    }
  }
  total = cv::v_reduce_sum(sum);
#endif
  for (; i < size; ++i) {
    const int d = static_cast<int>(a[i]) - static_cast<int>(b[i]);
    total += d * d;
  }
  return total;
}

/// The squared distance, whole.
inline int squared_distance(const uchar* a, const uchar* b, size_t size) {
  return summed_squares<false>(a, b, size, 0);
}

/// The squared distance when it is at most `stop`; otherwise some number above `stop`.
inline int squared_distance_until(const uchar* a, const uchar* b, size_t size, int stop) {
  return summed_squares<true>(a, b, size, stop);
}

/// FLANN's squared L2 distance (cvflann::L2) over byte rows: the same whole number as
/// cvflann::L2<unsigned char>'s float sum, a fraction of the instructions. `accum_dist` is
/// FLANN's own (a cut of the kd-tree against one value).
struct ByteL2 {
  typedef cvflann::True is_kdtree_distance;
  typedef cvflann::True is_vector_space_distance;
  typedef unsigned char ElementType;
  typedef float ResultType;
  typedef float CentersType;

  template <typename Row1, typename Row2>
  float operator()(Row1 a, Row2 b, size_t size, float /*worst_dist*/ = -1) const {
    return static_cast<float>(squared_distance(&a[0], &b[0], size));
  }

  template <typename U, typename V> float accum_dist(const U& a, const V& b, int) const {
    return (a - b) * (a - b);
  }
};

} // namespace pickdetect::detail
