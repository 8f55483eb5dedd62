// SPDX-License-Identifier: LGPL-2.1-or-later
// Accuracy guard: the voting method on a small built-in set of heaps must keep the targets
// (object precision >= 0.99, recall >= 0.98, centre error mean <= 0.5 px, p95 <= 1.5 px).
#include "common/scene.hpp"

#include <pickdetect/pickdetect.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
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
  int model = 0;
};

/// A heap: `count` boxes (each one of `boxes`, all of one size) at random poses and scales in
/// [min_scale, max_scale), overlapping, over distractor patches of other textures; visibility of
/// each box counted on the rendered layers.
cv::Mat make_heap(const std::vector<cv::Mat>& boxes, const std::vector<cv::Mat>& distractors,
                  int count, cv::RNG& rng, std::vector<Truth>& truth, double min_scale = 0.85,
                  double max_scale = 1.1) {
  const cv::Mat& box = boxes[0];
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
           rng.uniform(min_scale, max_scale)};
    // One box kind draws nothing, so the single-model heaps stay the scenes they were.
    const int model = boxes.size() > 1 ? rng.uniform(0, static_cast<int>(boxes.size())) : 0;
    test_scene::paste(scene, boxes[model], {p});
    cv::Mat mask;
    cv::warpAffine(ones, mask, cv::Mat(test_scene::model_to_scene(box.size(), p)), frame,
                   cv::INTER_NEAREST);
    owner.setTo(cv::Scalar(k), mask);
    area[k] = box.cols * box.rows * p.scale * p.scale;
    truth.push_back({p, 1.0, model});
  }
  for (int k = 0; k < count; ++k)
    truth[k].visible = cv::countNonZero(owner == k) / area[k];
  return scene;
}

/// Pictures of other textures for the floor under the heaps.
std::vector<cv::Mat> distractor_pictures() {
  std::vector<cv::Mat> out;
  for (const char* name : {"graf1.png", "building.jpg", "fruits.jpg"})
    out.push_back(cv::imread(kData + "/" + name, cv::IMREAD_GRAYSCALE));
  return out;
}

/// One method's figures on the built-in heaps; centre errors per (scene, true instance), NaN
/// where the method missed it.
struct Score {
  int tp = 0, fp = 0, required = 0, found_required = 0;
  std::vector<double> errors;   ///< Over the paired required instances (the TP).
  std::vector<double> error_of; ///< Per (scene, true instance); NaN where not found.
  double precision() const { return static_cast<double>(tp) / std::max(1, tp + fp); }
  double recall() const { return static_cast<double>(found_required) / std::max(1, required); }
  double mean() const {
    return errors.empty() ? NAN
                          : std::accumulate(errors.begin(), errors.end(), 0.0) / errors.size();
  }
};

/// Pairs each instance with the nearest unused true instance of its model within `reach`.
void score_scene(const Detection& d, const std::vector<Truth>& truth, double reach, Score& score,
                 std::vector<std::string>& problems) {
  std::vector<char> used(truth.size(), 0);
  std::vector<double> error(truth.size(), NAN);
  for (const Instance& inst : d.instances) {
    int best = -1;
    double best_error = reach;
    for (size_t k = 0; k < truth.size(); ++k) {
      const double e = std::hypot(inst.center.x - truth[k].pose.center.x,
                                  inst.center.y - truth[k].pose.center.y);
      if (!used[k] && truth[k].model == inst.model && e < best_error) {
        best = static_cast<int>(k);
        best_error = e;
      }
    }
    if (best < 0) {
      ++score.fp;
      problems.push_back("false instance of " + inst.model_name + " at (" +
                         std::to_string(inst.center.x) + ", " + std::to_string(inst.center.y) +
                         ")");
      continue;
    }
    used[best] = 1;
    if (truth[best].visible >= kDontCareVisible) {
      ++score.tp;
      score.errors.push_back(best_error);
      error[best] = best_error;
    }
  }
  for (size_t k = 0; k < truth.size(); ++k)
    if (truth[k].visible >= kDontCareVisible) {
      ++score.required;
      score.found_required += used[k];
      score.error_of.push_back(error[k]);
      if (!used[k])
        problems.push_back("missed the box at (" + std::to_string(truth[k].pose.center.x) + ", " +
                           std::to_string(truth[k].pose.center.y) + "), " +
                           std::to_string(truth[k].visible * 100) + " % visible");
    }
}

/// Mean of the errors at the indices where every score has one.
double mean_where_all_found(const std::vector<double>& of, const std::vector<const Score*>& all) {
  double sum = 0.0;
  int n = 0;
  for (size_t i = 0; i < of.size(); ++i) {
    if (std::any_of(all.begin(), all.end(),
                    [&](const Score* s) { return std::isnan(s->error_of[i]); }))
      continue;
    sum += of[i];
    ++n;
  }
  return n ? sum / n : NAN;
}

} // namespace

/// The voting method keeps the targets, and on the same frames is at least as precise and as
/// complete as both RANSAC baselines and places the instances they all find more exactly.
TEST(Accuracy, VotingKeepsTheTargetsOnBuiltInHeaps) {
  const cv::Mat box = cv::imread(kData + "/box.png", cv::IMREAD_GRAYSCALE);
  const std::vector<cv::Mat> distractors = distractor_pictures();
  const Detector detector({load_model(kData + "/box.png")});
  cv::RNG rng(1234);

  const Method methods[] = {Method::Voting, Method::RansacClustered, Method::RansacAll};
  Score scores[3];
  for (int scene_index = 0; scene_index < 6; ++scene_index) {
    std::vector<Truth> truth;
    const cv::Mat scene = make_heap({box}, distractors, 4 + scene_index % 3, rng, truth);
    const Features features = extract_features(scene);
    for (int m = 0; m < 3; ++m) {
      Settings settings;
      settings.method = methods[m];
      std::vector<std::string> problems;
      score_scene(detector.detect(features, scene.size(), settings), truth, 0.1 * box.cols,
                  scores[m], problems);
      if (methods[m] == Method::Voting)
        for (const std::string& p : problems)
          ADD_FAILURE() << "scene " << scene_index << ": " << p;
    }
  }
  const Score& voting = scores[0];
  ASSERT_GT(voting.required, 20);
  std::vector<double> sorted = voting.errors;
  std::sort(sorted.begin(), sorted.end());
  const double p95 = sorted[std::min(sorted.size() - 1, static_cast<size_t>(0.95 * sorted.size()))];
  EXPECT_GE(voting.precision(), 0.99) << voting.tp << " true, " << voting.fp << " false instances";
  EXPECT_GE(voting.recall(), 0.98)
      << voting.found_required << " of " << voting.required << " required boxes found";
  EXPECT_LE(voting.mean(), 0.5) << "centre error mean";
  EXPECT_LE(p95, 1.5) << "centre error p95";

  const std::vector<const Score*> all = {&scores[0], &scores[1], &scores[2]};
  const double voting_common = mean_where_all_found(voting.error_of, all);
  for (int m = 1; m < 3; ++m) {
    const char* name = method_name(methods[m]);
    EXPECT_GE(voting.precision(), scores[m].precision()) << "precision against " << name;
    EXPECT_GE(voting.recall(), scores[m].recall()) << "recall against " << name;
    EXPECT_LT(voting_common, mean_where_all_found(scores[m].error_of, all))
        << "centre error against " << name << " on the instances all three methods find";
    RecordProperty(std::string(name) + "_recall", std::to_string(scores[m].recall()));
    RecordProperty(std::string(name) + "_common_centre_px",
                   std::to_string(mean_where_all_found(scores[m].error_of, all)));
  }
  RecordProperty("precision", std::to_string(voting.precision()));
  RecordProperty("recall", std::to_string(voting.recall()));
  RecordProperty("centre_mean_px", std::to_string(voting.mean()));
  RecordProperty("common_centre_px", std::to_string(voting_common));
}

/// Look-alike products: three boxes share the top 80 % of their design (a brand's family) and
/// differ below. With all three models loaded, every box must be found under its own name.
TEST(Accuracy, VotingNamesEachProductOfALookAlikeFamily) {
  const cv::Mat box = cv::imread(kData + "/box.png", cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(box.empty());
  const int shared_rows = box.rows * 8 / 10;
  const std::string dir = (std::filesystem::temp_directory_path() /
                           ("pickdetect-lookalikes-" + std::to_string(::getpid())))
                              .string();
  std::filesystem::create_directories(dir);
  std::vector<cv::Mat> family = {box};
  std::vector<Model> models = {model_from_picture(kData + "/box.png", "box")};
  for (const char* other : {"home.jpg", "messi5.jpg"}) {
    cv::Mat lower = cv::imread(kData + "/" + other, cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(lower.empty()) << other;
    cv::Mat product = box.clone();
    cv::resize(lower, product.rowRange(shared_rows, box.rows),
               cv::Size(box.cols, box.rows - shared_rows), 0, 0, cv::INTER_AREA);
    const std::string path = dir + "/" + other + ".png";
    ASSERT_TRUE(cv::imwrite(path, product));
    family.push_back(product);
    models.push_back(model_from_picture(path, other));
  }
  std::filesystem::remove_all(dir);
  std::vector<cv::Mat> distractors;
  for (const char* name : {"graf1.png", "fruits.jpg"})
    distractors.push_back(cv::imread(kData + "/" + name, cv::IMREAD_GRAYSCALE));
  const Detector detector(models);
  cv::RNG rng(4321);
  Score score;
  for (int scene_index = 0; scene_index < 6; ++scene_index) {
    std::vector<Truth> truth;
    const cv::Mat scene = make_heap(family, distractors, 4 + scene_index % 3, rng, truth, 0.5, 0.8);
    std::vector<std::string> problems;
    score_scene(detector.detect(scene), truth, 0.1 * box.cols, score, problems);
    for (const std::string& p : problems)
      ADD_FAILURE() << "scene " << scene_index << ": " << p;
  }
  ASSERT_GT(score.required, 20);
  EXPECT_GE(score.precision(), 0.99) << score.tp << " true, " << score.fp << " false instances";
  EXPECT_GE(score.recall(), 0.98) << score.found_required << " of " << score.required
                                  << " required boxes found";
  RecordProperty("lookalike_precision", std::to_string(score.precision()));
  RecordProperty("lookalike_recall", std::to_string(score.recall()));
}

/// Heaps taken with a seventh of the light (every grey level times 0.15, plus the
/// sensor's rounding): SIFT's fixed contrast threshold alone would lose most of the boxes'
/// keypoints; the frame's exposure sets it, so the boxes are found as in full light.
TEST(Accuracy, VotingFindsTheBoxesInADimFrame) {
  const cv::Mat box = cv::imread(kData + "/box.png", cv::IMREAD_GRAYSCALE);
  const std::vector<cv::Mat> distractors = distractor_pictures();
  const Detector detector({load_model(kData + "/box.png")});
  auto run = [&](const Settings& settings, bool report) {
    cv::RNG rng(2468);
    Score score;
    for (int scene_index = 0; scene_index < 5; ++scene_index) {
      std::vector<Truth> truth;
      const cv::Mat lit = make_heap({box}, distractors, 4 + scene_index % 3, rng, truth);
      cv::Mat dim;
      lit.convertTo(dim, CV_8UC1, 0.15);
      EXPECT_LT(exposure_contrast_share(dim), 0.5) << "scene " << scene_index;
      std::vector<std::string> problems;
      score_scene(detector.detect(dim, settings), truth, 0.1 * box.cols, score, problems);
      for (const std::string& p : problems)
        if (report)
          ADD_FAILURE() << "scene " << scene_index << ": " << p;
    }
    return score;
  };
  const Score score = run(Settings(), true);
  ASSERT_GT(score.required, 15);
  EXPECT_GE(score.precision(), 0.99) << score.tp << " true, " << score.fp << " false instances";
  EXPECT_GE(score.recall(), 0.98) << score.found_required << " of " << score.required
                                  << " required boxes found";
  RecordProperty("dim_recall", std::to_string(score.recall()));
  // OpenCV's threshold, set by hand (the element's contrast-threshold), takes the place of
  // the automatic one: most boxes are lost.
  Settings fixed;
  fixed.contrast_threshold = kSiftContrastThreshold;
  const Score lost = run(fixed, false);
  EXPECT_LT(lost.recall(), 0.5) << lost.found_required << " of " << lost.required;
}
