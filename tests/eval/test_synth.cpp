// SPDX-License-Identifier: LGPL-2.1-or-later
// pickdetect-synth on tiny sets: the output parses as a dataset and its ground truth holds
// together (points and outline carried by one transform, fractions that add up, `covered`
// matching the outlines drawn on top), and equal seeds give equal output.
//
// Environment: PICKDETECT_SYNTH (the binary), TEST_DATA_DIR (Debian's opencv-doc pictures).
#include "dataset.hpp"
#include "geometry.hpp"

#include <glib.h>
#include <glib/gstdio.h>
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <cmath>
#include <string>
#include <vector>

using namespace pickdetect::eval;

namespace {

std::string env(const char* name) {
  const char* v = g_getenv(name);
  return v ? v : "";
}

std::string picture(const char* name) {
  return env("TEST_DATA_DIR") + "/" + name;
}

class Synth : public ::testing::Test {
protected:
  void SetUp() override {
    gchar* dir = g_dir_make_tmp("pickdetect-synth-test-XXXXXX", nullptr);
    ASSERT_NE(dir, nullptr);
    tmp_ = dir;
    g_free(dir);
    ASSERT_FALSE(env("PICKDETECT_SYNTH").empty()) << "PICKDETECT_SYNTH is not set";
  }
  void TearDown() override {
    const std::string cmd = "rm -rf '" + tmp_ + "'";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
  }

  /// Runs pickdetect-synth with the arguments; returns its exit status.
  int synth(std::vector<std::string> args) {
    args.insert(args.begin(), env("PICKDETECT_SYNTH"));
    std::vector<gchar*> argv;
    for (std::string& a : args)
      argv.push_back(a.data());
    argv.push_back(nullptr);
    gint status = 0;
    gchar* err = nullptr;
    GError* error = nullptr;
    const gboolean ok = g_spawn_sync(nullptr, argv.data(), nullptr, G_SPAWN_STDOUT_TO_DEV_NULL,
                                     nullptr, nullptr, nullptr, &err, &status, &error);
    EXPECT_TRUE(ok) << (error ? error->message : "");
    g_clear_error(&error);
    stderr_ = err ? err : "";
    g_free(err);
    return g_spawn_check_wait_status(status, nullptr) ? 0 : 1;
  }

  std::string path(const std::string& name) const { return tmp_ + "/" + name; }

  std::string tmp_;
  std::string stderr_;
};

std::string contents(const std::string& file) {
  gchar* text = nullptr;
  gsize n = 0;
  if (!g_file_get_contents(file.c_str(), &text, &n, nullptr))
    return {};
  std::string out(text, n);
  g_free(text);
  return out;
}

double angle_diff(double a, double b) {
  double d = std::fmod(std::abs(a - b), 360.0);
  return d > 180.0 ? 360.0 - d : d;
}

/// Rasterised share of `polygon` under the union of `above` (a tolerance check).
double covered_by(const Polygon& polygon, const std::vector<Polygon>& above, cv::Size frame) {
  const int margin = 600;
  cv::Mat own(frame + cv::Size(2 * margin, 2 * margin), CV_8UC1, cv::Scalar(0));
  cv::Mat top = own.clone();
  auto draw = [&](cv::Mat& m, const Polygon& p) {
    std::vector<cv::Point> pts; // 4 fractional bits
    for (const Point& q : p)
      pts.emplace_back(static_cast<int>(std::lround((q.x + margin - 0.5) * 16)),
                       static_cast<int>(std::lround((q.y + margin - 0.5) * 16)));
    cv::fillPoly(m, std::vector<std::vector<cv::Point>>{pts}, cv::Scalar(255), cv::LINE_8, 4);
  };
  draw(own, polygon);
  for (const Polygon& p : above)
    draw(top, p);
  const double total = cv::countNonZero(own);
  return total > 0 ? cv::countNonZero(own & top) / total : 0.0;
}

} // namespace

TEST_F(Synth, DatasetIsSelfConsistent) {
  ASSERT_EQ(synth({"--scenes", "4", "--size", "480x360", "--instances", "3-6", "--scale",
                   "0.45-0.6", "--seed", "5", "--format", "png", "--mixed-products", "--out",
                   path("set"), picture("box.png"), picture("opencv-logo.png")}),
            0)
      << stderr_;
  const Dataset ds = load_dataset(path("set"));
  ASSERT_EQ(ds.models.size(), 2u);
  ASSERT_EQ(ds.scenes.size(), 4u);
  const ModelInfo* box = ds.find_model("box");
  ASSERT_NE(box, nullptr);
  // A picture without alpha: the whole picture, centre and corners.
  cv::Mat box_picture = cv::imread(ds.path_of(box->image), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(box_picture.empty());
  EXPECT_DOUBLE_EQ(area(box->polygon), box_picture.cols * static_cast<double>(box_picture.rows));
  EXPECT_DOUBLE_EQ(box->principal_points[0].x, box_picture.cols / 2.0);
  // A picture with alpha keeps it, and its outline lies within the picture.
  const ModelInfo* logo = ds.find_model("opencv-logo");
  ASSERT_NE(logo, nullptr);
  cv::Mat logo_picture = cv::imread(ds.path_of(logo->image), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(logo_picture.channels(), 4);
  for (const Point& p : logo->polygon) {
    EXPECT_GE(p.x, 0);
    EXPECT_LE(p.x, logo_picture.cols);
  }

  int instances = 0, overlapped = 0;
  for (const Scene& scene : ds.scenes) {
    cv::Mat image = cv::imread(ds.path_of(scene.image));
    ASSERT_FALSE(image.empty()) << scene.image;
    EXPECT_EQ(image.cols, 480);
    EXPECT_EQ(image.rows, 360);
    std::vector<bool> z_seen(scene.instances.size(), false);
    for (size_t i = 0; i < scene.instances.size(); ++i) {
      const TrueInstance& t = scene.instances[i];
      const ModelInfo* model = ds.find_model(t.model);
      ASSERT_TRUE(t.covered && t.in_frame && t.z && t.angle && t.scale && t.tilt);
      ++instances;
      // Fractions of one outline: seen + hidden under others + outside <= whole.
      EXPECT_GE(t.visible, 0.0);
      EXPECT_LE(t.visible, *t.in_frame + 1e-9);
      EXPECT_LE(*t.in_frame, 1.0);
      EXPECT_LE(t.visible + *t.covered, 1.0 + 1e-6);
      EXPECT_GE(*t.scale, 0.45);
      EXPECT_LE(*t.scale, 0.6);
      EXPECT_LE(*t.tilt, 8.0);
      ASSERT_GE(*t.z, 0);
      ASSERT_LT(*t.z, static_cast<int>(scene.instances.size()));
      EXPECT_FALSE(z_seen[static_cast<size_t>(*t.z)]) << "z repeated";
      z_seen[static_cast<size_t>(*t.z)] = true;
      if (*t.z == static_cast<int>(scene.instances.size()) - 1) {
        EXPECT_EQ(*t.covered, 0.0) << "nothing lies on the top instance";
      }
      if (*t.covered > 0.05)
        ++overlapped;

      // Points and outline come from one homography: the one through the four corner points
      // carries the model's centre onto the instance's centre and its outline onto the outline.
      ASSERT_EQ(t.points.size(), 5u);
      std::vector<cv::Point2f> from, to;
      for (size_t k = 1; k < 5; ++k) {
        from.emplace_back(static_cast<float>(model->principal_points[k].x),
                          static_cast<float>(model->principal_points[k].y));
        to.emplace_back(static_cast<float>(t.points[k].x), static_cast<float>(t.points[k].y));
      }
      const cv::Matx33d h(cv::getPerspectiveTransform(from, to));
      auto map = [&h](const Point& p) {
        const cv::Vec3d q = h * cv::Vec3d(p.x, p.y, 1.0);
        return Point{q[0] / q[2], q[1] / q[2]};
      };
      EXPECT_LT(distance(map(model->principal_points[0]), t.points[0]), 0.05);
      ASSERT_EQ(t.polygon.size(), model->polygon.size());
      for (size_t k = 0; k < t.polygon.size(); ++k)
        EXPECT_LT(distance(map(model->polygon[k]), t.polygon[k]), 0.05);
      // Angle and scale describe the placement (tilt bends them a little).
      const double drawn = std::atan2(t.points[2].y - t.points[1].y, t.points[2].x - t.points[1].x);
      EXPECT_LT(angle_diff(drawn * 180.0 / CV_PI, *t.angle), 6.0);
      const double ratio = std::sqrt(area(t.polygon) / area(model->polygon));
      EXPECT_NEAR(ratio, *t.scale, 0.03 * *t.scale);
    }
  }
  EXPECT_GE(instances, 12);
  EXPECT_GE(overlapped, 1) << "no scene has overlap";
}

TEST_F(Synth, CoveredMatchesTheOutlinesOnTop) {
  // Pictures without alpha: the rendered layers are the outlines, so `covered` can be checked
  // against the polygons of the instances lying above.
  ASSERT_EQ(synth({"--scenes", "3", "--size", "400x300", "--instances", "5-7", "--scale", "0.5-0.6",
                   "--kind", "bin", "--seed", "9", "--format", "png", "--out", path("bin"),
                   picture("box.png")}),
            0)
      << stderr_;
  const Dataset ds = load_dataset(path("bin"));
  int checked = 0;
  for (const Scene& scene : ds.scenes) {
    for (const TrueInstance& t : scene.instances) {
      std::vector<Polygon> above;
      for (const TrueInstance& o : scene.instances)
        if (*o.z > *t.z)
          above.push_back(o.polygon);
      const double expected = covered_by(t.polygon, above, {scene.width, scene.height});
      EXPECT_NEAR(*t.covered, expected, 0.03) << scene.image << " z " << *t.z;
      // in_frame against the exact clipped area.
      EXPECT_NEAR(*t.in_frame, frame_area(t.polygon, scene.width, scene.height) / area(t.polygon),
                  0.03);
      ++checked;
    }
  }
  EXPECT_GE(checked, 15);
}

TEST_F(Synth, CoversCountAsCovering) {
  // The same scenes with and without foreign objects on them (the covers draw from their own
  // random stream): the covers add to `covered` and take from `visible`, never the other way.
  auto make = [&](const std::string& out, const std::string& covers) {
    return synth({"--scenes", "3", "--size", "400x300", "--instances", "3-4", "--scale", "0.5-0.6",
                  "--kind", "conveyor", "--seed", "5", "--format", "png", "--covers", covers,
                  "--out", path(out), picture("box.png")});
  };
  ASSERT_EQ(make("plain", "0"), 0) << stderr_;
  ASSERT_EQ(make("covered", "3"), 0) << stderr_;
  const Dataset plain = load_dataset(path("plain")), covered = load_dataset(path("covered"));
  ASSERT_EQ(plain.scenes.size(), covered.scenes.size());
  int more = 0;
  for (size_t s = 0; s < plain.scenes.size(); ++s) {
    ASSERT_EQ(plain.scenes[s].instances.size(), covered.scenes[s].instances.size());
    for (size_t i = 0; i < plain.scenes[s].instances.size(); ++i) {
      const TrueInstance& a = plain.scenes[s].instances[i];
      const TrueInstance& b = covered.scenes[s].instances[i];
      EXPECT_EQ(a.points[0].x, b.points[0].x);
      EXPECT_GE(*b.covered, *a.covered);
      EXPECT_LE(b.visible, a.visible);
      more += *b.covered > *a.covered + 0.01;
    }
  }
  EXPECT_GE(more, 3) << "three covers in each of three scenes must hide some instances";
  EXPECT_NE(synth({"--covers", "-1", "--out", path("x"), picture("box.png")}), 0);
  EXPECT_NE(stderr_.find("--covers"), std::string::npos) << stderr_;
}

TEST_F(Synth, SameSeedSameOutput) {
  const std::vector<std::string> common = {"--scenes", "2",       "--size",
                                           "320x240",  "--scale", "0.4-0.5",
                                           "--format", "png",     picture("box.png")};
  auto run = [&](const std::string& out, const std::string& seed) {
    std::vector<std::string> args = common;
    args.insert(args.end(), {"--seed", seed, "--out", path(out)});
    return synth(args);
  };
  ASSERT_EQ(run("a", "3"), 0) << stderr_;
  ASSERT_EQ(run("b", "3"), 0) << stderr_;
  ASSERT_EQ(run("c", "4"), 0) << stderr_;
  EXPECT_EQ(contents(path("a/dataset.json")), contents(path("b/dataset.json")));
  EXPECT_EQ(contents(path("a/scenes/0001.png")), contents(path("b/scenes/0001.png")));
  EXPECT_NE(contents(path("a/dataset.json")), contents(path("c/dataset.json")));
  EXPECT_FALSE(contents(path("a/scenes/0001.png")).empty());
}

TEST_F(Synth, ConveyorClip) {
  ASSERT_EQ(synth({"--video", path("belt.avi"), "--scenes", "6", "--size", "320x240", "--scale",
                   "0.3-0.35", "--seed", "2", "--out", path("belt"), picture("box.png")}),
            0)
      << stderr_;
  cv::VideoCapture clip(path("belt.avi"), cv::CAP_OPENCV_MJPEG);
  ASSERT_TRUE(clip.isOpened());
  int frames = 0;
  cv::Mat frame;
  while (clip.read(frame)) {
    EXPECT_EQ(frame.cols, 320);
    EXPECT_EQ(frame.rows, 240);
    ++frames;
  }
  EXPECT_EQ(frames, 6);
  // The annotated frames: the belt moves the objects right between frames.
  const Dataset ds = load_dataset(path("belt"));
  ASSERT_EQ(ds.scenes.size(), 6u);
  int instances = 0;
  for (const Scene& s : ds.scenes)
    instances += static_cast<int>(s.instances.size());
  EXPECT_GT(instances, 0);
}

TEST_F(Synth, FamilyOfLookAlikes) {
  ASSERT_EQ(
      synth({"--scenes", "1", "--size", "320x240", "--scale", "0.4-0.5", "--family", "0.6", "--out",
             path("family"), picture("box.png"), picture("fruits.jpg"), picture("home.jpg")}),
      0)
      << stderr_;
  const Dataset ds = load_dataset(path("family"));
  ASSERT_EQ(ds.models.size(), 2u);
  const cv::Mat box = cv::imread(picture("box.png"));
  const cv::Mat a = cv::imread(path("family/models/box_fruits.png"));
  const cv::Mat b = cv::imread(path("family/models/box_home.png"));
  ASSERT_FALSE(a.empty());
  ASSERT_FALSE(b.empty());
  ASSERT_EQ(a.size(), box.size());
  // The top 60 % is the design picture in both products; the rest differs between them.
  const int top = static_cast<int>(std::lround(0.6 * box.rows));
  EXPECT_EQ(cv::norm(a.rowRange(0, top), box.rowRange(0, top), cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(b.rowRange(0, top), box.rowRange(0, top), cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(a.rowRange(top, a.rows), b.rowRange(top, b.rows), cv::NORM_L1),
            10.0 * a.cols * (a.rows - top));

  EXPECT_NE(synth({"--family", "1.5", "--out", path("x"), picture("box.png"), picture("home.jpg")}),
            0);
  EXPECT_NE(stderr_.find("--family"), std::string::npos) << stderr_;
  EXPECT_NE(synth({"--family", "0.5", "--out", path("x"), picture("box.png")}), 0);
  EXPECT_NE(stderr_.find("--family"), std::string::npos) << stderr_;
}

TEST_F(Synth, RefusesBadInput) {
  EXPECT_NE(synth({"--out", path("x"), path("missing.png")}), 0);
  EXPECT_NE(stderr_.find("missing.png"), std::string::npos) << stderr_;
  EXPECT_NE(synth({"--size", "big", "--out", path("x"), picture("box.png")}), 0);
  EXPECT_NE(stderr_.find("--size"), std::string::npos) << stderr_;
  EXPECT_NE(synth({picture("box.png")}), 0);
}
