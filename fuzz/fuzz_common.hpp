// SPDX-License-Identifier: LGPL-2.1-or-later
// Shared by the fuzz targets: a small textured model picture made once from OpenCV's box.png.
#pragma once

#include <opencv2/core.hpp>

#include <cstddef>
#include <cstdint>
#include <string>

namespace fuzz {

/// A temporary folder holding small.png (box.png at 40 %, quick to describe) and box.png; made
/// once per process.
const std::string& work_dir();

/// Reads the fuzz input a little at a time; past its end, zeros.
class Input {
public:
  Input(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  uint8_t byte() { return pos_ < size_ ? data_[pos_++] : 0; }
  int range(int lo, int hi) { // [lo, hi]
    const unsigned v = static_cast<unsigned>(byte()) << 8 | byte();
    return lo + static_cast<int>(v % static_cast<unsigned>(hi - lo + 1));
  }
  double unit() { return range(0, 65535) / 65535.0; }
  const uint8_t* rest() const { return data_ + pos_; }
  size_t rest_size() const { return pos_ < size_ ? size_ - pos_ : 0; }

private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
};

/// Fills `m` (any stride) with the remaining input, repeated; zeros when there is none.
void fill(cv::Mat& m, const Input& in);

} // namespace fuzz
