// SPDX-License-Identifier: LGPL-2.1-or-later
// Accuracy guard: the voting method on a small built-in set of heaps must keep the targets
// (object precision >= 0.99, recall >= 0.98, centre error mean <= 0.5 px, p95 <= 1.5 px).
#include "../common/scene.hpp"

#include <pickdetect/pickdetect.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>

using namespace pickdetect;
using pickdetect::test_scene::Pose;

namespace {

const std::string kData = PICKDETECT_TEST_DATA;
/// Instances with less of them in view than this are "don't care", as in the benchmark.
constexpr double kDontCareVisible = 0.3;

struct Truth {
  Pose pose;
  double visible = 1.0;
};

/// A heap: `count` boxes at random poses and scales, overlapping, over distractor patches of
/// other textures; visibility of each box counted on the rendered layers.
cv::Mat make_heap(const cv::Mat& box, const std::vector<cv::Mat>& distractors, int count,
                  cv::RNG& rng, std::vector<Truth>& truth) {
  const cv::Size frame(1024, 768);
  cv::Mat scene = test_scene::plain_background(frame, rng.uniform(70, 150), rng.uniform(1, 1000));
  // Distractors lie under the boxes.
  for (const cv::Mat& d : distractors) {
    const cv::Rect r(rng.uniform(0, frame.width - 200), rng.uniform(0, frame.height - 150), 200,
                     150);
    cv::Mat patch;
    cv::resize(d, patch, r.size());
    patch.copyTo(scene(r));
  }
  cv::Mat owner(frame, CV_16SC1, cv::Scalar(-1));
  const cv::Mat ones(box.size(), CV_8UC1, cv::Scalar(255));
  std::vector<double> area(count);
  truth.clear();
  for (int k = 0; k < count; ++k) {
    Pose p{{static_cast<float>(rng.uniform(150.0, frame.width - 150.0)),
            static_cast<float>(rng.uniform(150.0, frame.height - 150.0))},
           rng.uniform(0.0, 360.0),
           rng.uniform(0.85, 1.1)};
    test_scene::paste(scene, box, {p});
    cv::Mat mask;
    cv::warpAffine(ones, mask, cv::Mat(test_scene::model_to_scene(box.size(), p)), frame,
                   cv::INTER_NEAREST);
    owner.setTo(cv::Scalar(k), mask);
    area[k] = box.cols * box.rows * p.scale * p.scale;
    truth.push_back({p, 1.0});
  }
  for (int k = 0; k < count; ++k)
    truth[k].visible = cv::countNonZero(owner == k) / area[k];
  return scene;
}

} // namespace

TEST(Accuracy, VotingKeepsTheTargetsOnBuiltInHeaps) {
  const cv::Mat box = cv::imread(kData + "/box.png", cv::IMREAD_GRAYSCALE);
  std::vector<cv::Mat> distractors;
  for (const char* name : {"graf1.png", "building.jpg", "fruits.jpg"})
    distractors.push_back(cv::imread(kData + "/" + name, cv::IMREAD_GRAYSCALE));
  const Detector detector({load_model(kData + "/box.png")});
  cv::RNG rng(1234);

  int tp = 0, fp = 0, required = 0, found_required = 0;
  std::vector<double> errors;
  for (int scene_index = 0; scene_index < 6; ++scene_index) {
    std::vector<Truth> truth;
    const cv::Mat scene = make_heap(box, distractors, 4 + scene_index % 3, rng, truth);
    const Detection d = detector.detect(scene);
    std::vector<char> used(truth.size(), 0);
    for (const Instance& inst : d.instances) {
      // Pair with the nearest unused true instance within a tenth of the box's width.
      int best = -1;
      double best_error = 0.1 * box.cols;
      for (size_t k = 0; k < truth.size(); ++k) {
        const double e = std::hypot(inst.center.x - truth[k].pose.center.x,
                                    inst.center.y - truth[k].pose.center.y);
        if (!used[k] && e < best_error) {
          best = static_cast<int>(k);
          best_error = e;
        }
      }
      if (best < 0) {
        ++fp;
        ADD_FAILURE() << "scene " << scene_index << ": false instance at (" << inst.center.x << ", "
                      << inst.center.y << ")";
        continue;
      }
      used[best] = 1;
      if (truth[best].visible >= kDontCareVisible) {
        ++tp;
        errors.push_back(best_error);
      }
    }
    for (size_t k = 0; k < truth.size(); ++k)
      if (truth[k].visible >= kDontCareVisible) {
        ++required;
        found_required += used[k];
        if (!used[k])
          ADD_FAILURE() << "scene " << scene_index << ": missed the box at ("
                        << truth[k].pose.center.x << ", " << truth[k].pose.center.y << "), "
                        << truth[k].visible * 100 << " % visible";
      }
  }
  ASSERT_GT(required, 20);
  const double precision = static_cast<double>(tp) / std::max(1, tp + fp);
  const double recall = static_cast<double>(found_required) / required;
  std::sort(errors.begin(), errors.end());
  const double mean = std::accumulate(errors.begin(), errors.end(), 0.0) / errors.size();
  const double p95 = errors[std::min(errors.size() - 1, static_cast<size_t>(0.95 * errors.size()))];
  EXPECT_GE(precision, 0.99) << tp << " true, " << fp << " false instances";
  EXPECT_GE(recall, 0.98) << found_required << " of " << required << " required boxes found";
  EXPECT_LE(mean, 0.5) << "centre error mean";
  EXPECT_LE(p95, 1.5) << "centre error p95";
  RecordProperty("precision", std::to_string(precision));
  RecordProperty("recall", std::to_string(recall));
  RecordProperty("centre_mean_px", std::to_string(mean));
}
