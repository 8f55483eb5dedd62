// SPDX-License-Identifier: LGPL-2.1-or-later
#include "fuzz_common.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdlib>
#include <cstring>
#include <stdexcept>

#ifndef FUZZ_DATA_DIR
#error "FUZZ_DATA_DIR must name the folder holding box.png"
#endif

namespace fuzz {

const std::string& work_dir() {
  static const std::string dir = [] {
    char templ[] = "/tmp/pickdetect-fuzz-XXXXXX";
    if (!mkdtemp(templ))
      throw std::runtime_error("mkdtemp failed");
    const cv::Mat box = cv::imread(std::string(FUZZ_DATA_DIR) + "/box.png", cv::IMREAD_GRAYSCALE);
    if (box.empty())
      throw std::runtime_error("box.png missing");
    cv::Mat small;
    cv::resize(box, small, cv::Size(), 0.4, 0.4, cv::INTER_AREA);
    cv::imwrite(std::string(templ) + "/small.png", small);
    cv::imwrite(std::string(templ) + "/box.png", box);
    return std::string(templ);
  }();
  return dir;
}

void fill(cv::Mat& m, const Input& in) {
  const uint8_t* src = in.rest();
  const size_t n = in.rest_size();
  size_t k = 0;
  for (int y = 0; y < m.rows; y++) {
    uint8_t* row = m.ptr<uint8_t>(y);
    const size_t bytes = m.cols * m.elemSize();
    if (n == 0) {
      std::memset(row, 0, bytes);
      continue;
    }
    for (size_t x = 0; x < bytes; x++, k++)
      row[x] = src[k % n];
  }
}

} // namespace fuzz
