// SPDX-License-Identifier: LGPL-2.1-or-later
// The benchmark metrics on small cases worked out by hand.
#include "dataset.hpp"
#include "geometry.hpp"
#include "metrics.hpp"
#include "tracking.hpp"

#include <gtest/gtest.h>

#include <algorithm>

using namespace pickdetect::eval;

namespace {

Polygon rect(double x0, double y0, double x1, double y1) {
  return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
}

/// The L of the unit-10 square without its upper right 6x6 (area 64), non-convex.
Polygon ell() {
  return {{0, 0}, {10, 0}, {10, 4}, {4, 4}, {4, 10}, {0, 10}};
}

Point centre(const Polygon& p) {
  Point c;
  for (const Point& q : p) {
    c.x += q.x / static_cast<double>(p.size());
    c.y += q.y / static_cast<double>(p.size());
  }
  return c;
}

TrueInstance truth(const std::string& model, const Polygon& polygon, double visible,
                   std::optional<double> covered = 0.0) {
  TrueInstance t;
  t.model = model;
  t.polygon = polygon;
  t.points = {centre(polygon)};
  t.visible = visible;
  t.covered = covered;
  return t;
}

DetectedInstance detection(const std::string& model, const Polygon& polygon,
                           bool pickable = false) {
  DetectedInstance d;
  d.model = model;
  d.polygon = polygon;
  d.points = {centre(polygon)};
  d.pickable = pickable;
  return d;
}

Dataset one_model(int width, int height, std::vector<TrueInstance> instances) {
  Dataset ds;
  ds.name = "hand";
  ModelInfo m;
  m.name = "box";
  m.image = "box.png";
  m.principal_points = {{5, 5}};
  m.polygon = rect(0, 0, 10, 10);
  ds.models.push_back(m);
  Scene s;
  s.image = "s.png";
  s.width = width;
  s.height = height;
  s.instances = std::move(instances);
  ds.scenes.push_back(s);
  return ds;
}

} // namespace

TEST(Geometry, AreaAndOrientation) {
  EXPECT_DOUBLE_EQ(area(rect(0, 0, 10, 5)), 50.0);
  Polygon r = rect(0, 0, 10, 5);
  std::reverse(r.begin(), r.end());
  EXPECT_DOUBLE_EQ(signed_area(r), -50.0);
  EXPECT_DOUBLE_EQ(signed_area(oriented(r)), 50.0);
  EXPECT_DOUBLE_EQ(area(ell()), 64.0);
  EXPECT_TRUE(is_convex(rect(0, 0, 1, 1)));
  EXPECT_FALSE(is_convex(ell()));
}

TEST(Geometry, IoUOfShiftedSquares) {
  const Overlap o = frame_overlap(rect(0, 0, 10, 10), rect(5, 0, 15, 10), 100, 100);
  EXPECT_DOUBLE_EQ(o.intersection, 50.0);
  EXPECT_DOUBLE_EQ(o.iou(), 50.0 / 150.0);
  // Orientation of either polygon does not matter.
  Polygon b = rect(5, 0, 15, 10);
  std::reverse(b.begin(), b.end());
  EXPECT_DOUBLE_EQ(frame_overlap(rect(0, 0, 10, 10), b, 100, 100).iou(), 50.0 / 150.0);
  // Rotated square inside a square: a diamond of half-diagonal 5 around (5, 5) has area 50.
  const Polygon diamond = {{5, 0}, {10, 5}, {5, 10}, {0, 5}};
  EXPECT_NEAR(frame_overlap(rect(0, 0, 10, 10), diamond, 100, 100).iou(), 0.5, 1e-12);
  // Disjoint.
  EXPECT_DOUBLE_EQ(frame_overlap(rect(0, 0, 1, 1), rect(2, 2, 3, 3), 100, 100).iou(), 0.0);
}

TEST(Geometry, NonConvexIntersections) {
  // L with a convex square: the L covers x < 4 or y < 4; in [2, 8]^2 that is 12 + 8.
  EXPECT_NEAR(intersection_area(ell(), rect(2, 2, 8, 8)), 20.0, 1e-12);
  EXPECT_NEAR(intersection_area(rect(2, 2, 8, 8), ell()), 20.0, 1e-12);
  // Two non-convex polygons: the L and its half turn (x > 6 or y > 6) share 2 squares of 16.
  const Polygon turned = {{10, 10}, {0, 10}, {0, 6}, {6, 6}, {6, 0}, {10, 0}};
  EXPECT_NEAR(intersection_area(ell(), turned), 32.0, 1e-12);
  EXPECT_NEAR(intersection_area(turned, ell()), 32.0, 1e-12);
  EXPECT_NEAR(intersection_area(ell(), ell()), 64.0, 1e-12);
}

TEST(Geometry, AreasClippedToTheFrame) {
  // A 10x10 square centred on the frame's corner keeps a quarter.
  EXPECT_DOUBLE_EQ(area(clip_to_frame(rect(-5, -5, 5, 5), 100, 100)), 25.0);
  // The L reaching out of a 7x7 frame keeps 49 minus its notch there (3x3): 40.
  EXPECT_NEAR(area(clip_to_frame(ell(), 7, 7)), 40.0, 1e-12);
  // Two squares overlapping only outside the frame do not overlap at all.
  const Overlap o = frame_overlap(rect(-10, 0, 5, 10), rect(-10, 0, -2, 10), 100, 100);
  EXPECT_DOUBLE_EQ(o.area_a, 50.0);
  EXPECT_DOUBLE_EQ(o.area_b, 0.0);
  EXPECT_DOUBLE_EQ(o.iou(), 0.0);
}

TEST(Metrics, PerfectDetectionAndPixelFigures) {
  const Dataset ds = one_model(100, 100, {truth("box", rect(10, 10, 30, 30), 1.0)});
  Scorer s(ds);
  s.add_scene(0, {detection("box", rect(12, 10, 32, 30))});
  const Summary r = s.model_summary("box");
  EXPECT_EQ(r.tp, 1);
  EXPECT_EQ(r.fp, 0);
  EXPECT_EQ(r.fn, 0);
  EXPECT_DOUBLE_EQ(*r.object_precision, 1.0);
  EXPECT_DOUBLE_EQ(*r.object_recall, 1.0);
  EXPECT_DOUBLE_EQ(*r.pixel_precision, 360.0 / 400.0);
  EXPECT_DOUBLE_EQ(*r.pixel_recall, 360.0 / 400.0);
  EXPECT_DOUBLE_EQ(*r.center_mean_px, 2.0);
  EXPECT_DOUBLE_EQ(*r.points_mean_px, 2.0);
}

TEST(Metrics, IoUThreshold) {
  // IoU exactly 0.5 matches; just below does not.
  const Dataset ds = one_model(100, 100, {truth("box", rect(0, 0, 30, 10), 1.0)});
  Scorer at(ds);
  at.add_scene(0, {detection("box", rect(0, 0, 15, 10))}); // 150 / 300
  EXPECT_EQ(at.model_summary("box").tp, 1);
  Scorer below(ds);
  below.add_scene(0, {detection("box", rect(0, 0, 14.9, 10))});
  EXPECT_EQ(below.model_summary("box").tp, 0);
  EXPECT_EQ(below.model_summary("box").fp, 1);
  EXPECT_EQ(below.model_summary("box").fn, 1);
}

TEST(Metrics, DontCareCountsNeitherWay) {
  const Dataset ds = one_model(
      100, 100,
      {truth("box", rect(0, 0, 10, 10), 1.0), truth("box", rect(50, 50, 60, 60), 0.29, 0.71)});
  Scorer s(ds);
  // One detection on the don't-care instance, nothing on the required one.
  s.add_scene(0, {detection("box", rect(50, 50, 60, 60))});
  const Summary r = s.model_summary("box");
  EXPECT_EQ(r.tp, 0);
  EXPECT_EQ(r.fp, 0);
  EXPECT_EQ(r.fn, 1);
  EXPECT_FALSE(r.object_precision.has_value());
  EXPECT_DOUBLE_EQ(*r.object_recall, 0.0);
  EXPECT_FALSE(r.pixel_precision.has_value()); // its area counts nowhere
  EXPECT_DOUBLE_EQ(*r.pixel_recall, 0.0);
  // Missing the don't-care instance is no error: visible 0.3 is required, 0.29 is not.
  const Dataset edge = one_model(100, 100, {truth("box", rect(0, 0, 10, 10), 0.3)});
  Scorer e(edge);
  e.add_scene(0, {});
  EXPECT_EQ(e.model_summary("box").fn, 1);
}

TEST(Metrics, OneToOneMatching) {
  const Dataset ds = one_model(100, 100, {truth("box", rect(0, 0, 10, 10), 1.0)});
  Scorer s(ds);
  // Two detections of the same instance: the better one is the TP, the other an FP.
  const std::vector<DetectedInstance> dets = {detection("box", rect(2, 0, 12, 10)),
                                              detection("box", rect(1, 0, 11, 10))};
  const std::vector<Pairing> p = match_scene(ds.scenes[0], dets, "box");
  EXPECT_EQ(p[0].instance, -1);
  EXPECT_EQ(p[1].instance, 0);
  s.add_scene(0, dets);
  EXPECT_EQ(s.model_summary("box").tp, 1);
  EXPECT_EQ(s.model_summary("box").fp, 1);
  EXPECT_DOUBLE_EQ(*s.model_summary("box").object_precision, 0.5);
}

TEST(Metrics, GreedyByDescendingIoU) {
  // D1 fits G1 best (0.818) and G2 too (0.667); D2 fits only G1 (0.667). Greedy gives D1 to
  // G1 and leaves D2 and G2 alone, although D2-G1 and D1-G2 would both be pairs.
  const Dataset ds = one_model(
      100, 100, {truth("box", rect(10, 0, 20, 10), 1.0), truth("box", rect(13, 0, 23, 10), 1.0)});
  const std::vector<DetectedInstance> dets = {detection("box", rect(11, 0, 21, 10)),
                                              detection("box", rect(8, 0, 18, 10))};
  const std::vector<Pairing> p = match_scene(ds.scenes[0], dets, "box");
  EXPECT_EQ(p[0].instance, 0);
  EXPECT_NEAR(p[0].iou, 9.0 / 11.0, 1e-12);
  EXPECT_EQ(p[1].instance, -1);
  Scorer s(ds);
  s.add_scene(0, dets);
  EXPECT_EQ(s.model_summary("box").tp, 1);
  EXPECT_EQ(s.model_summary("box").fp, 1);
  EXPECT_EQ(s.model_summary("box").fn, 1);
}

TEST(Metrics, ModelsAreMatchedApart) {
  Dataset ds = one_model(100, 100, {truth("box", rect(0, 0, 10, 10), 1.0)});
  ModelInfo other = ds.models[0];
  other.name = "other";
  ds.models.push_back(other);
  Scorer s(ds);
  // A perfect outline under the wrong model name is an FP of that model and a miss of "box".
  s.add_scene(0, {detection("other", rect(0, 0, 10, 10))});
  EXPECT_EQ(s.model_summary("box").fn, 1);
  EXPECT_EQ(s.model_summary("other").fp, 1);
  EXPECT_EQ(s.overall().fp, 1);
  EXPECT_EQ(s.overall().fn, 1);
  EXPECT_THROW(s.add_scene(0, {detection("nobody", rect(0, 0, 1, 1))}), FormatError);
}

TEST(Metrics, PixelAreasClippedToTheFrame) {
  // The instance hangs half out of the 100x100 frame; so does the detection.
  const Dataset ds = one_model(100, 100, {truth("box", rect(-20, 0, 20, 10), 1.0)});
  Scorer s(ds);
  s.add_scene(0, {detection("box", rect(-10, 0, 30, 10))});
  const Summary r = s.model_summary("box");
  // Inside the frame: truth [0, 20] (200), detection [0, 30] (300), common [0, 20] (200).
  // Unclipped the IoU would be 300 / 500 and the precision 300 / 400.
  EXPECT_EQ(r.tp, 1);
  EXPECT_DOUBLE_EQ(*r.pixel_precision, 200.0 / 300.0);
  EXPECT_DOUBLE_EQ(*r.pixel_recall, 1.0);
}

TEST(Metrics, CentreMeanAndP95) {
  Dataset ds = one_model(1000, 100, {});
  for (int i = 0; i < 5; ++i)
    ds.scenes[0].instances.push_back(truth("box", rect(100 * i, 0, 100 * i + 50, 50), 1.0));
  std::vector<DetectedInstance> dets;
  const double shift[] = {0, 1, 2, 3, 10};
  for (int i = 0; i < 5; ++i)
    dets.push_back(detection("box", rect(100 * i + shift[i], 0, 100 * i + 50 + shift[i], 50)));
  Scorer s(ds);
  s.add_scene(0, dets);
  const Summary r = s.model_summary("box");
  EXPECT_EQ(r.tp, 5);
  EXPECT_DOUBLE_EQ(*r.center_mean_px, 16.0 / 5.0);
  // Rank 0.95 * 4 = 3.8 between 3 and 10.
  EXPECT_NEAR(*r.center_p95_px, 3.0 + 0.8 * 7.0, 1e-12);
}

TEST(Metrics, PairedCentresCompareOnlyWhatEveryMethodFound) {
  // Three boxes; "a" finds all three, 1 px off each; "b" finds only the first, 0.5 px off.
  const Dataset ds =
      one_model(100, 100,
                {truth("box", rect(0, 0, 10, 10), 1.0), truth("box", rect(30, 30, 40, 40), 1.0),
                 truth("box", rect(60, 60, 70, 70), 1.0)});
  auto shifted = [](DetectedInstance d, double dx) {
    d.points[0].x += dx;
    return d;
  };
  std::map<std::string, Scorer> scorers;
  scorers.emplace("a", ds);
  scorers.emplace("b", ds);
  scorers.at("a").add_scene(0, {shifted(detection("box", rect(0, 0, 10, 10)), 1.0),
                                shifted(detection("box", rect(30, 30, 40, 40)), 1.0),
                                shifted(detection("box", rect(60, 60, 70, 70)), 1.0)});
  scorers.at("b").add_scene(0, {shifted(detection("box", rect(0, 0, 10, 10)), 0.5)});
  EXPECT_DOUBLE_EQ(*scorers.at("a").overall().center_mean_px, 1.0);
  EXPECT_DOUBLE_EQ(*scorers.at("b").overall().center_mean_px, 0.5);

  const PairedCenters paired = paired_centers(scorers);
  EXPECT_EQ(paired.instances, 1);
  EXPECT_DOUBLE_EQ(paired.mean_px.at("a"), 1.0);
  EXPECT_DOUBLE_EQ(paired.mean_px.at("b"), 0.5);
  EXPECT_NE(report_table(ds, scorers)
                .find("on the 1 required instances every method found: a "
                      "1.000 px, b 0.500 px."),
            std::string::npos);
  EXPECT_NE(report_json(ds, scorers).find("\"paired_centers\""), std::string::npos);

  // A method that found nothing leaves no instance to compare.
  scorers.emplace("c", ds);
  scorers.at("c").add_scene(0, {});
  EXPECT_EQ(paired_centers(scorers).instances, 0);
  EXPECT_TRUE(paired_centers(scorers).mean_px.empty());
}

TEST(Metrics, PickPrecisionAndRecall) {
  const Dataset ds = one_model(200, 100,
                               {truth("box", rect(0, 0, 20, 20), 1.0, 0.0),      // free
                                truth("box", rect(40, 0, 60, 20), 0.9, 0.1),     // covered
                                truth("box", rect(80, 0, 100, 20), 1.0, 0.01),   // free
                                truth("box", rect(120, 0, 140, 20), 0.1, 0.0)}); // don't care
  Scorer s(ds);
  s.add_scene(0, {detection("box", rect(0, 0, 20, 20), true),      // safe
                  detection("box", rect(40, 0, 60, 20), true),     // unsafe: covered 0.1
                  detection("box", rect(80, 0, 100, 20), false),   // free but not flagged
                  detection("box", rect(160, 0, 180, 20), true),   // false detection: unsafe
                  detection("box", rect(120, 0, 140, 20), true)}); // don't care, free: safe
  const Summary r = s.model_summary("box");
  EXPECT_EQ(r.tp, 3);
  EXPECT_EQ(r.fp, 1);
  EXPECT_DOUBLE_EQ(*r.pick_precision, 2.0 / 4.0);
  // Required and free: the first and third; only the first was flagged.
  EXPECT_DOUBLE_EQ(*r.pick_recall, 1.0 / 2.0);
}

TEST(Metrics, PickNeedsCoveredKnown) {
  const Dataset ds = one_model(100, 100, {truth("box", rect(0, 0, 20, 20), 1.0, std::nullopt)});
  Scorer s(ds);
  s.add_scene(0, {detection("box", rect(0, 0, 20, 20), true)});
  EXPECT_EQ(s.model_summary("box").tp, 1);
  EXPECT_FALSE(s.model_summary("box").pick_precision.has_value());
  EXPECT_FALSE(s.model_summary("box").pick_recall.has_value());
}

TEST(Metrics, OverallIsAMicroAverage) {
  Dataset ds = one_model(100, 100, {});
  ModelInfo other = ds.models[0];
  other.name = "other";
  ds.models.push_back(other);
  Scene& scene = ds.scenes[0];
  scene.instances = {truth("box", rect(0, 0, 10, 10), 1.0)};
  for (int i = 0; i < 3; ++i)
    scene.instances.push_back(truth("other", rect(20 * i, 50, 20 * i + 10, 60), 1.0));
  Scorer s(ds);
  // box: 1 of 1 found; other: 1 of 3 found. Macro recall would be 2/3, micro is 2/4.
  s.add_scene(0, {detection("box", rect(0, 0, 10, 10)), detection("other", rect(0, 50, 10, 60))});
  EXPECT_DOUBLE_EQ(*s.model_summary("box").object_recall, 1.0);
  EXPECT_DOUBLE_EQ(*s.model_summary("other").object_recall, 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(*s.overall().object_recall, 0.5);
  EXPECT_DOUBLE_EQ(*s.overall().pixel_recall, 200.0 / 400.0);
  // Timing: per model the median, overall the median of per-frame sums.
  s.add_time(0, "box", 4.0);
  s.add_time(0, "other", 6.0);
  EXPECT_DOUBLE_EQ(*s.model_summary("box").ms_per_frame, 4.0);
  EXPECT_DOUBLE_EQ(*s.overall().ms_per_frame, 10.0);
}

// All models in one element: a detection of a model that is not in the scene is a false
// detection, even where an instance of another model lies; the frame's time is one figure.
TEST(Metrics, AllModelsAtOnce) {
  Dataset ds = one_model(100, 100, {});
  ModelInfo other = ds.models[0];
  other.name = "other";
  ds.models.push_back(other);
  ds.scenes[0].instances = {truth("box", rect(0, 0, 10, 10), 1.0)};
  Scorer s(ds);
  s.add_scene(0, {detection("box", rect(0, 0, 10, 10)), detection("other", rect(0, 0, 10, 10))});
  s.add_frame_time(0, 7.0);
  EXPECT_EQ(s.model_summary("box").tp, 1);
  EXPECT_EQ(s.model_summary("other").fp, 1);
  EXPECT_FALSE(s.model_summary("other").object_recall); // Nothing of it to find.
  EXPECT_DOUBLE_EQ(*s.overall().object_precision, 0.5);
  EXPECT_DOUBLE_EQ(*s.overall().object_recall, 1.0);
  EXPECT_FALSE(s.model_summary("box").ms_per_frame);
  EXPECT_DOUBLE_EQ(*s.overall().ms_per_frame, 7.0);
  EXPECT_THROW(s.add_frame_time(1, 1.0), FormatError);
}

TEST(Dataset, ErrorsNameTheFileAndTheField) {
  const std::string good_model =
      R"("models": {"box": {"image": "m.png", "principal_points": [[5, 5]],
                            "polygon": [[0, 0], [10, 0], [10, 10]]}})";
  auto message = [](const std::string& text) {
    try {
      parse_dataset(text, "here/dataset.json", "here");
    } catch (const FormatError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message("{" + good_model + R"(, "scenes": [{"image": "a.png", "width": "wide",
            "height": 10, "instances": []}]})"),
            "here/dataset.json: scenes[0].width: expected a number, got a string");
  EXPECT_EQ(message("{" + good_model + R"(, "scenes": [{"image": "a.png", "width": 10,
            "height": 10, "instances": [{"model": "box", "points": [[1, 1]],
            "polygon": [[0, 0], [1, 0], [1, 1]]}]}]})"),
            "here/dataset.json: scenes[0].instances[0].visible: missing");
  EXPECT_EQ(message("{" + good_model + R"(, "scenes": [{"image": "a.png", "width": 10,
            "height": 10, "instances": [{"model": "cat", "points": [[1, 1]],
            "polygon": [[0, 0], [1, 0], [1, 1]], "visible": 1}]}]})"),
            "here/dataset.json: scenes[0].instances[0].model: 'cat' is not one of the "
            "dataset's models");
  EXPECT_EQ(message("{" + good_model + R"(, "scenes": [{"image": "a.png", "width": 10,
            "height": 10, "instances": [{"model": "box", "points": [[1, 1], [2, 2]],
            "polygon": [[0, 0], [1, 0], [1, 1]], "visible": 1}]}]})"),
            "here/dataset.json: scenes[0].instances[0].points: has 2 points but model 'box' has "
            "1 principal points");
  // A don't-care instance (a look-alike surface listed with visible 0) may leave its points
  // out; a required one may not.
  EXPECT_EQ(message("{" + good_model + R"(, "scenes": [{"image": "a.png", "width": 10,
            "height": 10, "instances": [{"model": "box", "points": [],
            "polygon": [[0, 0], [1, 0], [1, 1]], "visible": 0}]}]})"),
            "no error");
  EXPECT_EQ(message("{" + good_model + R"(, "scenes": [{"image": "a.png", "width": 10,
            "height": 10, "instances": [{"model": "box", "points": [],
            "polygon": [[0, 0], [1, 0], [1, 1]], "visible": 0.5}]}]})"),
            "here/dataset.json: scenes[0].instances[0].points: has 0 points but model 'box' has "
            "1 principal points");
  EXPECT_EQ(message(R"({"scenes": []})"), "here/dataset.json: models: missing");
  EXPECT_EQ(message("{" + good_model + R"(, "scenes": [{"image": "a.png", "width": 10,
            "height": 10, "instances": [{"model": "box", "points": [[1, 1]],
            "polygon": [[0, 0], [1, 0]], "visible": 1}]}]})"),
            "here/dataset.json: scenes[0].instances[0].polygon: a polygon needs at least 3 "
            "points, got 2");
  EXPECT_NE(message("{ not json").find("here/dataset.json: not valid JSON"), std::string::npos);
  EXPECT_EQ(message("{" + good_model + R"(, "scenes": []})"), "no error");
}

TEST(Dataset, DetectionsRoundTrip) {
  SceneDetections s;
  s.image = "scenes/a.png";
  s.method = "voting";
  s.ms["box"] = 12.5;
  DetectedInstance d = detection("box", rect(0.125, 1, 10.333333333333334, 11));
  d.score = 0.75;
  d.matches = 17;
  d.pickable = true;
  s.instances.push_back(d);
  const std::vector<SceneDetections> back =
      parse_detections(detections_line(s) + "\n\n" + detections_line(s), "mem");
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0].image, "scenes/a.png");
  EXPECT_EQ(back[0].method, "voting");
  EXPECT_DOUBLE_EQ(back[0].ms.at("box"), 12.5);
  EXPECT_FALSE(back[0].frame_ms);
  s.ms.clear();
  s.frame_ms = 30.25;
  const std::vector<SceneDetections> joint = parse_detections(detections_line(s), "mem");
  ASSERT_EQ(joint.size(), 1u);
  EXPECT_TRUE(joint[0].ms.empty());
  ASSERT_TRUE(joint[0].frame_ms);
  EXPECT_DOUBLE_EQ(*joint[0].frame_ms, 30.25);
  ASSERT_EQ(back[0].instances.size(), 1u);
  EXPECT_EQ(back[0].instances[0].matches, 17);
  EXPECT_TRUE(back[0].instances[0].pickable);
  EXPECT_DOUBLE_EQ(back[0].instances[0].polygon[1].x, 10.333333333333334);
  try {
    parse_detections("{\"image\": \"a\", \"instances\": [{\"model\": 3}]}\n", "det.jsonl");
    FAIL() << "no error";
  } catch (const FormatError& e) {
    EXPECT_STREQ(e.what(), "det.jsonl:1: instances[0].model: expected a string, got a number");
  }
}

TEST(Geometry, SelfCrossingOutlinesCountAsTheirHull) {
  // A bow tie (a folded square): its lobes cancel in the shoelace sum.
  const Polygon bow = {{0, 0}, {10, 10}, {10, 0}, {0, 10}};
  EXPECT_DOUBLE_EQ(signed_area(bow), 0.0);
  EXPECT_TRUE(self_intersects(bow));
  EXPECT_FALSE(self_intersects(rect(0, 0, 10, 10)));
  EXPECT_FALSE(self_intersects(ell()));
  EXPECT_DOUBLE_EQ(area(convex_hull(bow)), 100.0);
  EXPECT_DOUBLE_EQ(frame_area(bow, 100, 100), 100.0);
  EXPECT_DOUBLE_EQ(frame_area(bow, 5, 100), 50.0);
  EXPECT_DOUBLE_EQ(frame_overlap(bow, rect(0, 0, 10, 10), 100, 100).iou(), 1.0);
  // Collinear points drop out of the hull.
  EXPECT_EQ(convex_hull({{0, 0}, {5, 0}, {10, 0}, {10, 10}, {0, 10}}).size(), 4u);
}

namespace {

/// A sequence of `frames` frames of one model: object 1 rides right 10 px a frame, object 2
/// stands still; `dets(f)` gives frame f's detections.
template <typename Detections>
std::pair<Dataset, std::map<size_t, std::vector<DetectedInstance>>> two_objects(int frames,
                                                                                Detections dets) {
  Dataset ds = one_model(400, 300, {});
  ds.fps = 30.0;
  ds.scenes.clear();
  std::map<size_t, std::vector<DetectedInstance>> out;
  for (int f = 0; f < frames; ++f) {
    Scene s;
    s.image = "scenes/" + std::to_string(f) + ".png";
    s.width = 400;
    s.height = 300;
    TrueInstance a = truth("box", rect(10 + 10 * f, 10, 50 + 10 * f, 50), 1.0);
    a.track = 1;
    TrueInstance b = truth("box", rect(200, 200, 240, 240), 1.0);
    b.track = 2;
    s.instances = {a, b};
    ds.scenes.push_back(s);
    out[static_cast<size_t>(f)] = dets(f, s);
  }
  return {ds, out};
}

DetectedInstance with_track(DetectedInstance d, std::optional<long long> id) {
  d.track = id;
  return d;
}

} // namespace

TEST(Tracking, PerfectTracksScoreOne) {
  auto [ds, dets] = two_objects(8, [](int, const Scene& s) {
    return std::vector<DetectedInstance>{with_track(detection("box", s.instances[0].polygon), 7),
                                         with_track(detection("box", s.instances[1].polygon), 9)};
  });
  const TrackingSummary t = score_tracking(ds, dets);
  ASSERT_TRUE(t.mota && t.idf1);
  EXPECT_DOUBLE_EQ(*t.mota, 1.0);
  EXPECT_DOUBLE_EQ(*t.idf1, 1.0);
  EXPECT_EQ(t.id_switches, 0);
  EXPECT_EQ(t.fragmented, 0);
  EXPECT_EQ(t.ghosts, 0);
  EXPECT_EQ(t.objects_present, 2);
  EXPECT_EQ(t.objects_counted, 2);
}

TEST(Tracking, ASwitchFragmentsTheObjectAndCostsMotaAndIdf1) {
  // Object 1 under id 7 for frames 0-2, then id 8 for frames 3-7; a false box with id 50 in
  // frames 0-5 is a ghost; object 2 is missed in frame 4 and has no id in frame 6.
  auto [ds, dets] = two_objects(8, [](int f, const Scene& s) {
    std::vector<DetectedInstance> d = {
        with_track(detection("box", s.instances[0].polygon), f < 3 ? 7 : 8)};
    if (f != 4)
      d.push_back(with_track(detection("box", s.instances[1].polygon),
                             f == 6 ? std::nullopt : std::optional<long long>(9)));
    if (f < 6)
      d.push_back(with_track(detection("box", rect(300, 20, 340, 60)), 50));
    return d;
  });
  const TrackingSummary t = score_tracking(ds, dets);
  EXPECT_EQ(t.required, 16);
  EXPECT_EQ(t.fn, 1);
  EXPECT_EQ(t.fp, 6);
  EXPECT_EQ(t.id_switches, 3) << "7 -> 8, 9 -> none, none -> 9";
  EXPECT_EQ(t.detections, 15 + 6);
  EXPECT_EQ(t.idtp, 5 + 6) << "object 1 with id 8 (5 frames), object 2 with id 9 (6 frames)";
  EXPECT_NEAR(*t.mota, 1.0 - 10.0 / 16.0, 1e-12);
  EXPECT_NEAR(*t.idf1, 22.0 / 37.0, 1e-12);
  EXPECT_EQ(t.fragmented, 1);
  EXPECT_EQ(t.ghosts, 1);
  EXPECT_EQ(t.objects_counted, 2);
}
