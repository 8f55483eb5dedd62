// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: the median of a set of values.
#pragma once

#include <algorithm>
#include <cstddef>
#include <limits>
#include <vector>

namespace pickdetect::detail {

/// The median of `v` (the upper of the two middle values when their number is even); NaN
/// when `v` is empty.
template <typename T> T median(std::vector<T> v) {
  if (v.empty())
    return std::numeric_limits<T>::quiet_NaN();
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

} // namespace pickdetect::detail
