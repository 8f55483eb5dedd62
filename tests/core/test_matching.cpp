// SPDX-License-Identifier: LGPL-2.1-or-later
// Matching: the 2NN ratio test over all models at once, look-alike features rejected or shared,
// kd-tree against brute force, SIFT descriptors held as bytes.
#include "../../src/byte_descriptors.hpp"
#include "../support/box.hpp"
#include "../support/folder_test.hpp"
#include "common/scene.hpp"

#include <pickdetect/matching.hpp>
#include <pickdetect/pickdetect.hpp>

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <map>
#include <vector>

using namespace pickdetect;

TEST(Matcher, AFeatureThatFitsTwoModelsEquallyDecidesForNeither) {
  const Model a = load_model(std::string(PICKDETECT_TEST_DATA) + "/box.png");
  Model twin = a;
  twin.name = "twin";
  const Features scene = [&] {
    Features f;
    f.keypoints = a.sift.keypoints;
    f.descriptors = a.sift.descriptors.clone();
    return f;
  }();
  EXPECT_GT(Matcher({a}).match(scene.descriptors, 0.8).size(), a.sift.keypoints.size() / 2);
  EXPECT_TRUE(Matcher({a, twin}).match(scene.descriptors, 0.8).empty());
}

TEST(Matcher, ViewsOfOneProductAreNoRivals) {
  // Two views of one product that look alike (here the same picture): a feature of both names
  // the product, so it is neither rejected nor marked shared.
  const Model a = load_model(std::string(PICKDETECT_TEST_DATA) + "/box.png");
  Model back = a;
  back.view = "back";
  const cv::Mat scene = a.sift.descriptors;
  const size_t alone = Matcher({a}).match(scene, 0.8, Search::BruteForce).size();
  EXPECT_GT(alone, a.sift.keypoints.size() / 2);
  EXPECT_EQ(Matcher({a, back}).match(scene, 0.8, Search::BruteForce).size(), alone);
  const std::vector<Match> shared =
      Matcher({a, back}).match(scene, 0.8, Search::BruteForce, Ambiguity::Share);
  EXPECT_GE(shared.size(), alone);
  for (const Match& m : shared)
    EXPECT_FALSE(m.shared);
}

TEST(Matcher, SharingGivesAFeatureToEveryLookAlike) {
  const Model a = load_model(std::string(PICKDETECT_TEST_DATA) + "/box.png");
  Model twin = a;
  twin.name = "twin";
  const Model other = load_model(std::string(PICKDETECT_TEST_DATA) + "/graf1.png");
  const cv::Mat scene = a.sift.descriptors;
  const std::vector<Match> matches =
      Matcher({a, twin, other}).match(scene, 0.8, Search::BruteForce, Ambiguity::Share);
  size_t per_model[3] = {0, 0, 0};
  for (const Match& m : matches) {
    ++per_model[m.model];
    EXPECT_TRUE(m.shared || m.model == 2);
  }
  EXPECT_GT(per_model[0], a.sift.keypoints.size() / 2);
  EXPECT_EQ(per_model[0], per_model[1]);
  EXPECT_LT(per_model[2], per_model[0] / 20);
  // With one model, sharing changes nothing.
  const Matcher alone({a});
  const std::vector<Match> reject = alone.match(scene, 0.8, Search::BruteForce);
  const std::vector<Match> share = alone.match(scene, 0.8, Search::BruteForce, Ambiguity::Share);
  ASSERT_EQ(reject.size(), share.size());
  for (size_t i = 0; i < reject.size(); ++i) {
    EXPECT_EQ(reject[i].model_point, share[i].model_point);
    EXPECT_FALSE(share[i].shared);
  }
}

namespace {

/// How many of the `exact` matches `fast` holds too (the same model, scene and model keypoints).
size_t kept(const std::vector<Match>& exact, const std::vector<Match>& fast) {
  size_t shared = 0;
  for (const Match& e : exact)
    shared += std::any_of(fast.begin(), fast.end(), [&](const Match& k) {
      return k.model == e.model && k.scene_point == e.scene_point && k.model_point == e.model_point;
    });
  return shared;
}

} // namespace

TEST(Matcher, KdTreeSearchKeepsWhatBruteForceFinds) {
  const Model& model = test_scene::box_model();
  const cv::Mat box = test_scene::box_picture();
  cv::Mat scene = test_scene::plain_background({800, 600});
  test_scene::paste(scene, box, {{{250.f, 250.f}, 30.0, 1.0}, {{560.f, 360.f}, 200.0, 0.9}});
  const Features f = extract_features(scene);
  const Matcher matcher({model});
  const std::vector<Match> exact = matcher.match(f.descriptors, 0.8, Search::BruteForce);
  const std::vector<Match> fast = matcher.match(f.descriptors, 0.8, Search::KdTree);
  ASSERT_GT(exact.size(), 100u);
  const size_t shared = kept(exact, fast);
  EXPECT_GE(shared, exact.size() * 9 / 10)
      << shared << " of " << exact.size() << " exact matches kept";
  EXPECT_EQ(fast.size(), matcher.match(f.descriptors, 0.8, Search::KdTree).size());
}

namespace {

/// Whether every match's distance is the L2 distance between its scene descriptor and its model
/// descriptor, or (a part repeated in the model, one match for each of its copies) one of its
/// copies', to a float's rounding.
void expect_own_distances(const std::vector<Match>& matches, const cv::Mat& scene,
                          const cv::Mat& model) {
  std::map<int, std::vector<const Match*>> by_feature;
  for (const Match& m : matches)
    by_feature[m.scene_point].push_back(&m);
  for (const auto& [feature, its] : by_feature) {
    bool found = false;
    for (const Match* m : its)
      found = found || std::abs(m->distance -
                                cv::norm(scene.row(feature), model.row(m->model_point))) < 1e-3;
    ASSERT_TRUE(found) << "scene feature " << feature << ": " << its.front()->distance;
  }
}

} // namespace

TEST(Matcher, KdTreeSearchOverSiftsWholeNumbersGivesTheDescriptorsOwnDistances) {
  // The kd-tree holds SIFT's descriptors as bytes: what it reports is still the distance
  // between the descriptors themselves.
  const Model& model = test_scene::box_model();
  cv::Mat scene = test_scene::plain_background({800, 600});
  test_scene::paste(scene, test_scene::box_picture(), {{{300.f, 280.f}, 40.0, 0.9}});
  const Features f = extract_features(scene);
  const std::vector<Match> fast = Matcher({model}).match(f.descriptors, 0.8, Search::KdTree);
  ASSERT_GT(fast.size(), 50u);
  expect_own_distances(fast, f.descriptors, model.sift.descriptors);
}

TEST(Matcher, DescriptorsThatAreNotWholeNumbersAreMatchedAtTheirOwnDistances) {
  // A caller's own descriptors need not be SIFT's whole numbers from 0 to 255: bytes would
  // round them, so they are searched as they are.
  const Model& model = test_scene::box_model();
  cv::Mat fractional;
  model.sift.descriptors.convertTo(fractional, CV_32F, 0.7, 0.3);
  // Against the models' whole numbers (searched exhaustively)...
  const std::vector<Match> against_whole = Matcher({model}).match(fractional, 0.8, Search::KdTree);
  ASSERT_GT(against_whole.size(), model.sift.keypoints.size() / 4);
  expect_own_distances(against_whole, fractional, model.sift.descriptors);
  // ...and models of such descriptors against SIFT's own (a kd-tree over the floats).
  Model scaled = model;
  scaled.sift.descriptors = fractional;
  const std::vector<Match> against_fractional =
      Matcher({scaled}).match(model.sift.descriptors, 0.8, Search::KdTree);
  ASSERT_GT(against_fractional.size(), model.sift.keypoints.size() / 4);
  expect_own_distances(against_fractional, model.sift.descriptors, fractional);
}

TEST(ByteDescriptors, TheSquaredDistanceIsWholeAndStopsOnlyPastItsBound) {
  cv::RNG rng(20261207);
  for (int size : {128, 37}) { // SIFT's length, and one the 16-byte steps do not divide
    for (int pair = 0; pair < 200; ++pair) {
      cv::Mat a(1, size, CV_8U), b(1, size, CV_8U);
      rng.fill(a, cv::RNG::UNIFORM, 0, 256);
      b = a.clone();
      // Most pairs far apart, some near: a few values moved.
      if (pair % 2 == 0)
        rng.fill(b, cv::RNG::UNIFORM, 0, 256);
      else
        for (int k = 0; k < 4; ++k)
          b.at<uchar>(0, rng.uniform(0, size)) = static_cast<uchar>(rng.uniform(0, 256));
      const int exact = static_cast<int>(cv::norm(a, b, cv::NORM_L2SQR));
      const uchar* x = a.ptr<uchar>();
      const uchar* y = b.ptr<uchar>();
      ASSERT_EQ(detail::squared_distance(x, y, size), exact);
      for (int stop : {0, exact / 3, exact - 1, exact, exact + 1, 10000}) {
        const int until = detail::squared_distance_until(x, y, size, stop);
        if (exact <= stop)
          ASSERT_EQ(until, exact) << "stop " << stop;
        else
          ASSERT_GT(until, stop) << "distance " << exact;
      }
    }
  }
}

TEST(ByteDescriptors, OnlyWholeNumbersFromZeroTo255AreBytes) {
  cv::Mat rows(2, 128, CV_32F, cv::Scalar(255.f));
  rows.at<float>(1, 5) = 0.f;
  EXPECT_TRUE(detail::whole_bytes(rows));
  for (float odd : {0.5f, -1.f, 256.f, std::numeric_limits<float>::quiet_NaN()}) {
    cv::Mat changed = rows.clone();
    changed.at<float>(1, 7) = odd;
    EXPECT_FALSE(detail::whole_bytes(changed)) << odd;
  }
  cv::Mat bytes;
  rows.convertTo(bytes, CV_8U);
  EXPECT_FALSE(detail::whole_bytes(bytes)); // held as floats only
}

TEST(Matcher, ARepeatedDesignHasTheShiftsBetweenItsCopies) {
  const Model& box = test_scene::box_model();
  const Model bundle = test_scene::bundle_model(3);
  const Matcher matcher({box, bundle});
  // box.png alone repeats nothing worth a shift.
  EXPECT_TRUE(matcher.repeat_shifts(0).empty());
  // Three packs side by side: a pack's width and two, both ways, and nothing else.
  const float pack = static_cast<float>(box.image.cols);
  const std::vector<cv::Point2f>& shifts = matcher.repeat_shifts(1);
  EXPECT_EQ(shifts.size(), 4u);
  for (float expected : {-2 * pack, -pack, pack, 2 * pack}) {
    bool found = false;
    for (const cv::Point2f& s : shifts)
      found = found || std::hypot(s.x - expected, s.y) < 2.0;
    EXPECT_TRUE(found) << "no shift of (" << expected << ", 0)";
  }
  EXPECT_TRUE(matcher.repeat_shifts(2).empty()) << "no third model";
}

namespace {

/// How many matches each scene keypoint matched gets.
std::map<int, size_t> matches_per_feature(const std::vector<Match>& matches) {
  std::map<int, size_t> per_feature;
  for (const Match& m : matches)
    ++per_feature[m.scene_point];
  return per_feature;
}

} // namespace

// A picture printing one motif 48 times over (a 64 px patch of box.png in 8 x 6 tiles: wrapping
// paper, a hand-drawn picture of strokes of one width) is a texture, not a repeated design: a
// feature on the motif is matched once, if it passes the ratio test against the motif's other
// copies, not once for each of the 48 places it could mean (3,035 features made 122,141
// matches). A bundle of three packs keeps its copies: a feature of one pack, three matches.
TEST(Matcher, APartPrintedManyTimesOverIsATextureNotARepeatedDesign) {
  const cv::Mat motif = test_scene::box_picture()(cv::Rect(100, 60, 64, 64)).clone();
  cv::Mat tiles;
  cv::repeat(motif, 6, 8, tiles);
  const Model texture = test_scene::picture_model("texture", tiles, 0.0);
  const Features scene = extract_features(texture.image, cv::Mat(), FeatureKind::Sift);
  const std::vector<Match> matches =
      Matcher({texture}).match(scene.descriptors, 0.8, Search::BruteForce);
  EXPECT_LT(matches.size(), 2 * scene.keypoints.size());
  for (const auto& [feature, count] : matches_per_feature(matches))
    ASSERT_LE(count, Matcher::kMaxCopies) << "scene feature " << feature << " matched " << count
                                          << " times: a vote for each of the motif's places";

  const Model bundle = test_scene::bundle_model(3);
  const Features seen = extract_features(bundle.image, cv::Mat(), FeatureKind::Sift);
  const std::map<int, size_t> per_feature =
      matches_per_feature(Matcher({bundle}).match(seen.descriptors, 0.8, Search::BruteForce));
  const auto three = std::count_if(per_feature.begin(), per_feature.end(),
                                   [](const auto& fc) { return fc.second == 3; });
  EXPECT_GE(static_cast<double>(three), 0.9 * static_cast<double>(seen.keypoints.size()))
      << "a feature of one pack of three votes for each of the three";
}

// Each search asks for as many neighbours as a texture's group has rows, up to a bound (a motif
// printed 400 times over makes a group of 380, more than the bound): the other model's
// matches are still what an exhaustive search finds.
TEST(Matcher, ATextureOfHundredsOfCopiesLeavesAnotherModelsMatchesAsAnExhaustiveSearchFinds) {
  const cv::Mat motif = test_scene::box_picture()(cv::Rect(100, 60, 32, 32)).clone();
  cv::Mat tiles;
  cv::repeat(motif, 20, 20, tiles);
  const Model texture = test_scene::picture_model("texture", tiles, 0.0);
  cv::Mat scene = test_scene::plain_background({800, 600});
  test_scene::paste(scene, test_scene::box_picture(),
                    {{{250.f, 250.f}, 30.0, 1.0}, {{560.f, 360.f}, 200.0, 0.9}});
  const Features f = extract_features(scene);
  const Matcher matcher({test_scene::box_model(), texture});
  const std::vector<Match> exact = matcher.match(f.descriptors, 0.8, Search::BruteForce);
  const std::vector<Match> fast = matcher.match(f.descriptors, 0.8, Search::KdTree);
  std::vector<Match> of_box;
  std::copy_if(exact.begin(), exact.end(), std::back_inserter(of_box),
               [](const Match& m) { return m.model == 0; });
  const size_t found = of_box.size(), shared = kept(of_box, fast);
  ASSERT_GT(found, 100u);
  EXPECT_GE(shared, found * 9 / 10) << shared << " of " << found << " exact matches kept";
}

namespace {

class FamilyMatching : public test_scene::FolderTest {
protected:
  FamilyMatching() : FolderTest("pickdetect-family-matching-") {}
  /// A product of a family, as pickdetect-synth --family makes it: the top 40 % of box.png (the
  /// brand's panel) over a picture of its own (`own`, from OpenCV's samples).
  Model member(const std::string& own) const {
    const cv::Mat box = test_scene::box_picture();
    const cv::Rect part(0, kPanel, box.cols, box.rows - kPanel);
    cv::Mat picture = box.clone();
    const cv::Mat other =
        cv::imread(std::string(PICKDETECT_TEST_DATA) + "/" + own, cv::IMREAD_GRAYSCALE);
    EXPECT_FALSE(other.empty()) << own;
    cv::resize(other, picture(part), part.size(), 0, 0, cv::INTER_AREA);
    const std::string file = path("box_" + own.substr(0, own.find('.')) + ".png");
    cv::imwrite(file, picture);
    return load_model(file);
  }
  const int kPanel = test_scene::box_picture().rows * 2 / 5;
};

} // namespace

// A product's keypoints on the panel its family shares tell nothing of which product an object
// is: their matches are shared even where the scene feature lies nearer one product's copy of
// the panel (its descriptor taken off the product's own picture, a hair away from the other's).
// Keypoints of the product's own part are not.
TEST_F(FamilyMatching, APartSharedByAFamilyNamesNoProduct) {
  const Model fruits = member("fruits.jpg");
  const Model home = member("home.jpg");
  const Matcher matcher({fruits, home});
  const std::vector<Match> matches =
      matcher.match(fruits.sift.descriptors, 0.9, Search::BruteForce, Ambiguity::Share);
  // The rows of `fruits` that have a twin in `home` (within the repeat distance, 100), found by
  // brute force, and the rows wholly inside fruits' own part.
  cv::BFMatcher bf(cv::NORM_L2);
  std::vector<std::vector<cv::DMatch>> twins;
  bf.radiusMatch(fruits.sift.descriptors, home.sift.descriptors, twins, 100.f);
  int twin_matches = 0, own_matches = 0, own_shared = 0;
  for (const Match& m : matches) {
    if (m.model != 0)
      continue;
    const cv::KeyPoint& k = fruits.sift.keypoints[static_cast<size_t>(m.model_point)];
    if (!twins[static_cast<size_t>(m.scene_point)].empty()) {
      ++twin_matches;
      EXPECT_TRUE(m.shared) << "a panel feature at (" << k.pt.x << ", " << k.pt.y << ")";
    } else if (k.pt.y - k.size > kPanel) {
      ++own_matches;
      own_shared += m.shared;
    }
  }
  EXPECT_GT(twin_matches, 50);
  EXPECT_GT(own_matches, 50);
  EXPECT_LT(own_shared, own_matches / 10) << "the own part is no shared design";
}
