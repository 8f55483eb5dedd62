// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: the clock the stages are timed with (Timings).
#pragma once

#include <chrono>

namespace pickdetect::detail {

using Clock = std::chrono::steady_clock;

/// Milliseconds since `t0`.
inline double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

} // namespace pickdetect::detail
