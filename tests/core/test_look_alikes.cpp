// SPDX-License-Identifier: LGPL-2.1-or-later
// Look-alikes: of models found in one place, the product named by its distinct matches.
#include "../../src/look_alikes.hpp"

#include <pickdetect/pickdetect.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <vector>

using namespace pickdetect;

namespace {

/// An instance of `model` with the given outline and supporting keypoints.
Instance placed(int model, std::vector<cv::Point2f> outline, std::vector<cv::Point2f> support) {
  Instance inst;
  inst.model = model;
  inst.model_name = "m" + std::to_string(model);
  inst.outline = std::move(outline);
  inst.support = std::move(support);
  inst.matches = static_cast<int>(inst.support.size());
  inst.distinct_matches = inst.matches;
  return inst;
}

std::vector<cv::Point2f> square(float x, float y, float side) {
  return {{x, y}, {x + side, y}, {x + side, y + side}, {x, y + side}};
}

std::vector<cv::Point2f> spread(float x, float y, int n) {
  std::vector<cv::Point2f> p;
  for (int i = 0; i < n; ++i)
    p.emplace_back(x + 7.f * (i % 10), y + 9.f * static_cast<float>(i / 10));
  return p;
}

} // namespace

TEST(LookAlikes, TheWeakerOfTwoModelsInTheSamePlaceGoes) {
  // Model 1 found where model 0 is, nearly the same outline, its 5 keypoints on model 0's.
  std::vector<Instance> found = {placed(0, square(100, 100, 200), spread(120, 120, 60)),
                                 placed(1, square(103, 98, 200), spread(150, 150, 5))};
  detail::drop_look_alikes(found, 3);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].model, 0);
  // Whichever comes first: the stronger one stays.
  found = {placed(1, square(103, 98, 200), spread(150, 150, 5)),
           placed(0, square(100, 100, 200), spread(120, 120, 60))};
  detail::drop_look_alikes(found, 3);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].model, 0);
}

/// `inst` with `distinct` of its matches its own.
Instance with_distinct(Instance inst, int distinct) {
  inst.distinct_matches = distinct;
  return inst;
}

TEST(LookAlikes, TheProductIsNamedByItsDistinctMatches) {
  // Two models on the same keypoints (a shared design): model 1 has more matches, model 0
  // more of its own.
  std::vector<Instance> found = {
      with_distinct(placed(0, square(100, 100, 200), spread(120, 120, 60)), 40),
      with_distinct(placed(1, square(101, 99, 200), spread(120, 120, 62)), 2)};
  detail::drop_look_alikes(found, 3);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].model, 0);
  // The same on the same keypoints elsewhere: the shared design placed differently in model 1.
  found = {with_distinct(placed(0, square(100, 100, 200), spread(120, 120, 60)), 40),
           with_distinct(placed(1, square(90, 40, 150), spread(120, 120, 30)), 4)};
  detail::drop_look_alikes(found, 3);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].model, 0);
}

TEST(LookAlikes, NoProductIsNamedWhenNoneStandsOut) {
  // Own evidence too close to a rival's, or too little of it: which product lies there is not
  // known.
  for (const auto& [first, second] : {std::pair{7, 5}, std::pair{5, 0}}) {
    std::vector<Instance> found = {
        with_distinct(placed(0, square(100, 100, 200), spread(120, 120, 40)), first),
        with_distinct(placed(1, square(101, 99, 200), spread(120, 120, 40)), second)};
    detail::drop_look_alikes(found, 3);
    EXPECT_TRUE(found.empty()) << first << " against " << second << " distinct matches";
  }
  // Alone, an instance needs the given number of distinct matches.
  std::vector<Instance> found = {
      with_distinct(placed(0, square(100, 100, 200), spread(120, 120, 20)), 2)};
  detail::drop_look_alikes(found, 3);
  EXPECT_TRUE(found.empty());
  found = {with_distinct(placed(0, square(100, 100, 200), spread(120, 120, 20)), 3)};
  detail::drop_look_alikes(found, 3);
  EXPECT_EQ(found.size(), 1u);
}

TEST(LookAlikes, OverlappingProductsAndTwoOfOneProductStay) {
  // The same model twice in the same place is not a look-alike (mean shift keeps those apart).
  std::vector<Instance> found = {placed(0, square(100, 100, 200), spread(120, 120, 60)),
                                 placed(0, square(103, 98, 200), spread(150, 150, 5))};
  detail::drop_look_alikes(found, 3);
  EXPECT_EQ(found.size(), 2u);
  // A product lying half over another: outlines overlap, but far from the same place.
  found = {placed(0, square(100, 100, 200), spread(120, 120, 60)),
           placed(1, square(200, 100, 200), spread(310, 120, 20))};
  detail::drop_look_alikes(found, 3);
  EXPECT_EQ(found.size(), 2u);
  // Nearly the same outline, but the weaker one's keypoints lie outside the stronger one's:
  // its evidence is its own.
  found = {placed(0, square(100, 100, 200), spread(120, 120, 60)),
           placed(1, square(100, 110, 200), spread(150, 303, 6))};
  detail::drop_look_alikes(found, 3);
  EXPECT_EQ(found.size(), 2u);
}

TEST(LookAlikes, TwoViewsOfOneProductInOnePlaceAreNoRivals) {
  // Models 0 and 1 are views of one product ("carton"): their shared design names the product
  // though neither has distinct matches; the view with more matches is the one seen.
  auto view = [](Instance inst) {
    inst.model_name = "carton";
    inst.distinct_matches = 0;
    return inst;
  };
  std::vector<Instance> found = {view(placed(0, square(100, 100, 200), spread(120, 120, 30))),
                                 view(placed(1, square(101, 99, 200), spread(120, 120, 40)))};
  detail::drop_look_alikes(found, 0);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].model, 1);
  // Models of two products in the same state name neither.
  found = {with_distinct(placed(0, square(100, 100, 200), spread(120, 120, 30)), 0),
           with_distinct(placed(1, square(101, 99, 200), spread(120, 120, 40)), 0)};
  detail::drop_look_alikes(found, 0);
  EXPECT_TRUE(found.empty());
}

TEST(LookAlikes, SamePlaceOfOutlinesThatAreNotConvex) {
  // Two L-shaped outlines of three unit cells each (scaled by 100) that tile a 200 x 200
  // square: they share two cells, an intersection over union of 0.5. Their convex hulls share
  // 3 of 4 cells; measured against the L's own areas (3 each) that read as 3 / 3, one place.
  const float u = 100.f;
  Instance l = placed(0, {{0, 0}, {2 * u, 0}, {2 * u, u}, {u, u}, {u, 2 * u}, {0, 2 * u}}, {});
  Instance turned = placed(1, {{2 * u, 2 * u}, {0, 2 * u}, {0, u}, {u, u}, {u, 0}, {2 * u, 0}}, {});
  EXPECT_FALSE(detail::same_place(l, turned));
  EXPECT_TRUE(detail::same_place(l, l));
  // A convex outline against itself shifted by a twentieth of its side: one place.
  EXPECT_TRUE(
      detail::same_place(placed(0, square(0, 0, 200), {}), placed(1, square(10, 0, 200), {})));
}
