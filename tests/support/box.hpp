// SPDX-License-Identifier: LGPL-2.1-or-later
// The model the core's tests detect: OpenCV's box.png (Debian's opencv-doc), its picture and
// its model (loaded once).
#pragma once

#include <pickdetect/pickdetect.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <string>
#include <vector>

namespace pickdetect::test_scene {

/// Folder of OpenCV's sample pictures, given by the build (PICKDETECT_TEST_DATA).
inline const std::string kData = PICKDETECT_TEST_DATA;

/// box.png as a grey picture, read afresh.
inline cv::Mat box_picture() {
  return cv::imread(kData + "/box.png", cv::IMREAD_GRAYSCALE);
}

inline const Model& box_model() {
  static const Model model = load_model(kData + "/box.png");
  return model;
}

/// The box's print washed out towards white, to `contrast` of its own (by default its darkest
/// level 255 - 0.75 * 255), as a white glossy carton with pale print gives.
inline cv::Mat washed_out(const cv::Mat& grey, double contrast = 0.25) {
  cv::Mat out;
  grey.convertTo(out, CV_8U, contrast, 255 * (1 - contrast));
  return out;
}

/// The box model with its picture washed out (washed_out), its features found as the loaders
/// find them (at a lowered threshold: faint print).
inline Model faint_box_model(double contrast = 0.25) {
  Model m = box_model();
  m.image = washed_out(box_model().image, contrast);
  m.colour.release();
  compute_model_features(m);
  return m;
}

/// A model of a whole grey picture, as a picture file without alpha loads: the picture its
/// outline, its centre and corners its principal points; its features computed (with views up
/// to `max_tilt_deg`).
inline Model picture_model(const std::string& name, cv::Mat picture,
                           double max_tilt_deg = kDefaultMaxTiltDeg) {
  Model m;
  m.name = name;
  m.image = std::move(picture);
  m.mask = cv::Mat(m.image.size(), CV_8UC1, cv::Scalar(255));
  const float w = static_cast<float>(m.image.cols), h = static_cast<float>(m.image.rows);
  m.principal_points = {{w / 2, h / 2}, {0, 0}, {w, 0}, {w, h}, {0, h}};
  m.outline = {{0, 0}, {w, 0}, {w, h}, {0, h}};
  m.max_tilt_deg = max_tilt_deg;
  compute_model_features(m);
  return m;
}

/// A bundle of `packs` box.png pictures side by side, as one model (a repeated design), with
/// views up to `max_tilt_deg`.
inline Model bundle_model(int packs, double max_tilt_deg = kDefaultMaxTiltDeg) {
  std::vector<cv::Mat> row(packs, box_model().image);
  cv::Mat picture;
  cv::hconcat(row, picture);
  return picture_model("bundle", picture, max_tilt_deg);
}

inline const Detector& box_detector() {
  static const Detector detector({box_model()});
  return detector;
}

} // namespace pickdetect::test_scene
