// SPDX-License-Identifier: LGPL-2.1-or-later
// libFuzzer target: Detector::detect on a grey frame of fuzzed size, stride, content and
// settings. No exception, no sanitizer report; instances inside sane bounds.
#include "fuzz_common.hpp"

#include <pickdetect/detector.hpp>
#include <pickdetect/model.hpp>

#include <cmath>
#include <memory>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::unique_ptr<pickdetect::Detector> detector = [] {
    return std::make_unique<pickdetect::Detector>(
        std::vector<pickdetect::Model>{pickdetect::load_model(fuzz::work_dir() + "/small.png")});
  }();
  fuzz::Input in(data, size);
  const int width = in.range(1, 400), height = in.range(1, 300), pad = in.range(0, 40);
  pickdetect::Settings s;
  s.method = static_cast<pickdetect::Method>(in.range(0, 2));
  s.ratio = 0.01 + 0.98 * in.unit();
  s.min_matches = in.range(1, 12);
  s.bandwidth = in.byte() < 64 ? 0.0 : 200.0 * in.unit();
  s.max_instances = in.range(0, 4);
  s.allow_scale = in.byte() & 1;
  s.refine = in.byte() & 1;
  s.search = static_cast<pickdetect::Search>(in.range(0, 1));
  s.features = static_cast<pickdetect::FeatureKind>(in.range(0, 1));
  s.detection_scale = in.byte() < 128 ? 1.0 : 0.1 + 0.9 * in.unit();

  // A frame inside a larger buffer: any stride, and the padding is never touched.
  cv::Mat buffer(height, width + pad, CV_8UC1, cv::Scalar(0xA5));
  cv::Mat frame = buffer(cv::Rect(0, 0, width, height));
  fuzz::fill(frame, in);
  const pickdetect::Detection d = detector->detect(frame, s);
  for (const pickdetect::Instance& i : d.instances)
    if (!std::isfinite(i.center.x) || !std::isfinite(i.center.y) || !std::isfinite(i.scale) ||
        i.points.empty() || i.score < 0.0 || i.score > 1.0)
      __builtin_trap();
  return 0;
}
